#include "lexdyn/control/controller.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

#include "lexdyn/common/error.hpp"
#include "lexdyn/control/method.hpp"
#include "lexdyn/hessian/kinematic_hessian.hpp"
#include "lexdyn/tasks/contact_jacobian.hpp"
#include "lexdyn/tasks/equation_of_motion.hpp"

namespace lexdyn::control {

namespace {

using Clock = std::chrono::steady_clock;
inline double us(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::micro>(b - a).count(); }
inline size_t z(int i) { return static_cast<size_t>(i); }

}  // namespace

const char* toString(TickStatus s) {
  switch (s) {
    case TickStatus::Ok:
      return "ok";
    case TickStatus::SolverStoppedEarly:
      return "solver_stopped_early";
    case TickStatus::SolverIterationLimit:
      return "solver_iteration_limit";
    case TickStatus::Infeasible:
      return "infeasible";
    case TickStatus::NonFinite:
      return "non_finite";
  }
  return "unknown";
}

struct Controller::Impl {
  const model::RobotModel* model = nullptr;
  ControllerConfig cfg;
  tasks::ContactLayout layout;
  model::ModelData data;
  std::vector<std::unique_ptr<tasks::TaskData>> td;
  tasks::TaskModel* taskPtr(int i) const { return cfg.tasks[z(i)].get(); }

  std::unique_ptr<ControlMethod> method;  // lexdyn/control/methods (registry)
  int nv = 0, nx = 0, nj = 0, ng = 0;
  std::vector<char> contactActive;
  std::vector<char> used;  // per task: referenced by a level

  // Solver problem.
  solver::Problem problem;
  solver::Solver solver;
  std::vector<SolverLevel> levels;  // general solver levels, in order
  bool hasBounds = false;
  std::vector<int> boundsTasks;  // tasks in the bounds level, with their first row
  std::vector<int> boundsFirstRow;
  bool warm = false;

  // Per-tick buffers.
  Eigen::MatrixXd M;
  Eigen::VectorXd N;
  tasks::TickContext ctx;
  Eigen::MatrixXd Jp;                   // 3 x nv point Jacobian
  Eigen::MatrixXd JcT;                  // nv x ng, shared by the dynamics tasks (ctx.JcT)
  std::vector<Eigen::MatrixXd> pointJ;  // with JcT: each contact point's 3 x nv Jacobian of the tick
  bool sharedJcT = false;               // more than one used dynamics task
  bool firstFill = true;                // fillRows has not run yet (it checks velocity-only rows then)
  Eigen::Matrix<double, 3, 4> D;
  Eigen::VectorXd genForce;  // nv
  Command cmd;
  TickRecord rec;

  std::unique_ptr<hessian::KinematicHessianWorkspace> hws;  // analytic Hessians (needsKinematicHessians)

  Impl(const model::RobotModel& m, ControllerConfig c);
  void buildLevels();
  void fillRows();
  void finishTick(const RobotState& s);
};

Controller::Impl::Impl(const model::RobotModel& m, ControllerConfig c) : model(&m), cfg(std::move(c)), data(m.createData()) {
  const ControllerParams& p = cfg.params;
  if (!(p.dt > 0.0)) throw InputError("controller.dt", "expected a positive control period");
  method = makeMethod(p, "controller.method");
  nv = m.nv();
  nj = m.numJoints();
  layout = tasks::ContactLayout(nv, cfg.contacts);
  ng = layout.ng();
  nx = layout.nx();
  contactActive.assign(z(layout.count()), 0);
  for (const std::string& name : cfg.initial_contacts) {
    const int c = layout.find(name);
    if (c < 0) throw InputError("controller.initial_contacts", "unknown contact \"" + name + "\"");
    contactActive[z(c)] = 1;
  }
  const tasks::Domain dom = method->domain();
  // Tasks not used by any level are allowed (a case may define tasks for some methods only):
  // they are neither checked nor computed.
  used.assign(cfg.tasks.size(), 0);
  for (const LevelSpec& ls : cfg.levels)
    for (int t : ls.tasks)
      if (t >= 0 && t < static_cast<int>(cfg.tasks.size())) used[z(t)] = 1;
  for (size_t i = 0; i < cfg.tasks.size(); ++i) {
    const tasks::TaskModel& t = *cfg.tasks[i];
    if (used[i] && !t.supports(dom)) {
      throw InputError("task \"" + t.name() + "\"", std::string("does not support the ") +
                                                        (dom == tasks::Domain::Velocity ? "velocity" : "acceleration") +
                                                        " domain of method " + p.method);
    }
    td.push_back(t.createData(layout));
  }
  buildLevels();
  M.setZero(nv, nv);
  N.setZero(nv);
  Jp.setZero(3, nv);
  genForce.setZero(nv);
  // Jc^T is the same for every dynamics task of a tick (the unactuated and the actuated rows of
  // eq. 86): computed once when more than one is used.
  int dynamicsTasks = 0;
  for (size_t i = 0; i < cfg.tasks.size(); ++i)
    if (used[i] && dynamic_cast<const tasks::DynamicsTask*>(cfg.tasks[i].get()) != nullptr) ++dynamicsTasks;
  sharedJcT = dynamicsTasks > 1;
  if (sharedJcT) {
    JcT.setZero(nv, layout.ng());
    ctx.JcT = &JcT;
    pointJ.assign(static_cast<size_t>(layout.ng() / 4), Eigen::MatrixXd::Zero(3, nv));
  }
  ctx.model = model;
  ctx.data = &data;
  ctx.contacts = &layout;
  ctx.contact_active = &contactActive;
  ctx.dt = p.dt;
  ctx.domain = dom;
  ctx.M = &M;
  ctx.N = &N;
  ctx.free_row_jacobians = method->readsPreviousJacobians();
  if (method->needsKinematicHessians()) {
    hws = std::make_unique<hessian::KinematicHessianWorkspace>(m);
    ctx.hessian = hws.get();
  }
  cmd.q = m.neutralConfiguration();
  cmd.u.setZero(nv);
  cmd.udot.setZero(nv);
  cmd.tau.setZero(nj);
  cmd.gamma.setZero(ng);
  const int nt = static_cast<int>(cfg.tasks.size());
  rec.task_error_norm.setZero(nt);
  rec.task_active_rows.assign(z(nt), 0);
  rec.task_engaged_rows.assign(z(nt), 0);
  rec.level_augmented.assign(cfg.levels.size(), 0);
  rec.level_hessian_updated.assign(cfg.levels.size(), 0);
  rec.level_violation.setZero(static_cast<Eigen::Index>(cfg.levels.size()));
  rec.level_second_order_ratio.setConstant(static_cast<Eigen::Index>(cfg.levels.size()), std::numeric_limits<double>::quiet_NaN());
  rec.level_curvature_ratio.setConstant(static_cast<Eigen::Index>(cfg.levels.size()), std::numeric_limits<double>::quiet_NaN());
  rec.contact_wrench.setZero(6, layout.count());
}

void Controller::Impl::buildLevels() {
  const ControllerParams& p = cfg.params;
  const ControlMethod& meth = *method;
  const int nt = static_cast<int>(cfg.tasks.size());
  std::vector<int> seen(z(nt), 0);
  for (size_t l = 0; l < cfg.levels.size(); ++l) {
    const LevelSpec& ls = cfg.levels[l];
    for (int t : ls.tasks) {
      if (t < 0 || t >= nt) throw InputError("level \"" + ls.name + "\"", "task index " + std::to_string(t) + " out of range");
      if (seen[z(t)]++) throw InputError("level \"" + ls.name + "\"", "task \"" + taskPtr(t)->name() + "\" appears twice in the hierarchy");
    }
    if (!ls.weights.empty() && ls.weights.size() != ls.tasks.size())
      throw InputError("level \"" + ls.name + "\"", "weights must match the tasks one to one");
  }
  meth.checkLevels(cfg);

  // Bounds level: every bounds task, each variable at most once.
  std::vector<int> varOwner(z(nx), -1);
  std::vector<int> boundVars;
  std::vector<int> vars;
  for (const LevelSpec& ls : cfg.levels) {
    for (int t : ls.tasks) {
      const tasks::TaskModel& tm = *taskPtr(t);
      if (tm.kind() != tasks::TaskKind::Bounds) continue;
      tm.boundVariables(layout, vars);
      if (static_cast<int>(vars.size()) != tm.rows())
        throw InputError("task \"" + tm.name() + "\"", "bounds task returned a wrong number of variables");
      for (int v : vars) {
        if (v < 0 || v >= nx) throw InputError("task \"" + tm.name() + "\"", "bound variable out of range");
        if (varOwner[z(v)] >= 0) {
          throw InputError("task \"" + tm.name() + "\"",
                           "bounds variable " + std::to_string(v) + " already bounded by task \"" + taskPtr(varOwner[z(v)])->name() + "\"");
        }
        varOwner[z(v)] = t;
      }
      boundsTasks.push_back(t);
      boundsFirstRow.push_back(static_cast<int>(boundVars.size()));
      boundVars.insert(boundVars.end(), vars.begin(), vars.end());
    }
  }
  problem = solver::Problem(nx);
  hasBounds = !boundVars.empty();
  if (hasBounds) {
    const int m = static_cast<int>(boundVars.size());
    problem.addBoundsLevel("bounds", boundVars, Eigen::VectorXd::Ones(m), Eigen::VectorXd::Zero(m), Eigen::VectorXd::Zero(m));
  }

  auto addLevel = [&](SolverLevel lv, const std::string& name) {
    int rows = lv.task_rows;
    if (lv.augmentable) {
      lv.spare_row = rows;
      rows += nv;
    }
    lv.problem_level = problem.addLevel(name, Eigen::MatrixXd::Zero(rows, nx), Eigen::VectorXd::Constant(rows, -solver::kInf),
                                        Eigen::VectorXd::Constant(rows, solver::kInf));
    // Velocity-only task rows and the method's reserved rows (written on the velocity columns):
    // the solver multiplies the first nv columns only.
    bool velocityOnly = true;
    for (const TaskSlot& s : lv.slots) velocityOnly = velocityOnly && s.velocity_only;
    if (velocityOnly) problem.setLevelColumns(lv.problem_level, nv);
    levels.push_back(std::move(lv));
  };
  for (size_t l = 0; l < cfg.levels.size(); ++l) {
    const LevelSpec& ls = cfg.levels[l];
    // Tasks that must be alone first (equation of motion), then the others.
    SolverLevel sep, rest;
    sep.config_level = rest.config_level = static_cast<int>(l);
    sep.separate = true;
    for (size_t k = 0; k < ls.tasks.size(); ++k) {
      const int t = ls.tasks[k];
      const tasks::TaskModel& tm = *taskPtr(t);
      if (tm.kind() == tasks::TaskKind::Bounds || tm.rows() == 0) continue;
      const bool alone = meth.separatesLevels() && tm.separateLevel() && ls.tasks.size() > 1;
      SolverLevel& target = alone ? sep : rest;
      TaskSlot slot;
      slot.task = t;
      slot.row = target.task_rows;
      slot.scale = meth.rowScale(ls, l, k);
      slot.velocity_only = tm.velocityOnly();
      slot.constant = tm.constantMatrix();
      target.slots.push_back(slot);
      target.task_rows += tm.rows();
      if (tm.geometric()) target.augmentable = true;
    }
    if (!sep.slots.empty()) {
      sep.augmentable = false;
      addLevel(std::move(sep), ls.name + "/separate");
    }
    // Rows for the method's second-order terms (Newton, damping).
    rest.augmentable = meth.reservesRows(l, rest.augmentable);
    if (!rest.slots.empty() || rest.augmentable) addLevel(std::move(rest), ls.name);
  }
  solver::Options so = p.solver;
  // Split coordinates: the velocities are variables 0 .. nv - 1, the contact forces follow.
  if (so.split_from_variable == solver::Options::kSplitAtControllerForces) so.split_from_variable = nv;
  if (!p.stop_after_level.empty()) {
    // The paper's early stop applies once this configured level is optimal (sec. VIII-B): its last
    // solver level (a bounds-only level is the solver's bounds level).
    int cl = -1;
    std::string names;
    for (size_t l = 0; l < cfg.levels.size(); ++l) {
      if (cfg.levels[l].name == p.stop_after_level) cl = static_cast<int>(l);
      names += (l ? ", " : "") + cfg.levels[l].name;
    }
    if (cl < 0) throw InputError("controller.stop_after_level", "unknown level \"" + p.stop_after_level + "\" (levels: " + names + ")");
    int pl = hasBounds ? 0 : -1;
    for (const SolverLevel& lv : levels)
      if (lv.config_level == cl) pl = std::max(pl, lv.problem_level);
    so.stop_after_level = pl;
  }
  solver.setup(problem, so);
  method->setup(MethodSetup{*model, cfg, layout, problem, levels});
}

void Controller::Impl::fillRows() {
  // Bounds level.
  if (hasBounds) {
    solver::Level& bl = problem.level(0);
    for (size_t i = 0; i < boundsTasks.size(); ++i) {
      const tasks::TaskData& d = *td[z(boundsTasks[i])];
      const int m = static_cast<int>(d.lower.size());
      bl.lower.segment(boundsFirstRow[i], m) = d.lower;
      bl.upper.segment(boundsFirstRow[i], m) = d.upper;
    }
  }
  for (const SolverLevel& lv : levels) {
    solver::Level& pl = problem.level(lv.problem_level);
    for (const TaskSlot& s : lv.slots) {
      const tasks::TaskData& d = *td[z(s.task)];
      const int m = static_cast<int>(d.lower.size());
      // Velocity-only rows: the problem's columns past nv stay zero and only the velocity columns
      // are copied. The task's own are checked at the first copy (in debug builds at every one).
#ifdef NDEBUG
      const bool check = s.velocity_only && firstFill;
#else
      const bool check = s.velocity_only;
#endif
      if (check)
        LEXDYN_ALWAYS_ASSERT((d.A.rightCols(nx - nv).array() == 0.0).all(),
                             "task \"" + cfg.tasks[z(s.task)]->name() + "\" declares velocity-only rows but writes other columns");
      const int cols = s.velocity_only ? nv : nx;
      // A constant matrix (rows that are variables themselves) is in the problem after the first copy.
      const bool copyA = !s.constant || firstFill;
      if (s.scale == 1.0) {
        if (copyA) pl.A.middleRows(s.row, m).leftCols(cols) = d.A.leftCols(cols);
        pl.lower.segment(s.row, m) = d.lower;
        pl.upper.segment(s.row, m) = d.upper;
      } else {
        if (copyA) pl.A.middleRows(s.row, m).leftCols(cols) = s.scale * d.A.leftCols(cols);
        pl.lower.segment(s.row, m) = s.scale * d.lower;
        pl.upper.segment(s.row, m) = s.scale * d.upper;
      }
    }
  }
  firstFill = false;
}

void Controller::Impl::finishTick(const RobotState& s) {
  const solver::Result& r = solver.result();
  method->command(s, r.x, cmd);
  // Generalized forces M udot + N - Jc^T gamma: the actuated rows are the joint torques; contact
  // wrenches from the generators.
  genForce.noalias() = M * cmd.udot;
  genForce += N;
  rec.contact_wrench.setZero();
  for (int c = 0; c < layout.count(); ++c) {
    if (!contactActive[z(c)]) continue;
    const tasks::ContactSpec& cs = layout.contact(c);
    const Eigen::Isometry3d X = model->framePlacement(data, cs.frame);
    tasks::ContactLayout::generators(cs, X.linear(), D);
    for (size_t pt = 0; pt < cs.points.size(); ++pt) {
      const Eigen::Vector3d f = D * cmd.gamma.segment(layout.offset(c) + 4 * static_cast<int>(pt), 4);
      // The point's Jacobian of this tick, from the tasks' Jc^T when it was computed there.
      const Eigen::MatrixXd* J = &Jp;
      if (sharedJcT)
        J = &pointJ[static_cast<size_t>(layout.offset(c) / 4) + pt];
      else
        model->pointJacobian(data, cs.frame, cs.points[pt], Jp);
      genForce.noalias() -= J->transpose() * f;
      const Eigen::Vector3d pw = X * cs.points[pt];
      rec.contact_wrench.col(c).head<3>() += f;
      rec.contact_wrench.col(c).tail<3>() += (pw - X.translation()).cross(f);
    }
  }
  cmd.tau = genForce.tail(nj);
  rec.com = model->centerOfMass(data);
}

Controller::Controller(const model::RobotModel& model, ControllerConfig config) : impl_(std::make_unique<Impl>(model, std::move(config))) {}
Controller::~Controller() = default;
Controller::Controller(Controller&&) noexcept = default;
Controller& Controller::operator=(Controller&&) noexcept = default;

void Controller::reset(const RobotState& s) {
  Impl& I = *impl_;
  I.warm = false;
  for (size_t i = 0; i < I.td.size(); ++i) {
    I.cfg.tasks[i]->reset(*I.td[i]);
    std::fill(I.td[i]->held.begin(), I.td[i]->held.end(), 0);
  }
  I.method->reset();
  I.cmd.q = s.q;
  I.cmd.u = s.u;
  I.cmd.udot.setZero();
}

const Command& Controller::tick(const RobotState& s) {
  Impl& I = *impl_;
  const auto t0 = Clock::now();
  // 1. Model.
  I.model->update(I.data, s.q, s.u);
  I.model->massMatrix(I.data, I.M);
  I.model->nonlinearEffects(I.data, I.N);
  I.ctx.q = &s.q;
  I.ctx.u = &s.u;
  I.ctx.time = s.time;
  const auto t1 = Clock::now();
  if (I.hws) I.hws->update(*I.model, I.data);
  // 2. Tasks.
  if (I.sharedJcT) tasks::contactJacobianTranspose(I.ctx, I.Jp, I.JcT, &I.pointJ);
  for (size_t i = 0; i < I.td.size(); ++i)
    if (I.used[i]) I.cfg.tasks[i]->compute(I.ctx, *I.td[i]);
  I.fillRows();
  const auto t2 = Clock::now();
  // 3. The method's rows (Newton, damping) in the reserved rows of the levels.
  const MethodTick mt{I.ctx, I.td, I.levels, s, I.solver.result(), I.warm};
  std::fill(I.rec.level_augmented.begin(), I.rec.level_augmented.end(), 0);
  std::fill(I.rec.level_hessian_updated.begin(), I.rec.level_hessian_updated.end(), 0);
  I.rec.level_second_order_ratio.setConstant(std::numeric_limits<double>::quiet_NaN());
  I.rec.level_curvature_ratio.setConstant(std::numeric_limits<double>::quiet_NaN());
  I.method->addRows(mt, I.problem, I.rec);
  const auto t3 = Clock::now();
  // 4. Solve, warm-started from the previous tick.
  const solver::Result& r = I.warm ? I.solver.solve(I.problem, I.solver.result().active, I.solver.result().x) : I.solver.solve(I.problem);
  I.warm = true;
  const auto t4 = Clock::now();
  // 5. Command and record.
  TickStatus st = TickStatus::Ok;
  if (r.status == solver::Status::NonFiniteInput || r.status == solver::Status::NonFiniteResult || !r.x.allFinite()) {
    st = TickStatus::NonFinite;
  } else if (r.status == solver::Status::IterationLimit) {
    st = TickStatus::SolverIterationLimit;
  } else if (r.status == solver::Status::StoppedEarly) {
    st = TickStatus::SolverStoppedEarly;
  }
  if (st != TickStatus::NonFinite) {
    I.finishTick(s);
    st = I.method->checkSolution(I.problem, r, st);
    if (!I.cmd.u.allFinite() || !I.cmd.tau.allFinite()) st = TickStatus::NonFinite;
  }
  I.cmd.status = st;
  I.method->afterSolve(mt);

  TickRecord& rec = I.rec;
  rec.time = s.time;
  rec.status = st;
  rec.solver_status = r.status;
  rec.iterations = r.iterations;
  rec.optimality_iterations = r.optimality_iterations;
  rec.factorizations = r.factorizations;
  for (size_t i = 0; i < I.td.size(); ++i) {
    const tasks::TaskData& d = *I.td[i];
    rec.task_error_norm(static_cast<Eigen::Index>(i)) = d.error.norm();
    int engaged = 0;
    for (char e : d.engaged) engaged += e ? 1 : 0;
    rec.task_engaged_rows[i] = engaged;
    rec.task_active_rows[i] = 0;
  }
  // TaskData::held: the task's rows active in this solve (read at the next tick), from the
  // problem level's states starting at row `first`; their count is recorded.
  auto recordHeld = [&](int t, const std::vector<solver::RowState>& states, int first) {
    std::vector<char>& h = I.td[z(t)]->held;
    int held = 0;
    for (size_t k = 0; k < h.size(); ++k) {
      h[k] = states[z(first) + k] != solver::RowState::Inactive ? 1 : 0;
      held += h[k];
    }
    rec.task_active_rows[z(t)] = held;
  };
  for (size_t b = 0; b < I.boundsTasks.size(); ++b) recordHeld(I.boundsTasks[b], r.active.level[0], I.boundsFirstRow[b]);
  rec.level_violation.setZero();
  for (const SolverLevel& lv : I.levels) {
    for (const TaskSlot& sl : lv.slots) recordHeld(sl.task, r.active.level[z(lv.problem_level)], sl.row);
    const double v = r.violation[z(lv.problem_level)].head(lv.task_rows).norm();
    double& lvv = rec.level_violation(lv.config_level);
    lvv = std::sqrt(lvv * lvv + v * v);
  }
  const auto t5 = Clock::now();
  rec.model_us = us(t0, t1);
  rec.tasks_us = us(t1, t2);
  rec.hessian_us = us(t2, t3);
  rec.solver_us = us(t3, t4);
  rec.tick_us = us(t0, t5);
  return I.cmd;
}

const TickRecord& Controller::record() const { return impl_->rec; }
const Command& Controller::command() const { return impl_->cmd; }
const solver::Result& Controller::solverResult() const { return impl_->solver.result(); }
const solver::Problem& Controller::problem() const { return impl_->problem; }
const solver::Options& Controller::solverOptions() const { return impl_->solver.options(); }
const ControllerConfig& Controller::config() const { return impl_->cfg; }
const tasks::ContactLayout& Controller::contacts() const { return impl_->layout; }
const model::RobotModel& Controller::model() const { return *impl_->model; }
const model::ModelData& Controller::modelData() const { return impl_->data; }
int Controller::taskCount() const { return static_cast<int>(impl_->cfg.tasks.size()); }
const tasks::TaskModel& Controller::task(int i) const {
  checkIndex("Controller::task", i, static_cast<long>(impl_->cfg.tasks.size()));
  return *impl_->cfg.tasks[z(i)];
}
const tasks::TaskData& Controller::taskData(int i) const {
  checkIndex("Controller::taskData", i, static_cast<long>(impl_->td.size()));
  return *impl_->td[z(i)];
}
int Controller::levelCount() const { return static_cast<int>(impl_->cfg.levels.size()); }

int Controller::taskIndex(const std::string& name) const {
  const auto& ts = impl_->cfg.tasks;
  std::string known;
  for (size_t i = 0; i < ts.size(); ++i) {
    if (ts[i]->name() == name) return static_cast<int>(i);
    known += (known.empty() ? "" : ", ") + ts[i]->name();
  }
  throw InputError("task \"" + name + "\"", "unknown task (known: " + known + ")");
}

void Controller::setTaskTarget(int task, const Eigen::Ref<const Eigen::VectorXd>& target) {
  impl_->cfg.tasks[z(task)]->setTarget(*impl_->td[z(task)], target);
}

int Controller::contactIndex(const std::string& name) const {
  const int c = impl_->layout.find(name);
  if (c < 0) {
    std::string known;
    for (int i = 0; i < impl_->layout.count(); ++i) known += (i ? ", " : "") + impl_->layout.contact(i).name;
    throw InputError("contact \"" + name + "\"", "unknown contact (known: " + known + ")");
  }
  return c;
}

void Controller::setContactActive(int contact, bool active) {
  checkIndex("Controller::setContactActive", contact, static_cast<long>(impl_->contactActive.size()));
  impl_->contactActive[z(contact)] = active ? 1 : 0;
}
bool Controller::contactActive(int contact) const {
  checkIndex("Controller::contactActive", contact, static_cast<long>(impl_->contactActive.size()));
  return impl_->contactActive[z(contact)] != 0;
}

}  // namespace lexdyn::control
