// lexdyn-harness: runs a case file and writes DIR/trace.csv and DIR/summary.json.
//
//   lexdyn-harness run cases/stand.yaml --out out/stand [--quiet]
//   lexdyn-harness check cases/stand.yaml out/stand/trace.csv     (checks of a stored trace)
//
// Exit codes: 0 every check passed; 1 a check failed or the run stopped early (integrator
// failure, interruption, an internal error); 2 bad input (the message names the file and the
// key path).
#include "harness/cases/runner.hpp"
#include "lexdyn/common/error.hpp"

#include <CLI/CLI.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <exception>
#include <string>

namespace {

std::atomic<bool> g_interrupt{false};

extern "C" void onSignal(int) { g_interrupt.store(true); }

void printChecks(const std::vector<lexdyn::checks::CheckResult>& checks) {
  for (const auto& c : checks) {
    std::fprintf(stderr, "  %-4s %-28s value %-12.6g limit %-10.6g %s%s%s\n", c.passed ? "ok" : "FAIL", c.name.c_str(),
                 c.value, c.limit, c.unit.c_str(), c.detail.empty() ? "" : "  (", c.detail.empty() ? "" : (c.detail + ")").c_str());
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"lexdyn-harness: runs simulation cases and checks their traces"};
  app.require_subcommand(1);

  std::string case_path, out_dir, trace_path;
  bool quiet = false;
  CLI::App* run = app.add_subcommand("run", "run a case file");
  run->add_option("case", case_path, "case file (YAML)")->required();
  run->add_option("--out", out_dir, "output directory (trace.csv, summary.json)")->required();
  run->add_flag("--quiet", quiet, "no progress lines");

  CLI::App* check = app.add_subcommand("check", "evaluate a case's checks on a stored trace");
  check->add_option("case", case_path, "case file (YAML)")->required();
  check->add_option("trace", trace_path, "trace file (CSV)")->required();

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  }

  try {
    const lexdyn::cases::CaseSpec spec = lexdyn::cases::loadCase(case_path);
    if (*check) {
      const lexdyn::checks::TraceTable table = lexdyn::checks::readTrace(trace_path);
      const std::string* traced_case = lexdyn::checks::findMetadata(table.metadata, "case");
      if (traced_case && *traced_case != spec.name) {
        std::fprintf(stderr, "lexdyn-harness: warning: %s is a trace of case '%s', not of '%s' (%s)\n", trace_path.c_str(),
                     traced_case->c_str(), spec.name.c_str(), case_path.c_str());
      }
      const auto results = lexdyn::checks::runChecks(spec.checks, table);
      bool all = true;
      for (const auto& r : results) all = all && r.passed;
      const int tc = table.column(lexdyn::checks::kTimeChannel);
      if (table.rows.empty() || tc < 0) {
        std::fprintf(stderr, "[%s] %s: %zu rows\n", spec.name.c_str(), trace_path.c_str(), table.rows.size());
      } else {
        const bool partial = trace_path.size() > 8 && trace_path.compare(trace_path.size() - 8, 8, ".partial") == 0;
        std::fprintf(stderr, "[%s] %s: %zu rows, t = %g .. %g s%s\n", spec.name.c_str(), trace_path.c_str(),
                     table.rows.size(), table.rows.front()[static_cast<size_t>(tc)], table.rows.back()[static_cast<size_t>(tc)],
                     partial ? " (partial trace: the run did not finish)" : "");
      }
      printChecks(results);
      return all ? 0 : 1;
    }
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    lexdyn::cases::RunOptions options;
    options.out_dir = out_dir;
    options.progress = !quiet;
    options.interrupt = &g_interrupt;
    const lexdyn::cases::RunSummary s = lexdyn::cases::runCase(spec, options);
    std::fprintf(stderr, "[%s] %s: %.3f s simulated in %.3f s wall (%.1fx real time), %ld ticks\n", spec.name.c_str(),
                 s.status.c_str(), s.simulated_s, s.wall_s, s.realtime_factor, s.ticks);
    if (!s.message.empty()) std::fprintf(stderr, "  %s\n", s.message.c_str());
    printChecks(s.checks);
    std::fprintf(stderr, "  wrote %s and %s\n", s.trace_path.c_str(), s.summary_path.c_str());
    return lexdyn::cases::exitCode(s);
  } catch (const lexdyn::InputError& e) {
    std::fprintf(stderr, "lexdyn-harness: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lexdyn-harness: internal error: %s\n", e.what());
    return 1;
  }
}
