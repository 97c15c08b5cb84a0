// The records layer: every run status has one spelling that reads back as itself; the trace
// reader and the sweep's classification accept only the statuses they can hold.
#include "harness/checks/trace.hpp"
#include "harness/records/run_status.hpp"
#include "harness/records/sweep_record.hpp"
#include "lexdyn/common/error.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <tuple>

namespace {

using lexdyn::records::RunStatus;
namespace fs = std::filesystem;

TEST(RunStatus, EverySpellingReadsBackAsItsStatus) {
  std::set<std::string> seen;
  for (RunStatus s : lexdyn::records::allRunStatuses()) {
    const std::string text = lexdyn::records::toString(s);
    EXPECT_TRUE(seen.insert(text).second) << "spelling used twice: " << text;
    ASSERT_TRUE(lexdyn::records::parseRunStatus(text).has_value()) << text;
    EXPECT_EQ(*lexdyn::records::parseRunStatus(text), s) << text;
    std::ostringstream os;
    os << s;
    EXPECT_EQ(os.str(), text);
  }
  EXPECT_EQ(seen.size(), 12u);
  for (const char* other : {"", "Completed", "complete", "finished", "completed "}) {
    EXPECT_FALSE(lexdyn::records::parseRunStatus(other).has_value()) << "'" << other << "'";
  }
}

TEST(RunStatus, TheRunsOwnAndTheSweepsRecordedStatuses) {
  std::string own, recorded;
  for (RunStatus s : lexdyn::records::allRunStatuses()) {
    if (lexdyn::records::isRunsOwn(s)) own += std::string(own.empty() ? "" : " ") + lexdyn::records::toString(s);
    if (lexdyn::records::isRecordedBySweeps(s)) recorded += std::string(recorded.empty() ? "" : " ") + lexdyn::records::toString(s);
  }
  EXPECT_EQ(own, "completed integrator_failure controller_failure diverged internal_error interrupted input_error output_error");
  // A signal from outside, an output that could not be written and older drivers' lost runs say
  // something about the machine, never the configuration: a sweep does not record them.
  EXPECT_EQ(recorded, "completed integrator_failure controller_failure diverged internal_error input_error timeout crashed bad_input");
  EXPECT_EQ(lexdyn::records::spellings({RunStatus::Completed, RunStatus::Diverged}), "completed | diverged");
}

// A trace the writer wrote with each of the run's own statuses reads back with it; an end mark
// that names no run status is refused with the file and line.
TEST(RunStatus, TraceEndMarksRoundTripAndAnUnknownOneIsRefused) {
  const std::string dir = (fs::path(LEXDYN_BINARY_DIR) / "test_output" / "records_trace_end_marks").string();
  fs::remove_all(dir);
  fs::create_directories(dir);
  lexdyn::checks::TraceSchema schema;
  schema.add("t");
  const double row = 0.0;
  for (RunStatus s : lexdyn::records::allRunStatuses()) {
    if (!lexdyn::records::isRunsOwn(s)) continue;
    const std::string path = dir + "/" + lexdyn::records::toString(s) + ".csv";
    {
      lexdyn::checks::TraceWriter w(path, schema, {}, 1);
      w.write(&row);
      w.finish(s, "why");
    }
    const lexdyn::checks::TraceTable t = lexdyn::checks::readTrace(path);
    ASSERT_TRUE(t.end_status.has_value());
    EXPECT_EQ(*t.end_status, s);
    EXPECT_EQ(t.complete(), s == RunStatus::Completed);
  }
  // The writer's file with its end mark's status renamed.
  std::string text;
  {
    std::ifstream in(dir + "/diverged.csv");
    std::stringstream ss;
    ss << in.rdbuf();
    text = ss.str();
  }
  const size_t at = text.find("# end: diverged");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 15, "# end: fell_over");
  std::ofstream(dir + "/renamed.csv") << text;
  try {
    (void)lexdyn::checks::readTrace(dir + "/renamed.csv");
    ADD_FAILURE() << "an end mark of no run status was read";
  } catch (const lexdyn::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("renamed.csv:"), std::string::npos) << what;
    EXPECT_EQ(e.where().rfind(dir + "/renamed.csv:", 0), 0u) << e.where();
    EXPECT_NE(what.find("end mark 'fell_over' is no run status (completed | integrator_failure"), std::string::npos) << what;
  }
  fs::remove_all(dir);
}

// A sweep's run record reads back as written; one of another format or none (an older build's),
// or of a status a sweep never records (a run killed or stopped from outside), is refused.
TEST(SweepRunRecord, RoundTripsAndRefusesOtherFormatsAndUnrecordedStatuses) {
  lexdyn::records::SweepRunRecord r;
  r.status = RunStatus::Diverged;
  r.message = "the guard";
  r.exit_code = 3;
  r.simulated_s = 12.5;
  r.checks.push_back({"upright", false, 0.2, 0.3, -0.1, "m", "lowest"});
  r.statistics["final_error"] = 0.25;
  r.final_errors["right_hand"] = 0.125;
  r.peak_iterations = 7;
  const nlohmann::json j = lexdyn::records::toJson(r);
  EXPECT_EQ(j["format"], lexdyn::records::kSweepRunFormat);
  std::string why;
  const auto back = lexdyn::records::sweepRunFromJson(j, why);
  ASSERT_TRUE(back.has_value()) << why;
  EXPECT_EQ(lexdyn::records::toJson(*back), j);
  EXPECT_EQ(back->failures(), (std::vector<std::string>{lexdyn::records::kRunCompletedCheck, "upright"}));
  nlohmann::json old = j;
  old.erase("format");
  EXPECT_FALSE(lexdyn::records::sweepRunFromJson(old, why).has_value());
  EXPECT_NE(why.find("no format (written by an older build)"), std::string::npos) << why;
  old["format"] = "lexdyn-sweep-run/0";
  EXPECT_FALSE(lexdyn::records::sweepRunFromJson(old, why).has_value());
  EXPECT_NE(why.find("format 'lexdyn-sweep-run/0', this build reads 'lexdyn-sweep-run/1'"), std::string::npos) << why;
  for (const char* status : {"interrupted", "output_error", "no_summary", "", "fell"}) {
    nlohmann::json k = j;
    k["status"] = status;
    EXPECT_FALSE(lexdyn::records::sweepRunFromJson(k, why).has_value()) << status;
    EXPECT_NE(why.find("is not the end of a run"), std::string::npos) << why;
  }
  nlohmann::json nan = j;
  nan["checks"][0]["value"] = nullptr;  // NaN is written as null and reads back as NaN
  const auto n = lexdyn::records::sweepRunFromJson(nan, why);
  ASSERT_TRUE(n.has_value()) << why;
  EXPECT_TRUE(std::isnan(n->checks[0].value));
}

// A point record reads back as written (NaN comparisons as null); a damaged one is refused with
// the field it lacks, and one of another format or none with both formats named.
TEST(SweepPointRecord, RoundTripsAndNamesWhatIsWrong) {
  namespace rec = lexdyn::records;
  rec::SweepPointRecord p;
  p.point = 4;
  p.values = {{"kp", "2.5"}, {"servo", "stiff"}};
  p.overrides = {{"controller.tasks[position].gains.kp", "2.5"}};
  rec::SweepRunRecord run;
  run.checks.push_back({"upright", true, 0.1, 0.3, 0.2, "m", ""});
  p.runs["bfgs"] = {run, "lexdyn-harness run case.yaml", "lexdyn-harness sweep point s.yaml --index 4"};
  run.status = RunStatus::Diverged;
  p.runs["wls"] = {run, "a", "b"};
  rec::SweepComparisonRecord c;
  c.name = "final";
  c.better = "bfgs";
  c.worse = "wls";
  c.limit = 0.001;
  c.stopped_early = {"wls"};
  p.comparisons.push_back(c);
  p.failures = {"wls:run_completed"};
  const nlohmann::json j = rec::toJson(p);
  EXPECT_EQ(j["format"], rec::kSweepPointFormat);
  EXPECT_TRUE(j["comparisons"][0]["value"].is_null());
  std::string why;
  const auto back = rec::sweepPointFromJson(j, why);
  ASSERT_TRUE(back.has_value()) << why;
  EXPECT_EQ(rec::toJson(*back), j);
  EXPECT_EQ(back->run("wls").status, RunStatus::Diverged);
  EXPECT_EQ(back->value("servo"), "stiff");
  EXPECT_EQ(back->value("mu", "0"), "0");
  EXPECT_TRUE(std::isnan(back->comparisons[0].value));
  // (where, what is put there: null erases it, the message)
  const std::tuple<const char*, nlohmann::json, const char*> damages[] = {
      {"/failures", nlohmann::json::array({1}), "failures: not a list of strings"},
      {"/comparisons/0/better_wins", "yes", "comparisons: better_wins: not true or false"},
      {"/overrides/0/value", 2.5, "overrides: an entry without its path and value"},
      {"/runs/wls/format", nullptr, "the run of wls: a run record of no format"},
      {"/values", nullptr, "no values"},
      {"/point", 4.5, "point: not an integer"},
  };
  for (const auto& [where, what, expected] : damages) {
    nlohmann::json d = j;
    const nlohmann::json::json_pointer ptr(where);
    if (what.is_null())
      d[ptr.parent_pointer()].erase(ptr.back());
    else
      d[ptr] = what;
    EXPECT_FALSE(rec::sweepPointFromJson(d, why).has_value()) << where;
    EXPECT_EQ(why.rfind(expected, 0), 0u) << where << ": " << why;
  }
  nlohmann::json old = j;
  old.erase("format");
  EXPECT_FALSE(rec::sweepPointFromJson(old, why).has_value());
  EXPECT_NE(why.find("a point record of no format (written by an older build), this build reads 'lexdyn-sweep-point/1'"), std::string::npos)
      << why;
}

// A failure database line reads back; a line without a format (written before the key existed)
// reads as version 1; another format, or a line without its check, is refused naming it.
TEST(SweepFailureEntry, ReadsLinesOfNoFormatAsVersionOneAndRefusesOthers) {
  namespace rec = lexdyn::records;
  const rec::SweepFailureEntry e{"pointmass-damping", "wls", "no_overshoot", {{"mu", "0.47"}}, 7.785};
  const nlohmann::json j = rec::toJson(e);
  EXPECT_EQ(j["format"], rec::kSweepFailureFormat);
  std::string why;
  auto back = rec::sweepFailureFromJson(j, why);
  ASSERT_TRUE(back.has_value()) << why;
  EXPECT_EQ(rec::toJson(*back), j);
  nlohmann::json old = j;
  old.erase("format");
  back = rec::sweepFailureFromJson(old, why);
  ASSERT_TRUE(back.has_value()) << why;
  EXPECT_EQ(rec::toJson(*back), j);
  nlohmann::json other = j;
  other["format"] = "lexdyn-sweep-failure/2";
  EXPECT_FALSE(rec::sweepFailureFromJson(other, why).has_value());
  EXPECT_NE(why.find("format 'lexdyn-sweep-failure/2', this build reads 'lexdyn-sweep-failure/1'"), std::string::npos) << why;
  nlohmann::json no_check = j;
  no_check.erase("check");
  EXPECT_FALSE(rec::sweepFailureFromJson(no_check, why).has_value());
  EXPECT_EQ(why, "no check");
  nlohmann::json bad_values = j;
  bad_values["values"]["mu"] = 0.47;
  EXPECT_FALSE(rec::sweepFailureFromJson(bad_values, why).has_value());
  EXPECT_EQ(why, "values: not an object of strings");
}

}  // namespace
