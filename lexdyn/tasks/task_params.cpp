#include "lexdyn/tasks/task_params.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <sstream>

#include "lexdyn/common/error.hpp"

namespace lexdyn::tasks {

namespace {
std::string str(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}
}  // namespace

std::string taskWhere(const std::string& task, const std::string& field) {
  return field.empty() ? "task \"" + task + "\"" : "task \"" + task + "\": " + field;
}

void throwTaskInput(const std::string& task, const std::string& field, const std::string& what) {
  throw InputError(taskWhere(task, field), what);
}

void requireFinite(double v, const std::string& task, const std::string& field) {
  if (!std::isfinite(v)) throwTaskInput(task, field, "must be a finite number, found " + str(v));
}

void requireNonNegative(double v, const std::string& task, const std::string& field) {
  if (!std::isfinite(v) || v < 0.0) throwTaskInput(task, field, "must be finite and >= 0, found " + str(v));
}

void requirePositive(double v, const std::string& task, const std::string& field) {
  if (!std::isfinite(v) || v <= 0.0) throwTaskInput(task, field, "must be finite and > 0, found " + str(v));
}

void requireFinite(const Eigen::Ref<const Eigen::VectorXd>& v, const std::string& task, const std::string& field) {
  for (int i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      throwTaskInput(task, field + "[" + std::to_string(i) + "]", "must be a finite number, found " + str(v[i]));
    }
  }
}

void requireRotation(const Eigen::Matrix3d& R, const std::string& task, const std::string& field) {
  if (!R.allFinite()) throwTaskInput(task, field, "must be a rotation matrix, found non-finite entries");
  const double orth = (R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orth > 1e-6 || R.determinant() <= 0.0) {
    throwTaskInput(
        task, field,
        "must be a rotation matrix (orthonormal to 1e-6, det 1), found |R R^T - I| = " + str(orth) + ", det = " + str(R.determinant()));
  }
}

model::FrameId resolveFrame(const model::RobotModel& model, const std::string& name, const std::string& task, const std::string& field) {
  try {
    return model.frameId(name);
  } catch (const InputError& e) {
    throwTaskInput(task, field, e.detail());
  }
}

int resolveJoint(const model::RobotModel& model, const std::string& name, const std::string& task, const std::string& field) {
  try {
    return model.jointIndex(name);
  } catch (const InputError& e) {
    throwTaskInput(task, field, e.detail());
  }
}

void markBodyChain(const model::RobotModel& model, int body, std::vector<char>& mask) {
  LEXDYN_ALWAYS_ASSERT(static_cast<int>(mask.size()) == model.nv(), "chainDofs: the mask needs nv entries");
  for (int k : model.tree().bodies[static_cast<size_t>(body)].ancestor_dofs) mask[static_cast<size_t>(model.treeDofModel(k))] = 1;
}

Eigen::Vector3d rotationError(const Eigen::Matrix3d& R_d, const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(Eigen::Matrix3d(R_d * R.transpose()));
  return aa.angle() * aa.axis();
}

}  // namespace lexdyn::tasks
