// Golden traces (harness/golden): the per-channel comparison with absolute and relative
// tolerances reports the first time and channel that diverge; structural differences (missing
// channels, rows, times, run status) are mismatches; channel selection drops the wall-time
// channels; golden files keep their provenance; the repository's manifest and golden files agree.
#include "harness/golden/golden.hpp"
#include "lexdyn/common/error.hpp"
#include "../common/expect_text.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

namespace lexdyn::golden {
namespace {

using lexdyn::testing::inputErrorOf;
namespace fs = std::filesystem;

std::string tempDir(const std::string& name) {
  const fs::path p = fs::path(LEXDYN_BINARY_DIR) / "test_output" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}

checks::TraceTable table() {
  checks::TraceTable t;
  t.metadata = {{"compiler", "GNU 12"}, {"golden_run_status", "completed"}};
  t.names = {"t", "a", "b", "c"};
  for (int k = 0; k < 10; ++k) {
    const double time = 0.1 * k;
    t.rows.push_back({time, std::sin(time), 1000.0 + time, k == 3 ? std::numeric_limits<double>::quiet_NaN() : 0.0});
  }
  return t;
}

TEST(Golden, IdenticalTracesMatch) {
  const Comparison c = compare(table(), table(), Tolerance{}, {});
  EXPECT_TRUE(c.ok) << c.report();
  EXPECT_EQ(c.rows, 10);
  EXPECT_EQ(c.channels, 4);
  EXPECT_EQ(c.max_abs_diff, 0.0);
  EXPECT_EQ(c.report().rfind("ok: 10 rows x 4 channels", 0), 0u) << c.report();
}

TEST(Golden, TolerancesAreAbsolutePlusRelative) {
  checks::TraceTable f = table();
  f.rows[5][2] += 0.9e-3;  // b ~ 1000.5: rel 1e-6 allows 1.0005e-3
  EXPECT_TRUE(compare(table(), f, Tolerance{0.0, 1e-6}, {}).ok);
  f.rows[5][2] += 0.2e-3;
  Comparison c = compare(table(), f, Tolerance{0.0, 1e-6}, {});
  EXPECT_FALSE(c.ok);
  EXPECT_EQ(c.first_channel, "b");
  EXPECT_NEAR(c.first_t, 0.5, 1e-15);
  EXPECT_NEAR(c.allowed, 1e-6 * (1000.0 + 0.1 * 5), 1e-15);
  // A per-channel tolerance (glob) overrides the default.
  EXPECT_TRUE(compare(table(), f, Tolerance{0.0, 1e-6}, {{"b*", Tolerance{2e-3, 0.0}}}).ok);
  EXPECT_FALSE(compare(table(), f, Tolerance{0.0, 1e-6}, {{"a*", Tolerance{2e-3, 0.0}}}).ok);
}

TEST(Golden, TheFirstDivergenceInTimeThenChannelOrderIsReported) {
  checks::TraceTable f = table();
  f.rows[7][1] += 1.0;  // a at 0.7 s
  f.rows[4][2] += 1.0;  // b at 0.4 s (earlier in time, later channel)
  f.rows[4][3] = 5.0;   // c at 0.4 s too
  const Comparison c = compare(table(), f, Tolerance{}, {});
  EXPECT_FALSE(c.ok);
  EXPECT_EQ(c.first_channel, "b");
  EXPECT_NEAR(c.first_t, 0.4, 1e-15);
  EXPECT_EQ(c.golden_value, 1000.4);
  EXPECT_EQ(c.fresh_value, 1001.4);
  EXPECT_EQ(c.diverging_at_first_t, 2);
  EXPECT_EQ(c.diverging_values, 3);
  const std::string r = c.report();
  EXPECT_NE(r.find("first divergence at t = 0.4 s in channel b (golden 1000.4, fresh 1001.4"), std::string::npos) << r;
}

TEST(Golden, NaNMatchesOnlyNaN) {
  checks::TraceTable f = table();
  f.rows[3][3] = 0.0;  // golden NaN
  EXPECT_FALSE(compare(table(), f, Tolerance{1.0, 1.0}, {}).ok);
  checks::TraceTable g = table();
  g.rows[2][3] = std::numeric_limits<double>::infinity();
  f = g;
  EXPECT_TRUE(compare(g, f, Tolerance{}, {}).ok);
  f.rows[2][3] = 1e300;
  EXPECT_FALSE(compare(g, f, Tolerance{1e301, 0.0}, {}).ok);
}

TEST(Golden, StructuralDifferencesAreMismatches) {
  checks::TraceTable f = table();
  f.names[3] = "d";  // golden channel c missing; d is extra
  Comparison c = compare(table(), f, Tolerance{}, {});
  EXPECT_FALSE(c.ok);
  EXPECT_NE(c.report().find("channel c is not in the fresh trace"), std::string::npos) << c.report();
  EXPECT_NE(c.report().find("1 channels only in the fresh trace"), std::string::npos) << c.report();
  f = table();
  f.rows.resize(6);  // the run stopped early
  f.metadata[1].second = "controller_failure";
  c = compare(table(), f, Tolerance{}, {});
  EXPECT_FALSE(c.ok);
  EXPECT_NE(c.report().find("row count: golden 10 rows, t = 0 .. 0.9 s; fresh 6 rows, t = 0 .. 0.5 s"), std::string::npos) << c.report();
  EXPECT_NE(c.report().find("run status: golden completed, fresh controller_failure"), std::string::npos) << c.report();
  f = table();
  f.rows[2][0] += 0.05;
  c = compare(table(), f, Tolerance{}, {});
  EXPECT_FALSE(c.ok);
  EXPECT_NE(c.report().find("row 2: golden time 0.2 s, fresh 0.25 s"), std::string::npos) << c.report();
  f = table();
  f.metadata[0].second = "Clang 15";
  c = compare(table(), f, Tolerance{}, {});
  EXPECT_TRUE(c.ok);  // a note only
  EXPECT_NE(c.report().find("built differently: compiler"), std::string::npos) << c.report();
}

TEST(Golden, SelectionDropsTheWallTimeChannelsAndFilesKeepProvenance) {
  Manifest m;
  m.channels = {"q.*", "time.*"};
  m.exclude = {"q.B"};
  checks::TraceTable t;
  t.names = {"t", "q.A", "q.B", "time.tick_us", "x"};
  t.rows = {{0.0, 1.0, 2.0, 3.0, 4.0}, {0.005, 1.5, 2.5, 3.5, 4.5}};
  t.metadata = {{"case", "c"}};
  const checks::TraceTable s = selectChannels(t, m);
  EXPECT_EQ(s.names, (std::vector<std::string>{"t", "q.A"}));
  EXPECT_EQ(s.rows[1], (std::vector<double>{0.005, 1.5}));
  const std::string dir = tempDir("golden_files");
  Entry e;
  e.case_name = "c";
  e.duration_s = 2.0;
  e.every_n_ticks = 10;
  writeGolden(dir + "/c.bfgs.csv", s, provenance(e, "bfgs", lexdyn::records::RunStatus::Completed, dir));
  const checks::TraceTable r = checks::readTrace(dir + "/c.bfgs.csv");
  EXPECT_EQ(r.rows, s.rows);
  for (const char* key : {"golden_format", "golden_case", "golden_method", "golden_duration_s", "golden_every_n_ticks", "golden_run_status",
                          "git_revision", "case"}) {
    EXPECT_NE(checks::findMetadata(r.metadata, key), nullptr) << key;
  }
  EXPECT_EQ(*checks::findMetadata(r.metadata, "golden_method"), "bfgs");
  EXPECT_TRUE(compare(r, s, Tolerance{0.0, 0.0}, {}).ok);  // the file round-trips exactly
  EXPECT_TRUE(goldenFileProblems(r).empty());
}

TEST(Golden, AGoldenFileCutAtALineEndIsNamedAsCut) {
  checks::TraceTable t = table();
  const std::string dir = tempDir("golden_cut");
  Entry e;
  e.case_name = "c";
  e.duration_s = 1.0;
  e.every_n_ticks = 1;
  writeGolden(dir + "/c.csv", t, provenance(e, "", lexdyn::records::RunStatus::Completed, dir));
  std::ifstream in(dir + "/c.csv");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Cut after its last row (the end mark gone) and after its fifth row: both at a line end.
  const size_t mark = text.rfind("# end:");
  ASSERT_NE(mark, std::string::npos);
  for (const size_t cut : {mark, text.rfind('\n', text.rfind('\n', mark - 1) - 1) + 1}) {
    std::ofstream(dir + "/cut.csv") << text.substr(0, cut);
    const checks::TraceTable r = checks::readTrace(dir + "/cut.csv");
    const std::vector<std::string> p = goldenFileProblems(r);
    ASSERT_EQ(p.size(), 1u) << cut;
    EXPECT_NE(p[0].find("no end mark"), std::string::npos) << p[0];
    EXPECT_NE(p[0].find("cut"), std::string::npos) << p[0];
  }
}

TEST(Golden, ManifestErrorsNameFileLineAndKey) {
  const std::string dir = tempDir("golden_manifest");
  auto err = [&](const std::string& text) {
    std::ofstream(dir + "/manifest.yaml") << text;
    return inputErrorOf([&] { loadManifest(dir + "/manifest.yaml"); });
  };
  const std::string cases = std::string(LEXDYN_SOURCE_DIR) + "/cases/";
  EXPECT_NE(err("format: lexdyn-golden-manifest/1\nentries:\n  - {case: nowhere.yaml, methods: [bfgs], duration_s: 1}\n")
                .find("manifest.yaml:3: entries[0].case: case file not found"),
            std::string::npos);
  EXPECT_NE(err("format: lexdyn-golden-manifest/1\nentries:\n  - {case: " + cases + "exp1.yaml, methods: [newton], duration_s: 1}\n")
                .find("entries[0].methods[0]"),
            std::string::npos);
  EXPECT_NE(err("format: lexdyn-golden-manifest/1\nentries:\n  - {case: " + cases + "exp1.yaml, duration_s: 1}\n")
                .find("missing required key 'methods'"),
            std::string::npos);
  EXPECT_NE(err("format: lexdyn-golden-manifest/1\nentries:\n  - {case: " + cases + "stand.yaml, duration_s: 11}\n")
                .find("entries[0].duration_s: longer than the case"),
            std::string::npos);
  EXPECT_NE(err("format: lexdyn-golden-manifest/1\ntolerance: {abs: 1, relative: 2}\nentries: []\n").find("tolerance.relative"),
            std::string::npos);
}

TEST(Golden, WallClockChannelsAreNeverCompared) {
  // Even in a golden that holds them (e.g. edited by hand), time.* channels are skipped: they
  // differ from run to run; a missing time.* channel is no problem either.
  checks::TraceTable g = table(), f = table();
  g.names.push_back("time.tick_us");
  f.names.push_back("time.tick_us");
  for (size_t r = 0; r < g.rows.size(); ++r) {
    g.rows[r].push_back(100.0 + static_cast<double>(r));
    f.rows[r].push_back(5000.0);
  }
  Comparison c = compare(g, f, Tolerance{0.0, 0.0}, {});
  EXPECT_TRUE(c.ok) << c.report();
  f = table();  // no time.* at all in the fresh trace
  c = compare(g, f, Tolerance{0.0, 0.0}, {});
  EXPECT_TRUE(c.ok) << c.report();
  EXPECT_EQ(c.report().find("time.tick_us"), std::string::npos) << c.report();
  // An ordinary channel that differs is still found.
  f = g;
  f.rows[9][1] += 1e-3;
  c = compare(g, f, Tolerance{1e-6, 0.0}, {});
  EXPECT_FALSE(c.ok);
  EXPECT_EQ(c.first_channel, "a");
}

TEST(Golden, RepositoryManifestAndGoldenFilesAgree) {
  const Manifest m = loadManifest(std::string(LEXDYN_SOURCE_DIR) + "/golden/manifest.yaml");
  ASSERT_FALSE(m.entries.empty());
  std::vector<std::string> expected;
  for (const Entry& e : m.entries) {
    for (const std::string& method : e.methods) {
      const std::string path = goldenPath(m, e.case_name, method);
      expected.push_back(fs::path(path).filename().string());
      ASSERT_TRUE(fs::is_regular_file(path)) << path << " missing: lexdyn-harness golden update --only " << goldenId(e.case_name, method);
      const checks::TraceTable t = checks::readTrace(path);
      EXPECT_EQ(*checks::findMetadata(t.metadata, "golden_case"), e.case_name) << path;
      EXPECT_EQ(*checks::findMetadata(t.metadata, "golden_method"), method.empty() ? "none" : method) << path;
      EXPECT_EQ(std::stod(*checks::findMetadata(t.metadata, "golden_duration_s")), e.duration_s) << path;
      EXPECT_EQ(std::stoi(*checks::findMetadata(t.metadata, "golden_every_n_ticks")), e.every_n_ticks) << path;
      EXPECT_LT(t.column("time.tick_us"), 0) << path;
      ASSERT_FALSE(t.rows.empty()) << path;
    }
  }
  // No stale golden files beside the manifest's.
  for (const auto& f : fs::directory_iterator(m.dir)) {
    if (f.path().extension() != ".csv") continue;
    EXPECT_NE(std::find(expected.begin(), expected.end(), f.path().filename().string()), expected.end())
        << f.path() << " is not in the manifest";
  }
}

}  // namespace
}  // namespace lexdyn::golden
