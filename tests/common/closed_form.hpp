// Closed-form references shared by the model and simulator tests.
#pragma once

#include <cmath>

namespace lexdyn::testing {

/// Arithmetic-geometric mean of a, b > 0 (to rounding): K(k) = pi / (2 agm(1, sqrt(1 - k^2))).
inline double agm(double a, double b) {
  for (int i = 0; i < 60 && std::abs(a - b) > 1e-16 * a; ++i) {
    const double an = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = an;
  }
  return a;
}

}  // namespace lexdyn::testing
