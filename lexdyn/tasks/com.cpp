#include "lexdyn/tasks/com.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/hessian/kinematic_hessian.hpp"

namespace lexdyn::tasks {

void markMassiveBodiesChain(const model::RobotModel& model, std::vector<char>& mask) {
  const model::KinematicTree& tree = model.tree();
  for (int b = 0; b < static_cast<int>(tree.bodies.size()); ++b) {
    if (tree.bodies[static_cast<size_t>(b)].mass > 0.0) markBodyChain(model, b, mask);
  }
}

void accumulateComRowsHessian(const TickContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& w, Eigen::Ref<Eigen::MatrixXd> H) {
  LEXDYN_ALWAYS_ASSERT(ctx.hessian != nullptr && w.size() == 3, "CoM rows: accumulateHessian needs ctx.hessian, w(3)");
  hessian::accumulateComHessian(*ctx.model, *ctx.hessian, Eigen::Vector3d(w), H);
}

ComTask::ComTask(std::string name, const model::RobotModel& model, const ComParams& params) : TrackingTask(std::move(name), model, 3, 3) {
  if (params.target) setInitialTarget(*params.target);
  pd_ = resolvePd(params.gains, this->name());
}

void ComTask::compute(const TickContext& ctx, TaskData& d) const {
  const model::RobotModel& model = *ctx.model;
  const model::ModelData& data = *ctx.data;
  model.centerOfMassJacobian(data, d.J);
  const Eigen::Vector3d c = model.centerOfMass(data);
  holdTarget(d, c);
  const Eigen::Vector3d e = d.target.head<3>() - c;
  writePdRows<3>(ctx, pd_, e, model.centerOfMassBias(data), nv_, d);  // eq. 61 / 55
}

void ComTask::accumulateHessian(const TickContext& ctx, const TaskData&, const Eigen::Ref<const Eigen::VectorXd>& w,
                                Eigen::Ref<Eigen::MatrixXd> H) const {
  accumulateComRowsHessian(ctx, w, H);
}

void ComTask::chainDofs(const model::RobotModel& model, std::vector<char>& mask) const { markMassiveBodiesChain(model, mask); }

}  // namespace lexdyn::tasks
