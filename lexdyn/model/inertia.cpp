#include "lexdyn/model/inertia.hpp"

#include "lexdyn/common/format.hpp"
#include "lexdyn/common/input_ranges.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace lexdyn::model {

namespace {

constexpr double kZeroMoment_kgm2 = ranges::kMinPrincipalInertia_kgm2;

// The worst triangle violation of ascending moments: I_c - I_a - I_b (> 0 when violated).
double triangleExcess(const Eigen::Vector3d& m) { return m[2] - m[0] - m[1]; }

}  // namespace

std::string formatMoments(const Eigen::Vector3d& m) {
  return formatNumber(m[0], 4) + ", " + formatNumber(m[1], 4) + ", " + formatNumber(m[2], 4);
}

InertiaCheck checkInertia(const Eigen::Matrix3d& I) {
  InertiaCheck c;
  const Eigen::Matrix3d S = 0.5 * (I + I.transpose());
  c.moments = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(S, Eigen::EigenvaluesOnly).eigenvalues();
  const double largest = std::max(std::abs(c.moments[0]), std::abs(c.moments[2]));
  if (largest < kZeroMoment_kgm2) {
    c.kind = InertiaClass::Zero;
    return c;
  }
  const double rounding = 1e-12 * largest;
  const double noise = kInertiaNoiseRel * largest + kInertiaNoiseAbs_kgm2;
  const double negative = -c.moments[0];
  const double excess = triangleExcess(c.moments);
  if (negative <= rounding && excess <= rounding) return c;
  if (negative > noise) {
    c.kind = InertiaClass::Impossible;
    c.problem = "a negative principal moment (" + formatMoments(c.moments) + " kg m^2): more than rounding noise (" +
                formatNumber(kInertiaNoiseRel * 100.0, 3) + " % of the largest moment)";
    return c;
  }
  if (excess > noise) {
    c.kind = InertiaClass::Impossible;
    c.problem = "principal moments " + formatMoments(c.moments) + " kg m^2 violate the triangle inequality (" +
                formatNumber(c.moments[0], 4) + " + " + formatNumber(c.moments[1], 4) + " < " + formatNumber(c.moments[2], 4) +
                ") by more than rounding noise (" + formatNumber(kInertiaNoiseRel * 100.0, 3) + " %)";
    return c;
  }
  c.kind = InertiaClass::Noise;
  c.problem = negative > rounding ? "a negative principal moment (" + formatMoments(c.moments) + " kg m^2)"
                                  : "principal moments " + formatMoments(c.moments) + " kg m^2 that violate the triangle inequality by " +
                                        formatNumber(excess, 3) + " kg m^2";
  return c;
}

Eigen::Matrix3d projectInertia(const Eigen::Matrix3d& I) {
  const Eigen::Matrix3d S = 0.5 * (I + I.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(S);
  Eigen::Vector3d m = es.eigenvalues();  // ascending
  // The set {m >= 0, m_a + m_b >= m_c} is a convex cone; with ascending moments only m0 >= 0 and
  // m0 + m1 >= m2 can be active. Alternate projections onto the two half-spaces converge to the
  // nearest point (Dykstra's corrections are not needed when one step lands inside both, which
  // is the case here: a few rounds at most).
  for (int round = 0; round < 50; ++round) {
    bool changed = false;
    for (int k = 0; k < 3; ++k) {
      if (m[k] < 0.0) {
        m[k] = 0.0;
        changed = true;
      }
    }
    std::sort(m.data(), m.data() + 3);
    const double excess = triangleExcess(m);
    if (excess > 0.0) {
      // Projection onto m0 + m1 - m2 >= 0 along its normal (1, 1, -1) / sqrt(3).
      m += excess / 3.0 * Eigen::Vector3d(1.0, 1.0, -1.0);
      changed = true;
      std::sort(m.data(), m.data() + 3);
    }
    if (!changed) break;
  }
  // The eigenvectors are in ascending order of the original moments; the projection keeps that order.
  return es.eigenvectors() * m.asDiagonal() * es.eigenvectors().transpose();
}

}  // namespace lexdyn::model
