// The malformed inputs that once crashed a tool, hung it, were accepted as if nothing were wrong
// or were refused without saying what was wrong: each still gives its expected exit code and
// message (tests/malformed/expectations.txt; docs/architecture.md, "Errors and exit codes"). The
// large ones (deep nesting, size guards) are generated here instead of being kept as files.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <vector>

namespace {

namespace fs = std::filesystem;

const std::string kDir = std::string(LEXDYN_SOURCE_DIR) + "/tests/malformed";
const std::string kBin = std::string(LEXDYN_BINARY_DIR) + "/bin/";

std::string outDir() {
  static const std::string d = [] {
    const fs::path p = fs::path(LEXDYN_BINARY_DIR) / "test_output" / "malformed";
    fs::remove_all(p);
    fs::create_directories(p / "generated");
    return p.string();
  }();
  return d;
}

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t");
  const size_t b = s.find_last_not_of(" \t");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

struct Outcome {
  int code = -1;
  std::string err;
};

// Runs a command from the corpus directory, under a 60 s limit (timeout's 124 = a hang).
Outcome runIn(const std::string& dir, const std::string& cmd, const std::string& tag) {
  const std::string err = outDir() + "/" + tag + ".stderr";
  const std::string full = "cd '" + dir + "' && timeout 60 " + cmd + " > /dev/null 2> '" + err + "'";
  const int status = std::system(full.c_str());
  Outcome o;
  o.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  std::ifstream in(err);
  std::ostringstream ss;
  ss << in.rdbuf();
  o.err = ss.str();
  return o;
}

// The tool command of an expectation line.
std::string command(const std::string& spec, const std::string& tag) {
  std::istringstream in(spec);
  std::string verb, rest;
  in >> verb;
  std::getline(in, rest);
  rest = trim(rest);
  if (verb == "run") return kBin + "lexdyn-harness run " + rest + " --out '" + outDir() + "/" + tag + "' --quiet";
  if (verb == "check") return kBin + "lexdyn-harness check " + rest + " --case ../../cases/pointmass-damping.yaml";
  if (verb == "solve") return kBin + "lexdyn-solve " + rest;
  if (verb == "golden-list") return kBin + "lexdyn-harness golden list --manifest " + rest;
  if (verb == "golden-check") return kBin + "lexdyn-harness golden check --work '" + outDir() + "/" + tag + "' --manifest " + rest;
  if (verb == "sweep") return kBin + "lexdyn-solver-sweep " + rest;
  if (verb == "harness") return kBin + "lexdyn-harness " + rest + " --out '" + outDir() + "/" + tag + "'";
  return "";
}

TEST(MalformedInputs, EachGivesItsExitCodeAndMessage) {
  std::ifstream in(kDir + "/expectations.txt");
  ASSERT_TRUE(in) << kDir;
  std::string line;
  int n = 0, lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (trim(line).empty() || trim(line)[0] == '#') continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string part;
    while (std::getline(ss, part, '|')) f.push_back(trim(part));
    ASSERT_GE(f.size(), 3u) << "expectations.txt:" << lineno;
    const std::string tag = "line" + std::to_string(lineno);
    const std::string cmd = command(f[0], tag);
    ASSERT_FALSE(cmd.empty()) << "expectations.txt:" << lineno << ": unknown command " << f[0];
    const Outcome o = runIn(kDir, cmd, tag);
    EXPECT_EQ(o.code, std::stoi(f[1])) << "expectations.txt:" << lineno << ": " << f[0] << "\n" << o.err;
    EXPECT_NE(o.err.find(f[2]), std::string::npos)
        << "expectations.txt:" << lineno << ": " << f[0] << "\nexpected: " << f[2] << "\nfound: " << o.err;
    ++n;
  }
  EXPECT_GE(n, 140);
}

void write(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

std::string repeat(const std::string& s, int n) {
  std::string out;
  out.reserve(s.size() * static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) out += s;
  return out;
}

// Inputs too large to keep as files: nesting that overflowed a parser's stack, sizes that ran for
// minutes or exhausted memory.
TEST(MalformedInputs, LargeGeneratedInputs) {
  const std::string g = outDir() + "/generated";
  const std::string models = std::string(LEXDYN_SOURCE_DIR) + "/models/point_mass/";
  std::ifstream pm_in(models + "point_mass.urdf");
  const std::string pm((std::istreambuf_iterator<char>(pm_in)), std::istreambuf_iterator<char>());
  const std::string head = "<robot name=\"point_mass\">";
  const std::string body = pm.substr(pm.find(head) + head.size());
  auto urdfCase = [&](const std::string& name, const std::string& urdf) {
    write(g + "/" + name + ".urdf", urdf);
    std::ifstream c(std::string(LEXDYN_SOURCE_DIR) + "/cases/pointmass-damping.yaml");
    std::string text((std::istreambuf_iterator<char>(c)), std::istreambuf_iterator<char>());
    text.replace(text.find("../models/point_mass/point_mass.urdf"), 36, name + ".urdf");
    text.replace(text.find("../models/point_mass/point_mass.yaml"), 36, models + "point_mass.yaml");
    write(g + "/" + name + ".yaml", text);
    return kBin + "lexdyn-harness run " + name + ".yaml --out out-" + name + " --quiet";
  };
  struct Case {
    std::string cmd;
    int code;
    std::string fragment;
  };
  std::vector<Case> cases;
  // A URDF nested 100000 elements deep segfaulted lexdyn-harness run.
  cases.push_back({urdfCase("deep", head + repeat("<a>", 100000) + repeat("</a>", 100000) + body), 2,
                   "deep.urdf:1: elements are nested more than 64 deep"});
  // 20000 links in a chain of fixed joints overflowed the stack of the tree walk.
  std::string chain;
  for (int i = 0; i < 20000; ++i) {
    chain += "<link name=\"l" + std::to_string(i) + "\"/><joint name=\"j" + std::to_string(i) + "\" type=\"fixed\"><parent link=\"" +
             (i == 0 ? std::string("mass") : "l" + std::to_string(i - 1)) + "\"/><child link=\"l" + std::to_string(i) + "\"/></joint>";
  }
  cases.push_back({urdfCase("chain", pm.substr(0, pm.rfind("</robot>")) + chain + "</robot>\n"), 2, "more than 1000 links (size guard)"});
  // YAML nested 100000 deep: a clear message, not "bad file".
  write(g + "/nested.yaml", "name: x\nduration_s: " + repeat("[", 100000) + repeat("]", 100000) + "\n");
  cases.push_back({kBin + "lexdyn-harness run nested.yaml --out out-nested --quiet", 2, "nested.yaml:2: YAML nesting deeper than"});
  // 20000 one-row levels ran past 120 s at 11 GB; 2^31 variables aborted on std::bad_alloc.
  std::string levels = "{\"variables\": 2, \"levels\": [";
  for (int i = 0; i < 20000; ++i) levels += std::string(i ? "," : "") + "{\"A\": [[1, 0.5]], \"lower\": [1], \"upper\": [1]}";
  write(g + "/levels.json", levels + "]}");
  cases.push_back({kBin + "lexdyn-solve levels.json", 2, "levels.json: levels: expected at most 100 levels (size guard"});
  write(g + "/vars.json", "{\"variables\": 2147483648, \"levels\": [{\"A\": [[1]], \"lower\": [0], \"upper\": [0]}]}");
  cases.push_back(
      {kBin + "lexdyn-solve vars.json", 2, "vars.json: variables: expected at most 2000 variables (size guard), found 2147483648"});
  // A trace of 100000 channels took 28 s in a quadratic duplicate check.
  std::string wide = "t";
  for (int i = 0; i < 100000; ++i) wide += ",c" + std::to_string(i);
  wide += "\n0" + repeat(",0", 100000) + "\n# end: completed\n";
  write(g + "/wide.csv", wide);
  cases.push_back({kBin + "lexdyn-harness check wide.csv --case " + std::string(LEXDYN_SOURCE_DIR) + "/cases/pointmass-damping.yaml", 2,
                   "needs trace channel 'task.position.error', which is not recorded"});
  for (size_t i = 0; i < cases.size(); ++i) {
    const Outcome o = runIn(g, cases[i].cmd, "generated" + std::to_string(i));
    EXPECT_EQ(o.code, cases[i].code) << cases[i].cmd.substr(0, 200) << "\n" << o.err.substr(0, 500);
    EXPECT_NE(o.err.find(cases[i].fragment), std::string::npos) << cases[i].fragment << "\nfound: " << o.err.substr(0, 500);
  }
}

}  // namespace
