// Every problem of an input file in one pass (docs/architecture.md, "Errors and exit codes"):
// readers record errors and warnings as they go instead of throwing at the first, and throw one
// lexdyn::InputError listing all the errors at the end. Warnings say what was assumed; they are
// kept with what was read (RobotDescription::warnings) and reach the run's summary.
#pragma once

#include <string>
#include <vector>

namespace lexdyn {

/// One problem: where (file:line) and what (the element and what was expected and found).
struct Problem {
  std::string where;
  std::string what;
  std::string text() const { return where.empty() ? what : where + ": " + what; }
};

class ProblemList {
 public:
  /// `file` names the input in the summary line of several errors.
  explicit ProblemList(std::string file, bool strict = false) : file_(std::move(file)), strict_(strict) {}

  void error(const std::string& where, const std::string& what) {
    errors_.push_back({where, what});
    ++hard_errors_;
  }
  void warning(const std::string& where, const std::string& what) { warnings_.push_back({where, what}); }
  /// Something the format's ecosystem accepts and lexdyn reads leniently (a warning saying what
  /// was assumed); an error in strict mode.
  void lenient(const std::string& where, const std::string& what) {
    if (strict_) {
      errors_.push_back({where, what + " (refused in strict mode)"});
    } else {
      warnings_.push_back({where, what});
    }
  }
  bool strict() const { return strict_; }
  bool hasErrors() const { return !errors_.empty(); }
  /// Errors other than lenient readings refused in strict mode (after which reading goes on).
  bool hasHardErrors() const { return hard_errors_ > 0; }
  const std::vector<Problem>& errors() const { return errors_; }
  const std::vector<Problem>& warnings() const { return warnings_; }
  /// Throws lexdyn::InputError when there are errors: with one, its own where and what; with
  /// several, "FILE: N problems:" and one indented line per problem, by file (in the order
  /// they were first named) and line.
  void throwIfErrors() const;
  /// The same, only when a hard error was recorded (a stage that cannot go on after one).
  void throwIfHardErrors() const {
    if (hard_errors_ > 0) throwIfErrors();
  }
  /// Throws at once with the errors so far plus this one (a problem after which nothing more
  /// can be read).
  [[noreturn]] void fatal(const std::string& where, const std::string& what);
  /// Runs f(); an InputError it throws is recorded as an error (the reader goes on with the next
  /// item). Returns false when f threw.
  template <class F>
  bool attempt(F&& f);

 private:
  std::string file_;
  bool strict_ = false;
  std::vector<Problem> errors_, warnings_;
  int hard_errors_ = 0;
};

}  // namespace lexdyn

#include "lexdyn/common/error.hpp"

template <class F>
bool lexdyn::ProblemList::attempt(F&& f) {
  try {
    f();
    return true;
  } catch (const InputError& e) {
    errors_.push_back({e.where(), e.detail()});
    ++hard_errors_;
    return false;
  }
}
