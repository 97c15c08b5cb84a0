// `lexdyn-harness sweep ...` (docs/sweeps.md): the subcommands and their options.
#pragma once

#include <atomic>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace lexdyn::cli {

struct SweepCommand {
  CLI::App* sweep = nullptr;
  CLI::App *run = nullptr, *point = nullptr, *chunk = nullptr, *merge = nullptr, *submit = nullptr, *list = nullptr, *check = nullptr;
  std::string file, out, method, db, partition, points_list, duration;
  std::vector<std::string> values;
  int jobs = 0, chunk_size = 0, throttle = 0;
  long points = -1, index = -1;
  double timeout_s = 0.0;
  bool keep_traces = false, no_shrink = false, no_db = false, quiet = false, dry_run = false;
};

/// Adds `sweep` and its subcommands to the app.
void addSweepCommands(CLI::App& app, SweepCommand& c);

/// Runs the chosen subcommand. `signal` holds the number of a SIGINT / SIGTERM received (0:
/// none), `interrupted` the same as a flag (for a single run). Throws InputError on bad input.
int runSweepCommand(const SweepCommand& c, const std::atomic<int>& signal, const std::atomic<bool>& interrupted);

}  // namespace lexdyn::cli
