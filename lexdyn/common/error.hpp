// Error handling, three levels (docs/architecture.md, "Errors"):
//  - LEXDYN_DEBUG_ASSERT(cond): internal invariant, checked in debug builds only.
//  - LEXDYN_ALWAYS_ASSERT(cond, msg): impossible state; always checked, aborts.
//  - throw InputError(...): anything a user can get wrong (files, fields, sizes). The
//    message says what was expected, what was found, and where (file, field / line).
#pragma once

#include <stdexcept>
#include <string>

namespace lexdyn {

/// A user-facing input error (bad file, bad field, bad size). Carries where it happened.
class InputError : public std::runtime_error {
 public:
  /// `where` is e.g. "cases/exp1.yaml: controller.gains.kp" or "problem.json: levels[2].A[3]".
  InputError(const std::string& where, const std::string& what)
      : std::runtime_error(where.empty() ? what : where + ": " + what), where_(where), what_(what) {}
  const std::string& where() const noexcept { return where_; }
  const std::string& detail() const noexcept { return what_; }

 private:
  std::string where_;
  std::string what_;
};

/// A failure to write an output (a full disk, a read-only or unwritable folder, a file-size
/// limit): a run failure (exit code 3), never bad input. `where` names the file, `what` says
/// what was being done and the operating system's reason ("No space left on device").
class OutputError : public std::runtime_error {
 public:
  OutputError(const std::string& where, const std::string& what)
      : std::runtime_error(where.empty() ? what : where + ": " + what), where_(where) {}
  const std::string& where() const noexcept { return where_; }

 private:
  std::string where_;
};

[[noreturn]] void abortWithMessage(const char* file, int line, const char* cond, const std::string& msg);

/// Throws std::out_of_range ("FUNCTION: index I out of range [0, N)") unless 0 <= i < n: public
/// functions that take an index check it with this (one comparison, no allocation unless it
/// throws).
inline void checkIndex(const char* function, long i, long n) {
  if (i < 0 || i >= n) {
    throw std::out_of_range(std::string(function) + ": index " + std::to_string(i) + " out of range [0, " + std::to_string(n) + ")");
  }
}

}  // namespace lexdyn

#define LEXDYN_ALWAYS_ASSERT(cond, msg)                                        \
  do {                                                                         \
    if (!(cond)) ::lexdyn::abortWithMessage(__FILE__, __LINE__, #cond, (msg)); \
  } while (0)

#ifdef NDEBUG
#define LEXDYN_DEBUG_ASSERT(cond) ((void)0)
#else
#define LEXDYN_DEBUG_ASSERT(cond) LEXDYN_ALWAYS_ASSERT(cond, "debug assertion")
#endif
