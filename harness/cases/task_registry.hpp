// The task types a case file can name (docs/cases.md, "Tasks"): one registry that reads a task's
// YAML entry into the params struct of its lexdyn/tasks header and builds the TaskModel from it.
//
// Every params field of the task headers has a key of the same name (`gains: {kp, kv}`,
// `damper: {interaction, safety, xi, adaptive}`), plus two conveniences that only produce those
// fields: `target_rpy_rad` for orientation targets and `joints: {NAME: value}` overrides of a
// posture's target. A TaskSpec is plain data (copyable); makeTask() builds the task for a model
// and a contact layout, so one case file is turned into a controller for any method.
#pragma once

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

#include <memory>
#include <string>
#include <vector>

namespace lexdyn::cases {

/// One task of a case file. Only the params member of its type is meaningful.
struct TaskSpec {
  std::string name;
  std::string type;   ///< one of taskTypes()
  std::string where;  ///< "file:line: controller.tasks[i]" for messages
  tasks::JointLimitsParams joint_limits;
  tasks::TorqueLimitsParams torque_limits;
  tasks::TrustRegionParams trust_region;
  tasks::SelfCollisionParams self_collision;
  tasks::ContactTaskParams contact;
  tasks::PositionParams position;
  tasks::OrientationParams orientation;
  tasks::ComParams com;
  tasks::ComBoxParams com_box;
  tasks::JointPositionParams joint_position;
  tasks::PostureParams posture;
};

/// The 15 task types, in the order of docs/controller.md.
const std::vector<std::string>& taskTypes();

/// Reads one entry of `controller.tasks` (a mapping with `name`, `type` and the type's keys).
/// `contacts` are the names of the controller's contacts (for `contact` tasks). Values are
/// checked against the ranges of lexdyn/common/input_ranges.hpp: positions, joint targets within
/// the joints' limits, PD gains stable at `control_period_s` (0: not checked). Throws
/// lexdyn::InputError naming the file, line and key path.
TaskSpec readTaskSpec(const yaml::Node& node, const model::RobotDescription& robot,
                      const std::vector<std::string>& contacts, double control_period_s = 0.0);

/// Builds the task. Errors of the task's own validation are rethrown naming the case file
/// entry (TaskSpec::where).
std::unique_ptr<tasks::TaskModel> makeTask(const TaskSpec& spec, const model::RobotModel& model,
                                           const tasks::ContactLayout& layout);

/// A scalar that may also be `.inf`, `+.inf`, `-.inf` (YAML's infinities; also `inf`, `-inf`).
double asBound(const yaml::Node& n);
/// A sequence of 3 such scalars.
Eigen::Vector3d asBound3(const yaml::Node& n);

/// "a, b, c" (for error messages listing the valid names).
std::string joinNames(const std::vector<std::string>& v);
/// The frame named by n; an unknown one fails at n, listing the robot's frames.
std::string frameName(const yaml::Node& n, const model::RobotDescription& d);
/// The joint named by n; an unknown one fails at n, listing the robot's joints.
std::string jointName(const yaml::Node& n, const model::RobotDescription& d);
/// R = Rz(yaw) Ry(pitch) Rx(roll) of rpy = [roll, pitch, yaw] (rad).
Eigen::Matrix3d rotationFromRpy(const Eigen::Vector3d& rpy);

/// Names used in trace channels: non-empty, letters, digits, '_' and '-' only.
void requireChannelName(const yaml::Node& n, const std::string& name);

}  // namespace lexdyn::cases
