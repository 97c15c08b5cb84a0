#include "harness/sweep/slurm.hpp"

#include "harness/checks/output_files.hpp"

#include "harness/sweep/sweep_records.hpp"
#include "lexdyn/common/error.hpp"

#include <cstdio>
#include <filesystem>
#include <optional>

namespace lexdyn::sweep {

namespace fs = std::filesystem;

namespace {

// Runs a command and returns its standard output (trimmed); `ok` false when it failed.
std::string capture(const std::string& cmd, bool& ok) {
  std::string out;
  std::FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) {
    ok = false;
    return out;
  }
  char buf[512];
  while (std::fgets(buf, sizeof(buf), p)) out += buf;
  ok = ::pclose(p) == 0;
  while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
  return out;
}

}  // namespace

int submitSweep(const SweepSpec& s, const DriverOptions& o, const SlurmOptions& so) {
  // The folder is locked while its scripts are written, and free before sbatch starts the tasks.
  std::optional<files::FolderLock> lock(std::in_place, o.out_dir, "lexdyn-harness sweep submit " + s.name);
  prepareOutDir(s, o.out_dir);
  const fs::path out = fs::absolute(o.out_dir).lexically_normal();
  const std::string file = fs::absolute(s.path).lexically_normal().string();
  const std::vector<long> missing = missingPoints(s, o.out_dir, o.points);
  int n = 1;
  while (fs::exists(out / "slurm" / ("submit-" + std::to_string(n)))) ++n;
  const fs::path dir = out / "slurm" / ("submit-" + std::to_string(n));
  fs::create_directories(dir);
  std::string list;
  for (long p : missing) list += std::to_string(p) + "\n";
  writeAtomically((dir / "points.txt").string(), list);
  const long tasks = (static_cast<long>(missing.size()) + so.chunk - 1) / so.chunk;
  std::string head = "#!/bin/bash\n#SBATCH --job-name=lexdyn-sweep-" + s.name + "\n";
  if (!so.partition.empty()) head += "#SBATCH --partition=" + so.partition + "\n";
  const std::string points_opt = o.points >= 0 ? " --points " + std::to_string(o.points) : "";
  std::string array = head + "#SBATCH --array=0-" + std::to_string(std::max(0L, tasks - 1)) +
                      (so.throttle > 0 ? "%" + std::to_string(so.throttle) : "") +
                      "\n#SBATCH --cpus-per-task=1\n#SBATCH --output=" + (dir / "task-%a.log").string() + "\n" + "cd " +
                      shellQuote(fs::current_path().string()) + "\nexec " + shellQuote(o.harness_exe) + " sweep chunk " + shellQuote(file) +
                      " --out " + shellQuote(out.string()) + " --points @" + shellQuote((dir / "points.txt").string()) + " --chunk-size " +
                      std::to_string(so.chunk) + " --task \"$SLURM_ARRAY_TASK_ID\"" +
                      (o.timeout_s > 0.0 ? " --timeout " + numberText(o.timeout_s) : "") + (o.keep_traces ? " --keep-traces" : "") + "\n";
  std::string merge = head + "#SBATCH --cpus-per-task=" + std::to_string(so.merge_cpus) +
                      "\n#SBATCH --output=" + (dir / "merge.log").string() + "\n" + "cd " + shellQuote(fs::current_path().string()) +
                      "\nexec " + shellQuote(o.harness_exe) + " sweep merge " + shellQuote(file) + " --out " + shellQuote(out.string()) +
                      points_opt + " -j " + std::to_string(so.merge_cpus) + (o.shrink ? "" : " --no-shrink") +
                      (o.db_path.empty() ? " --no-db" : " --db " + shellQuote(fs::absolute(o.db_path).string())) + " --quiet\n";
  writeAtomically((dir / "array.sh").string(), array);
  writeAtomically((dir / "merge.sh").string(), merge);
  std::fprintf(stderr, "[sweep %s] %zu missing points in %ld array tasks of %d; scripts in %s\n", s.name.c_str(), missing.size(), tasks,
               so.chunk, dir.string().c_str());
  lock.reset();
  if (so.dry_run) return 0;
  bool ok = true;
  std::string dependency;
  if (tasks > 0) {
    const std::string id = capture(so.sbatch + " --parsable " + shellQuote((dir / "array.sh").string()), ok);
    if (!ok || id.empty()) {
      std::fprintf(stderr, "lexdyn-harness: sbatch failed for %s: %s\n", (dir / "array.sh").string().c_str(), id.c_str());
      return 3;
    }
    dependency = " --dependency=afterany:" + id.substr(0, id.find(';'));
    std::printf("array job %s\n", id.c_str());
  }
  const std::string mid = capture(so.sbatch + " --parsable" + dependency + " " + shellQuote((dir / "merge.sh").string()), ok);
  if (!ok || mid.empty()) {
    std::fprintf(stderr, "lexdyn-harness: sbatch failed for %s: %s\n", (dir / "merge.sh").string().c_str(), mid.c_str());
    return 3;
  }
  std::printf("merge job %s\n", mid.c_str());
  writeAtomically((dir / "jobs.txt").string(), "merge " + mid + "\n");
  return 0;
}

}  // namespace lexdyn::sweep
