// What lexdyn's command-line tools do with an exception that reaches main (docs/architecture.md,
// "Errors and exit codes"): a message on stderr and an exit code.
#pragma once

#include "lexdyn/common/error.hpp"

#include <cstdio>
#include <exception>
#include <new>

namespace lexdyn::cli {

/// Called inside a catch block: prints the exception being handled as `TOOL: error: ...` (an
/// input error, an output that cannot be written, out of memory) or `TOOL: internal error: ...`, and returns the exit code: 2 for
/// an input error, `failure_code` (the tool's run failure) for anything else (an output error
/// included: a full disk is a run failure, not bad input).
inline int exitCodeOfException(const char* tool, int failure_code) {
  try {
    throw;
  } catch (const lexdyn::InputError& e) {
    std::fprintf(stderr, "%s: error: %s\n", tool, e.what());
    return 2;
  } catch (const lexdyn::OutputError& e) {
    std::fprintf(stderr, "%s: error: %s\n", tool, e.what());
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "%s: error: out of memory\n", tool);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: internal error: %s\n", tool, e.what());
  } catch (...) {
    std::fprintf(stderr, "%s: internal error: an exception of unknown type\n", tool);
  }
  return failure_code;
}

}  // namespace lexdyn::cli
