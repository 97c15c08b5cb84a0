// lexdyn-harness: runs case files, checks stored traces, compares methods, golden traces.
//
//   lexdyn-harness run CASE --out DIR [--method bfgs|ah|gn|wls] [--duration S] [--set PATH=VALUE]... [--quiet]
//                                     [--wall-clock-checks] [--dump-problems DIR [--dump-window FROM:TO]]
//   lexdyn-harness case CASE [--method M] [--duration S] [--set PATH=VALUE]... [--out FILE]
//                                                         (the effective case as one YAML file)
//   lexdyn-harness check TRACE --case CASE [--json] [--wall-clock-checks]  (the case's checks on a stored trace)
//   lexdyn-harness check CASE TRACE [--json]              (the same, older argument order)
//   lexdyn-harness compare --case CASE TRACE... [--json]  (the case's comparisons between methods)
//   lexdyn-harness sweep run|point|chunk|merge|submit|list|check FILE ...   (docs/sweeps.md)
//   lexdyn-harness report --runs DIR [--sweeps DIR] [--history FILE] --out DIR [...]
//                                      (runs harness/scripts/report.py; docs/report.md)
//   lexdyn-harness robot init URDF --out DIR [--srdf FILE] [--package-path DIR]... [--base B] [--posture P]
//   lexdyn-harness robot check DATA_OR_CASE_OR_URDF [--urdf FILE] [--package-path DIR]... [--png FILE]
//                                      (bringing a robot in; docs/model.md)
//   lexdyn-harness golden list [--manifest FILE] [--cases A,B] [--only ID]   (ID CASE_FILE METHOD lines)
//   lexdyn-harness golden update|check [--manifest FILE] [--cases A,B] [--only ID]
//                                      [--work DIR] [--progress]
//
// Exit codes (docs/architecture.md, "Errors and exit codes"), the first that applies:
//   130 / 143  interrupted by SIGINT / SIGTERM (a run keeps its trace, marked, and its summary);
//   2          bad input: case, robot, trace or manifest file, command line (the message names
//              the file, the line and the key path); nothing is simulated;
//   3          run failure: integrator, controller or solver failure, an internal error, out of
//              memory (the trace is kept and marked with the reason);
//   1          a check, comparison or golden failed, or `check` / `compare` were given the trace
//              of a run that did not complete;
//   0          the run completed and every check that decides passed (wall-clock checks decide
//              only with --wall-clock-checks).
#include "harness/cases/runner.hpp"
#include "harness/checks/output_files.hpp"
#include "harness/cli/exception_exit.hpp"
#include "harness/cli/robot_cmd.hpp"
#include "harness/cli/sweep_cmd.hpp"
#include "harness/golden/golden.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/control/method.hpp"

#include <CLI/CLI.hpp>

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <csignal>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

std::atomic<bool> g_interrupt{false};
std::atomic<int> g_signal{0};

extern "C" void onSignal(int s) {
  g_signal.store(s);
  g_interrupt.store(true);
}

int interruptedCode() { return lexdyn::cases::kExitInterrupted + (g_signal.load() > 0 ? g_signal.load() : SIGINT); }

void printChecks(const std::vector<lexdyn::checks::CheckResult>& checks, const std::vector<std::string>& expected_to_fail = {}) {
  for (const auto& c : checks) {
    // A check that does not decide (a wall-clock measurement without --wall-clock-checks) is
    // reported as "info", labelled; a failure the case expects (expected_failures) as "xfail".
    const bool expected = std::find(expected_to_fail.begin(), expected_to_fail.end(), c.name) != expected_to_fail.end();
    const char* mark = c.decides ? (c.passed ? "ok" : (expected ? "xfail" : "FAIL")) : "info";
    std::fprintf(stderr, "  %-4s %-28s value %-12.6g limit %-10.6g %s%s%s%s%s\n", mark, c.name.c_str(), c.value, c.limit, c.unit.c_str(),
                 c.detail.empty() ? "" : "  (", c.detail.empty() ? "" : (c.detail + ")").c_str(),
                 c.decides ? ""
                           : (c.passed ? "  [machine-dependent, reported only: within the limit here]"
                                       : "  [machine-dependent, reported only: above the limit here]"),
                 c.partial_window.empty() ? "" : "  [part of its window]");
  }
}

/// A trace that does not end with the mark of a completed run: the checks only saw part of it.
bool warnIfIncomplete(const std::string& path, const lexdyn::checks::TraceTable& table) {
  if (table.complete()) return false;
  std::fprintf(stderr,
               "lexdyn-harness: %s is not the trace of a complete run (%s): the results cover its rows only and "
               "do not pass\n",
               path.c_str(), table.completeness().c_str());
  return true;
}

bool isPartial(const std::string& path) { return path.size() > 8 && path.compare(path.size() - 8, 8, ".partial") == 0; }

void describeTrace(const std::string& label, const std::string& path, const lexdyn::checks::TraceTable& table) {
  const int tc = table.column(lexdyn::checks::kTimeChannel);
  if (table.rows.empty() || tc < 0) {
    std::fprintf(stderr, "[%s] %s: %zu rows\n", label.c_str(), path.c_str(), table.rows.size());
    return;
  }
  const std::string* every = lexdyn::checks::findMetadata(table.metadata, "trace_every_n_ticks");
  const bool decimated = every && *every != "1";
  std::fprintf(stderr, "[%s] %s: %zu rows, t = %g .. %g s%s%s\n", label.c_str(), path.c_str(), table.rows.size(),
               table.rows.front()[static_cast<size_t>(tc)], table.rows.back()[static_cast<size_t>(tc)],
               isPartial(path) ? " (partial trace: the run did not finish)" : "",
               decimated ? " (decimated: rate-based checks see fewer rows than the live run did)" : "");
}

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

// "FROM:TO" in seconds, both finite, FROM <= TO; "FROM:" keeps `to` (RunOptions' default: the end
// of the run). Throws InputError.
void parseDumpWindow(const std::string& text, double& from, double& to) {
  const auto colon = text.find(':');
  auto number = [&](const std::string& s, double& v) {
    char* end = nullptr;
    v = std::strtod(s.c_str(), &end);
    return !s.empty() && end == s.c_str() + s.size() && std::isfinite(v);
  };
  double a = 0.0, b = to;
  const bool ok = colon != std::string::npos && number(text.substr(0, colon), a) &&
                  (colon + 1 == text.size() || number(text.substr(colon + 1), b)) && a <= b;
  if (!ok)
    throw lexdyn::InputError("--dump-window",
                             "expected FROM:TO in seconds with FROM <= TO (e.g. 31.5:32.5, or 31.5: to the end), found '" + text + "'");
  from = a;
  to = b;
}

int runCheck(const std::vector<std::string>& positional, const std::string& case_opt, bool json, bool wall_clock) {
  std::string case_path = case_opt, trace_path;
  if (positional.size() == 2 && case_opt.empty()) {
    case_path = positional[0];
    trace_path = positional[1];
  } else if (positional.size() == 1) {
    trace_path = positional[0];
  } else {
    throw lexdyn::InputError("check", "expected TRACE --case CASE (or CASE TRACE)");
  }
  const lexdyn::checks::TraceTable table = lexdyn::checks::readTrace(trace_path);
  // The run's overrides (--set, --duration, a sweep's point) are in its effective case, DIR/case.yaml
  // beside the trace: without --case the checks are those of the case as it ran.
  const std::string* overrides = lexdyn::checks::findMetadata(table.metadata, "overrides");
  // Overrides other than the run's length and method (which leave the checks as they are).
  bool overridden = false;
  if (overrides) {
    for (size_t at = 0; at < overrides->size();) {
      const size_t end = std::min(overrides->find("; ", at), overrides->size());
      const std::string item = overrides->substr(at, end - at);
      const std::string path = item.substr(0, item.find('='));
      if (!item.empty() && item != "none" && path != "stop_at_s" && path != "controller.method") overridden = true;
      at = end + 2;
    }
  }
  const fs::path effective = fs::path(trace_path).parent_path() / "case.yaml";
  if (case_path.empty()) {
    if (fs::is_regular_file(effective)) {
      case_path = effective.string();
    } else {
      const std::string* cf = lexdyn::checks::findMetadata(table.metadata, "case_file");
      if (!cf || !fs::is_regular_file(*cf))
        throw lexdyn::InputError(trace_path, "the trace does not name a readable case file; give --case CASE");
      case_path = *cf;
      if (overridden)
        std::fprintf(stderr,
                     "lexdyn-harness: warning: %s ran with overrides (%s) and its folder has no case.yaml: the checks are those of %s "
                     "without them\n",
                     trace_path.c_str(), overrides->c_str(), case_path.c_str());
    }
  } else if (std::error_code ec; overridden && !fs::equivalent(case_path, effective, ec)) {
    std::fprintf(stderr, "lexdyn-harness: warning: %s ran with overrides (%s); the checks are those of %s without them%s\n",
                 trace_path.c_str(), overrides->c_str(), case_path.c_str(),
                 fs::is_regular_file(effective) ? (" (the run's own: --case " + effective.string() + ")").c_str() : "");
  }
  const lexdyn::cases::CaseSpec spec = lexdyn::cases::loadCase(case_path);
  const std::string* traced_case = lexdyn::checks::findMetadata(table.metadata, "case");
  if (traced_case && *traced_case != spec.name) {
    std::fprintf(stderr, "lexdyn-harness: warning: %s is a trace of case '%s', not of '%s' (%s)\n", trace_path.c_str(),
                 traced_case->c_str(), spec.name.c_str(), case_path.c_str());
  }
  const auto results = lexdyn::checks::runChecks(spec.checks, table, wall_clock);
  const bool all = lexdyn::checks::allPassed(results);
  const std::string* method = lexdyn::checks::findMetadata(table.metadata, lexdyn::checks::kMethodMetadata);
  describeTrace(spec.name + (method ? " " + *method : ""), trace_path, table);
  // A failure the case declares (expected_failures) is judged as `run` judges it: a trace that
  // ended as declared, with exactly the listed checks failing, passes.
  const lexdyn::cases::ExpectedFailure* x = lexdyn::cases::expectedFailureFor(spec, method ? *method : "");
  printChecks(results, x ? x->checks : std::vector<std::string>{});
  if (json) std::printf("%s\n", lexdyn::cases::checkResultsJson(results).c_str());
  if (x && table.end_status && table.end_status != lexdyn::records::RunStatus::Interrupted) {
    // Cut short as the run was: the trace's last time, not the case file's duration (a run given
    // --duration keeps the case's own stop).
    const int tc = table.column(lexdyn::checks::kTimeChannel);
    const double last_t = tc >= 0 && !table.rows.empty() ? table.rows.back()[static_cast<size_t>(tc)] : 0.0;
    const bool cut_short = last_t < spec.scenario_duration_s - 1e-6;
    const std::vector<std::string> mismatches = lexdyn::cases::expectationMismatches(*x, *table.end_status, results, cut_short);
    if (mismatches.empty()) {
      std::fprintf(stderr, "  expected failure, as the case says (%s): %s\n", x->where.c_str(), x->reason.c_str());
      return lexdyn::cases::kExitPass;
    }
    std::fprintf(stderr, "  NOT the expected failure (%s: %s):\n", x->where.c_str(), x->reason.c_str());
    for (const std::string& m : mismatches) std::fprintf(stderr, "    %s\n", m.c_str());
    return lexdyn::cases::kExitCheckFailed;
  }
  const bool incomplete = warnIfIncomplete(trace_path, table);
  return all && !incomplete ? lexdyn::cases::kExitPass : lexdyn::cases::kExitCheckFailed;
}

int runCompare(const std::string& case_path, const std::vector<std::string>& traces, bool json) {
  if (case_path.empty()) throw lexdyn::InputError("compare", "expected --case CASE");
  const lexdyn::cases::CaseSpec spec = lexdyn::cases::loadCase(case_path);
  if (spec.comparisons.empty()) throw lexdyn::InputError(case_path, "the case has no comparisons");
  std::map<std::string, lexdyn::checks::TraceTable> by_method;
  bool incomplete = false;
  for (const std::string& p : traces) {
    lexdyn::checks::TraceTable t = lexdyn::checks::readTrace(p);
    const std::string* m = lexdyn::checks::findMetadata(t.metadata, lexdyn::checks::kMethodMetadata);
    if (!m) throw lexdyn::InputError(p, "the trace records no method (not a lexdyn run)");
    const std::string* c = lexdyn::checks::findMetadata(t.metadata, "case");
    if (c && *c != spec.name) {
      std::fprintf(stderr, "lexdyn-harness: warning: %s is a trace of case '%s', not of '%s'\n", p.c_str(), c->c_str(), spec.name.c_str());
    }
    describeTrace(spec.name + " " + *m, p, t);
    if (warnIfIncomplete(p, t)) incomplete = true;
    if (by_method.count(*m)) throw lexdyn::InputError(p, "a second trace of method " + *m);
    by_method.emplace(*m, std::move(t));
  }
  std::vector<lexdyn::checks::CheckResult> results;
  std::vector<char> evaluated;  // per comparison: both methods' traces were given
  for (const auto& cs : spec.comparisons) {
    evaluated.push_back(by_method.count(cs.better) && by_method.count(cs.worse) ? 1 : 0);
    if (!evaluated.back()) {
      lexdyn::checks::CheckResult r;
      r.name = cs.name;
      r.type = cs.type;
      r.passed = false;
      r.value = std::numeric_limits<double>::quiet_NaN();
      r.limit = cs.margin;
      r.detail = "needs traces of methods " + cs.better + " and " + cs.worse;
      results.push_back(r);
      continue;
    }
    results.push_back(lexdyn::checks::compareMethods(cs, by_method.at(cs.better), by_method.at(cs.worse)));
  }
  // Runs cut short of the case's duration (run --duration) may not reach a documented failure.
  std::string cut;
  for (const auto& [method, t] : by_method) {
    const std::string* d = lexdyn::checks::findMetadata(t.metadata, "duration_s");
    const std::string* sd = lexdyn::checks::findMetadata(t.metadata, lexdyn::checks::kScenarioDurationMetadata);
    if (d && sd && std::strtod(d->c_str(), nullptr) < std::strtod(sd->c_str(), nullptr)) cut = *d + " s of the case's " + *sd + " s";
  }
  std::vector<std::string> expected;  // documented failures that were evaluated (one not evaluated is no outcome)
  for (size_t i = 0; i < spec.comparisons.size(); ++i) {
    if (!spec.comparisons[i].expected_failure_reason.empty() && evaluated[i]) expected.push_back(spec.comparisons[i].name);
  }
  printChecks(results, expected);
  // A comparison the case documents as failing: its failure is the expected outcome, a pass is
  // a change of that outcome (better or worse, the case and docs/results.md are out of date).
  bool as_documented = true;
  for (size_t i = 0; i < results.size(); ++i) {
    const auto& cs = spec.comparisons[i];
    if (cs.expected_failure_reason.empty() || !evaluated[i]) {
      if (!results[i].passed) as_documented = false;
      continue;
    }
    if (!results[i].passed) {
      std::fprintf(stderr, "  expected failure of %s, as the case says (%s): %s\n", cs.name.c_str(), cs.where.c_str(),
                   cs.expected_failure_reason.c_str());
    } else if (!cut.empty()) {
      std::fprintf(stderr, "  %s passed: its documented failure is not reached by runs of %s (%s)\n", cs.name.c_str(), cut.c_str(),
                   cs.where.c_str());
    } else {
      as_documented = false;
      std::fprintf(stderr,
                   "  NOT as the case says: %s passed, the case documents that it fails (%s: %s); the outcome changed: "
                   "update the case and docs/results.md\n",
                   cs.name.c_str(), cs.where.c_str(), cs.expected_failure_reason.c_str());
    }
  }
  if (json) std::printf("%s\n", lexdyn::cases::checkResultsJson(results).c_str());
  if (as_documented && !incomplete && !expected.empty()) std::fprintf(stderr, "compare: every comparison as documented\n");
  return as_documented && !incomplete ? lexdyn::cases::kExitPass : lexdyn::cases::kExitCheckFailed;
}

// One line per selected golden: ID CASE_FILE METHOD ("-" for a case without methods).
/// One golden of the manifest chosen by --cases (case names) and --only (golden ids CASE.METHOD,
/// or case names: every golden of that case); both given: goldens matching both.
struct SelectedGolden {
  const lexdyn::golden::Entry* entry;
  std::string method, id;
};

std::vector<SelectedGolden> selectGoldens(const lexdyn::golden::Manifest& m, const std::string& manifest_path, const std::string& cases_opt,
                                          const std::string& only) {
  const std::vector<std::string> wanted_cases = splitList(cases_opt);
  const std::vector<std::string> wanted_only = splitList(only);
  auto listed = [](const std::vector<std::string>& v, const std::string& x) { return std::find(v.begin(), v.end(), x) != v.end(); };
  std::vector<SelectedGolden> out;
  for (const auto& e : m.entries) {
    if (!wanted_cases.empty() && !listed(wanted_cases, e.case_name)) continue;
    for (const auto& method : e.methods) {
      const std::string id = lexdyn::golden::goldenId(e.case_name, method);
      if (!wanted_only.empty() && !listed(wanted_only, id) && !listed(wanted_only, e.case_name)) continue;
      out.push_back({&e, method, id});
    }
  }
  if (out.empty()) throw lexdyn::InputError(manifest_path, "no golden matches --cases / --only");
  return out;
}

int runGoldenList(const std::string& manifest_path, const std::string& cases_opt, const std::string& only) {
  const lexdyn::golden::Manifest m = lexdyn::golden::loadManifest(manifest_path);
  for (const SelectedGolden& g : selectGoldens(m, manifest_path, cases_opt, only)) {
    std::printf("%s %s %s\n", g.id.c_str(), g.entry->case_path.c_str(), g.method.empty() ? "-" : g.method.c_str());
  }
  return 0;
}

int runGoldenCommand(bool update, const std::string& manifest_path, const std::string& cases_opt, const std::string& only, std::string work,
                     bool progress) {
  const lexdyn::golden::Manifest m = lexdyn::golden::loadManifest(manifest_path);
  const std::vector<SelectedGolden> selected = selectGoldens(m, manifest_path, cases_opt, only);
  bool temp_work = false;
  if (work.empty()) {
    work = (fs::temp_directory_path() / ("lexdyn-golden-" + std::to_string(::getpid()))).string();
    temp_work = true;
  }
  int failed = 0, run_failures = 0;
  for (const SelectedGolden& g : selected) {
    const lexdyn::golden::Entry& e = *g.entry;
    const std::string& method = g.method;
    const std::string& id = g.id;
    const std::string path = lexdyn::golden::goldenPath(m, e.case_name, method);
    if (!update && !fs::is_regular_file(path)) {
      std::fprintf(stderr, "  MISSING %s: %s does not exist (lexdyn-harness golden update --only %s)\n", id.c_str(), path.c_str(),
                   id.c_str());
      ++failed;
      continue;
    }
    lexdyn::records::RunStatus status = lexdyn::records::RunStatus::Completed;
    const lexdyn::checks::TraceTable fresh = lexdyn::golden::runGolden(e, method, m, work, status, progress, &g_interrupt);
    if (g_interrupt.load() || status == lexdyn::records::RunStatus::Interrupted) {
      std::fprintf(stderr, "  interrupted during %s: nothing written for it\n", id.c_str());
      if (temp_work) {
        std::error_code ec;
        fs::remove_all(work, ec);
      }
      return interruptedCode();
    }
    if (status == lexdyn::records::RunStatus::InternalError || status == lexdyn::records::RunStatus::InputError) {
      // The run stopped on an exception: a golden would record that, not the case's behaviour.
      std::fprintf(stderr, "  FAIL %s: the run stopped with %s (%s)\n", id.c_str(), lexdyn::records::toString(status),
                   fresh.end_message.c_str());
      ++run_failures;
      continue;
    }
    if (update) {
      lexdyn::golden::writeGolden(path, fresh, lexdyn::golden::provenance(e, method, status, m.dir));
      std::fprintf(stderr, "  wrote %s: %zu rows x %zu channels, %g s, run %s\n", path.c_str(), fresh.rows.size(), fresh.names.size(),
                   e.duration_s, lexdyn::records::toString(status));
      continue;
    }
    const lexdyn::checks::TraceTable golden = lexdyn::checks::readTrace(path);
    lexdyn::golden::Comparison c = lexdyn::golden::compare(golden, fresh, m.tolerance, m.channel_tolerances);
    for (const std::string& p : lexdyn::golden::goldenFileProblems(golden)) {
      c.problems.insert(c.problems.begin(), p);
      c.ok = false;
    }
    std::fprintf(stderr, "  %-4s %s: %s\n", c.ok ? "ok" : "FAIL", id.c_str(), c.report().c_str());
    if (!c.ok) ++failed;
  }
  if (temp_work) {
    std::error_code ec;
    fs::remove_all(work, ec);
  }
  const int n = static_cast<int>(selected.size());
  if (!update) std::fprintf(stderr, "golden check: %d of %d match\n", n - failed - run_failures, n);
  if (run_failures > 0) return lexdyn::cases::kExitRunFailure;
  return failed == 0 ? lexdyn::cases::kExitPass : lexdyn::cases::kExitCheckFailed;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"lexdyn-harness: runs simulation cases, checks their traces, compares methods, golden traces"};
  app.require_subcommand(1);

  std::string case_path, out_dir, case_opt, method, manifest = std::string(LEXDYN_SOURCE_DIR) + "/golden/manifest.yaml";
  std::string cases_opt, only, work;
  std::string duration;
  bool quiet = false, progress = false, json = false, wall_clock = false;
  std::vector<std::string> positional, traces, sets;
  std::string case_out;
  std::string dump_dir, dump_window;

  std::string method_names;  // the registry's, "bfgs | ah | gn | wls"
  for (const std::string& m : lexdyn::control::methodNames()) method_names += (method_names.empty() ? "" : " | ") + m;

  CLI::App* run = app.add_subcommand("run", "run a case file");
  run->add_option("case", case_path, "case file (YAML)")->required();
  run->add_option("--out", out_dir, "output directory (trace.csv, summary.json)")->required();
  run->add_option("--method", method, "lexdyn method, overrides the case's: " + method_names);
  run->add_option("--duration", duration, "simulate at most this long (s)");
  run->add_flag("--quiet", quiet, "no progress lines");
  run->add_option("--set", sets, "override a value of the case: PATH=VALUE (docs/cases.md, \"Overrides\"); repeatable");

  CLI::App* casecmd = app.add_subcommand("case", "print the effective case (the file with --method, --duration and --set applied)");
  casecmd->add_option("case", case_path, "case file (YAML)")->required();
  casecmd->add_option("--method", method, "lexdyn method: " + method_names);
  casecmd->add_option("--duration", duration, "simulate at most this long (s): stop_at_s");
  casecmd->add_option("--set", sets, "override a value of the case: PATH=VALUE; repeatable");
  casecmd->add_option("--out", case_out, "write it to this file (paths relative to it) instead of stdout (absolute paths)");
  run->add_flag("--wall-clock-checks", wall_clock, "tick_time checks decide pass/fail (machine-dependent; reported otherwise)");
  run->add_option("--dump-problems", dump_dir,
                  "write each tick's solver problem to DIR/tick_NNNNNN.json (lexdyn controllers; for lexdyn-solve)");
  run->add_option("--dump-window", dump_window, "with --dump-problems: only the ticks with FROM <= t <= TO (s), e.g. 31.5:32.5");

  CLI::App* check = app.add_subcommand("check", "evaluate a case's checks on a stored trace");
  check->add_option("args", positional, "TRACE (with --case CASE), or CASE TRACE")->required()->expected(1, 2);
  check->add_option("--case", case_opt, "case file (default: the one the trace names)");
  check->add_flag("--json", json, "also print the results as JSON on stdout (summary.json's checks)");
  check->add_flag("--wall-clock-checks", wall_clock, "tick_time checks decide pass/fail (machine-dependent; reported otherwise)");

  CLI::App* compare = app.add_subcommand("compare", "evaluate a case's comparisons on traces of several methods");
  compare->add_option("traces", traces, "trace files (one per method)")->required();
  compare->add_option("--case", case_opt, "case file")->required();
  compare->add_flag("--json", json, "also print the results as JSON on stdout");

  lexdyn::cli::SweepCommand sweep;
  lexdyn::cli::addSweepCommands(app, sweep);
  lexdyn::cli::RobotCommand robot;
  lexdyn::cli::addRobotCommands(app, robot);

  // The report is built by harness/scripts/report.py (Debian's matplotlib through
  // /usr/bin/python3); its options pass through unchanged.
  CLI::App* report = app.add_subcommand("report", "build the report from stored results (harness/scripts/report.py; docs/report.md)");
  report->allow_extras();
  report->prefix_command();
  report->set_help_flag();  // report.py answers --help itself

  CLI::App* golden = app.add_subcommand("golden", "golden traces: update (regenerate) or check (compare)");
  golden->require_subcommand(1);
  CLI::App* gupdate = golden->add_subcommand("update", "regenerate golden traces");
  CLI::App* gcheck = golden->add_subcommand("check", "re-run and compare with the golden traces");
  CLI::App* glist = golden->add_subcommand("list", "print the manifest's goldens: ID CASE_FILE METHOD (- for none)");
  glist->add_option("--manifest", manifest, "golden manifest (default: the source tree's golden/manifest.yaml)");
  glist->add_option("--cases", cases_opt, "comma-separated case names");
  glist->add_option("--only", only, "comma-separated golden ids (CASE.METHOD) or case names");
  for (CLI::App* g : {gupdate, gcheck}) {
    g->add_option("--manifest", manifest, "golden manifest (default: the source tree's golden/manifest.yaml)");
    g->add_option("--cases", cases_opt, "comma-separated case names");
    g->add_option("--only", only, "comma-separated golden ids (CASE.METHOD) or case names");
    g->add_option("--work", work, "directory for the runs (default: a temporary one, removed)");
    g->add_flag("--progress", progress, "progress lines of the runs");
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return lexdyn::cases::kExitBadInput;
  }

  // SIGINT / SIGTERM: a run stops after the current tick, keeps its trace (marked) and writes its
  // summary; golden runs stop; every subcommand then exits 128 + the signal.
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  // A file-size limit (ulimit -f) is then a write error with its reason ("File too large", exit
  // code 3), not a kill by SIGXFSZ.
  std::signal(SIGXFSZ, SIG_IGN);
  auto interrupted = [](int code) { return g_interrupt.load() ? interruptedCode() : code; };
  try {
    if (*report) {
      const std::string script = std::string(LEXDYN_SOURCE_DIR) + "/harness/scripts/report.py";
      if (!fs::is_regular_file("/usr/bin/python3"))
        throw lexdyn::InputError("report", "needs /usr/bin/python3 (Debian's python3 with python3-matplotlib)");
      std::vector<std::string> args = {"/usr/bin/python3", script};
      for (const std::string& a : report->remaining()) args.push_back(a);
      std::vector<char*> argv_c;
      for (auto& a : args) argv_c.push_back(a.data());
      argv_c.push_back(nullptr);
      std::fflush(stdout);
      // The replay converts meshes other than STL with `lexdyn-harness robot mesh` (this program).
      std::error_code self_ec;
      const fs::path self = fs::canonical("/proc/self/exe", self_ec);
      if (!self_ec) ::setenv("LEXDYN_HARNESS", self.c_str(), 1);
      // report.py reads the stored results with the lexdyn Python package of this checkout
      // (python/lexdyn; docs/python.md, "Where Python finds the package").
      const char* python_path = std::getenv("PYTHONPATH");
      const std::string package_path =
          std::string(LEXDYN_SOURCE_DIR) + "/python" + (python_path && *python_path ? std::string(":") + python_path : std::string());
      ::setenv("PYTHONPATH", package_path.c_str(), 1);
      ::execv(argv_c[0], argv_c.data());
      throw std::runtime_error(std::string("cannot run ") + script + ": " + std::strerror(errno));
    }
    if (*sweep.sweep) return lexdyn::cli::runSweepCommand(sweep, g_signal, g_interrupt);
    if (*robot.robot) return lexdyn::cli::runRobotCommand(robot);
    if (*check) return interrupted(runCheck(positional, case_opt, json, wall_clock));
    if (*compare) return interrupted(runCompare(case_opt, traces, json));
    if (*golden && *glist) return interrupted(runGoldenList(manifest, cases_opt, only));
    if (*golden) return interrupted(runGoldenCommand(static_cast<bool>(*gupdate), manifest, cases_opt, only, work, progress));
    // --duration is an override like --set (stop_at_s), and --method is recorded as one
    // (controller.method), so that the effective case (DIR/case.yaml) holds them.
    std::vector<lexdyn::cases::Override> overrides;
    if (!duration.empty()) overrides.push_back({"stop_at_s", duration, "--duration " + duration});
    for (const std::string& s : sets) overrides.push_back(lexdyn::cases::parseOverride(s));
    lexdyn::cases::CaseSpec spec = lexdyn::cases::loadCase(case_path, overrides);
    if (!method.empty()) lexdyn::cases::overrideMethod(spec, method, "--method");
    if (*casecmd) {
      if (case_out.empty()) {
        std::fputs(lexdyn::cases::effectiveCaseText(spec, "").c_str(), stdout);
        return 0;
      }
      const fs::path dir = fs::path(case_out).parent_path().empty() ? fs::path(".") : fs::path(case_out).parent_path();
      const std::string text = lexdyn::cases::effectiveCaseText(spec, dir.string());
      lexdyn::files::writeAtomically(case_out, text);
      std::fprintf(stderr, "wrote %s\n", case_out.c_str());
      return 0;
    }
    lexdyn::cases::RunOptions options;
    options.out_dir = out_dir;
    options.progress = !quiet;
    options.interrupt = &g_interrupt;
    options.interrupt_signal = &g_signal;
    options.wall_clock_checks = wall_clock;
    options.dump_problems_dir = dump_dir;
    if (!dump_window.empty()) {
      if (dump_dir.empty()) throw lexdyn::InputError("--dump-window", "needs --dump-problems DIR");
      parseDumpWindow(dump_window, options.dump_from_s, options.dump_to_s);
    }
    const lexdyn::cases::RunSummary s = lexdyn::cases::runCase(spec, options);
    const std::string label = spec.name + (s.method.empty() ? "" : " " + s.method);
    std::fprintf(stderr, "[%s] %s: %.3f s simulated in %.3f s wall (%.1fx real time), %ld ticks\n", label.c_str(),
                 lexdyn::records::toString(s.status), s.simulated_s, s.wall_s, s.realtime_factor, s.ticks);
    if (!s.message.empty()) std::fprintf(stderr, "  %s\n", s.message.c_str());
    if (s.has_controller_stats) {
      std::string errs;
      for (const auto& t : s.controller.tasks) {
        char buf[128];
        std::snprintf(buf, sizeof(buf), "%s%s %.4g", errs.empty() ? "" : ", ", t.name.c_str(), t.final_error);
        errs += buf;
      }
      std::fprintf(stderr, "  final task errors: %s\n", errs.c_str());
      std::fprintf(stderr, "  peak active-set iterations %d at t = %g s\n", s.controller.peak_iterations,
                   s.controller.peak_iterations_at_s);
    }
    printChecks(s.checks, s.expected_failure ? s.expected_failure->checks : std::vector<std::string>{});
    if (s.expected_failure) {
      const lexdyn::cases::ExpectedFailure& x = *s.expected_failure;
      if (s.expectation_mismatches.empty() && !s.expected_failure_reached) {
        std::fprintf(stderr, "  the case's expected failure (%s: %s) was not reached by the run's end at %g s\n", x.where.c_str(),
                     x.reason.c_str(), s.duration_s);
      } else if (s.expectation_mismatches.empty()) {
        std::fprintf(stderr, "  expected failure, as the case says (%s): %s\n", x.where.c_str(), x.reason.c_str());
      } else {
        std::fprintf(stderr, "  NOT the expected failure (%s: %s):\n", x.where.c_str(), x.reason.c_str());
        for (const std::string& m : s.expectation_mismatches) std::fprintf(stderr, "    %s\n", m.c_str());
      }
    }
    for (const auto& k : s.skipped_checks) std::fprintf(stderr, "  skip %-28s %s\n", k.name.c_str(), k.reason.c_str());
    if (std::any_of(s.checks.begin(), s.checks.end(), [](const auto& c) { return !c.partial_window.empty(); })) {
      std::fprintf(stderr,
                   "  [part of its window]: the run stopped at %g s of the scenario's %g s (stop_at_s, run --duration); such a check "
                   "covers what was run (summary.json: partial_window)\n",
                   s.duration_s, spec.scenario_duration_s);
    }
    std::fprintf(stderr, "  wrote %s and %s\n", s.trace_path.c_str(), s.summary_path.c_str());
    return lexdyn::cases::exitCode(s);
  } catch (...) {
    return lexdyn::cli::exitCodeOfException("lexdyn-harness", lexdyn::cases::kExitRunFailure);
  }
}
