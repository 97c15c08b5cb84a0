// Runs a command in its own process group with a timeout: the one place where the sweep driver
// starts processes (POSIX fork/exec).
#pragma once

#include <atomic>
#include <string>
#include <vector>

namespace lexdyn::sweep {

struct ProcessOutcome {
  bool started = false;
  bool timed_out = false;
  bool interrupted = false;  ///< killed because `interrupt` was set
  int exit_code = -1;        ///< when it exited normally
  int signal = 0;            ///< when a signal ended it
  double wall_s = 0.0;
  std::string error;         ///< why it could not start
};

/// Runs argv[0] (a path) with stdout and stderr appended to `log_path`, in a new process group
/// that dies with this process (PR_SET_PDEATHSIG), and waits. After `timeout_s` (> 0) the group
/// is killed (SIGKILL); so it is when *interrupt becomes nonzero.
ProcessOutcome runProcess(const std::vector<std::string>& argv, const std::string& log_path, double timeout_s,
                          const std::atomic<int>* interrupt);

/// The last `n` lines of a text file ("" when it cannot be read).
std::string tailOfFile(const std::string& path, int n);

}  // namespace lexdyn::sweep
