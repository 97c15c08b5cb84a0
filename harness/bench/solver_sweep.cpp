// lexdyn-solver-sweep: a heavy randomized verification sweep of the solver (not part of ctest;
// docs/solver.md, "Verification"). Random hierarchies (rank-deficient, duplicated, zero and
// conflicting rows, bounds levels, equalities and inequalities) are solved and each result is
// checked:
//  - status: solved; a hard-cap hit (iteration_limit) or a non-finite result is a failure;
//  - the KKT certificate built from x and the multipliers alone (tests/support/reference.hpp);
//  - a result whose certificate fails goes to the exact reference (rational arithmetic,
//    tests/support/exact_reference.hpp), which decides: a result it proves optimal is not a
//    failure (a false alarm of the double-precision certificate, counted), one it proves wrong
//    or cannot decide is;
//  - with --brute-force, tiny problems are also compared with an enumeration of every active set;
//  - with --exact-every K, every K-th problem also goes to the exact reference, whatever the
//    certificate said: a disagreement in either direction is counted and printed;
//  - with --controller-shaped, the problems are shaped like the controller's (velocities, then
//    contact forces with their bounds; split coordinates, declared velocity-only levels), and each
//    is solved again warm from its answer's active set with every second bound released: that
//    result is checked the same way, and its levels' violations must be the cold solve's
//    (--warm does this for the default generator's problems).
// Every problem is generated from its own seed (its options too), so a failing problem reruns
// alone with the command the sweep prints (or from the JSON file --write-failures DIR writes).
//
// Exit codes (docs/architecture.md, "Errors and exit codes"): 0 every problem verified; 1 a
// failure (a wrong result, a cap hit, a non-finite result, a certificate/exact disagreement);
// 2 bad options; 3 an internal error; 130 / 143 interrupted by SIGINT / SIGTERM (the summary
// of the problems done so far is printed, with "interrupted": true).
#include <CLI/CLI.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include "exact_reference.hpp"
#include "harness/cli/exception_exit.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/solver/problem_io.hpp"
#include "lexdyn/solver/solver.hpp"
#include "reference.hpp"

namespace {

using namespace lexdyn::solver;

constexpr int kExitPass = 0, kExitFailed = 1, kExitBadInput = 2, kExitInternal = 3, kExitInterrupted = 128;
// The exact reference's default work budget per check (docs/solver.md, "The solver sweep").
constexpr long kDefaultWorkLimit = 100000000;

std::atomic<int> g_signal{0};
extern "C" void onSignal(int s) { g_signal.store(s); }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Randomized verification sweep of the hierarchical least-squares solver (docs/solver.md)"};
  std::uint64_t seed = 1;
  long cases = 100000;
  int maxN = 12, maxLevels = 7, maxRows = 8;
  long exactEvery = 0;
  int maxIterations = Options{}.max_iterations;
  bool spanning = false, spanningAny = false, spanningStructured = false, lazy = false, suffix = false, noBoundRestarts = false,
       noSwaps = false, controllerShaped = false, warmToo = false;
  double unitLevels = 0.0;
  bool brute = false;
  double exactTimeLimit = 0.0;
  long exactWorkLimit = kDefaultWorkLimit;
  std::string writeDir;
  app.add_option("--seed", seed, "seed of the first problem; problem i has seed + i");
  app.add_option("--cases", cases, "number of random problems")->check(CLI::Range(1L, 1000000000L));
  app.add_option("--max-variables", maxN, "largest number of variables, in [1, 100]")->check(CLI::Range(1, 100));
  app.add_option("--max-levels", maxLevels, "largest number of general levels, in [1, 50] (with --controller-shaped: of task levels)")
      ->check(CLI::Range(1, 50));
  app.add_option("--max-rows", maxRows, "largest number of rows per level, in [1, 100]")->check(CLI::Range(1, 100));
  app.add_option("--exact-every", exactEvery, "also verify every K-th problem with the exact reference (0: only flagged ones)")
      ->check(CLI::Range(0L, 1000000000L));
  app.add_option("--exact-work-limit", exactWorkLimit,
                 "work one exact check may take (limbs of a pivot's row x the rows it clears, summed over its pivots); beyond, its "
                 "verdict is undecided, the same on any machine (0: no limit; default " +
                     std::to_string(kDefaultWorkLimit) + ")")
      ->check(CLI::Range(0L, 1000000000000L));
  app.add_option("--exact-time-limit", exactTimeLimit,
                 "seconds one exact check may take; beyond, its verdict is undecided (machine-dependent; 0: no limit, the default)")
      ->check(CLI::Range(0.0, 1.0e6));
  app.add_option("--max-iterations", maxIterations, "the solver's hard iteration cap (default 1000)")->check(CLI::Range(1, 1000000));
  app.add_option("--write-failures", writeDir, "write each failing problem to DIR/problem-SEED.json");
  app.add_flag("--spanning-stages", spanning, "solve with Options::spanning_stages (docs/solver.md)");
  app.add_flag("--spanning-any-rows", spanningAny, "solve with Options::spanning_any_rows (docs/solver.md)");
  app.add_flag("--spanning-structured", spanningStructured, "solve with Options::spanning_structured (docs/solver.md)");
  app.add_flag("--lazy-snapshots", lazy, "solve with Options::lazy_snapshots (docs/solver.md)");
  app.add_flag("--unit-suffix", suffix, "solve with Options::project_unit_suffix (docs/solver.md)");
  app.add_flag("--no-restart-after-bound-change", noBoundRestarts, "solve with Options::restart_after_bound_change off (docs/solver.md)");
  app.add_flag("--no-swap-reflectors", noSwaps, "solve with Options::swap_reflectors off (docs/solver.md)");
  app.add_option("--unit-levels", unitLevels, "probability that a level is made of single-variable rows, in [0, 1]")
      ->check(CLI::Range(0.0, 1.0));
  app.add_flag("--controller-shaped", controllerShaped,
               "controller-shaped problems (velocities then forces, split coordinates, restarts after bound changes), each solved cold "
               "and again warm; the options of each problem are drawn with it (docs/solver.md)");
  app.add_flag("--warm", warmToo,
               "solve each problem again warm from its answer's active set with every second bound released, and check that result "
               "too (always on with --controller-shaped)");
  app.add_flag("--brute-force", brute, "compare tiny problems (<= 9 rows) with active-set enumeration");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitPass : kExitBadInput;
  }
  if (!controllerShaped && (spanningAny || spanningStructured) && !spanning) {
    std::fprintf(stderr, "lexdyn-solver-sweep: error: --spanning-any-rows and --spanning-structured need --spanning-stages\n");
    return kExitBadInput;
  }
  if (controllerShaped && (spanning || spanningAny || spanningStructured || lazy || suffix || unitLevels > 0.0 || brute)) {
    std::fprintf(
        stderr,
        "lexdyn-solver-sweep: error: --controller-shaped draws each problem's options itself: it takes none of "
        "--spanning-stages, --spanning-any-rows, --spanning-structured, --lazy-snapshots, --unit-suffix, --unit-levels, --brute-force\n");
    return kExitBadInput;
  }
  if (controllerShaped && maxN < 2) {
    std::fprintf(stderr, "lexdyn-solver-sweep: error: --controller-shaped needs --max-variables 2 or more (a velocity and a force)\n");
    return kExitBadInput;
  }
  if (!writeDir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(writeDir, ec);
    if (ec || !std::filesystem::is_directory(writeDir)) {
      std::fprintf(stderr, "lexdyn-solver-sweep: error: --write-failures %s: cannot create the directory\n", writeDir.c_str());
      return kExitBadInput;
    }
  }
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);

  char unitLevelsBuf[32];
  std::snprintf(unitLevelsBuf, sizeof(unitLevelsBuf), "%.17g", unitLevels);
  const std::string unitLevelsText = unitLevelsBuf;
  const std::string options = " --max-variables " + std::to_string(maxN) + " --max-levels " + std::to_string(maxLevels) + " --max-rows " +
                              std::to_string(maxRows) + (brute ? " --brute-force" : "") +
                              (maxIterations != Options{}.max_iterations ? " --max-iterations " + std::to_string(maxIterations) : "") +
                              (spanning ? " --spanning-stages" : "") + (spanningAny ? " --spanning-any-rows" : "") +
                              (spanningStructured ? " --spanning-structured" : "") + (lazy ? " --lazy-snapshots" : "") +
                              (suffix ? " --unit-suffix" : "") + (noBoundRestarts ? " --no-restart-after-bound-change" : "") +
                              (noSwaps ? " --no-swap-reflectors" : "") + (unitLevels > 0.0 ? " --unit-levels " + unitLevelsText : "") +
                              (controllerShaped ? " --controller-shaped" : "") + (warmToo && !controllerShaped ? " --warm" : "");
  Options solverOptions;
  solverOptions.max_iterations = maxIterations;
  solverOptions.spanning_stages = spanning;
  solverOptions.spanning_any_rows = spanningAny;
  solverOptions.spanning_structured = spanningStructured;
  solverOptions.lazy_snapshots = lazy;
  solverOptions.project_unit_suffix = suffix;
  solverOptions.restart_after_bound_change = !noBoundRestarts;
  solverOptions.swap_reflectors = !noSwaps;
  // The counts of the problems finished; one interrupted in its exact check is not counted (its
  // counts are taken back whole).
  struct Counts {
    long done = 0, solved = 0, failures = 0, capHits = 0, nonFinite = 0, kktFlagged = 0, exactChecked = 0, exactCleared = 0,
         exactConfirmed = 0, exactUndecided = 0, exactOutOfTime = 0, exactOutOfWork = 0, exactMaxWork = 0, disagreements = 0,
         bruteChecked = 0, held = 0, cycles = 0, coldRestarts = 0, iters = 0, maxIt = 0, warmChecked = 0, splitApplied = 0,
         boundRestarts = 0;
  } n;
  long &done = n.done, &solved = n.solved, &failures = n.failures, &capHits = n.capHits, &nonFinite = n.nonFinite,
       &kktFlagged = n.kktFlagged, &exactChecked = n.exactChecked, &exactCleared = n.exactCleared, &exactConfirmed = n.exactConfirmed,
       &exactUndecided = n.exactUndecided, &exactOutOfTime = n.exactOutOfTime, &exactOutOfWork = n.exactOutOfWork,
       &exactMaxWork = n.exactMaxWork, &disagreements = n.disagreements, &bruteChecked = n.bruteChecked, &held = n.held, &cycles = n.cycles,
       &coldRestarts = n.coldRestarts, &iters = n.iters, &maxIt = n.maxIt, &warmChecked = n.warmChecked, &splitApplied = n.splitApplied,
       &boundRestarts = n.boundRestarts;
  const auto t0 = std::chrono::steady_clock::now();
  // Checks one result (status, certificate, exact reference): the failure's text, or "" when it
  // passes. Sets `interrupted` when a signal stopped its exact check (then nothing is decided).
  auto verify = [&](std::uint64_t s, const char* what, const Problem& p, const Result& r, bool sample, bool& interrupted) -> std::string {
    held += r.held_after_reblock;
    cycles += r.cycles_broken;
    coldRestarts += r.cold_restarts;
    iters += r.iterations;
    maxIt = std::max<long>(maxIt, r.iterations);
    boundRestarts += r.bound_change_restarts;
    if (r.status == Status::IterationLimit) {
      ++capHits;
      return "hard iteration cap hit (" + std::to_string(r.iterations) + " iterations)";
    }
    if (r.status == Status::NonFiniteResult) {
      ++nonFinite;
      return "non-finite result";
    }
    if (r.status != Status::Solved) return std::string("status ") + toString(r.status);
    const std::string kkt = test::checkKkt(p, r);
    if (!kkt.empty()) ++kktFlagged;
    if (kkt.empty() && !sample) return "";
    ++exactChecked;
    const test::ExactVerdict v = test::exactCheck(p, r, 4, exactTimeLimit, &g_signal, exactWorkLimit);
    if (v.interrupted) {
      interrupted = true;
      return "";
    }
    exactOutOfTime += v.out_of_time ? 1 : 0;
    exactOutOfWork += v.out_of_work ? 1 : 0;
    exactMaxWork = std::max(exactMaxWork, v.work);
    if (!kkt.empty()) {
      if (v.kind == test::ExactVerdict::Optimal) {
        ++exactCleared;
        std::printf("problem seed %llu%s: the certificate failed (%s) but the exact reference proves the result optimal\n",
                    static_cast<unsigned long long>(s), what, kkt.c_str());
        return "";
      }
      (v.kind == test::ExactVerdict::NotOptimal ? exactConfirmed : exactUndecided) += 1;
      return kkt + "; exact reference: " + test::toString(v.kind) + (v.detail.empty() ? "" : " (" + v.detail + ")");
    }
    if (v.kind == test::ExactVerdict::NotOptimal) {
      ++disagreements;
      return "the certificate holds but the exact reference proves the result wrong: " + v.detail;
    }
    if (v.kind == test::ExactVerdict::Undecided) ++exactUndecided;
    return "";
  };
  // The first level whose violation in `r` is not the reference's (ref(l)) to 1e-7 (1 + ref), or "".
  auto levelApart = [](const Problem& p, const Result& r, const auto& ref, const char* against) -> std::string {
    for (int l = 0; l < p.levelCount(); ++l)
      if (std::abs(r.violation_norm(l) - ref(l)) > 1e-7 * (1 + ref(l)))
        return "level " + std::to_string(l) + " violation " + std::to_string(r.violation_norm(l)) + " differs from " + against + " " +
               std::to_string(ref(l));
    return "";
  };
  try {
    for (long c = 0; c < cases; ++c) {
      if (g_signal.load()) break;
      const Counts before = n;
      const std::uint64_t s = seed + static_cast<std::uint64_t>(c);
      Options problemOptions = solverOptions;
      Problem p(1);
      if (controllerShaped) {
        p = test::controllerShapedProblem(s, maxN, maxLevels, maxRows, problemOptions);
      } else {
        test::GenOptions g = test::sweepOptions(s, maxN, maxLevels, maxRows);
        g.pUnitLevel = unitLevels;
        p = test::randomProblem(s, g);
      }
      ++done;
      if (brute && p.totalRows() > 9) continue;
      Solver solver;
      solver.setup(p, problemOptions);
      const Result& r = solver.solve(p);
      ++solved;
      splitApplied += r.split_applied ? 1 : 0;
      const bool sample = exactEvery > 0 && c % exactEvery == 0;
      bool interrupted = false;
      std::string err = verify(s, "", p, r, sample, interrupted);
      if (interrupted) {  // neither a pass nor a failure: the problem is not counted
        n = before;
        break;
      }
      if (err.empty() && (controllerShaped || warmToo)) {
        // Warm from the answer's active set with every second bound released: the search frees
        // and fixes them again (restarts after a bound change both ways).
        ActiveSet warm = r.active;
        for (size_t i = 0; i < warm.level[0].size(); i += 2) warm.level[0][i] = RowState::Inactive;
        Solver again;
        again.setup(p, problemOptions);
        const Result& w = again.solve(p, warm, r.x);
        ++warmChecked;
        err = verify(s, " (warm)", p, w, sample, interrupted);
        if (interrupted) {
          n = before;
          break;
        }
        if (err.empty())
          err = levelApart(
              p, w, [&](int l) { return r.violation_norm(l); }, "the cold solve's");
        if (!err.empty()) err = "warm: " + err;
      }
      if (err.empty() && brute) {
        ++bruteChecked;
        const auto ref = test::bruteForce(p);
        err = levelApart(
            p, r, [&](int l) { return ref[static_cast<size_t>(l)]; }, "brute force");
      }
      if (!err.empty()) {
        ++failures;
        if (failures <= 20) {
          std::printf("problem seed %llu (%d variables, %d levels, %d rows): %s\n  rerun: lexdyn-solver-sweep --seed %llu --cases 1%s\n",
                      static_cast<unsigned long long>(s), p.variables(), p.levelCount(), p.totalRows(), err.c_str(),
                      static_cast<unsigned long long>(s), options.c_str());
          if (!writeDir.empty()) {
            const std::string file = writeDir + "/problem-" + std::to_string(s) + ".json";
            writeProblemJson(p, file, &problemOptions);
            std::printf("  problem: %s (lexdyn-solve --details %s)\n", file.c_str(), file.c_str());
          }
          std::fflush(stdout);
        }
      }
      if ((c + 1) % 100000 == 0) std::fprintf(stderr, "lexdyn-solver-sweep: %ld/%ld, %ld failures\n", c + 1, cases, failures);
    }
  } catch (...) {
    return lexdyn::cli::exitCodeOfException("lexdyn-solver-sweep", kExitInternal);
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf(
      "{\"problems\": %ld, \"solved\": %ld, \"failures\": %ld, \"cap_hits\": %ld, \"non_finite\": %ld, "
      "\"certificate_failures\": %ld, \"exact_checked\": %ld, \"exact_cleared\": %ld, \"exact_confirmed\": %ld, "
      "\"exact_undecided\": %ld, \"exact_out_of_work\": %ld, \"exact_out_of_time\": %ld, \"exact_max_work\": %ld, "
      "\"certificate_exact_disagreements\": %ld, \"brute_force_checked\": %ld, "
      "\"held_after_reblock\": %ld, \"cycles_broken\": %ld, \"cold_restarts\": %ld, \"mean_iterations\": %.3f, \"max_iterations\": %ld, "
      "\"warm_checked\": %ld, \"split_applied\": %ld, \"bound_change_restarts\": %ld, \"seconds\": %.1f, \"interrupted\": %s}\n",
      done, solved, failures, capHits, nonFinite, kktFlagged, exactChecked, exactCleared, exactConfirmed, exactUndecided, exactOutOfWork,
      exactOutOfTime, exactMaxWork, disagreements, bruteChecked, held, cycles, coldRestarts,
      solved ? static_cast<double>(iters) / static_cast<double>(solved + warmChecked) : 0.0, maxIt, warmChecked, splitApplied,
      boundRestarts, secs, g_signal.load() ? "true" : "false");
  if (g_signal.load()) return kExitInterrupted + g_signal.load();
  if (solved == 0) {
    // Nothing was verified (e.g. --brute-force with sizes that never give 9 rows or fewer).
    std::fprintf(stderr, "lexdyn-solver-sweep: no problem was verified (--brute-force takes problems of at most 9 rows)\n");
    return kExitFailed;
  }
  return failures == 0 ? kExitPass : kExitFailed;
}
