// Helpers for tests that run lexdyn's command-line tools as processes: a file's text, a run with
// its exit code and output (and the expectations on them), a run interrupted by a signal.
#pragma once

#include "expect_text.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>

namespace lexdyn::testing {

/// The whole text of a file ("" when it cannot be read).
inline std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// The path of one of the build's programs, build/bin/NAME.
inline std::string binPath(const std::string& name) { return std::string(LEXDYN_BINARY_DIR) + "/bin/" + name; }

/// The exit code of a std::system status (-1 when the process did not exit).
inline int exitCode(int status) { return WIFEXITED(status) ? WEXITSTATUS(status) : -1; }

struct CliResult {
  int code = -1;
  std::string out, err;
};

/// Runs `command` (a shell command line) with its standard output and error in `dir`/stdout.txt
/// and `dir`/stderr.txt.
inline CliResult runCli(const std::string& command, const std::string& dir) {
  const std::string out = dir + "/stdout.txt", err = dir + "/stderr.txt";
  CliResult r;
  r.code = exitCode(std::system((command + " > " + out + " 2> " + err).c_str()));
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

/// Expects the run to have exited with `code` and its standard error to hold every one of `parts`.
inline void expectExit(const CliResult& r, int code, std::initializer_list<std::string> parts = {}) {
  EXPECT_EQ(r.code, code) << r.err;
  EXPECT_TRUE(containsAll(r.err, parts));
}

/// `lexdyn-harness ARGS` run as runCli does.
inline CliResult harness(const std::string& args, const std::string& dir) { return runCli(binPath("lexdyn-harness") + " " + args, dir); }

/// Runs `command` (a shell command line with its redirections, no single quote) in the
/// background, waits until the shell condition `started` holds (or the command has ended), sends
/// it SIG`sig` (INT, TERM, KILL) and waits for it. Returns its exit status (128 + the signal's
/// number when it did not handle it), or -1 when the shell failed; `code_file` holds the status.
inline int runAndSignal(const std::string& command, const std::string& started, const std::string& sig, const std::string& code_file) {
  const std::string script = "(" + command + " & pid=$!; while ! (" + started +
                             ") && kill -0 $pid 2>/dev/null; do sleep 0.01; done; kill -" + sig +
                             " $pid; { wait $pid; } 2>/dev/null; echo $? > " + code_file + ")";
  if (std::system(("bash -c '" + script + "'").c_str()) != 0) return -1;
  int code = -1;
  std::ifstream(code_file) >> code;
  return code;
}

/// `lexdyn-harness run CASE --out OUT --quiet` (its standard error in `dir`/stderr.txt), sent
/// SIG`sig` `pause_s` seconds after it has started writing its trace. Returns its exit status as
/// runAndSignal does (`dir`/code).
inline int harnessRunSignalled(const std::string& case_file, const std::string& out, const std::string& dir, const std::string& sig,
                               const std::string& pause_s) {
  return runAndSignal(binPath("lexdyn-harness") + " run " + case_file + " --out " + out + " --quiet 2> " + dir + "/stderr.txt",
                      "[ -s " + out + "/trace.csv.partial ] && sleep " + pause_s, sig, dir + "/code");
}

}  // namespace lexdyn::testing
