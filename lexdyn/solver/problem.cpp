#include "lexdyn/solver/problem.hpp"

#include <cmath>
#include <sstream>

#include "lexdyn/common/error.hpp"

namespace lexdyn::solver {

namespace {

std::string levelWhere(const std::string& source, int l, const Level& lv) {
  std::ostringstream os;
  os << source << ": levels[" << l << "]";
  if (!lv.name.empty()) os << " (\"" << lv.name << "\")";
  return os.str();
}

// A level of that name and kind with those bounds (the rest is the caller's).
Level makeLevel(std::string name, LevelKind kind, Eigen::VectorXd lower, Eigen::VectorXd upper) {
  Level l;
  l.name = std::move(name);
  l.kind = kind;
  l.lower = std::move(lower);
  l.upper = std::move(upper);
  return l;
}

}  // namespace

int Problem::totalRows() const {
  int m = 0;
  for (const auto& l : levels_) m += l.rows();
  return m;
}

int Problem::addLevel(std::string name, Eigen::MatrixXd A, Eigen::VectorXd lower, Eigen::VectorXd upper) {
  Level l = makeLevel(std::move(name), LevelKind::General, std::move(lower), std::move(upper));
  l.A = std::move(A);
  levels_.push_back(std::move(l));
  return levelCount() - 1;
}

void Problem::setLevelColumns(int i, int columns) {
  Level& l = level(i);
  if (l.kind != LevelKind::General) throw InputError("problem: level \"" + l.name + "\"", "columns are declared for general levels only");
  if (columns < -1 || columns > n_)
    throw InputError("problem: level \"" + l.name + "\"",
                     "declared columns " + std::to_string(columns) + " outside -1 .. " + std::to_string(n_));
  l.columns = columns;
}

int Problem::addBoundsLevel(std::string name, std::vector<int> variable, Eigen::VectorXd coefficient, Eigen::VectorXd lower,
                            Eigen::VectorXd upper) {
  if (!levels_.empty()) {
    throw InputError("problem: level \"" + name + "\"", "a bounds level is only allowed as the first level");
  }
  Level l = makeLevel(std::move(name), LevelKind::Bounds, std::move(lower), std::move(upper));
  l.variable = std::move(variable);
  l.coefficient = std::move(coefficient);
  levels_.push_back(std::move(l));
  return 0;
}

void Problem::validate(const std::string& source) const {
  if (n_ <= 0) {
    throw InputError(source + ": variables", "expected a positive number of variables, found " + std::to_string(n_));
  }
  for (int l = 0; l < levelCount(); ++l) {
    const Level& lv = levels_[static_cast<size_t>(l)];
    const std::string where = levelWhere(source, l, lv);
    const int m = static_cast<int>(lv.lower.size());
    if (lv.upper.size() != m) {
      throw InputError(where, "lower has " + std::to_string(m) + " entries but upper has " + std::to_string(lv.upper.size()));
    }
    if (lv.kind == LevelKind::General) {
      if (lv.A.rows() != m) {
        throw InputError(where, "A has " + std::to_string(lv.A.rows()) + " rows but the bounds have " + std::to_string(m) + " entries");
      }
      if (lv.A.cols() != n_) {
        throw InputError(
            where, "A has " + std::to_string(lv.A.cols()) + " columns, expected " + std::to_string(n_) + " (the number of variables)");
      }
      for (int r = 0; r < m; ++r) {
        for (int c = 0; c < n_; ++c) {
          if (!std::isfinite(lv.A(r, c))) {
            std::ostringstream os;
            os << "A[" << r << "][" << c << "] is " << lv.A(r, c) << ", expected a finite number";
            throw InputError(where + ".A[" + std::to_string(r) + "]", os.str());
          }
          if (lv.columns >= 0 && c >= lv.columns && lv.A(r, c) != 0.0) {
            std::ostringstream os;
            os << "A[" << r << "][" << c << "] is " << lv.A(r, c) << ", but the level declares its nonzero entries in its first "
               << lv.columns << " columns";
            throw InputError(where + ".A[" + std::to_string(r) + "]", os.str());
          }
        }
      }
    } else {
      if (l != 0) throw InputError(where, "a bounds level is only allowed as the first level");
      if (static_cast<int>(lv.variable.size()) != m || lv.coefficient.size() != m) {
        throw InputError(where, "bounds level: variable/coefficient/lower/upper sizes differ");
      }
      std::vector<char> seen(static_cast<size_t>(n_), 0);
      for (int r = 0; r < m; ++r) {
        const int v = lv.variable[static_cast<size_t>(r)];
        const std::string rw = where + ".row[" + std::to_string(r) + "]";
        if (v < 0 || v >= n_) throw InputError(rw, "variable index " + std::to_string(v) + " out of range");
        if (seen[static_cast<size_t>(v)]) {
          throw InputError(rw, "variable " + std::to_string(v) + " appears twice in the bounds level");
        }
        seen[static_cast<size_t>(v)] = 1;
        if (!std::isfinite(lv.coefficient(r)) || lv.coefficient(r) == 0.0) {
          throw InputError(rw, "bounds coefficient must be finite and nonzero");
        }
      }
    }
    for (int r = 0; r < m; ++r) {
      const std::string rw = where + ".row[" + std::to_string(r) + "]";
      if (std::isnan(lv.lower(r)) || std::isnan(lv.upper(r))) throw InputError(rw, "bound is NaN");
      if (lv.lower(r) == kInf) throw InputError(rw, "lower bound is +inf");
      if (lv.upper(r) == -kInf) throw InputError(rw, "upper bound is -inf");
      if (lv.lower(r) > lv.upper(r)) {
        std::ostringstream os;
        os << "lower bound " << lv.lower(r) << " is greater than upper bound " << lv.upper(r);
        throw InputError(rw, os.str());
      }
    }
  }
}

bool Problem::detectBoundsLevel() {
  if (levels_.empty() || levels_[0].kind != LevelKind::General) return false;
  Level& lv = levels_[0];
  const int m = lv.rows();
  if (m == 0) return false;
  std::vector<int> var(static_cast<size_t>(m), -1);
  Eigen::VectorXd coef(m);
  std::vector<char> seen(static_cast<size_t>(n_), 0);
  for (int r = 0; r < m; ++r) {
    int found = -1;
    for (int c = 0; c < n_; ++c) {
      if (lv.A(r, c) != 0.0) {
        if (found >= 0) return false;
        found = c;
      }
    }
    if (found < 0 || seen[static_cast<size_t>(found)]) return false;
    seen[static_cast<size_t>(found)] = 1;
    var[static_cast<size_t>(r)] = found;
    coef(r) = lv.A(r, found);
  }
  lv.kind = LevelKind::Bounds;
  lv.variable = std::move(var);
  lv.coefficient = coef;
  lv.A.resize(0, 0);
  return true;
}

}  // namespace lexdyn::solver
