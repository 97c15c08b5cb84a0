// The run record (summary.json) through the records layer: the file a real run writes reads back
// into the same record, and writing that record gives the same JSON; a damaged or foreign
// summary is refused with every bad field named at once.
#include "harness/cases/runner.hpp"
#include "harness/records/run_record.hpp"
#include "lexdyn/common/error.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;
using lexdyn::records::RunStatus;

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// exp1's WLS run cut to 0.3 s: a lexdyn controller (tasks, solver, timing), an expected failure
// (cut short), a scenario duration and a machine-dependent check are all in its summary.
const std::string& exp1WlsSummary() {
  static const std::string path = [] {
    const fs::path dir = fs::path(LEXDYN_BINARY_DIR) / "test_output" / "records_exp1_wls";
    fs::remove_all(dir);
    lexdyn::cases::CaseSpec spec = lexdyn::cases::loadCase(std::string(LEXDYN_SOURCE_DIR) + "/cases/exp1.yaml");
    lexdyn::cases::overrideMethod(spec, "wls", "test");
    spec.duration_s = 0.3;
    spec.stop_at_s = 0.3;
    lexdyn::cases::RunOptions o;
    o.out_dir = dir.string();
    o.progress = false;
    const lexdyn::cases::RunSummary s = lexdyn::cases::runCase(spec, o);
    EXPECT_EQ(s.status, RunStatus::Completed) << s.message;
    return s.summary_path;
  }();
  return path;
}

TEST(RunRecord, ARealRunsSummaryReadsBackAndWritesTheSameJson) {
  const std::string& path = exp1WlsSummary();
  const lexdyn::records::RunRecord r = lexdyn::records::readRunRecord(path);
  EXPECT_EQ(r.format, lexdyn::records::kRunSummaryFormat);
  EXPECT_EQ(r.case_name, "exp1");
  EXPECT_EQ(r.status, RunStatus::Completed);
  EXPECT_EQ(r.method, "wls");
  EXPECT_DOUBLE_EQ(r.simulated_s, 0.3);
  ASSERT_TRUE(r.scenario_duration_s.has_value());
  EXPECT_GT(*r.scenario_duration_s, 0.3);
  ASSERT_TRUE(r.expected_failure.has_value());
  EXPECT_EQ(r.expected_failure->checks.empty(), false);
  ASSERT_TRUE(r.controller.has_value());
  EXPECT_EQ(r.controller->ticks, 61);  // t = 0, 0.005, ..., 0.3 s
  EXPECT_FALSE(r.controller->tasks.empty());
  EXPECT_FALSE(r.checks.empty());
  bool machine_dependent = false;
  for (const auto& c : r.checks) machine_dependent = machine_dependent || c.machine_dependent;
  EXPECT_TRUE(machine_dependent) << "exp1 has a wall-clock check";
  EXPECT_FALSE(r.trace_header.empty());
  // One writer: the record written again is the file's JSON, field for field.
  EXPECT_EQ(lexdyn::records::toJson(r), nlohmann::json::parse(slurp(path)));
}

// docs/file-formats.md's table of summary.json keys is the writer's: every key a real run writes
// is documented, and every documented key is written (statistics only when figures are asked for).
TEST(RunRecord, TheDocumentedKeysAreTheWrittenOnes) {
  const std::string doc = slurp(std::string(LEXDYN_SOURCE_DIR) + "/docs/file-formats.md");
  const size_t from = doc.find("**Run summary**"), to = doc.find("**Sweep run**");
  ASSERT_NE(from, std::string::npos);
  ASSERT_NE(to, std::string::npos);
  std::set<std::string> documented;
  std::istringstream lines(doc.substr(from, to - from));
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("| `", 0) != 0) continue;
    const std::string first = line.substr(2, line.find(" |", 2) - 2);  // "`a`, `b`"
    for (size_t p = first.find('`'); p != std::string::npos; p = first.find('`', first.find('`', p + 1) + 1)) {
      const size_t q = first.find('`', p + 1);
      documented.insert(first.substr(p + 1, q - p - 1));
    }
  }
  const nlohmann::json j = nlohmann::json::parse(slurp(exp1WlsSummary()));
  std::set<std::string> written;
  for (auto it = j.begin(); it != j.end(); ++it) written.insert(it.key());
  for (const std::string& k : written) EXPECT_TRUE(documented.count(k)) << "summary.json key '" << k << "' is not in docs/file-formats.md";
  for (const std::string& k : documented) {
    if (k == "statistics") continue;  // written when a sweep asks for figures
    EXPECT_TRUE(written.count(k)) << "docs/file-formats.md documents '" << k << "', which the run did not write";
  }
  EXPECT_GT(documented.size(), 25u);
}

TEST(RunRecord, EveryBadFieldIsNamedAtOnce) {
  nlohmann::json j = nlohmann::json::parse(slurp(exp1WlsSummary()));
  j.erase("simulated_s");
  j["checks"][1]["passed"] = "yes";
  j["status"] = "fell_over";
  j["controller"]["status_counts"]["ok"] = 1.5;
  try {
    (void)lexdyn::records::runRecordFromJson(j, "run/summary.json");
    ADD_FAILURE() << "a damaged summary was read";
  } catch (const lexdyn::InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("run/summary.json: not a run summary this build can read: ", 0), 0u) << what;
    for (const char* part : {"simulated_s: missing", "checks[1].passed: not true or false",
                             "status: 'fell_over' is no run status (completed |", "controller.status_counts.ok: not an integer"}) {
      EXPECT_NE(what.find(part), std::string::npos) << part << " in " << what;
    }
  }
}

// A summary holding NaN (another writer's; the harness writes null) or cut short is refused with
// the file, the line and the key, as lexdyn.read_summary does.
TEST(RunRecord, ANaNOrACutSummaryIsNamedByLineAndKey) {
  const std::string text = slurp(exp1WlsSummary());
  const fs::path dir = fs::path(LEXDYN_BINARY_DIR) / "test_output" / "records_bad";
  fs::create_directories(dir);
  const size_t at = text.find("\"simulated_s\": ");
  ASSERT_NE(at, std::string::npos);
  const size_t end = text.find_first_of(",\n", at);
  const std::string nan = text.substr(0, at) + "\"simulated_s\": NaN" + text.substr(end);
  const long line = 1 + std::count(text.begin(), text.begin() + static_cast<long>(at), '\n');
  const std::pair<std::string, std::string> cases[] = {
      {nan, "nan.json: not a run summary: line " + std::to_string(line) + ": simulated_s: expected a finite number or null, found NaN"},
      {text.substr(0, text.size() / 2), "cut.json: not a run summary: line "},
  };
  for (const auto& [content, expected] : cases) {
    const std::string name = expected.substr(0, expected.find(':'));
    std::ofstream((dir / name).string()) << content;
    try {
      (void)lexdyn::records::readRunRecord((dir / name).string());
      ADD_FAILURE() << name << " was read";
    } catch (const lexdyn::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
}

TEST(RunRecord, AnEmptyStatusIsNoStatus) {
  nlohmann::json j = nlohmann::json::parse(slurp(exp1WlsSummary()));
  j["status"] = "";
  try {
    (void)lexdyn::records::runRecordFromJson(j, "s.json");
    ADD_FAILURE() << "an empty status was read";
  } catch (const lexdyn::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("status: '' is no run status"), std::string::npos) << e.what();
  }
}

TEST(RunRecord, ASummaryOfAnotherFormatIsRefusedByItsFormat) {
  nlohmann::json j = nlohmann::json::parse(slurp(exp1WlsSummary()));
  j["format"] = "lexdyn-run-summary/2";
  try {
    (void)lexdyn::records::runRecordFromJson(j, "s.json");
    ADD_FAILURE();
  } catch (const lexdyn::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("s.json: a run summary of format 'lexdyn-run-summary/2'; this build reads 'lexdyn-run-summary/1'"),
              std::string::npos)
        << e.what();
  }
  j.erase("format");
  try {
    (void)lexdyn::records::runRecordFromJson(j, "s.json");
    ADD_FAILURE();
  } catch (const lexdyn::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no format (no 'format' key: written by an older build)"), std::string::npos) << e.what();
  }
  try {
    (void)lexdyn::records::readRunRecord(exp1WlsSummary() + ".missing");
    ADD_FAILURE();
  } catch (const lexdyn::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("summary.json.missing: cannot be read"), std::string::npos) << e.what();
  }
}

}  // namespace
