#include "lexdyn/control/methods/detail/velocity_domain.hpp"

#include <algorithm>
#include <cmath>

#include "lexdyn/control/switching.hpp"

namespace lexdyn::control::methods {

ReservedRows clearReservedRows(solver::Problem& problem, const SolverLevel& level, int nv, int written) {
  solver::Level& pl = problem.level(level.problem_level);
  ReservedRows r{pl.A.middleRows(level.spare_row, nv), pl.lower.segment(level.spare_row, nv), pl.upper.segment(level.spare_row, nv)};
  if (written < 0) {
    r.A.setZero();
  } else {
    r.A.topLeftCorner(written, nv).setZero();
  }
  r.lower.setConstant(-solver::kInf);
  r.upper.setConstant(solver::kInf);
  return r;
}

void writeDampingRows(ReservedRows& rows, double mu, const std::vector<char>* mask) {
  const int nv = static_cast<int>(rows.lower.size());
  int k = 0;
  for (int i = 0; i < nv; ++i) {
    if (mask && !(*mask)[z(i)]) continue;
    rows.A(k, i) = mu;
    rows.lower(k) = rows.upper(k) = 0.0;
    ++k;
  }
}

namespace {

// Calls f(row of TaskData::A restricted to the velocity columns) for every task row of the
// level with a finite bound.
template <class F>
void forEachConstrainingRow(const SolverLevel& level, const MethodTick& tick, int nv, F&& f) {
  for (const TaskSlot& sl : level.slots) {
    const tasks::TaskData& d = *tick.td[z(sl.task)];
    for (Eigen::Index r = 0; r < d.A.rows(); ++r) {
      if (!std::isfinite(d.lower(r)) && !std::isfinite(d.upper(r))) continue;
      f(d.A.row(r).head(nv));
    }
  }
}

}  // namespace

double levelGaussNewtonTrace(const SolverLevel& level, const MethodTick& tick, int nv) {
  double t = 0.0;
  forEachConstrainingRow(level, tick, nv, [&](const auto& j) { t += j.squaredNorm(); });
  return t;
}

void accumulateLevelGaussNewtonStep(const SolverLevel& level, const MethodTick& tick, const Eigen::Ref<const Eigen::VectorXd>& s,
                                    Eigen::Ref<Eigen::VectorXd> y) {
  const int nv = static_cast<int>(s.size());
  forEachConstrainingRow(level, tick, nv, [&](const auto& j) { y += j.transpose() * j.dot(s); });
}

void accumulateLevelGaussNewton(const SolverLevel& level, const MethodTick& tick, Eigen::Ref<Eigen::MatrixXd> H) {
  const int nv = static_cast<int>(H.rows());
  forEachConstrainingRow(level, tick, nv, [&](const auto& j) { H.noalias() += j.transpose() * j; });
}

bool VelocityDomainMethod::reservesRows(size_t level, bool geometric) const {
  (void)level;
  // Newton rows, or constant damping rows.
  return geometric && (newtonRows() || params_.damping > 0.0);
}

void VelocityDomainMethod::setup(const MethodSetup& s) {
  model_ = &s.model;
  config_ = &s.config;
  nv_ = s.model.nv();
  ng_ = s.layout.ng();
  int off = 0;
  for (int l = 0; l < s.problem.levelCount(); ++l) {
    stack_off_.push_back(off);
    off += s.problem.level(l).rows();
  }
  std::vector<GeomTerm> acc;  // geometric tasks seen so far (levels in order)
  for (size_t k = 0; k < s.levels.size(); ++k) {
    const SolverLevel& L = s.levels[k];
    for (const TaskSlot& sl : L.slots) {
      const tasks::TaskModel& tm = *s.config.tasks[z(sl.task)];
      if (!tm.geometric()) continue;
      GeomTerm g;
      g.task = sl.task;
      g.lambda_row = stack_off_[z(L.problem_level)] + sl.row;
      g.rows = tm.rows();
      g.equality = tm.kind() == tasks::TaskKind::Equality;
      std::vector<char> mask(z(nv_), 0);
      tm.chainDofs(s.model, mask);
      for (int i = 0; i < nv_; ++i)
        if (mask[z(i)]) g.chain.push_back(i);
      acc.push_back(g);
    }
    if (!L.augmentable) continue;
    NewtonLevel a;
    a.level = static_cast<int>(k);
    a.terms = acc;
    a.occupied.assign(z(nv_), 0);
    setupLevel(lv_.size(), a);
    lv_.push_back(std::move(a));
  }
  w_.setZero(64);
  for (const auto& t : s.config.tasks) w_.conservativeResize(std::max<Eigen::Index>(w_.size(), t->rows()));
  qmod_.setZero(nv_);
  R_.setZero(nv_, nv_);
}

void VelocityDomainMethod::reset() {
  have_prev_ = false;
  for (NewtonLevel& a : lv_) {
    std::fill(a.occupied.begin(), a.occupied.end(), 0);
    a.written_rows = -1;
  }
  resetLevels();
}

bool VelocityDomainMethod::engaged(const GeomTerm& g, const tasks::TaskData& d) {
  bool engaged = g.equality;
  for (char e : d.engaged) engaged = engaged || (e != 0);
  return engaged;
}

Eigen::VectorXd::SegmentReturnType VelocityDomainMethod::multipliers(const GeomTerm& g, const SolverLevel& sl, const MethodTick& tick,
                                                                     bool have_lambda) {
  auto wv = w_.head(g.rows);
  if (!have_lambda)
    wv.setZero();
  else if (params_.multiplier_scale == MultiplierScale::Dt)
    wv = params_.dt * tick.last.lambda.col(sl.problem_level).segment(g.lambda_row, g.rows);
  else
    wv = tick.last.lambda.col(sl.problem_level).segment(g.lambda_row, g.rows);
  return wv;
}

void VelocityDomainMethod::addRows(const MethodTick& tick, solver::Problem& problem, TickRecord& rec) {
  const ControllerParams& p = params_;
  const int nv = nv_;
  beginTick(tick);
  for (size_t k = 0; k < lv_.size(); ++k) {
    NewtonLevel& a = lv_[k];
    const SolverLevel& L = tick.levels[z(a.level)];
    // Only the rows written at the last tick need zeroing (most levels are not augmented).
    ReservedRows spare = clearReservedRows(problem, L, nv, a.written_rows);
    a.written_rows = 0;

    // Occupied dofs (the I* of eq. 89, sec. VII): the chains of the geometric tasks of this level
    // and earlier ones that constrain the solution (equalities always, inequalities while engaged).
    std::fill(a.occupied.begin(), a.occupied.end(), 0);
    for (const GeomTerm& g : a.terms) {
      if (engaged(g, *tick.td[z(g.task)]))
        for (int i : g.chain) a.occupied[z(i)] = 1;
    }

    // Constant Levenberg-Marquardt damping (eq. 81).
    if (p.damping > 0.0) {
      writeDampingRows(spare, p.damping, &a.occupied);
      a.written_rows = nv;
      rec.level_augmented[z(L.config_level)] = 1;
      int m = 0;
      for (char o : a.occupied) m += o ? 1 : 0;
      const double jtj = levelGaussNewtonTrace(L, tick, nv);
      rec.level_second_order_ratio[L.config_level] = p.damping * p.damping * m / jtj;
      rec.level_curvature_ratio[L.config_level] = 0.0;
      continue;
    }
    if (!newtonRows()) continue;

    // The second-order term of the level, with the multipliers of the previous solve.
    const bool have_lambda = tick.have_last && have_prev_;
    prepareLevel(k, a, L, tick, have_lambda, rec);

    // Switching (eq. 95) on the previous tick's task-row violation of this level.
    bool augment = false;
    if (tick.have_last) {
      LevelOutcome o;
      o.violation_norm = tick.last.violation[z(L.problem_level)].head(L.task_rows).norm();
      if (p.rank_switching) {
        for (int r = 0; r < L.task_rows; ++r) o.held_rows += tick.last.active.level[z(L.problem_level)][z(r)] != solver::RowState::Inactive;
        o.rank = tick.last.rank[z(L.problem_level)];
      }
      augment = switchToNewton(o, p.dt, p.nu_dt2, p.rank_switching);
    }
    if (!augment) continue;
    const int rows = factorLevel(k, a, L, tick, have_lambda, R_);
    a.written_rows = rows;
    for (int r = 0; r < rows; ++r) {
      spare.A.row(r).head(nv) = R_.row(r);
      const double target = (p.newton_target == NewtonTarget::PreviousVelocity) ? R_.row(r).dot(tick.state.u) : 0.0;  // eq. 62 / 35
      spare.lower(r) = spare.upper(r) = target;
    }
    rec.level_augmented[z(L.config_level)] = rows > 0 ? 1 : 0;
    if (rows > 0) {
      // Size of the second-order term against the level's Gauss-Newton term.
      const double jtj = levelGaussNewtonTrace(L, tick, nv);
      const double added = R_.topRows(rows).squaredNorm();  // trace(R^T R)
      int m = 0;
      for (char o : a.occupied) m += o ? 1 : 0;
      rec.level_second_order_ratio[L.config_level] = added / jtj;
      rec.level_curvature_ratio[L.config_level] = (added - m * identityDiagonal(k)) / jtj;
    }
  }
}

void VelocityDomainMethod::command(const RobotState& s, const Eigen::VectorXd& x, Command& cmd) {
  const double dt = params_.dt;
  cmd.u = x.head(nv_);
  cmd.udot = (cmd.u - s.u) / dt;
  cmd.gamma = x.tail(ng_) / dt;
  if (params_.use_qmod) {
    // eq. 73-76: q_mod = q + dt (u(k+1) + u) / 2.
    qmod_ = 0.5 * (cmd.u + s.u);
    model_->integrate(s.q, qmod_, dt, cmd.q);
  } else {
    model_->integrate(s.q, cmd.u, dt, cmd.q);  // eq. 32
  }
}

void VelocityDomainMethod::afterSolve(const MethodTick& tick) {
  storePrevious(tick);
  have_prev_ = true;
}

}  // namespace lexdyn::control::methods
