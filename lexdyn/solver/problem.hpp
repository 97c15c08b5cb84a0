// A lexicographic (prioritised) least-squares problem: an ordered list of levels, each made
// of dense rows  lower <= A x <= upper  (an equality when lower == upper; either side may be
// infinite). Level l minimises the norm of its violation while every earlier level keeps its
// optimal violation (docs/solver.md, paper sec. II eq. 2-6).
//
// The first level may instead be a *bounds level*: rows that each involve one variable
// (coefficient * x[var] within [lower, upper]), each variable at most once. The solver handles
// it by fixing variables instead of building general rows (paper sec. IX).
#pragma once

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "lexdyn/common/error.hpp"

namespace lexdyn::solver {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

enum class LevelKind { General, Bounds };

struct Level {
  std::string name;
  LevelKind kind = LevelKind::General;
  Eigen::MatrixXd A;      ///< General: rows x variables. Bounds: unused (0 x 0).
  Eigen::VectorXd lower;  ///< -inf for an unbounded side.
  Eigen::VectorXd upper;  ///< +inf for an unbounded side.
  // Bounds level only: row r reads coefficient[r] * x[variable[r]].
  std::vector<int> variable;
  Eigen::VectorXd coefficient;
  /// General: A's nonzero entries lie in its first `columns` columns (-1: anywhere). A caller
  /// that knows (the controller's velocity-only task rows) sets it with Problem::setLevelColumns;
  /// the solver then leaves the other columns out of its products A x, its row norms, its copies
  /// of the rows and, where that keeps every bit, the fixed variables' terms (the same bits).
  int columns = -1;

  int rows() const { return static_cast<int>(lower.size()); }
};

class Problem {
 public:
  Problem() = default;
  explicit Problem(int variables) : n_(variables) {}

  int variables() const { return n_; }
  int levelCount() const { return static_cast<int>(levels_.size()); }
  int totalRows() const;

  /// Appends a general level; returns its index.
  int addLevel(std::string name, Eigen::MatrixXd A, Eigen::VectorXd lower, Eigen::VectorXd upper);
  /// Appends a bounds level (only allowed as the first level); returns its index.
  int addBoundsLevel(std::string name, std::vector<int> variable, Eigen::VectorXd coefficient, Eigen::VectorXd lower,
                     Eigen::VectorXd upper);

  const Level& level(int i) const {
    checkIndex("Problem::level", i, static_cast<long>(levels_.size()));
    return levels_[static_cast<size_t>(i)];
  }
  /// Mutable access for per-tick updates of values (sizes must stay as set up).
  Level& level(int i) {
    checkIndex("Problem::level", i, static_cast<long>(levels_.size()));
    return levels_[static_cast<size_t>(i)];
  }

  /// Declares that general level i's A is zero past its first `columns` columns (-1: no
  /// declaration). Throws lexdyn::InputError for a bounds level or a count outside 0 .. n.
  void setLevelColumns(int i, int columns);

  /// Checks sizes, bounds order (lower <= upper), finite A and finite-or-infinite bounds
  /// (no NaN), and the bounds-level rules. Throws lexdyn::InputError naming `source`, the level
  /// and the row.
  void validate(const std::string& source = "problem") const;

  /// If level 0 is general and every row involves exactly one variable, each variable at most
  /// once, converts it into a bounds level. Returns true if converted.
  bool detectBoundsLevel();

 private:
  int n_ = 0;
  std::vector<Level> levels_;
};

}  // namespace lexdyn::solver
