#include "lexdyn/tasks/joint_limits.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "lexdyn/common/error.hpp"

namespace lexdyn::tasks {

JointLimitsTask::JointLimitsTask(std::string name, const model::RobotModel& model, const JointLimitsParams& params)
    : TaskModel(std::move(name)), params_(params), nv_(model.nv()), nj_(model.numJoints()), offset_(model.jointVelocityOffset()) {
  requirePositive(params.interaction_fraction, this->name(), "interaction_fraction");
  if (params.interaction_fraction > 0.5) {
    throwTaskInput(this->name(), "interaction_fraction",
                   "must be <= 0.5 (a fraction of the joint range), found " + std::to_string(params.interaction_fraction));
  }
  requireNonNegative(params.safety_fraction, this->name(), "safety_fraction");
  if (!(params.safety_fraction < params.interaction_fraction)) {
    throwTaskInput(this->name(), "safety_fraction",
                   "must be smaller than interaction_fraction (" + std::to_string(params.interaction_fraction) + "), found " +
                       std::to_string(params.safety_fraction));
  }
  requirePositive(params.xi, this->name(), "xi");
  q_min_ = model.jointLowerLimits();
  q_max_ = model.jointUpperLimits();
  v_max_ = params.velocity_limits ? model.jointVelocityLimits() : Eigen::VectorXd::Constant(nj_, std::numeric_limits<double>::infinity());
}

std::unique_ptr<TaskData> JointLimitsTask::createData(const ContactLayout& layout) const {
  requireLayoutNv(layout, nv_);
  auto d = makeData<DamperTaskData>(layout, false);
  d->dampers.resize(static_cast<size_t>(2 * nj_));  // lower limit of each joint, then upper
  for (int j = 0; j < nj_; ++j) d->A(j, offset_ + j) = 1.0;
  return d;
}

void JointLimitsTask::reset(TaskData& d) const { static_cast<DamperTaskData&>(d).resetDampers(); }

void JointLimitsTask::compute(const TickContext& ctx, TaskData& base) const {
  auto& d = static_cast<DamperTaskData&>(base);
  const Eigen::VectorXd& q = ctx.q->joints;
  const Eigen::VectorXd& u = *ctx.u;
  for (int j = 0; j < nj_; ++j) {
    const double range = q_max_[j] - q_min_[j];  // +inf for a continuous joint
    const double d_lower = q[j] - q_min_[j];
    const double d_upper = q_max_[j] - q[j];
    const double v_max = v_max_[j];
    double lower = -v_max, upper = v_max;
    bool engaged = false;
    if (std::isfinite(range)) {
      const double d_i = params_.interaction_fraction * range;
      const double d_s = params_.safety_fraction * range;
      const DamperParams dp{d_i, d_s, params_.xi, params_.adaptive};
      const double qdot = u[offset_ + j];
      lower = std::clamp(damperVelocityBound(d_lower, qdot, dp, d.dampers[static_cast<size_t>(j)]), -v_max, v_max);
      upper = std::clamp(-damperVelocityBound(d_upper, -qdot, dp, d.dampers[static_cast<size_t>(nj_ + j)]), -v_max, v_max);
      engaged = damperEngaged(d_lower, d_i) || damperEngaged(d_upper, d_i);
    }
    if (ctx.domain == Domain::Acceleration) {
      // Bounds on qdot + dt qddot (eq. 57's velocity update).
      const double qdot = u[offset_ + j];
      lower = (lower - qdot) / ctx.dt;
      upper = (upper - qdot) / ctx.dt;
    }
    d.lower[j] = lower;
    d.upper[j] = upper;
    d.error[j] = std::min(d_lower, d_upper);
    d.engaged[static_cast<size_t>(j)] = engaged ? 1 : 0;
  }
}

void JointLimitsTask::boundVariables(const ContactLayout&, std::vector<int>& vars) const {
  vars.resize(static_cast<size_t>(nj_));
  for (int j = 0; j < nj_; ++j) vars[static_cast<size_t>(j)] = offset_ + j;
}

}  // namespace lexdyn::tasks
