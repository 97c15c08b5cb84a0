// Validation helpers for the parameters of task types: every failure is a lexdyn::InputError
// whose `where` names the task and the field, e.g. `task "right_hand": kp`.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "lexdyn/model/robot_model.hpp"

namespace lexdyn::tasks {

/// `task "<name>": <field>` (or `task "<name>"` for an empty field).
std::string taskWhere(const std::string& task, const std::string& field);
[[noreturn]] void throwTaskInput(const std::string& task, const std::string& field, const std::string& what);

/// Value checks; `what` in the message says what was expected and what was found.
void requireFinite(double v, const std::string& task, const std::string& field);
void requireNonNegative(double v, const std::string& task, const std::string& field);  ///< finite, >= 0
void requirePositive(double v, const std::string& task, const std::string& field);     ///< finite, > 0
void requireFinite(const Eigen::Ref<const Eigen::VectorXd>& v, const std::string& task, const std::string& field);
/// R orthonormal (|R R^T - I| <= 1e-6) with det(R) > 0.
void requireRotation(const Eigen::Matrix3d& R, const std::string& task, const std::string& field);

/// The model's frame of that name; an unknown name becomes an InputError naming the task and
/// the field (and listing the model's frames, as RobotModel::frameId does).
model::FrameId resolveFrame(const model::RobotModel& model, const std::string& name, const std::string& task, const std::string& field);
/// The model's joint of that name (model joint order), as resolveFrame.
int resolveJoint(const model::RobotModel& model, const std::string& name, const std::string& task, const std::string& field);

/// Sets mask[k] = 1 for every dof that moves `body` (KinematicTree::bodies[body].ancestor_dofs).
/// mask must have nv entries.
void markBodyChain(const model::RobotModel& model, int body, std::vector<char>& mask);

/// Orientation error e = log(R_d R^T): the rotation vector (world axes, angle in [0, pi]) of
/// the rotation taking R to R_d. Allocation-free.
Eigen::Vector3d rotationError(const Eigen::Matrix3d& R_d, const Eigen::Matrix3d& R);

}  // namespace lexdyn::tasks
