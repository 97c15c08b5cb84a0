// Configuration of a controller (const after construction; docs/controller.md).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "lexdyn/solver/solver.hpp"
#include "lexdyn/tasks/task.hpp"

namespace lexdyn::control {

/// Target of the Newton rows R u(k+1) = target: 0 (eq. 35 and the Taylor model eq. 26: the step
/// dq = dt u(k+1) itself is penalised, as in the paper's damping analysis eq. 81), or R u(k) as
/// eq. 62 is printed (only the change of velocity is penalised). The default is Zero: with
/// eq. 62's target a velocity already built up along a singular direction is never damped, and
/// the 3R benchmark keeps oscillating at the singularity (docs/controller.md).
enum class NewtonTarget { Zero, PreviousVelocity };

/// The secant pair's y of LexDynBFGS: which reading of eq. 88 (docs/controller.md, "Readings
/// of eq. 87-89").
enum class BfgsSecant {
  /// y = sum_i (J_i(k) - J_i(k-1))^T lambda_i with the multipliers of the last solve only (the
  /// paper's "we only use the Lagrange multipliers of the current iterate"): B approximates the
  /// second-order term H of eq. 21 alone. The default.
  CurrentMultipliers,
  /// y = grad L(k) - grad L(k-1) with each gradient's own multipliers, sum_i J_i(k)^T lambda_i
  /// - J_i(k-1)^T lambda_i(prev): the above plus sum_i J_i(k-1)^T (lambda_i - lambda_i(prev)).
  FullDifference,
  /// y = J_l^T J_l s + the above (current multipliers), J_l the level's own constraining task
  /// rows: the secant pair of J^T J + H, so that B approximates the J^T J + H that the paper
  /// says its B computes (sec. VI-A, after eq. 89).
  GaussNewton,
};

/// Scale between the solver's multipliers and those of the Hessian (eq. 37).
enum class MultiplierScale {
  Dt,   ///< lambda_optim = dt lambda_ctrl (eq. 37; the default)
  One,  ///< lambda_ctrl itself (a sensitivity: 1/dt = 200 times larger second-order term)
};

/// The controller's solver options unless a case sets them: the solver's defaults, with split
/// coordinates at the contact forces (Options::kSplitAtControllerForces), spanning stages (its
/// minimum-velocity and minimum-wrench levels; with spanning_any_rows also a level of Newton
/// rows that spans the velocities left to it; with spanning_structured the minimum-wrench
/// level's QR reads only its nonzero rows), lazy snapshots (nearly every tick is a solve
/// of one iteration from the warm start) and the projected unit suffix (the minimum-velocity
/// level below a level of Newton rows).
inline solver::Options defaultSolverOptions() {
  solver::Options o;
  o.split_from_variable = solver::Options::kSplitAtControllerForces;
  o.spanning_stages = true;
  o.spanning_any_rows = true;
  o.spanning_structured = true;
  o.lazy_snapshots = true;
  o.project_unit_suffix = true;
  return o;
}

/// solver::Options::paper(dt) (the paper's early-stop rules) with the controller's other
/// defaults (defaultSolverOptions), as `solver: {paper_rules: true}` in a case.
inline solver::Options paperSolverOptions(double dt) {
  solver::Options o = defaultSolverOptions();
  const solver::Options paper = solver::Options::paper(dt);  // its stop rules, else the solver's defaults
  o.stop_slack_norm = paper.stop_slack_norm;
  o.stop_optimality_iterations = paper.stop_optimality_iterations;
  o.stop_total_iterations = paper.stop_total_iterations;
  return o;
}

struct ControllerParams {
  /// Name of a registered method (lexdyn/control/method.hpp, findMethod): "bfgs" (LexDynBFGS,
  /// sec. VI-A), "ah" (LexDynAH, sec. VI-B), "gn" (pure Gauss-Newton, Fig. 14), "wls" (the
  /// acceleration-domain LSSOL baseline), or one an application registered.
  std::string method = "bfgs";
  double dt = 0.005;  ///< control period, s
  // Thresholds the paper gives as multiples of dt^2 are stored as those multiples.
  // Switching (eq. 95): a level is augmented while omega = 1/2 ||w_optim||^2 >= nu_dt2 * dt^2,
  // with w_optim = dt * w_ctrl (eq. 37).
  double nu_dt2 = 1e-12;
  NewtonTarget newton_target = NewtonTarget::Zero;
  // LexDynBFGS (sec. VI-A, VII, VIII-A).
  double xi_dt2 = 1e-12;                                    ///< curvature threshold on y^T s (units of dt^2)
  double zeta_dt2 = 1e-3;                                   ///< eq. 89 lower bound and sign-change increment (dt^2)
  double new_dof_diagonal_dt2 = 1e-3;                       ///< diagonal put on newly occupied dofs, sec. VII (dt^2)
  bool sign_change_guard = true;                            ///< sec. VIII-A
  bool sr1 = false;                                         ///< SR1 instead of BFGS (beyond the paper; off by default)
  BfgsSecant bfgs_secant = BfgsSecant::CurrentMultipliers;  ///< reading of eq. 88 (y)
  /// alpha of the paper's weighted identity alpha I* on the occupied joints of an augmented
  /// level (sec. IX-A: "if the movements are too jerky a weighted and dotted identity matrix
  /// alpha I* could be added to B"), in the units of B (those of J^T J, e.g. m^2/rad^2 for a
  /// position task). LexDynBFGS: factors B + alpha I*; LexDynAH: eps + alpha after Higham.
  /// 0 (off) by default, as in the paper's experiments.
  double newton_identity_weight = 0.0;
  // LexDynAH (sec. VI-B).
  double rho_dt2 = 1e-12;  ///< skip Hessian terms with |lambda_optim| <= rho (dt^2)
  double eps_dt2 = 1e-3;   ///< eps I* added after the Higham regularisation, eq. 91 (dt^2)
  /// Adds the Gauss-Newton term J_l^T J_l of the level's own constraining task rows to the
  /// analytic Hessian before Higham's regularisation, H = J_l^T J_l + sum lambda H (the J^T J + H
  /// of the Lagrangian that the paper's B approximates, sec. VI-A). Off by default (eq. 21).
  bool ah_add_jtj = false;
  // Both LexDynBFGS and LexDynAH.
  MultiplierScale multiplier_scale = MultiplierScale::Dt;  ///< eq. 37
  // Constant Levenberg-Marquardt damping mu on every augmentable level (velocity domain: rows
  // mu u(k+1) = 0, eq. 81; WLS: mu udot = 0 on the objective level, eq. 50). 0: off. Used by the
  // point-mass study of sec. V-A.
  double damping = 0.0;
  bool use_qmod = false;  ///< eq. 73-76 instead of eq. 32
  /// Rank-based switching (the paper's future work): augment when the level's active rows lose
  /// rank after projection, in addition to eq. 95. Off by default.
  bool rank_switching = false;
  /// WLS: level-1 violation above this (relative) is a controller failure (the QP is infeasible).
  double wls_infeasibility_tolerance = 1e-6;
  /// Default: the solver's defaults with split coordinates at the contact forces
  /// (defaultSolverOptions; docs/solver.md, "Split coordinates"); the paper's rules:
  /// paperSolverOptions(dt).
  solver::Options solver = defaultSolverOptions();
  /// Name of a configured level: the solver's early-stop rules (paper_rules) apply only once it
  /// and the levels above it are optimal ("usually ... the contact constraints", sec. VIII-B;
  /// solver::Options::stop_after_level). Empty: they apply at any iteration.
  std::string stop_after_level;
};

/// One level of the hierarchy: task indices, in order. WLS uses exactly two levels: level 0 the
/// hard constraints, level 1 the weighted objective (weights per task, same order as tasks).
struct LevelSpec {
  std::string name;
  std::vector<int> tasks;
  std::vector<double> weights;  ///< WLS objective level only
};

struct ControllerConfig {
  ControllerParams params;
  std::vector<tasks::ContactSpec> contacts;  ///< every contact the controller may use
  std::vector<std::unique_ptr<tasks::TaskModel>> tasks;
  /// Levels after the bounds level, highest priority first. Bounds tasks (kind() == Bounds)
  /// may be listed in any level; they always go to the first (bounds) level of the solver.
  std::vector<LevelSpec> levels;
  /// Contacts active at start (names).
  std::vector<std::string> initial_contacts;
};

}  // namespace lexdyn::control
