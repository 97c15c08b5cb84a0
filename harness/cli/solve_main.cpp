// lexdyn-solve: solve a hierarchical least-squares problem file, or benchmark a sequence of them.
//
//   lexdyn-solve FILE                 prints {"status", "reason", "x", "level_violation", "iterations"}
//   lexdyn-solve --details FILE       adds the active set, ranks and per-row violations
//   lexdyn-solve --bench FILES...     consecutive ticks: each solved cold and warm-started from the
//                                     previous tick; prints timing statistics as JSON
//     --repeats N                     runs the sequence N times; adds the minimum over the repeats
//                                     of each statistic's median and each tick's best over the
//                                     repeats (tick_best_*: a shared machine's false tails)
//     --warm-only                     skips the cold solves (profiles of the warm path)
//     --per-tick FILE                 writes one CSV row per tick: each solve's best time over the
//                                     repeats next to its work (iterations, factorised stages,
//                                     activations, deactivations, restarts after a bound change)
//                                     and status; written atomically after the JSON is printed
//     --stage-times                   adds stage_times: the timed solves' factorisation time, level
//                                     by level (wall clock, a diagnostic; the solves are the same)
//
// Solver options: a problem file a controller dumped (lexdyn-harness run --dump-problems) carries
// the options the controller solved it with (`solver_options`), and lexdyn-solve runs those by
// default (the first file's, with --bench); a file without them runs the solver's defaults;
// --default-options ignores the file's. The flags below change single options on top of either.
// The output names what ran: "solver_options" and "solver_options_from".
//
// Exit codes (docs/architecture.md, "Errors and exit codes"):
//   0    a solution was produced: status solved (relaxed levels included), or stopped_early by the
//        paper's rules when the file's options or --paper-rules asked for them;
//   2    bad input: the problem file (file and key path named; size guards of docs/file-formats.md)
//        or the command line;
//   3    solver failure: the hard iteration cap (iteration_limit), a non-finite result, an
//        internal error, out of memory; the JSON result is still printed when there is one; with
//        --bench, a --per-tick file that could not be written at the end (after the JSON);
//   130 / 143  interrupted by SIGINT / SIGTERM (--bench stops between solves, prints nothing).
// lexdyn-solve runs no check, so it never exits 1.
#include <CLI/CLI.hpp>
#include <Eigen/QR>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <functional>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "lexdyn/common/error.hpp"
#include "harness/checks/output_files.hpp"
#include "harness/cli/exception_exit.hpp"
#include "lexdyn/solver/problem_io.hpp"
#include "lexdyn/solver/solver.hpp"

namespace {

constexpr int kExitPass = 0, kExitBadInput = 2, kExitSolverFailure = 3, kExitInterrupted = 128;

std::atomic<int> g_signal{0};
extern "C" void onSignal(int s) { g_signal.store(s); }

int interrupted() {
  const int s = g_signal.load();
  std::fprintf(stderr, "lexdyn-solve: interrupted by %s\n", s == SIGINT ? "SIGINT" : (s == SIGTERM ? "SIGTERM" : "a signal"));
  return kExitInterrupted + s;
}

using Clock = std::chrono::steady_clock;
using lexdyn::solver::Options;
using lexdyn::solver::Problem;
using lexdyn::solver::Solver;
using lexdyn::solver::Status;

double elapsedUs(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::micro>(b - a).count(); }

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const size_t i = static_cast<size_t>(pos);
  const double f = pos - static_cast<double>(i);
  return (i + 1 < v.size()) ? v[i] * (1.0 - f) + v[i + 1] * f : v[i];
}

// Time of one Eigen ColPivHouseholderQR of a 103 x 74 matrix (median of many), the unit that
// makes timings comparable across machines.
double qrUnitUs() {
  std::mt19937_64 rng(20200710);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd A(103, 74);
  for (int j = 0; j < A.cols(); ++j)
    for (int i = 0; i < A.rows(); ++i) A(i, j) = u(rng);
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(103, 74);
  std::vector<double> t;
  double sink = 0.0;
  for (int rep = 0; rep < 301; ++rep) {
    const auto a = Clock::now();
    qr.compute(A);
    const auto b = Clock::now();
    sink += qr.matrixQR()(0, 0);
    if (rep > 0) t.push_back(elapsedUs(a, b));
  }
  if (sink == 12345.0) std::fprintf(stderr, " ");
  return percentile(t, 0.5);
}

// `us` holds the repeats one after the other, `perRepeat` solves each: each tick's best (smallest)
// time over the repeats, in tick order.
std::vector<double> tickBest(const std::vector<double>& us, size_t perRepeat) {
  std::vector<double> best;
  if (perRepeat == 0) return best;
  best.assign(us.begin(), us.begin() + static_cast<std::ptrdiff_t>(std::min(perRepeat, us.size())));
  for (size_t i = perRepeat; i < us.size(); ++i) best[i % perRepeat] = std::min(best[i % perRepeat], us[i]);
  return best;
}

// One tick's solve (cold or warm) in a --bench run: its best time over the repeats and the work of
// the first repeat's solve. A solve's work depends only on its problem, its options and its warm
// start, and every repeat starts the warm chain cold again at tick 0, so the repeats' work is
// the same; recordSolve says so on stderr if it ever is not.
struct TickSolve {
  bool timed = false;
  double best_us = 0.0;
  int iterations = 0, factorizations = 0, activations = 0, deactivations = 0, bound_change_restarts = 0;
  std::string status;
};

void recordSolve(TickSolve& t, const lexdyn::solver::Result& r, double us, size_t tick, const char* kind) {
  if (!t.timed) {
    t.timed = true;
    t.best_us = us;
    t.iterations = r.iterations;
    t.factorizations = r.factorizations;
    t.activations = r.activations;
    t.deactivations = r.deactivations;
    t.bound_change_restarts = r.bound_change_restarts;
    t.status = lexdyn::solver::toString(r.status);
    return;
  }
  t.best_us = std::min(t.best_us, us);
  if (r.iterations != t.iterations || r.factorizations != t.factorizations || r.activations != t.activations ||
      r.deactivations != t.deactivations || r.bound_change_restarts != t.bound_change_restarts)
    std::fprintf(stderr,
                 "lexdyn-solve: warning: tick %zu's %s solve did other work in a later repeat (%d iterations, %d stages; first %d, %d)\n",
                 tick, kind, r.iterations, r.factorizations, t.iterations, t.factorizations);
}

nlohmann::json stats(const std::vector<double>& us, const std::vector<int>& iters, int capHits, double unit,
                     const std::vector<double>& repeatMedians, size_t perRepeat, const std::vector<TickSolve>& perTick,
                     const std::vector<std::string>& files) {
  nlohmann::json j;
  double sumIt = 0.0;
  int maxIt = 0;
  for (int it : iters) {
    sumIt += it;
    maxIt = std::max(maxIt, it);
  }
  j["count"] = us.size();
  if (us.empty()) {
    // Nothing timed (a single file has no warm tick): no figure rather than zeros.
    for (const char* k : {"median_us", "p99_us", "max_us", "median_qr_units", "p99_qr_units", "max_qr_units", "min_repeat_median_us",
                          "min_repeat_median_qr_units", "tick_best_median_us", "tick_best_p99_us", "tick_best_max_us",
                          "tick_best_p99_qr_units", "tick_best_max_qr_units"})
      j[k] = nullptr;
    j["mean_iterations"] = nullptr;
    j["max_iterations"] = nullptr;
    j["iteration_limit_hits"] = 0;
    j["max_factorizations"] = nullptr;
    j["slowest_tick"] = nullptr;
    return j;
  }
  j["median_us"] = percentile(us, 0.5);
  j["p99_us"] = percentile(us, 0.99);
  j["max_us"] = *std::max_element(us.begin(), us.end());
  j["mean_iterations"] = sumIt / static_cast<double>(iters.size());
  j["max_iterations"] = maxIt;
  j["iteration_limit_hits"] = capHits;
  j["median_qr_units"] = percentile(us, 0.5) / unit;
  j["p99_qr_units"] = percentile(us, 0.99) / unit;
  j["max_qr_units"] = *std::max_element(us.begin(), us.end()) / unit;
  const double minMedian = *std::min_element(repeatMedians.begin(), repeatMedians.end());
  j["min_repeat_median_us"] = minMedian;
  j["min_repeat_median_qr_units"] = minMedian / unit;
  // Each tick's best over the repeats: a scheduler slice or other work on a shared machine
  // lengthens some repeats of a tick, rarely all; the pooled p99 and max above count every slow
  // repeat as a tail of the solver.
  const std::vector<double> best = tickBest(us, perRepeat);
  const double bestMax = *std::max_element(best.begin(), best.end());
  j["tick_best_median_us"] = percentile(best, 0.5);
  j["tick_best_p99_us"] = percentile(best, 0.99);
  j["tick_best_max_us"] = bestMax;
  j["tick_best_p99_qr_units"] = percentile(best, 0.99) / unit;
  j["tick_best_max_qr_units"] = bestMax / unit;
  // The deterministic work beside the times: the largest number of stages factorised in one
  // solve, and the tick with the largest best time, with its work (a peak is judged by both).
  int maxFact = 0;
  size_t slowest = perTick.size();
  for (size_t k = 0; k < perTick.size(); ++k) {
    if (!perTick[k].timed) continue;
    maxFact = std::max(maxFact, perTick[k].factorizations);
    if (slowest == perTick.size() || perTick[k].best_us > perTick[slowest].best_us) slowest = k;
  }
  j["max_factorizations"] = maxFact;
  if (slowest < perTick.size()) {
    const TickSolve& t = perTick[slowest];
    j["slowest_tick"] = {{"tick", slowest},
                         {"file", files[slowest]},
                         {"best_us", t.best_us},
                         {"iterations", t.iterations},
                         {"factorizations", t.factorizations}};
  }
  return j;
}

// The options a run uses: the first file's (unless --default-options) or the solver's defaults,
// then the command line's single options. `from` says which, for the output.
struct OptionFlags {
  bool use_file = true;
  std::function<void(Options&)> apply;
};

// --per-tick FILE: one CSV row per tick, cold and warm (docs/file-formats.md).
std::string perTickCsv(const std::vector<std::string>& files, const std::vector<TickSolve>& cold, const std::vector<TickSolve>& warm) {
  std::string out = "tick,file";
  for (const char* kind : {"cold", "warm"})
    for (const char* field : {"best_us", "iterations", "factorizations", "activations", "deactivations", "bound_change_restarts", "status"})
      out += std::string(",") + kind + "_" + field;
  out += "\n";
  char buf[160];
  for (size_t k = 0; k < files.size(); ++k) {
    // The file name as given, quoted (RFC 4180) when it holds a comma, a quote or a line break.
    std::string name = files[k];
    if (name.find_first_of(",\"\r\n") != std::string::npos) {
      std::string quoted = "\"";
      for (char ch : name) quoted += ch == '"' ? std::string("\"\"") : std::string(1, ch);
      name = quoted + "\"";
    }
    out += std::to_string(k) + "," + name;
    for (const TickSolve* t : {&cold[k], &warm[k]}) {
      if (t->timed) {
        std::snprintf(buf, sizeof buf, ",%.3f,%d,%d,%d,%d,%d,", t->best_us, t->iterations, t->factorizations, t->activations,
                      t->deactivations, t->bound_change_restarts);
        out += buf + t->status;
      } else {
        out += ",,,,,,,";
      }
    }
    out += "\n";
  }
  return out;
}

// --stage-times: where the timed solves' factorisations went, level by level (StageTimes).
nlohmann::json stageTimesJson(const lexdyn::solver::StageTimes& t, const Problem& problem, size_t solves) {
  nlohmann::json j;
  const double n = solves > 0 ? static_cast<double>(solves) : 1.0;
  j["solves"] = solves;
  j["passes"] = t.passes;
  j["preparation_us_per_solve"] = t.preparation_us / n;
  j["layout_us_per_solve"] = t.layout_us / n;
  double total = t.preparation_us + t.layout_us;
  nlohmann::json levels = nlohmann::json::array();
  for (size_t l = 0; l < t.stage_us.size() && l < static_cast<size_t>(problem.levelCount()); ++l) {
    total += t.stage_us[l];
    if (problem.level(static_cast<int>(l)).kind == lexdyn::solver::LevelKind::Bounds) continue;
    const long c = t.stage_count[l];
    levels.push_back({{"level", problem.level(static_cast<int>(l)).name},
                      {"factorizations", c},
                      {"us_per_solve", t.stage_us[l] / n},
                      {"us_per_factorization", c > 0 ? nlohmann::json(t.stage_us[l] / static_cast<double>(c)) : nlohmann::json()}});
  }
  j["stages"] = levels;
  j["factorization_us_per_solve"] = total / n;
  return j;
}

int runBench(const std::vector<std::string>& files, const OptionFlags& flags, bool detectBounds, int repeats, bool warmOnly,
             const std::string& perTickPath, bool stageTimes) {
  if (!perTickPath.empty()) {
    // A path that cannot be written is bad input, found before anything is solved.
    const std::string probe = perTickPath + ".partial";
    std::FILE* f = std::fopen(probe.c_str(), "w");
    if (!f) throw lexdyn::InputError(perTickPath, "--per-tick: cannot write: " + lexdyn::files::reason(errno));
    std::fclose(f);
    std::remove(probe.c_str());
  }
  std::vector<Problem> ticks;
  ticks.reserve(files.size());
  Options options;
  std::string from = "the solver's defaults";
  std::string first_options;    // the first file's, as written ("" for none)
  bool differing_said = false;  // one warning for the files whose options differ
  for (size_t i = 0; i < files.size(); ++i) {
    if (g_signal.load()) return interrupted();
    lexdyn::solver::ProblemFile f = lexdyn::solver::readProblemFile(files[i]);
    if (i == 0 && f.options && flags.use_file) {
      options = *f.options;
      from = "the first problem file";
      first_options = lexdyn::solver::solverOptionsToJson(*f.options);
    } else if (i > 0 && flags.use_file && !differing_said &&
               (f.options ? lexdyn::solver::solverOptionsToJson(*f.options) : std::string()) != first_options) {
      std::fprintf(stderr, "lexdyn-solve: warning: %s: its solver options differ from the first file's; --bench runs the first's\n",
                   files[i].c_str());
      differing_said = true;
    }
    ticks.push_back(std::move(f.problem));
    if (detectBounds) ticks.back().detectBoundsLevel();
    if (files.size() >= 200 && (i + 1) % 200 == 0) std::fprintf(stderr, "lexdyn-solve: loaded %zu/%zu\n", i + 1, files.size());
  }
  if (ticks.empty()) return 0;
  flags.apply(options);
  Solver cold, warm;
  cold.setup(ticks[0], options);
  warm.setup(ticks[0], options);
  lexdyn::solver::StageTimes coldTimes, warmTimes;
  if (stageTimes) cold.setStageTimes(&coldTimes);
  const double unit = qrUnitUs();
  std::vector<double> coldUs, warmUs, coldMedians, warmMedians;
  std::vector<int> coldIt, warmIt;
  int coldCap = 0, warmCap = 0;
  double maxAbsX = 0.0;
  std::vector<TickSolve> coldTicks(ticks.size()), warmTicks(ticks.size());
  for (int rep = 0; rep < repeats; ++rep) {
    const size_t coldFrom = coldUs.size(), warmFrom = warmUs.size();
    for (size_t k = 0; k < ticks.size(); ++k) {
      if (g_signal.load()) return interrupted();
      if (!warmOnly) {
        const auto a = Clock::now();
        const auto& rc = cold.solve(ticks[k]);
        const auto b = Clock::now();
        coldUs.push_back(elapsedUs(a, b));
        recordSolve(coldTicks[k], rc, coldUs.back(), k, "cold");
        coldIt.push_back(rc.iterations);
        coldCap += (rc.status == Status::IterationLimit);
        maxAbsX = std::max(maxAbsX, rc.x.lpNorm<Eigen::Infinity>());
      }
      if (k == 0) {
        warm.setStageTimes(nullptr);  // not timed
        warm.solve(ticks[0]);         // each repeat starts cold, like the first
        if (stageTimes) warm.setStageTimes(&warmTimes);
        continue;
      }
      const auto c = Clock::now();
      const auto& rw = warm.solve(ticks[k], warm.result().active, warm.result().x);
      const auto d = Clock::now();
      warmUs.push_back(elapsedUs(c, d));
      recordSolve(warmTicks[k], rw, warmUs.back(), k, "warm");
      warmIt.push_back(rw.iterations);
      warmCap += (rw.status == Status::IterationLimit);
      maxAbsX = std::max(maxAbsX, rw.x.lpNorm<Eigen::Infinity>());
    }
    auto medianFrom = [](const std::vector<double>& v, size_t from) {
      return percentile(std::vector<double>(v.begin() + static_cast<std::ptrdiff_t>(from), v.end()), 0.5);
    };
    if (coldUs.size() > coldFrom) coldMedians.push_back(medianFrom(coldUs, coldFrom));
    if (warmUs.size() > warmFrom) warmMedians.push_back(medianFrom(warmUs, warmFrom));
    if (repeats > 1) std::fprintf(stderr, "lexdyn-solve: repeat %d/%d\n", rep + 1, repeats);
  }
  nlohmann::json out;
  out["qr_unit_us"] = unit;
  out["ticks"] = ticks.size();
  out["repeats"] = repeats;
  if (!warmOnly) out["cold"] = stats(coldUs, coldIt, coldCap, unit, coldMedians, ticks.size(), coldTicks, files);
  out["warm"] = stats(warmUs, warmIt, warmCap, unit, warmMedians, ticks.size() - 1, warmTicks, files);
  out["max_abs_x"] = maxAbsX;
  if (stageTimes) {
    nlohmann::json st;
    if (!warmOnly) st["cold"] = stageTimesJson(coldTimes, ticks[0], coldUs.size());
    st["warm"] = stageTimesJson(warmTimes, ticks[0], warmUs.size());
    out["stage_times"] = st;
  }
  out["solver_options"] = nlohmann::json::parse(lexdyn::solver::solverOptionsToJson(options));
  out["solver_options_from"] = from;
  std::cout << out.dump(2) << std::endl;
  // After the JSON, so that a full disk costs the file, not the run's figures: OutputError, exit 3.
  if (!perTickPath.empty()) lexdyn::files::writeAtomically(perTickPath, perTickCsv(files, coldTicks, warmTicks));
  // A benchmark measures time; a tick that hit the cap is counted in iteration_limit_hits.
  return kExitPass;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"lexdyn-solve: hierarchical least-squares solver (docs/solver.md)"};
  std::vector<std::string> files;
  bool bench = false, details = false, noBounds = false, warmOnly = false, spanning = false, spanningAny = false,
       spanningStructured = false, lazy = false, suffix = false, noBoundRestarts = false, noSwaps = false, stageTimes = false;
  bool defaultOptions = false;
  int maxIterations = 1000, repeats = 1, options_split = -1;
  double paperDt = 0.0;
  app.add_flag("--bench", bench, "treat the files as consecutive ticks and print timing statistics");
  app.add_option("--repeats", repeats, "with --bench: run the sequence this many times")->check(CLI::Range(1, 1000));
  app.add_flag("--warm-only", warmOnly, "with --bench: skip the cold solves");
  app.add_flag("--stage-times", stageTimes,
               "with --bench: also print where the timed solves' factorisations went, level by level (wall clock; stage_times)");
  std::string perTick;
  app.add_option("--per-tick", perTick,
                 "with --bench: write one CSV row per tick (best time over the repeats, iterations, factorised stages, activations, "
                 "deactivations, restarts after a bound change, status)")
      ->check([](const std::string& v) { return v.empty() ? std::string("expected a file name") : std::string(); });
  app.add_option("--split-from", options_split, "split coordinates: prefer eliminating variables from this index on (docs/solver.md)")
      ->check(CLI::Range(0, 1000000));
  app.add_flag("--spanning-stages", spanning, "solve single-variable-row levels that span their stage by one QR (docs/solver.md)");
  app.add_flag("--spanning-any-rows", spanningAny,
               "with --spanning-stages: levels of rows that read several variables too (docs/solver.md)");
  app.add_flag("--spanning-structured", spanningStructured,
               "with --spanning-stages: structured spanning stages, a row per coordinate plus a few others (docs/solver.md)");
  app.add_flag("--lazy-snapshots", lazy, "save restart snapshots only once a solve restarts (docs/solver.md)");
  app.add_flag("--no-restart-after-bound-change", noBoundRestarts,
               "factorise every level again after a variable is fixed at its bound or freed (docs/solver.md)");
  app.add_flag("--no-swap-reflectors", noSwaps,
               "apply the reflectors of unit columns by the generic arithmetic, not as exact swaps (docs/solver.md)");
  app.add_flag("--unit-suffix", suffix, "project the level before a projected last level too when its rows are unit rows (docs/solver.md)");
  app.add_flag("--details", details, "also print the active set, ranks and per-row violations");
  app.add_flag("--no-bounds-level", noBounds, "do not treat a first level of single-variable rows as bounds");
  app.add_option("--max-iterations", maxIterations, "hard cap on active-set iterations")->check(CLI::Range(1, 1000000));
  app.add_flag("--default-options", defaultOptions,
               "run the solver's default options, not the ones a dumped problem file carries (solver_options)");
  app.add_option("--paper-rules", paperDt, "enable the paper's termination rules for this control period (s, in [1e-6, 10])");
  app.add_option("files", files, "problem files (JSON)")->required();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitPass : kExitBadInput;
  }
  if (app.count("--paper-rules") && !(paperDt >= 1e-6 && paperDt <= 10.0)) {
    std::fprintf(stderr, "lexdyn-solve: error: --paper-rules: expected a control period in [1e-6, 10] s, found %g\n", paperDt);
    return kExitBadInput;
  }
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  OptionFlags flags;
  flags.use_file = !defaultOptions;
  flags.apply = [&](Options& o) {
    if (paperDt > 0.0) {
      const Options paper = Options::paper(paperDt);
      o.stop_slack_norm = paper.stop_slack_norm;
      o.stop_optimality_iterations = paper.stop_optimality_iterations;
      o.stop_total_iterations = paper.stop_total_iterations;
    }
    if (app.count("--max-iterations")) o.max_iterations = maxIterations;
    if (app.count("--split-from")) o.split_from_variable = options_split;
    if (spanning) o.spanning_stages = true;
    if (spanningAny) o.spanning_any_rows = true;
    if (spanningStructured) o.spanning_structured = true;
    // Without spanning stages the two would do nothing: say so rather than run something else.
    if ((spanningAny || spanningStructured) && !o.spanning_stages)
      throw lexdyn::InputError(spanningAny ? "--spanning-any-rows" : "--spanning-structured",
                               "needs spanning stages (--spanning-stages, or spanning_stages true in the file's solver_options)");
    if (lazy) o.lazy_snapshots = true;
    if (noBoundRestarts) o.restart_after_bound_change = false;
    if (noSwaps) o.swap_reflectors = false;
    if (suffix) o.project_unit_suffix = true;
  };
  try {
    if (!bench && (app.count("--repeats") || warmOnly || app.count("--per-tick") || stageTimes)) {
      std::fprintf(stderr, "lexdyn-solve: error: --repeats, --warm-only, --per-tick and --stage-times need --bench\n");
      return kExitBadInput;
    }
    if (bench) return runBench(files, flags, !noBounds, repeats, warmOnly, perTick, stageTimes);
    if (files.size() != 1) {
      std::fprintf(stderr, "lexdyn-solve: error: expected one problem file, found %zu (use --bench for several)\n", files.size());
      return kExitBadInput;
    }
    lexdyn::solver::ProblemFile file = lexdyn::solver::readProblemFile(files[0]);
    Problem& problem = file.problem;
    if (!noBounds) problem.detectBoundsLevel();
    Options options = file.options && flags.use_file ? *file.options : Options{};
    flags.apply(options);
    Solver solver;
    solver.setup(problem, options);
    const auto& r = solver.solve(problem);
    if (g_signal.load()) return interrupted();
    const std::string from = file.options && flags.use_file ? "the problem file" : "the solver's defaults";
    std::cout << lexdyn::solver::resultToJson(problem, r, details, &options, from) << std::endl;
    // Only a solution is a pass: the hard cap leaves an iterate, a non-finite result nothing. An
    // early stop is one when the options asked for the paper's rules.
    const bool stop_rules = options.stop_slack_norm > 0.0 || options.stop_optimality_iterations > 0 || options.stop_total_iterations > 0;
    const bool requested_stop = r.status == Status::StoppedEarly && stop_rules;
    if (r.status == Status::Solved || requested_stop) return kExitPass;
    std::fprintf(stderr, "lexdyn-solve: solver failure on %s: status %s (%s) after %d iterations\n", files[0].c_str(),
                 lexdyn::solver::toString(r.status), lexdyn::solver::toString(r.reason), r.iterations);
    return kExitSolverFailure;
  } catch (...) {
    return lexdyn::cli::exitCodeOfException("lexdyn-solve", kExitSolverFailure);
  }
}
