// The task types a case file can name (docs/cases.md, "Tasks"): one registry entry per type
// (task_registry.cpp) with its reader, which reads a task's YAML entry into the params struct of
// its lexdyn/tasks header, its builder (the TaskModel from those params), and what the harness
// asks of the type (its PD gains, the meaning of its target's values). Nothing else compares
// task type names.
//
// Every params field of the task headers has a key of the same name (`gains: {kp, kv}`,
// `damper: {interaction, safety, xi, adaptive}`), plus two conveniences that only produce those
// fields: `target_rpy_rad` for orientation targets and `joints: {NAME: value}` overrides of a
// posture's target. A TaskSpec is plain data (copyable); makeTask() builds the task for a model
// and a contact layout, so one case file is turned into a controller for any method.
#pragma once

#include "harness/checks/check_registry.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/common/yaml_strict.hpp"
#include "lexdyn/model/robot_description.hpp"
#include "lexdyn/tasks/com.hpp"
#include "lexdyn/tasks/com_box.hpp"
#include "lexdyn/tasks/contact.hpp"
#include "lexdyn/tasks/joint_limits.hpp"
#include "lexdyn/tasks/joint_position.hpp"
#include "lexdyn/tasks/orientation.hpp"
#include "lexdyn/tasks/position.hpp"
#include "lexdyn/tasks/posture.hpp"
#include "lexdyn/tasks/self_collision.hpp"
#include "lexdyn/tasks/torque_limits.hpp"
#include "lexdyn/tasks/trust_region.hpp"

#include <any>
#include <memory>
#include <string>
#include <vector>

namespace lexdyn::cases {

/// One task of a case file: its name and type, and the params struct of its type (from the type's
/// lexdyn/tasks header: tasks::PositionParams for position, ...; empty for a type without).
struct TaskSpec {
  std::string name;
  std::string type;   ///< one of taskTypes()
  std::string where;  ///< "file:line: controller.tasks[i]" for messages
  std::any params;

  /// The params struct of the task's type; aborts when the spec holds another (internal error).
  template <class P>
  const P& paramsAs() const {
    const P* p = std::any_cast<P>(&params);
    LEXDYN_ALWAYS_ASSERT(p, "task '" + name + "' of type " + type + " holds the params of another type (or none)");
    return *p;
  }
};

/// The 15 task types, in the order of docs/controller.md.
const std::vector<std::string>& taskTypes();

/// Reads one entry of `controller.tasks` (a mapping with `name`, `type` and the type's keys).
/// `contacts` are the names of the controller's contacts (for `contact` tasks). Values are
/// checked against the ranges of lexdyn/common/input_ranges.hpp: positions, joint targets within
/// the joints' limits, PD gains stable at `control_period_s` (0: not checked). Throws
/// lexdyn::InputError naming the file, line and key path.
TaskSpec readTaskSpec(const yaml::Node& node, const model::RobotDescription& robot, const std::vector<std::string>& contacts,
                      double control_period_s = 0.0);

/// Builds the task. Errors of the task's own validation are rethrown naming the case file
/// entry (TaskSpec::where).
std::unique_ptr<tasks::TaskModel> makeTask(const TaskSpec& spec, const model::RobotModel& model, const tasks::ContactLayout& layout);

/// The PD gains of a task (position, orientation, com, joint_position, posture, contact);
/// nullptr for a type without.
const tasks::PdGains* taskGains(const TaskSpec& spec);

/// What the values of a task's target are (set_target events, the trace's target channels).
struct TaskTargetLayout {
  std::vector<std::string> channels;  ///< traced as target.<task>.<name>; empty: not traced
  bool positions = false;             ///< every value is a position (m)
  std::vector<std::string> joints;    ///< value k is the position of joints[k]
};
TaskTargetLayout taskTarget(const TaskSpec& spec, const model::RobotDescription& robot);

/// A scalar that may also be `.inf`, `+.inf`, `-.inf` (YAML's infinities; also `inf`, `-inf`).
double asBound(const yaml::Node& n);
/// A sequence of 3 such scalars.
Eigen::Vector3d asBound3(const yaml::Node& n);

/// "a, b, c" (for error messages listing the valid names).
using checks::joinNames;
/// The frame named by n; an unknown one fails at n, listing the robot's frames.
std::string frameName(const yaml::Node& n, const model::RobotDescription& d);
/// The joint named by n; an unknown one fails at n, listing the robot's joints.
std::string jointName(const yaml::Node& n, const model::RobotDescription& d);
/// R = Rz(yaw) Ry(pitch) Rx(roll) of rpy = [roll, pitch, yaw] (rad).
Eigen::Matrix3d rotationFromRpy(const Eigen::Vector3d& rpy);

/// Names used in trace channels: non-empty, letters, digits, '_' and '-' only.
void requireChannelName(const yaml::Node& n, const std::string& name);
/// The string of `n`, a name used in trace channels (requireChannelName).
std::string channelName(const yaml::Node& n);

}  // namespace lexdyn::cases
