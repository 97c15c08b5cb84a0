// The records layer: every run status has one spelling that reads back as itself; the trace
// reader and the sweep's classification accept only the statuses they can hold.
#include "harness/checks/trace.hpp"
#include "harness/records/run_status.hpp"
#include "lexdyn/common/error.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

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
  const std::string dir = (fs::temp_directory_path() / "lexdyn_test_records").string();
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
    EXPECT_NE(what.find("renamed.csv"), std::string::npos) << what;
    EXPECT_NE(what.find("end mark 'fell_over' is no run status (completed | integrator_failure"), std::string::npos) << what;
  }
  fs::remove_all(dir);
}

}  // namespace
