#include "lexdyn/control/augmentation.hpp"

#include <cmath>

#include "lexdyn/common/error.hpp"
#include "lexdyn/control/switching.hpp"
#include "lexdyn/hessian/bfgs.hpp"
#include "lexdyn/hessian/higham.hpp"
#include "lexdyn/hessian/kinematic_hessian.hpp"

namespace lexdyn::control {

namespace {
inline size_t z(int i) { return static_cast<size_t>(i); }
}  // namespace

// One geometric task contributing to a level's hierarchical Hessian (eq. 21).
struct GeomTerm {
  int task = -1;
  int lambda_row = -1;  // first row of the task in the stacked rows of Result::lambda
  int rows = 0;
  bool equality = true;
};

struct AugLevel {
  int level = -1;                // index into the controller's solver levels
  std::vector<GeomTerm> terms;   // geometric tasks of this level and of every earlier level
  std::unique_ptr<hessian::QuasiNewtonMatrix> qn;  // BFGS / SR1 (LexDynBFGS)
  std::vector<char> occupied, prevOccupied;
  bool initialized = false;
  bool augmented = false;
};

struct Augmentation::Impl {
  const model::RobotModel* model = nullptr;
  const ControllerConfig* cfg = nullptr;
  ControllerParams params;
  int nv = 0;
  bool velocity = true;
  std::vector<AugLevel> lv;
  std::vector<int> stackOff;     // problem level -> first stacked row (Result::lambda rows)
  // Previous tick.
  bool havePrev = false;
  std::vector<Eigen::MatrixXd> Jprev;  // per task (geometric tasks only)
  model::Configuration qPrev;
  Eigen::VectorXd uPrev, s, y, w, rhs, acc;
  Eigen::MatrixXd H, R;
  std::vector<int> occList;
  hessian::HighamRegularizer higham;
  hessian::SignChangeGuard guard;
  std::vector<char> taskMask;
};

Augmentation::Augmentation(const model::RobotModel& model, const ControllerConfig& cfg, const tasks::ContactLayout& layout,
                           const solver::Problem& problem, const std::vector<SolverLevel>& levels)
    : impl_(std::make_unique<Impl>()) {
  Impl& I = *impl_;
  I.model = &model;
  I.cfg = &cfg;
  I.params = cfg.params;
  I.nv = model.nv();
  I.velocity = cfg.params.method != Method::WLS;
  (void)layout;
  int off = 0;
  for (int l = 0; l < problem.levelCount(); ++l) {
    I.stackOff.push_back(off);
    off += problem.level(l).rows();
  }
  std::vector<GeomTerm> acc;  // geometric tasks seen so far (levels in order)
  for (size_t k = 0; k < levels.size(); ++k) {
    const SolverLevel& L = levels[k];
    for (const TaskSlot& sl : L.slots) {
      const tasks::TaskModel& tm = *cfg.tasks[z(sl.task)];
      if (!tm.geometric()) continue;
      GeomTerm g;
      g.task = sl.task;
      g.lambda_row = I.stackOff[z(L.problem_level)] + sl.row;
      g.rows = tm.rows();
      g.equality = tm.kind() == tasks::TaskKind::Equality;
      acc.push_back(g);
    }
    if (!L.augmentable) continue;
    AugLevel a;
    a.level = static_cast<int>(k);
    a.terms = acc;
    a.occupied.assign(z(I.nv), 0);
    a.prevOccupied.assign(z(I.nv), 0);
    if (cfg.params.method == Method::LexDynBFGS) {
      const double dt2 = cfg.params.dt * cfg.params.dt;
      hessian::QuasiNewtonOptions qo;
      qo.update = cfg.params.sr1 ? hessian::QuasiNewtonUpdate::Sr1 : hessian::QuasiNewtonUpdate::Bfgs;
      qo.xi = cfg.params.xi_dt2 * dt2;
      qo.eps = cfg.params.eps_dt2 * dt2;
      qo.identity_weight = cfg.params.newton_identity_weight;
      a.qn = hessian::makeQuasiNewton(I.nv, qo);
    }
    I.lv.push_back(std::move(a));
  }
  I.Jprev.resize(cfg.tasks.size());
  for (size_t t = 0; t < cfg.tasks.size(); ++t)
    if (cfg.tasks[t]->geometric()) I.Jprev[t].setZero(cfg.tasks[t]->rows(), I.nv);
  I.qPrev = model.neutralConfiguration();
  for (Eigen::VectorXd* v : {&I.uPrev, &I.s, &I.y, &I.rhs, &I.acc}) v->setZero(I.nv);
  I.w.setZero(64);
  for (const auto& t : cfg.tasks) I.w.conservativeResize(std::max<Eigen::Index>(I.w.size(), t->rows()));
  I.H.setZero(I.nv, I.nv);
  I.R.setZero(I.nv, I.nv);
  I.occList.reserve(z(I.nv));
  I.higham.setup(I.nv);
  I.guard.setup(I.nv);
  I.taskMask.assign(z(I.nv), 0);
}

Augmentation::~Augmentation() = default;

void Augmentation::reset() {
  Impl& I = *impl_;
  I.havePrev = false;
  for (AugLevel& a : I.lv) {
    a.initialized = false;
    a.augmented = false;
    std::fill(a.occupied.begin(), a.occupied.end(), 0);
    std::fill(a.prevOccupied.begin(), a.prevOccupied.end(), 0);
  }
  I.guard.reset();
}

void Augmentation::apply(const tasks::TickContext& ctx, const std::vector<std::unique_ptr<tasks::TaskData>>& td,
                         const std::vector<SolverLevel>& levels, solver::Problem& problem, const solver::Result& last,
                         bool haveLast, const RobotState& state, TickRecord& rec) {
  Impl& I = *impl_;
  const ControllerParams& p = I.params;
  const double dt = p.dt;
  const double dt2 = dt * dt;
  const int nv = I.nv;
  std::fill(rec.level_augmented.begin(), rec.level_augmented.end(), 0);
  std::fill(rec.level_hessian_updated.begin(), rec.level_hessian_updated.end(), 0);
  const bool newton = I.velocity && (p.method == Method::LexDynBFGS || p.method == Method::LexDynAH);

  // Step actually taken since the previous tick, and the sign-change guard (sec. VIII-A).
  if (I.havePrev) {
    I.model->difference(I.qPrev, state.q, I.s);
    if (p.method == Method::LexDynBFGS && p.sign_change_guard) {
      I.acc = (state.u - I.uPrev) / dt;
      I.guard.observe(I.acc);
    }
  }

  for (AugLevel& a : I.lv) {
    const SolverLevel& L = levels[z(a.level)];
    solver::Level& pl = problem.level(L.problem_level);
    auto spareA = pl.A.middleRows(L.spare_row, nv);
    auto spareLo = pl.lower.segment(L.spare_row, nv);
    auto spareUp = pl.upper.segment(L.spare_row, nv);
    spareA.setZero();
    spareLo.setConstant(-solver::kInf);
    spareUp.setConstant(solver::kInf);

    // Occupied dofs (the I* of eq. 89, sec. VII): the chains of the geometric tasks of this level
    // and earlier ones that constrain the solution (equalities always, inequalities while engaged).
    std::fill(a.occupied.begin(), a.occupied.end(), 0);
    for (const GeomTerm& g : a.terms) {
      const tasks::TaskData& d = *td[z(g.task)];
      bool engaged = g.equality;
      for (char e : d.engaged) engaged = engaged || (e != 0);
      if (engaged) I.cfg->tasks[z(g.task)]->chainDofs(*I.model, a.occupied);
    }

    // Constant Levenberg-Marquardt damping (eq. 50 / 81).
    if (p.damping > 0.0) {
      int k = 0;
      for (int i = 0; i < nv; ++i) {
        if (I.velocity && !a.occupied[z(i)]) continue;
        spareA(k, i) = p.damping;
        spareLo(k) = spareUp(k) = 0.0;
        ++k;
      }
      rec.level_augmented[z(L.config_level)] = 1;
      continue;
    }
    if (!newton) continue;

    // Multipliers of this level's problem at the previous solve, in optimisation units (eq. 37).
    const bool haveLambda = haveLast && I.havePrev;
    auto weights = [&](const GeomTerm& g) {
      auto wv = I.w.head(g.rows);
      if (haveLambda) wv = dt * last.lambda.col(L.problem_level).segment(g.lambda_row, g.rows);
      else wv.setZero();
      return wv;
    };

    if (p.method == Method::LexDynBFGS) {
      hessian::QuasiNewtonMatrix& B = *a.qn;
      if (!a.initialized) {
        // eq. 89: max(zeta, 1/2 ||dt edot_PD,i||^2) on the chain of every active task.
        I.rhs.setZero();
        for (const GeomTerm& g : a.terms) {
          const tasks::TaskData& d = *td[z(g.task)];
          bool engaged = g.equality;
          for (char e : d.engaged) engaged = engaged || (e != 0);
          if (!engaged) continue;
          // edot_PD = -(target of the row) (eq. 61): the rows read J u(k+1) = -edot_PD.
          double e2 = 0.0;
          for (int r = 0; r < g.rows; ++r) {
            const double t = std::isfinite(d.lower(r)) && d.lower(r) == d.upper(r) ? d.lower(r) : 0.0;
            e2 += t * t;
          }
          const double v = std::max(p.zeta_dt2 * dt2, 0.5 * dt2 * e2);
          std::fill(I.taskMask.begin(), I.taskMask.end(), 0);
          I.cfg->tasks[z(g.task)]->chainDofs(*I.model, I.taskMask);
          for (int i = 0; i < nv; ++i)
            if (I.taskMask[z(i)]) I.rhs(i) += v;
        }
        B.initialize(I.rhs);
        a.initialized = true;
      } else {
        if (haveLambda) {
          // eq. 88 (sign: y = grad L(k) - grad L(k-1) = sum_i (J_i(k) - J_i(k-1))^T lambda_i).
          I.y.setZero();
          for (const GeomTerm& g : a.terms) {
            const tasks::TaskData& d = *td[z(g.task)];
            hessian::accumulateGradientChange(d.J, I.Jprev[z(g.task)], weights(g), I.y);
          }
          if (B.update(I.s, I.y)) rec.level_hessian_updated[z(L.config_level)] = 1;
        }
        B.setOccupied(a.occupied, p.new_dof_diagonal_dt2 * dt2);  // sec. VII
        if (p.sign_change_guard) {
          for (int dof : I.guard.triggered())
            if (a.occupied[z(dof)]) B.addDiagonal(dof, p.zeta_dt2 * dt2);  // sec. VIII-A
        }
      }
    } else {
      // LexDynAH: eq. 21, skipping |lambda| <= rho.
      I.H.setZero();
      if (haveLambda) {
        for (const GeomTerm& g : a.terms) {
          auto wv = weights(g);
          for (int r = 0; r < g.rows; ++r)
            if (std::abs(wv(r)) <= p.rho_dt2 * dt2) wv(r) = 0.0;
          if (wv.lpNorm<Eigen::Infinity>() == 0.0) continue;
          I.cfg->tasks[z(g.task)]->accumulateHessian(ctx, *td[z(g.task)], wv, I.H);
        }
      }
    }

    // Switching (eq. 95) on the previous tick's task-row violation of this level.
    bool augment = false;
    if (haveLast) {
      LevelOutcome o;
      o.violation_norm = last.violation[z(L.problem_level)].head(L.task_rows).norm();
      if (p.rank_switching) {
        for (int r = 0; r < L.task_rows; ++r) o.held_rows += last.active.level[z(L.problem_level)][z(r)] != solver::RowState::Inactive;
        o.rank = last.rank[z(L.problem_level)];
      }
      augment = switchToNewton(o, dt, p.nu_dt2, p.rank_switching);
    }
    a.augmented = augment;
    if (!augment) continue;
    int rows = 0;
    if (p.method == Method::LexDynBFGS) {
      rows = a.qn->factor(I.R);
    } else {
      rows = I.higham.regularizeAndFactor(I.H, a.occupied, p.eps_dt2 * dt2 + p.newton_identity_weight, I.R, I.occList);
    }
    for (int k = 0; k < rows; ++k) {
      spareA.row(k).head(nv) = I.R.row(k);
      const double target = (p.newton_target == NewtonTarget::PreviousVelocity) ? I.R.row(k).dot(state.u) : 0.0;  // eq. 62 / 35
      spareLo(k) = spareUp(k) = target;
    }
    rec.level_augmented[z(L.config_level)] = rows > 0 ? 1 : 0;
  }
}

void Augmentation::afterSolve(const std::vector<std::unique_ptr<tasks::TaskData>>& td, const RobotState& state) {
  Impl& I = *impl_;
  for (size_t t = 0; t < I.Jprev.size(); ++t)
    if (I.Jprev[t].size() > 0) I.Jprev[t] = td[t]->J;
  I.qPrev = state.q;
  I.uPrev = state.u;
  I.havePrev = true;
}

}  // namespace lexdyn::control
