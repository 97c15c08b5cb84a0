// Rotational inertias as URDF files carry them: the check of a physically possible inertia and
// the projection of rounding noise (a slightly negative principal moment, a triangle inequality
// violated by a little) to the nearest physical inertia (docs/model.md, "Inertias").
#pragma once

#include <Eigen/Core>

#include <string>

namespace lexdyn::model {

/// Rounding noise the loader repairs: a principal moment down to -kInertiaNoiseRel * (largest
/// moment) - kInertiaNoiseAbs_kgm2, and I_a + I_b >= I_c violated by up to kInertiaNoiseRel * I_c
/// + kInertiaNoiseAbs_kgm2. Beyond that an inertia is refused as impossible.
inline constexpr double kInertiaNoiseRel = 1e-2;
inline constexpr double kInertiaNoiseAbs_kgm2 = 1e-9;

enum class InertiaClass {
  Valid,       ///< positive semi-definite and the triangle inequalities hold (to 1e-12 relative)
  Zero,        ///< every principal moment below 1e-12 kg m^2 (a point mass)
  Noise,       ///< impossible by rounding noise only: repaired by projectInertia
  Impossible,  ///< refused
};

struct InertiaCheck {
  InertiaClass kind = InertiaClass::Valid;
  Eigen::Vector3d moments = Eigen::Vector3d::Zero();  ///< principal moments, ascending, kg m^2
  std::string problem;                                ///< for Noise and Impossible: what is wrong, in words
};

/// Classifies a symmetric inertia about the centre of mass (kg m^2).
InertiaCheck checkInertia(const Eigen::Matrix3d& I);

/// The nearest physical inertia to I: the principal moments moved to the closest point with every
/// moment >= 0 and every triangle inequality holding (Euclidean on the moments), same principal axes.
Eigen::Matrix3d projectInertia(const Eigen::Matrix3d& I);

/// "a, b, c" (principal moments, 4 significant digits) for messages.
std::string formatMoments(const Eigen::Vector3d& moments);

}  // namespace lexdyn::model
