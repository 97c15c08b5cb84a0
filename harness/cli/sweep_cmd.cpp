#include "harness/cli/sweep_cmd.hpp"

#include "harness/checks/output_files.hpp"
#include "harness/sweep/slurm.hpp"
#include "harness/sweep/sweep_records.hpp"
#include "harness/sweep/sweep_run.hpp"
#include "lexdyn/common/error.hpp"

#include <CLI/CLI.hpp>

#include <unistd.h>

#include <optional>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

namespace lexdyn::cli {

namespace fs = std::filesystem;

namespace {

// The options several sweep subcommands share: the same member of SweepCommand, with the help
// text of the subcommand where it differs. Each adds one option and returns the builder, so a
// subcommand's options read in the order of its help.
struct SweepOptions {
  CLI::App* s;
  SweepCommand& c;

  SweepOptions& out(const std::string& help) {
    s->add_option("--out", c.out, help)->required();
    return *this;
  }
  SweepOptions& jobs(const std::string& help) {
    s->add_option("-j,--jobs", c.jobs, help);
    return *this;
  }
  SweepOptions& points(const std::string& help) {
    s->add_option("--points", c.points, help);
    return *this;
  }
  SweepOptions& timeout() {
    s->add_option("--timeout", c.timeout_s, "seconds per run (default: the sweep file's timeout_s)");
    return *this;
  }
  SweepOptions& keepTraces() {
    s->add_flag("--keep-traces", c.keep_traces, "keep the traces of passing runs too");
    return *this;
  }
  SweepOptions& noShrink() {
    s->add_flag("--no-shrink", c.no_shrink, "do not shrink the failures");
    return *this;
  }
  SweepOptions& db(const std::string& help) {
    s->add_option("--db", c.db, help);
    return *this;
  }
  SweepOptions& noDb(const std::string& help) {
    s->add_flag("--no-db", c.no_db, help);
    return *this;
  }
  SweepOptions& quiet() {
    s->add_flag("--quiet", c.quiet, "no progress lines");
    return *this;
  }
};

const char* const kDefaultDb = "failure database (default: .lexdyn/sweep-failures/<sweep>.jsonl)";

}  // namespace

void addSweepCommands(CLI::App& app, SweepCommand& c) {
  c.sweep = app.add_subcommand("sweep", "property-based sweeps of gains and thresholds (docs/sweeps.md)");
  c.sweep->require_subcommand(1);
  // A subcommand with the sweep file, its first argument.
  auto command = [&](CLI::App*& sub, const char* name, const char* help) {
    sub = c.sweep->add_subcommand(name, help);
    sub->add_option("file", c.file, "sweep file (YAML, cases/sweeps/)")->required();
    return SweepOptions{sub, c};
  };

  command(c.run, "run", "run a sweep on the local cores (resumable: run it again to finish an interrupted one)")
      .out("output directory")
      .jobs("parallel processes (default: the number of cores)")
      .points("run only the first N points (a smaller budget)")
      .timeout()
      .keepTraces()
      .noShrink()
      .db(kDefaultDb)
      .noDb("neither replay nor record failures")
      .quiet();

  command(c.point, "point", "one run of a sweep in this process (what the driver runs for each point and method)");
  c.point->add_option("--method", c.method, "method")->required();
  c.point->add_option("--out", c.out, "the run's directory")->required();
  c.point->add_option("--index", c.index, "the point (its values from the seed and the index)");
  c.point->add_option("--value", c.values, "NAME=VALUE of a parameter (instead of --index; the others at the base case's values)");
  c.point->add_option("--duration", c.duration, "run length (s; default: the sweep's)");
  SweepOptions{c.point, c}.quiet();

  command(c.chunk, "chunk", "run some points of a sweep, one at a time (a Slurm array task)").out("output directory");
  c.chunk->add_option("--points", c.points_list, "point indices, comma-separated, or @FILE (one per line)")->required();
  c.chunk->add_option("--chunk-size", c.chunk_size, "with @FILE: this task's slice of that many points");
  c.chunk->add_option("--task", c.index, "with @FILE: the slice (the array task id)");
  SweepOptions{c.chunk, c}.timeout().keepTraces();

  command(c.merge, "merge", "merge the points of OUT, shrink the failures, write the summary")
      .out("output directory")
      .jobs("parallel shrinking runs (default: the number of cores)")
      .points("the sweep's first N points only")
      .noShrink()
      .db(kDefaultDb)
      .noDb("do not record failures")
      .quiet();

  command(c.submit, "submit", "run a sweep on Slurm: an array job over the missing points, then a merge job")
      .out("output directory (on a file system the nodes share)");
  c.submit->add_option("--chunk", c.chunk_size, "points per array task (default 4)");
  c.submit->add_option("--partition", c.partition, "Slurm partition");
  c.submit->add_option("--throttle", c.throttle, "at most this many array tasks at once (sbatch --array=...%N)");
  SweepOptions{c.submit, c}
      .points("the sweep's first N points only")
      .jobs("CPUs of the merge job (parallel shrinking runs; default 1)")
      .db("failure database of the merge job")
      .noDb("no failure database");
  c.submit->add_flag("--dry-run", c.dry_run, "write the job scripts, do not submit them");

  command(c.list, "list", "print the points: index and parameter values").points("the first N points only");

  command(c.check, "check", "validate a sweep file (every parameter value loads in the base case)");
}

namespace {

std::string selfExe() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find this program's path (/proc/self/exe)");
  return p.string();
}

std::string defaultDb(const sweep::SweepSpec& s) { return (fs::path(".lexdyn") / "sweep-failures" / (s.name + ".jsonl")).string(); }

sweep::DriverOptions driverOptions(const SweepCommand& c, const sweep::SweepSpec& s, const std::atomic<int>& signal) {
  sweep::DriverOptions o;
  o.out_dir = c.out;
  o.jobs = c.jobs > 0 ? c.jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  o.points = c.points;
  o.timeout_s = c.timeout_s;
  o.keep_traces = c.keep_traces;
  o.shrink = !c.no_shrink;
  o.db_path = c.no_db ? "" : (c.db.empty() ? defaultDb(s) : c.db);
  o.progress = !c.quiet;
  o.harness_exe = selfExe();
  o.interrupt = &signal;
  const std::string script = std::string(LEXDYN_SOURCE_DIR) + "/harness/scripts/sweep_plots.py";
  if (fs::is_regular_file("/usr/bin/python3") && fs::is_regular_file(script))
    o.plot_command = "/usr/bin/python3 " + sweep::shellQuote(script);
  return o;
}

std::vector<long> parsePoints(const SweepCommand& c) {
  std::vector<long> all;
  std::string text = c.points_list;
  const bool from_file = !text.empty() && text[0] == '@';
  if (from_file) {
    std::ifstream in(text.substr(1));
    if (!in) throw InputError(text.substr(1), "cannot open the point list");
    std::string line;
    text.clear();
    while (std::getline(in, line)) text += line + ",";
  }
  size_t i = 0;
  while (i < text.size()) {
    size_t j = text.find_first_of(",\n", i);
    if (j == std::string::npos) j = text.size();
    const std::string item = text.substr(i, j - i);
    if (!item.empty()) {
      char* end = nullptr;
      const long v = std::strtol(item.c_str(), &end, 10);
      if (end != item.c_str() + item.size() || v < 0) throw InputError("--points", "expected point indices, found '" + item + "'");
      all.push_back(v);
    }
    i = j + 1;
  }
  if (!from_file) return all;
  if (c.chunk_size <= 0 || c.index < 0) throw InputError("--points", "@FILE needs --chunk-size and --task");
  std::vector<long> out;
  for (long k = c.index * c.chunk_size; k < (c.index + 1) * c.chunk_size && k < static_cast<long>(all.size()); ++k)
    out.push_back(all[static_cast<size_t>(k)]);
  return out;
}

}  // namespace

int runSweepCommand(const SweepCommand& c, const std::atomic<int>& signal, const std::atomic<bool>& interrupted) {
  if (*c.point) {
    const sweep::SweepSpec s = sweep::loadSweep(c.file, false);
    sweep::RunConfig rc;
    rc.method = c.method;
    if (std::find(s.methods.begin(), s.methods.end(), c.method) == s.methods.end()) {
      throw InputError("--method", "the sweep runs " + cases::joinNames(s.methods) + ", not " + c.method);
    }
    if (c.index >= 0 && !c.values.empty()) throw InputError("--value", "give either --index or --value");
    if (c.index >= 0) {
      if (c.index >= s.points) throw InputError("--index", "the sweep has " + std::to_string(s.points) + " points");
      rc.values = sweep::pointAt(s, c.index).values;
    } else {
      rc.values.assign(s.parameters.size(), "");
      for (const std::string& nv : c.values) {
        const size_t eq = nv.find('=');
        size_t k = 0;
        while (eq != std::string::npos && k < s.parameters.size() && s.parameters[k].name != nv.substr(0, eq)) ++k;
        if (eq == std::string::npos || k == s.parameters.size()) {
          std::string names;
          for (const auto& p : s.parameters) names += (names.empty() ? "" : ", ") + p.name;
          throw InputError("--value " + nv, "expected NAME=VALUE with NAME one of " + names);
        }
        rc.values[k] = nv.substr(eq + 1);
      }
    }
    if (!c.duration.empty()) {
      char* end = nullptr;
      rc.duration_s = std::strtod(c.duration.c_str(), &end);
      if (end != c.duration.c_str() + c.duration.size() || !(rc.duration_s > 0.0))
        throw InputError("--duration", "expected a positive number of seconds");
    }
    return sweep::runPointHere(s, rc, c.out, &interrupted, !c.quiet);
  }
  const sweep::SweepSpec s = sweep::loadSweep(c.file, !*c.chunk);
  if (*c.check) {
    std::printf("%s: %ld points x %zu methods, %zu parameters, %zu property checks, %zu comparisons\n", c.file.c_str(), s.points,
                s.methods.size(), s.parameters.size(), s.checks.size(), s.comparisons.size());
    return 0;
  }
  if (*c.list) {
    std::printf("point");
    for (const auto& p : s.parameters) std::printf("\t%s", p.name.c_str());
    std::printf("\n");
    const long n = c.points >= 0 ? std::min(c.points, s.points) : s.points;
    for (long i = 0; i < n; ++i) {
      std::printf("%ld", i);
      for (const auto& v : sweep::pointAt(s, i).values) std::printf("\t%s", v.c_str());
      std::printf("\n");
    }
    return 0;
  }
  sweep::DriverOptions o = driverOptions(c, s, signal);
  // One job per sweep folder; the tasks of a Slurm array (chunks of disjoint points) share it.
  // `submit` holds it while it prepares the folder, not while Slurm starts the tasks.
  std::optional<files::FolderLock> lock;
  if (!*c.submit) {
    const std::string sub = *c.run ? "run" : (*c.merge ? "merge" : "chunk");
    lock.emplace(o.out_dir, "lexdyn-harness sweep " + sub + " " + s.name,
                 *c.chunk ? files::FolderLock::Mode::kShared : files::FolderLock::Mode::kExclusive);
  }
  if (*c.run) return sweep::runSweep(s, o);
  if (*c.merge) return sweep::mergeSweep(s, o);
  if (*c.chunk) {
    o.jobs = 1;
    o.shrink = false;
    return sweep::runPoints(s, parsePoints(c), o);
  }
  if (*c.submit) {
    sweep::SlurmOptions so;
    so.chunk = c.chunk_size > 0 ? c.chunk_size : 4;
    so.partition = c.partition;
    so.throttle = c.throttle;
    so.merge_cpus = c.jobs > 0 ? c.jobs : 1;
    so.dry_run = c.dry_run;
    o.jobs = so.merge_cpus;
    return sweep::submitSweep(s, o, so);
  }
  return 2;
}

}  // namespace lexdyn::cli
