#include "lexdyn/tasks/com.hpp"

#include <algorithm>

#include "lexdyn/common/error.hpp"
#include "lexdyn/hessian/kinematic_hessian.hpp"

namespace lexdyn::tasks {

void markMassiveBodiesChain(const model::RobotModel& model, std::vector<char>& mask) {
  const model::KinematicTree& tree = model.tree();
  for (int b = 0; b < static_cast<int>(tree.bodies.size()); ++b) {
    if (tree.bodies[static_cast<size_t>(b)].mass > 0.0) markBodyChain(model, b, mask);
  }
}

ComTask::ComTask(std::string name, const model::RobotModel& model, const ComParams& params)
    : TaskModel(std::move(name)), nv_(model.nv()) {
  if (params.target) {
    requireFinite(*params.target, this->name(), "target");
    initial_target_ = params.target;
  }
  pd_ = resolvePd(params.gains, this->name());
}

void ComTask::checkTarget(const Eigen::Ref<const Eigen::VectorXd>& target) const { requireFinite(target, name(), "target"); }

std::unique_ptr<TaskData> ComTask::createData(const ContactLayout& layout) const {
  requireLayoutNv(layout, nv_);
  auto d = std::make_unique<TaskData>();
  initData(*d, layout);
  std::fill(d->engaged.begin(), d->engaged.end(), 1);
  reset(*d);
  return d;
}

void ComTask::reset(TaskData& d) const {
  d.target_set = initial_target_.has_value();
  if (initial_target_) d.target = *initial_target_;
}

void ComTask::compute(const TickContext& ctx, TaskData& d) const {
  const model::RobotModel& model = *ctx.model;
  const model::ModelData& data = *ctx.data;
  model.centerOfMassJacobian(data, d.J);
  const Eigen::Vector3d c = model.centerOfMass(data);
  if (!d.target_set) {
    d.target = c;  // hold
    d.target_set = true;
  }
  const Eigen::Vector3d e = d.target.head<3>() - c;
  writePdRows<3>(ctx, pd_, e, model.centerOfMassBias(data), nv_, d);  // eq. 61 / 55
}

void ComTask::accumulateHessian(const TickContext& ctx, const TaskData&, const Eigen::Ref<const Eigen::VectorXd>& w,
                                Eigen::Ref<Eigen::MatrixXd> H) const {
  LEXDYN_ALWAYS_ASSERT(ctx.hessian != nullptr && w.size() == 3, "com: accumulateHessian needs ctx.hessian, w(3)");
  hessian::accumulateComHessian(*ctx.model, *ctx.hessian, Eigen::Vector3d(w), H);
}

void ComTask::chainDofs(const model::RobotModel& model, std::vector<char>& mask) const {
  markMassiveBodiesChain(model, mask);
}

}  // namespace lexdyn::tasks
