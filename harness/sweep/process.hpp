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
  std::string error;        ///< why it could not start
  int error_errno = 0;      ///< the system's error code of `error`, when it has one
  std::string output_tail;  ///< the last 4 kB the process wrote (stdout and stderr)
  std::string log_error;    ///< why the log could not be written ("" when it was)
};

/// Runs argv[0] (a path) with stdout and stderr appended to `log_path` (through the driver, which
/// keeps their tail), in a new process group
/// that dies with this process (PR_SET_PDEATHSIG), and waits. After `timeout_s` (> 0) the group
/// is killed (SIGKILL); so it is when *interrupt or *abort becomes nonzero (`interrupted`).
ProcessOutcome runProcess(const std::vector<std::string>& argv, const std::string& log_path, double timeout_s,
                          const std::atomic<int>* interrupt, const std::atomic<int>* abort = nullptr);

/// "SIGKILL", "SIGTERM", ... ("signal N" for others).
std::string signalName(int sig);

/// The last `n` lines of a text file ("" when it cannot be read).
std::string tailOfFile(const std::string& path, int n);
/// The last `n` lines of a text.
std::string lastLines(const std::string& text, int n);

}  // namespace lexdyn::sweep
