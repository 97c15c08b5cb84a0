#include "lexdyn/tasks/task.hpp"

#include <cmath>

#include "lexdyn/common/error.hpp"
#include "lexdyn/tasks/task_params.hpp"

namespace lexdyn::tasks {

ContactLayout::ContactLayout(int nv, std::vector<ContactSpec> contacts) : nv_(nv), contacts_(std::move(contacts)) {
  offset_.reserve(contacts_.size());
  ng_ = 0;
  for (const ContactSpec& c : contacts_) {
    offset_.push_back(ng_);
    ng_ += 4 * static_cast<int>(c.points.size());
  }
}

int ContactLayout::find(const std::string& name) const {
  for (int c = 0; c < count(); ++c)
    if (contacts_[static_cast<size_t>(c)].name == name) return c;
  return -1;
}

void ContactLayout::generators(const Eigen::Matrix3d& R, const Eigen::Vector3d& normal_in_frame, double mu,
                               Eigen::Ref<Eigen::Matrix<double, 3, 4>> D) {
  const Eigen::Vector3d n = (R * normal_in_frame).normalized();
  // Tangent basis: any unit vector orthogonal to n, chosen deterministically.
  const Eigen::Vector3d ref = (std::abs(n.x()) < 0.9) ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d t1 = (ref - n * n.dot(ref)).normalized();
  const Eigen::Vector3d t2 = n.cross(t1);
  D.col(0) = (n + mu * t1).normalized();
  D.col(1) = (n - mu * t1).normalized();
  D.col(2) = (n + mu * t2).normalized();
  D.col(3) = (n - mu * t2).normalized();
}

void ContactLayout::generators(const ContactSpec& spec, const Eigen::Matrix3d& R, Eigen::Ref<Eigen::Matrix<double, 3, 4>> D) {
  if (spec.point)
    generators(Eigen::Matrix3d::Identity(), Eigen::Vector3d::UnitZ(), spec.friction, D);
  else
    generators(R, spec.normal_in_frame, spec.friction, D);
}

void TaskModel::requireLayoutNv(const ContactLayout& layout, int nv) const {
  if (layout.nv() != nv) {
    throwTaskInput(name(), "", "built for nv = " + std::to_string(nv) + ", layout has nv = " + std::to_string(layout.nv()));
  }
}

void TaskModel::requireLayoutSizes(const ContactLayout& layout, int nv, int ng) const {
  if (layout.nv() != nv || layout.ng() != ng) {
    throwTaskInput(name(), "",
                   "built for a contact layout with nv = " + std::to_string(nv) + ", ng = " + std::to_string(ng) +
                       ", given nv = " + std::to_string(layout.nv()) + ", ng = " + std::to_string(layout.ng()));
  }
}

void TaskModel::initData(TaskData& d, const ContactLayout& layout, bool engaged) const {
  const int m = rows();
  d.A.setZero(m, layout.nx());
  d.lower.setZero(m);
  d.upper.setZero(m);
  d.error.setZero(m);
  d.J.setZero(m, layout.nv());
  d.engaged.assign(static_cast<size_t>(m), engaged ? 1 : 0);
  d.held.assign(static_cast<size_t>(m), 0);
  d.target.setZero(targetSize());
  d.target_set = false;
}

std::unique_ptr<TaskData> TaskModel::createData(const ContactLayout& layout) const { return makeData(layout, false); }

void TaskModel::boundVariables(const ContactLayout&, std::vector<int>& vars) const {
  vars.clear();
  throw InputError("task \"" + name() + "\"", "is not a bounds task");
}

void TaskModel::accumulateHessian(const TickContext&, const TaskData&, const Eigen::Ref<const Eigen::VectorXd>&,
                                  Eigen::Ref<Eigen::MatrixXd>) const {}

void TaskModel::chainDofs(const model::RobotModel&, std::vector<char>&) const {}

void TaskModel::setTarget(TaskData& d, const Eigen::Ref<const Eigen::VectorXd>& target) const {
  if (targetSize() == 0) throw InputError("task \"" + name() + "\"", "has no target to set");
  if (target.size() != targetSize()) {
    throw InputError("task \"" + name() + "\"",
                     "target needs " + std::to_string(targetSize()) + " values, got " + std::to_string(target.size()));
  }
  checkTarget(target);
  d.target = target;
  d.target_set = true;
}

void TaskModel::checkTarget(const Eigen::Ref<const Eigen::VectorXd>& target) const {
  for (int i = 0; i < target.size(); ++i) {
    if (std::isnan(target[i])) {
      throw InputError("task \"" + name() + "\": target[" + std::to_string(i) + "]", "must be a number, found NaN");
    }
  }
}

}  // namespace lexdyn::tasks
