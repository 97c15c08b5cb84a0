// The `controller: {type: lexdyn, ...}` section of a case file (docs/cases.md): method,
// parameters, solver options, contacts, tasks and the two hierarchies (velocity-domain `levels`
// and the WLS `wls_levels`), as data; buildControllerConfig() turns it into a
// control::ControllerConfig for a model.
#pragma once

#include "harness/cases/task_registry.hpp"
#include "lexdyn/common/yaml_strict.hpp"
#include "lexdyn/control/config.hpp"
#include "lexdyn/tasks/contact_margins.hpp"

#include <Eigen/Core>

#include <limits>
#include <map>
#include <string>
#include <vector>

namespace lexdyn::cases {

/// A contact the controller may use: a robot data contact surface, or a frame with points.
/// No margin (`contact_margins: none`: the paper's formulation).
inline constexpr tasks::ContactMargins kNoContactMargins{0.0, 0.0, 0.0};

/// The margins a friction contact plans with when the case gives none (docs/controller.md,
/// "Contact margins": exp1's measured margins, scaled to the contact and the robot): 10 % of the
/// friction coefficient; a CoP margin of 14 % of the narrowest half extent of the contact's points
/// (in the frame's x-y plane), at most 1 cm, rounded down to the millimetre (none for fewer than 3
/// points or a point contact); a minimum normal force of 6.3 % of the robot's weight shared by
/// the contact's points, rounded to 0.1 N.
tasks::ContactMargins defaultContactMargins(const std::vector<Eigen::Vector3d>& points, bool point_contact, double weight_N);

/// The divergence guard (docs/cases.md, "Divergence guard"): ends a run whose plan the simulated
/// robot no longer follows, with status `diverged` and the reason. Thresholds far from any
/// healthy run (measured on the committed cases: docs/cases.md).
struct DivergenceGuard {
  bool enabled = true;
  double position_m = 0.25;             ///< base position: the plan's (last command) against the simulator's
  double angle_rad = 0.5;               ///< base attitude and every joint: plan against simulator
  double contact_lost_s = 1.0;          ///< a contact the plan holds without force in the simulator this long
  double contact_lost_fraction = 0.01;  ///< "without force": below this fraction of the robot's weight
  double torque_factor = 10.0;          ///< a commanded torque beyond this multiple of its effort limit
  double task_error = 100.0;            ///< a task error norm beyond this (m or rad): beyond any workspace
};

struct ContactEntry {
  std::string name;
  std::string where;
  std::string surface;  ///< the data-file surface it was taken from (may be empty)
  std::string frame;
  std::vector<Eigen::Vector3d> points;  ///< in the frame
  bool fixed = false;
  double friction = 0.7;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< in the frame
  /// 3: a point contact (its task holds the point's position; the force's normal is the
  /// ground's, world +z); 6: the frame's pose held. Default: 3 for one point that is not fixed.
  int dims = 6;
  std::string grasp;   ///< linked simulator grasp (switched with the contact); empty: none
  std::string sensor;  ///< linked force/torque sensor (traced for comparison); empty: none
  /// The plan's contact margins (controller.contact_margins, then the contact's `margins`);
  /// points and friction above are the real contact's (the checks judge against them).
  tasks::ContactMargins margins;
  bool margins_default = false;  ///< the margins are defaultContactMargins (the case gives none)
};

struct LevelEntry {
  std::string name;
  std::string where;
  std::vector<std::string> tasks;
  std::vector<double> weights;  ///< wls_levels objective only (same order as tasks)
};

struct LexdynSpec {
  std::string method = "bfgs";       ///< a registered method (control::findMethod)
  std::string method_where;          ///< where the method comes from (file key or --method)
  control::ControllerParams params;  ///< of the current method: method, dt and solver filled in as well
  /// `params` for every registered method (with its method_params override applied), by name;
  /// setMethod() copies the method's entry into `params`.
  std::map<std::string, control::ControllerParams> params_by_method;
  bool feedforward_torque = true;  ///< Command::tau sent as the servo's feed-forward torque
  /// The state the controller reads each tick: the simulator's measured (q, u) (`measured`), or
  /// its own previous command (`integrated`: q(k+1), u(k+1) of the last tick, the simulator
  /// only tracking the joint set-points; reset from the measured initial state).
  std::string state_feedback = "measured";  ///< measured | integrated | measured_position
  std::vector<ContactEntry> contacts;
  /// controller.contact_margins: every friction contact's margins unless it gives its own; when
  /// the case gives none (contact_margins_default), each contact's are defaultContactMargins.
  tasks::ContactMargins contact_margins = kNoContactMargins;
  bool contact_margins_default = false;
  DivergenceGuard guard;  ///< controller.divergence_guard
  std::vector<std::string> initial_contacts;
  std::vector<TaskSpec> tasks;
  std::vector<LevelEntry> levels;      ///< methods with the strict hierarchy: bfgs, ah, gn
  std::vector<LevelEntry> wls_levels;  ///< methods with the weighted hierarchy: wls, exactly two (hard, objective)
  std::string levels_where, wls_levels_where;

  /// Whether the case defines the hierarchy of method m (control::MethodInfo::weighted_hierarchy:
  /// `wls_levels`, otherwise `levels`).
  bool hasHierarchy(const std::string& m) const { return !hierarchy(m).empty(); }
  /// The hierarchy used by method m, its key (`levels` or `wls_levels`) and where it was read.
  const std::vector<LevelEntry>& hierarchy(const std::string& m) const;
  const char* hierarchyKey(const std::string& m) const;
  const std::string& hierarchyWhere(const std::string& m) const;
  int findTask(const std::string& name) const;     ///< -1 when absent
  int findContact(const std::string& name) const;  ///< -1 when absent
};

/// Reads the section (everything but `type`, which the caller has read) and finishes `m`. `dt` is the case's
/// control period (for solver.paper_rules). Throws lexdyn::InputError naming file, line, key.
LexdynSpec readLexdynSpec(yaml::StrictMap& m, const model::RobotDescription& robot, double dt);

/// The controller configuration for `spec.method` (tasks of the other hierarchy are built too
/// and ignored by the controller).
control::ControllerConfig buildControllerConfig(const LexdynSpec& spec, const model::RobotModel& model);

/// Sets the method (e.g. from --method), checking that the case has its hierarchy.
void setMethod(LexdynSpec& spec, const std::string& method, const std::string& where);

/// Names of the tasks the hierarchy of method m uses, in task order.
std::vector<std::string> usedTasks(const LexdynSpec& spec, const std::string& m);

}  // namespace lexdyn::cases
