#include "lexdyn/tasks/self_collision.hpp"

#include <limits>

#include "lexdyn/common/error.hpp"
#include "lexdyn/hessian/kinematic_hessian.hpp"

namespace lexdyn::tasks {

SelfCollisionTask::SelfCollisionTask(std::string name, const model::RobotModel& model, const SelfCollisionParams& params)
    : TaskModel(std::move(name)), nv_(model.nv()) {
  const model::RobotDescription& desc = model.description();
  std::vector<int> indices;
  if (params.pairs.empty()) {
    for (int p = 0; p < model.numCollisionPairs(); ++p) indices.push_back(p);
  } else {
    for (size_t k = 0; k < params.pairs.size(); ++k) {
      const std::string field = "pairs[" + std::to_string(k) + "]";
      const int a = desc.findCapsule(params.pairs[k].first);
      const int b = desc.findCapsule(params.pairs[k].second);
      if (a < 0) throwTaskInput(this->name(), field, "unknown capsule '" + params.pairs[k].first + "'");
      if (b < 0) throwTaskInput(this->name(), field, "unknown capsule '" + params.pairs[k].second + "'");
      int found = -1;
      for (int p = 0; p < model.numCollisionPairs(); ++p) {
        const auto& cp = desc.collision_pairs[static_cast<size_t>(p)];
        if ((cp.capsule_a == a && cp.capsule_b == b) || (cp.capsule_a == b && cp.capsule_b == a)) found = p;
      }
      if (found < 0) {
        throwTaskInput(this->name(), field,
                       "[" + params.pairs[k].first + ", " + params.pairs[k].second + "] is not a collision pair of the robot data file");
      }
      for (int prev : indices) {
        if (prev == found) throwTaskInput(this->name(), field, "pair listed twice");
      }
      indices.push_back(found);
    }
  }
  for (int p : indices) {
    const auto& cp = desc.collision_pairs[static_cast<size_t>(p)];
    Pair pr;
    pr.pair = p;
    pr.frame_a = model.frameId(desc.links[static_cast<size_t>(desc.capsules[static_cast<size_t>(cp.capsule_a)].link)].name);
    pr.frame_b = model.frameId(desc.links[static_cast<size_t>(desc.capsules[static_cast<size_t>(cp.capsule_b)].link)].name);
    pr.body_a = model.frameBody(pr.frame_a);
    pr.body_b = model.frameBody(pr.frame_b);
    pairs_.push_back(pr);
  }
  damper_.interaction = params.interaction_distance.value_or(desc.collision_interaction_distance);
  damper_.safety = params.safety_distance.value_or(desc.collision_safety_distance);
  damper_.xi = params.xi;
  damper_.adaptive = params.adaptive;
  validateDamper(damper_, this->name(), "");
}

std::unique_ptr<TaskData> SelfCollisionTask::createData(const ContactLayout& layout) const {
  requireLayoutNv(layout, nv_);
  auto d = makeData<SelfCollisionTaskData>(layout, false);
  d->point_a.setZero(3, rows());
  d->point_b.setZero(3, rows());
  d->normal.setZero(3, rows());
  d->upper.setConstant(std::numeric_limits<double>::infinity());
  d->dampers.resize(static_cast<size_t>(rows()));
  d->jacobian_zero.assign(static_cast<size_t>(rows()), 1);  // J and A start zero
  return d;
}

void SelfCollisionTask::reset(TaskData& d) const { static_cast<SelfCollisionTaskData&>(d).resetDampers(); }

void SelfCollisionTask::compute(const TickContext& ctx, TaskData& base) const {
  auto& d = static_cast<SelfCollisionTaskData&>(base);
  const model::RobotModel& model = *ctx.model;
  const model::ModelData& data = *ctx.data;
  const Eigen::VectorXd& u = *ctx.u;
  const double d_i = damper_.interaction;
  for (int r = 0; r < rows(); ++r) {
    const Pair& pr = pairs_[static_cast<size_t>(r)];
    char& zero = d.jacobian_zero[static_cast<size_t>(r)];
    // The distance first: a pair at or beyond the interaction distance gives a free row (lower
    // bound -inf), which constrains nothing whatever its coefficients. Its Jacobian is computed
    // only when the method reads earlier ticks' Jacobians (TickContext::free_row_jacobians) and
    // the row was active in the previous solve (TaskData::held: it may hold a multiplier then);
    // otherwise its rows of J and A are zeros (written once, when the pair leaves the
    // interaction distance). Its witness points and normal are this tick's in any case
    // (LexDynAH's Hessian weighs the rows by the previous tick's multipliers, which a free row
    // can hold). A row whose Jacobian is wanted before its distance is known gets both from
    // one call.
    const bool held = ctx.free_row_jacobians && d.held[static_cast<size_t>(r)];
    model::CapsuleDistance cd =
        held ? model.capsuleDistance(data, pr.pair, d.J.row(r)) : model.capsuleDistance(data, pr.pair, d.J.row(r).head(0));
    const bool engaged = damperEngaged(cd.distance, d_i);
    const bool jacobian = engaged || held;
    if (!jacobian && !zero) {
      d.J.row(r).setZero();
      d.A.row(r).head(nv_).setZero();
      zero = 1;
    }
    if (jacobian && !held) cd = model.capsuleDistance(data, pr.pair, d.J.row(r));
    double ddot = 0.0;  // the damper does not read it for a free row
    if (jacobian) {
      zero = 0;
      d.A.row(r).head(nv_) = d.J.row(r);
      ddot = d.J.row(r).dot(u);
    }
    d.point_a.col(r) = model.framePlacement(data, pr.frame_a).inverse() * cd.point_a;
    d.point_b.col(r) = model.framePlacement(data, pr.frame_b).inverse() * cd.point_b;
    d.normal.col(r) = cd.normal;
    const double dist = cd.distance;
    double lower;
    if (ctx.domain == Domain::Velocity) {
      lower = damperVelocityBound(dist, ddot, damper_, d.dampers[static_cast<size_t>(r)]);
    } else {
      lower = damperAccelerationBound(dist, ddot, 0.0, ctx.dt, damper_, d.dampers[static_cast<size_t>(r)]);  // Jdot_d u neglected
    }
    d.lower[r] = lower;
    d.upper[r] = std::numeric_limits<double>::infinity();
    d.error[r] = dist;
    d.engaged[static_cast<size_t>(r)] = engaged ? 1 : 0;
  }
}

void SelfCollisionTask::accumulateHessian(const TickContext& ctx, const TaskData& base, const Eigen::Ref<const Eigen::VectorXd>& w,
                                          Eigen::Ref<Eigen::MatrixXd> H) const {
  const auto& d = static_cast<const SelfCollisionTaskData&>(base);
  LEXDYN_ALWAYS_ASSERT(ctx.hessian != nullptr && w.size() == rows(), "self_collision: accumulateHessian needs ctx.hessian, w(rows)");
  for (int r = 0; r < rows(); ++r) {
    if (w[r] == 0.0) continue;
    const Pair& pr = pairs_[static_cast<size_t>(r)];
    const Eigen::Vector3d wn = w[r] * d.normal.col(r);
    // d ~= n^T (p_a - p_b) with n and the witness points held on their bodies.
    hessian::accumulatePointHessian(*ctx.model, *ctx.data, *ctx.hessian, pr.frame_a, d.point_a.col(r), wn, H);
    hessian::accumulatePointHessian(*ctx.model, *ctx.data, *ctx.hessian, pr.frame_b, d.point_b.col(r), -wn, H);
  }
}

void SelfCollisionTask::chainDofs(const model::RobotModel& model, std::vector<char>& mask) const {
  for (const Pair& pr : pairs_) {
    markBodyChain(model, pr.body_a, mask);
    markBodyChain(model, pr.body_b, mask);
  }
}

}  // namespace lexdyn::tasks
