// The ranges every number read from a user file must fall in (docs/simulator.md, "Ranges"), in
// one place so that the loaders and the documentation agree. They are physical or numerical
// sanity bounds, far outside what a meaningful robot, case or solver problem uses and far inside
// the range where the arithmetic stays finite: a value outside is bad input (exit code 2) with
// file, line and key path, never a run that fails later without naming the key.
#pragma once

namespace lexdyn::ranges {

inline constexpr double kTwoPi = 6.283185307179586;

// --- robot files (URDF, data file) ------------------------------------------------------------
inline constexpr double kMinLinkMass_kg = 1e-6;  ///< a moving body (URDF <mass>)
inline constexpr double kMaxLinkMass_kg = 1e6;
inline constexpr double kMinPrincipalInertia_kgm2 = 1e-12;  ///< each principal moment about the CoM
inline constexpr double kMaxPrincipalInertia_kgm2 = 1e6;
inline constexpr double kMaxLength_m = 1e3;      ///< URDF origins, data-file frames, points
inline constexpr double kMaxJointLimit = 1e3;    ///< |lower|, |upper| (rad or m)
inline constexpr double kMinEffortLimit = 1e-6;  ///< N m or N
inline constexpr double kMaxEffortLimit = 1e6;
inline constexpr double kMinVelocityLimit = 1e-6;  ///< rad/s or m/s
inline constexpr double kMaxVelocityLimit = 1e4;
inline constexpr double kMaxGravity_mps2 = 100.0;  ///< |gravity|
inline constexpr double kMaxFriction = 10.0;       ///< friction coefficients, (0, 10]
inline constexpr double kMaxAngle_rad = kTwoPi;    ///< |angle|: Euler / roll-pitch-yaw angles, yaw, phases
inline constexpr int kMaxXmlDepth = 64;            ///< URDF element nesting (a URDF needs 4)

// --- case files -------------------------------------------------------------------------------
inline constexpr double kMinControlPeriod_s = 1e-4;
inline constexpr double kMaxControlPeriod_s = 1.0;
inline constexpr long kMaxTicks = 2000000;           ///< duration_s / control_period_s
inline constexpr double kMaxTime_s = 1e6;            ///< periods, ramps, trajectory times
inline constexpr double kMaxPosition_m = 1e3;        ///< targets, box bounds, base placement
inline constexpr double kMinContactStiffness = 1e2;  ///< N/m^exponent
inline constexpr double kMaxContactStiffness = 1e10;
inline constexpr double kMaxContactExponent = 3.0;
inline constexpr double kMaxContactDissipation_s_per_m = 1e3;
inline constexpr double kMinSlipVelocity_mps = 1e-6;
inline constexpr double kMaxSlipVelocity_mps = 1.0;
inline constexpr double kMaxServoKp = 1e7;  ///< N m/rad (N/m)
inline constexpr double kMaxServoKd = 1e5;  ///< N m s/rad (N s/m)
inline constexpr double kMaxGraspStiffness_N_per_m = 1e8;
inline constexpr double kMaxGraspDamping_Ns_per_m = 1e6;
inline constexpr double kMaxGraspRotStiffness_Nm_per_rad = 1e6;
inline constexpr double kMaxGraspRotDamping_Nms_per_rad = 1e4;
inline constexpr double kMinIntegratorRtol = 1e-12;
inline constexpr double kMaxIntegratorRtol = 0.1;
inline constexpr double kMinIntegratorAtol = 1e-15;
inline constexpr double kMaxIntegratorAtol = 1.0;
inline constexpr int kMaxIntegratorStepsPerTick = 1000000;
inline constexpr int kMaxTraceEvery = 1000000;  ///< every_n_ticks, flush_every_rows
/// Task PD gains (1/s^2, 1/s): the discrete law of a task over one period (eq. 61 integrated
/// with the period dt: e(k+1) = e(k) - dt v(k+1), v(k+1) = (1 - kv dt) v(k) + kp dt e(k)) has the
/// characteristic polynomial z^2 - (2 - kp dt^2 - kv dt) z + (1 - kv dt); it is stable for
/// kv dt < 2 and kp dt^2 + 2 kv dt < 4, marginal on these bounds. Gains beyond are refused.
inline constexpr double kMaxPdKvDt = 2.0;
inline constexpr double kMaxPdKpDt2Plus2KvDt = 4.0;
inline constexpr double kMinWeight = 1e-12;  ///< WLS objective weights
inline constexpr double kMaxWeight = 1e12;
inline constexpr double kMaxDimensionless = 1e6;     ///< controller thresholds in multiples of dt^2, damping
inline constexpr double kMaxSolverTolerance = 1e-2;  ///< rank, feasibility, zero, dual tolerances
inline constexpr int kMaxSolverIterations = 1000000;

}  // namespace lexdyn::ranges
