// Paper-shaped hierarchical least-squares problems (docs/performance.md, "Solver"): 74 variables
// x = [qdot (38); dt gamma (36)], 10 levels, 190 rows:
//   1  bounds gamma >= 0                                  36 (bounds level)
//   2  [M, -Jc^T] x = M qdot(k) - dt N (eq. 86)           38 equality
//   3  trust box |qdot_i| <= Delta / dt                   38 two-sided
//   4-8 equality tasks on qdot                            6, 6, 3, 6, 3
//   9  one-sided inequality on qdot                       16
//   10 minimum velocity qdot = 0                          38
// Regimes: nominal (a few active inequalities), stress (about 30), near-singular (a task with
// singular values 1e-3 and 1e-7 relative, and two tasks sharing rows with opposite targets).
// Every tick of a sequence drifts smoothly; everything comes from a fixed seed.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "lexdyn/solver/problem.hpp"

namespace lexdyn::bench {

enum class Regime { Nominal, Stress, NearSingular };

/// Parses "nominal", "stress" or "near-singular" (throws lexdyn::InputError otherwise).
Regime parseRegime(const std::string& name);

class PaperProblemSequence {
 public:
  PaperProblemSequence(Regime regime, std::uint64_t seed = 20200710);
  ~PaperProblemSequence();
  /// The problem of tick k (control period 5 ms).
  solver::Problem tick(int k) const;

 private:
  struct Data;
  std::unique_ptr<Data> d_;
  Regime regime_;
};

}  // namespace lexdyn::bench
