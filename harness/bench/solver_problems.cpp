// lexdyn-bench-solver-problems: writes a drifting sequence of paper-shaped hierarchical
// least-squares problems as JSON files tick_0000.json ... (see paper_problems.hpp), the input of
// `lexdyn-solve --bench` (harness/scripts/bench-solver.sh). Same command, same files.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <string>

#include "lexdyn/common/error.hpp"
#include "lexdyn/solver/problem_io.hpp"
#include "paper_problems.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Writes drifting sequences of paper-shaped hierarchical least-squares problems"};
  std::string regime = "nominal", out;
  int ticks = 1000;
  std::uint64_t seed = 20200710;
  app.add_option("--regime", regime, "nominal | stress | near-singular")->check(CLI::IsMember({"nominal", "stress", "near-singular"}));
  app.add_option("--ticks", ticks, "number of ticks")->check(CLI::PositiveNumber);
  app.add_option("--seed", seed, "generator seed");
  app.add_option("--out", out, "output directory")->required();
  CLI11_PARSE(app, argc, argv);
  try {
    const lexdyn::bench::PaperProblemSequence seq(lexdyn::bench::parseRegime(regime), seed);
    std::filesystem::create_directories(out);
    for (int k = 0; k < ticks; ++k) {
      char name[64];
      std::snprintf(name, sizeof(name), "/tick_%04d.json", k);
      lexdyn::solver::writeProblemJson(seq.tick(k), out + name);
      if ((k + 1) % 200 == 0) std::fprintf(stderr, "lexdyn-bench-solver-problems: %s %d/%d\n", regime.c_str(), k + 1, ticks);
    }
  } catch (const lexdyn::InputError& e) {
    std::fprintf(stderr, "lexdyn-bench-solver-problems: error: %s\n", e.what());
    return 2;
  }
  return 0;
}
