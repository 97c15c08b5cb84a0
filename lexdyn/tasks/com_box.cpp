#include "lexdyn/tasks/com_box.hpp"

#include <algorithm>
#include <cmath>

#include "lexdyn/common/error.hpp"
#include "lexdyn/hessian/kinematic_hessian.hpp"
#include "lexdyn/tasks/com.hpp"

namespace lexdyn::tasks {

ComBoxTask::ComBoxTask(std::string name, const model::RobotModel& model, const ComBoxParams& params)
    : TaskModel(std::move(name)), nv_(model.nv()), damper_(params.damper) {
  validateDamper(params.damper, this->name(), "damper.");
  initial_box_ << params.lower, params.upper;
  checkTarget(initial_box_);
}

void ComBoxTask::checkTarget(const Eigen::Ref<const Eigen::VectorXd>& box) const {
  static const char* kAxis[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    const double lo = box[i], hi = box[3 + i];
    const std::string axis = kAxis[i];
    if (std::isnan(lo) || lo == std::numeric_limits<double>::infinity()) {
      throwTaskInput(name(), "lower." + axis, "must be a number or -inf, found " + std::to_string(lo));
    }
    if (std::isnan(hi) || hi == -std::numeric_limits<double>::infinity()) {
      throwTaskInput(name(), "upper." + axis, "must be a number or +inf, found " + std::to_string(hi));
    }
    if (!(hi - lo >= 2.0 * damper_.safety)) {
      throwTaskInput(
          name(), "upper." + axis,
          "must be at least lower + 2 * safety distance (" + std::to_string(lo + 2.0 * damper_.safety) + "), found " + std::to_string(hi));
    }
  }
}

std::unique_ptr<TaskData> ComBoxTask::createData(const ContactLayout& layout) const {
  requireLayoutNv(layout, nv_);
  auto d = makeData<DamperTaskData>(layout, false);
  d->dampers.resize(6);  // lower side of x, y, z, then upper side
  reset(*d);
  return d;
}

void ComBoxTask::reset(TaskData& d) const {
  d.target = initial_box_;
  d.target_set = true;
  static_cast<DamperTaskData&>(d).resetDampers();
}

void ComBoxTask::compute(const TickContext& ctx, TaskData& base) const {
  auto& d = static_cast<DamperTaskData&>(base);
  const model::RobotModel& model = *ctx.model;
  const model::ModelData& data = *ctx.data;
  model.centerOfMassJacobian(data, d.J);
  const Eigen::Vector3d c = model.centerOfMass(data);
  const Eigen::Vector3d bias = model.centerOfMassBias(data);
  Eigen::Vector3d Ju;
  Ju.noalias() = d.J * (*ctx.u);
  d.A.leftCols(nv_) = d.J;
  const double d_i = damper_.interaction;
  for (int i = 0; i < 3; ++i) {
    const double d_lo = c[i] - d.target[i];
    const double d_hi = d.target[3 + i] - c[i];
    // Velocity-domain bounds on J_i u(k+1): the damper of the lower side bounds +J_i, the one
    // of the upper side bounds -J_i.
    // d_lo grows with the CoM velocity, d_hi shrinks with it.
    double lower = damperVelocityBound(d_lo, Ju[i], damper_, d.dampers[static_cast<size_t>(i)]);
    double upper = -damperVelocityBound(d_hi, -Ju[i], damper_, d.dampers[static_cast<size_t>(3 + i)]);
    if (ctx.domain == Domain::Acceleration) {
      lower = (lower - Ju[i]) / ctx.dt - bias[i];
      upper = (upper - Ju[i]) / ctx.dt - bias[i];
    }
    d.lower[i] = lower;
    d.upper[i] = upper;
    d.error[i] = std::min(d_lo, d_hi);
    d.engaged[static_cast<size_t>(i)] = (damperEngaged(d_lo, d_i) || damperEngaged(d_hi, d_i)) ? 1 : 0;
  }
}

void ComBoxTask::accumulateHessian(const TickContext& ctx, const TaskData&, const Eigen::Ref<const Eigen::VectorXd>& w,
                                   Eigen::Ref<Eigen::MatrixXd> H) const {
  accumulateComRowsHessian(ctx, w, H);
}

void ComBoxTask::chainDofs(const model::RobotModel& model, std::vector<char>& mask) const { markMassiveBodiesChain(model, mask); }

}  // namespace lexdyn::tasks
