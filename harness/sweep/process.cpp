#include "harness/sweep/process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <fstream>
#include <sstream>
#include <thread>

namespace lexdyn::sweep {

std::string signalName(int sig) {
  switch (sig) {
    case SIGKILL:
      return "SIGKILL";
    case SIGTERM:
      return "SIGTERM";
    case SIGINT:
      return "SIGINT";
    case SIGSEGV:
      return "SIGSEGV";
    case SIGABRT:
      return "SIGABRT";
    case SIGBUS:
      return "SIGBUS";
    case SIGFPE:
      return "SIGFPE";
    case SIGHUP:
      return "SIGHUP";
    case SIGXFSZ:
      return "SIGXFSZ";
    default:
      return "signal " + std::to_string(sig);
  }
}

ProcessOutcome runProcess(const std::vector<std::string>& argv, const std::string& log_path, double timeout_s,
                          const std::atomic<int>* interrupt, const std::atomic<int>* abort) {
  ProcessOutcome out;
  // Everything the child needs is built before fork (no allocation between fork and exec).
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const int log_fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (log_fd < 0) {
    out.error_errno = errno;
    out.error = "cannot open " + log_path + ": " + std::strerror(out.error_errno);
    return out;
  }
  // The child's output comes through a pipe: the driver appends it to the log and keeps its last
  // lines, so that why a run failed is known also when the log cannot be written (a full disk).
  int pipe_fd[2];
  if (::pipe2(pipe_fd, O_CLOEXEC) != 0) {
    out.error_errno = errno;
    out.error = std::string("pipe: ") + std::strerror(out.error_errno);
    ::close(log_fd);
    return out;
  }
  const pid_t parent = ::getpid();
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) {
    out.error = std::string("fork: ") + std::strerror(errno);
    ::close(log_fd);
    ::close(pipe_fd[0]);
    ::close(pipe_fd[1]);
    return out;
  }
  if (pid == 0) {
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);  // the driver died before prctl
    ::dup2(pipe_fd[1], STDOUT_FILENO);
    ::dup2(pipe_fd[1], STDERR_FILENO);
    const int null_fd = ::open("/dev/null", O_RDONLY);
    if (null_fd >= 0) ::dup2(null_fd, STDIN_FILENO);
    // Default signal dispositions in the child (the driver handles SIGINT / SIGTERM).
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    ::execv(args[0], args.data());
    const char msg[] = "exec failed\n";
    (void)!::write(STDERR_FILENO, msg, sizeof(msg) - 1);
    ::_exit(127);
  }
  ::setpgid(pid, pid);  // also from the parent, so that the group exists before any kill
  ::close(pipe_fd[1]);
  out.started = true;
  bool pipe_open = true;
  // Moves what the child wrote to the log and the kept tail; waits at most `ms` for it.
  auto drain = [&](int ms) {
    if (!pipe_open) {
      if (ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(ms));
      return;
    }
    for (int wait_ms = ms; pipe_open; wait_ms = 0) {
      pollfd pfd{pipe_fd[0], POLLIN, 0};
      if (::poll(&pfd, 1, wait_ms) <= 0) return;
      char buf[4096];
      const ssize_t n = ::read(pipe_fd[0], buf, sizeof(buf));
      if (n <= 0) {
        if (n == 0 || errno != EINTR) pipe_open = false;
        return;
      }
      out.output_tail.append(buf, static_cast<size_t>(n));
      if (out.output_tail.size() > 4096) out.output_tail.erase(0, out.output_tail.size() - 4096);
      const char* p = buf;
      size_t left = out.log_error.empty() ? static_cast<size_t>(n) : 0;
      while (left > 0) {
        const ssize_t w = ::write(log_fd, p, left);
        if (w < 0) {
          if (errno == EINTR) continue;
          out.log_error = log_path + ": " + std::strerror(errno);
          break;
        }
        p += w;
        left -= static_cast<size_t>(w);
      }
    }
  };
  int status = 0;
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  // Time the process spends stopped (SIGSTOP, a suspended job) does not count toward its timeout.
  double stopped_s = 0.0, stopped_at = -1.0;
  bool killed = false;
  for (;;) {
    const pid_t r = ::waitpid(pid, &status, WNOHANG | WUNTRACED | WCONTINUED);
    if (r == pid && WIFSTOPPED(status)) {
      if (stopped_at < 0.0) stopped_at = elapsed();
      continue;
    }
    if (r == pid && WIFCONTINUED(status)) {
      if (stopped_at >= 0.0) stopped_s += elapsed() - stopped_at;
      stopped_at = -1.0;
      continue;
    }
    if (r == pid) break;
    if (r < 0 && errno != EINTR) {
      out.error = std::string("waitpid: ") + std::strerror(errno);
      break;
    }
    const double running_s = elapsed() - stopped_s - (stopped_at >= 0.0 ? elapsed() - stopped_at : 0.0);
    if (!killed && timeout_s > 0.0 && running_s > timeout_s) {
      out.timed_out = true;
      ::kill(-pid, SIGKILL);
      killed = true;
    }
    if (!killed && ((interrupt && interrupt->load() != 0) || (abort && abort->load() != 0))) {
      out.interrupted = true;
      ::kill(-pid, SIGKILL);
      killed = true;
    }
    drain(killed ? 5 : 20);
  }
  // What is left: the pipe ends when the child's group has closed it (at most 2 s more).
  for (int k = 0; pipe_open && k < 100; ++k) drain(20);
  ::close(pipe_fd[0]);
  ::close(log_fd);
  out.wall_s = elapsed();
  if (WIFEXITED(status)) out.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) {
    out.signal = WTERMSIG(status);
    out.exit_code = 128 + out.signal;
  }
  return out;
}

std::string lastLines(const std::string& text, int n) {
  std::deque<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    lines.push_back(line);
    if (static_cast<int>(lines.size()) > n) lines.pop_front();
  }
  std::string out;
  for (const auto& l : lines) out += (out.empty() ? "" : "\n") + l;
  return out;
}

std::string tailOfFile(const std::string& path, int n) {
  std::ifstream in(path);
  if (!in) return "";
  std::deque<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    lines.push_back(line);
    if (static_cast<int>(lines.size()) > n) lines.pop_front();
  }
  std::string out;
  for (const auto& l : lines) out += (out.empty() ? "" : "\n") + l;
  return out;
}

}  // namespace lexdyn::sweep
