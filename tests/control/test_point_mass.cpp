// The 1-D point mass of the paper's sec. V-A (Fig. 1): PD control with Levenberg-Marquardt
// damping mu, in the acceleration domain (eq. 47-52) and emulated in the velocity domain
// (eq. 78-83), run through the controller and compared with the paper's recursions and with the
// closed-form solution eq. 49. The loop is closed ideally: the next state is the command.
#include <gtest/gtest.h>

#include <cmath>

#include "lexdyn/control/controller.hpp"
#include "lexdyn/control/method.hpp"
#include "lexdyn/tasks/position.hpp"
#include "../common/expect_text.hpp"

namespace lexdyn::control {
namespace {

const std::string kDir = std::string(LEXDYN_SOURCE_DIR) + "/models/point_mass/";

struct Trajectory {
  std::vector<double> x, v;
};

// x0 = 1, v0 = 0, target x_d = 0.
Trajectory runController(const std::string& method, double kp, double kv, double mu, double dt, int ticks, bool qmod = false) {
  const model::RobotModel m = model::RobotModel::fromFiles(kDir + "point_mass.urdf", kDir + "point_mass.yaml");
  ControllerConfig cfg;
  cfg.params.method = method;
  cfg.params.dt = dt;
  cfg.params.damping = mu;
  cfg.params.use_qmod = qmod;
  tasks::PositionParams pp;
  pp.frame = "mass";
  pp.target = Eigen::Vector3d::Zero();
  pp.gains.kp = kp;
  pp.gains.kv = kv;
  cfg.tasks.push_back(std::make_unique<tasks::PositionTask>("position", m, pp));
  if (method == "wls") {
    cfg.levels = {{"hard", {}, {}}, {"objective", {0}, {1.0}}};
  } else {
    cfg.levels = {{"position", {0}, {}}};
  }
  Controller c(m, std::move(cfg));
  RobotState s;
  s.q = m.neutralConfiguration();
  s.q.joints(0) = 1.0;
  s.u = Eigen::VectorXd::Zero(1);
  c.reset(s);
  Trajectory tr;
  for (int k = 0; k <= ticks; ++k) {
    tr.x.push_back(s.q.joints(0));
    tr.v.push_back(s.u(0));
    if (k == ticks) break;
    const Command& cmd = c.tick(s);
    EXPECT_TRUE(cmd.ok()) << toString(cmd.status);
    s.q = cmd.q;
    s.u = cmd.u;
    s.time += dt;
  }
  return tr;
}

// The trajectory from x = 1, xdot = 0 over `ticks` steps of step(x, xdot).
template <class Step>
Trajectory recursion(int ticks, Step step) {
  Trajectory tr;
  double x = 1.0, v = 0.0;
  for (int k = 0; k <= ticks; ++k) {
    tr.x.push_back(x);
    tr.v.push_back(v);
    step(x, v);
  }
  return tr;
}

// Eq. 78-83: xdot(k+1) = (xdot - dt eddot) / (1 + mu^2), x(k+1) = x + dt xdot(k+1), with
// eddot = -kp e - kv edot, e = x_d - x = -x, edot = -xdot.
Trajectory velocityRecursion(double kp, double kv, double mu, double dt, int ticks) {
  return recursion(ticks, [=](double& x, double& v) {
    const double edd = kp * x + kv * v;
    v = (v - dt * edd) / (1.0 + mu * mu);
    x = x + dt * v;
  });
}

// Eq. 50-52: xddot = -(kv xdot + kp x) / (1 + mu^2); x(k+1) = x + dt xdot + dt^2/2 xddot.
Trajectory accelerationRecursion(double kp, double kv, double mu, double dt, int ticks) {
  return recursion(ticks, [=](double& x, double& v) {
    const double a = -(kv * v + kp * x) / (1.0 + mu * mu);
    x = x + dt * v + 0.5 * dt * dt * a;
    v = v + dt * a;
  });
}

// Closed form of xddot + a xdot + b x = 0, x(0) = 1, xdot(0) = 0 (eq. 49 and its damped
// variants eq. 51).
double closedForm(double a, double b, double t) {
  const double delta = 0.5 * a;
  const double disc = b - delta * delta;
  if (std::abs(disc) < 1e-12 * b) return (1.0 + delta * t) * std::exp(-delta * t);  // critical
  if (disc > 0) {
    const double wd = std::sqrt(disc);
    return std::exp(-delta * t) * (std::cos(wd * t) + delta / wd * std::sin(wd * t));
  }
  const double r = std::sqrt(-disc), r1 = -delta + r, r2 = -delta - r;
  const double c1 = -r2 / (r1 - r2), c2 = r1 / (r1 - r2);
  return c1 * std::exp(r1 * t) + c2 * std::exp(r2 * t);
}

double maxDiff(const Trajectory& a, const Trajectory& b) {
  double d = 0.0;
  for (size_t k = 0; k < a.x.size(); ++k) d = std::max({d, std::abs(a.x[k] - b.x[k]), std::abs(a.v[k] - b.v[k])});
  return d;
}

double minX(const Trajectory& t) { return *std::min_element(t.x.begin(), t.x.end()); }

constexpr double kKp = 1.0;
const double kKv = 2.0 * std::sqrt(kKp);  // kv(kp): critical damping for m = 1
constexpr double kDt = 0.005;
constexpr int kTicks = 4000;  // 20 s

TEST(PointMass, VelocityDomainReproducesEq82And83) {
  for (double mu : {0.0, 0.1, 0.5, 1.0, 3.0}) {
    const Trajectory c = runController("gn", kKp, kKv, mu, kDt, kTicks);
    const Trajectory r = velocityRecursion(kKp, kKv, mu, kDt, kTicks);
    EXPECT_LE(maxDiff(c, r), 1e-12) << "mu " << mu;
  }
}

TEST(PointMass, QmodIntegrationFollowsEq73To76) {
  // q_mod = q + dt (u(k+1) + u) / 2 (eq. 73-76); the velocity update is eq. 79 unchanged.
  const Trajectory c = runController("gn", kKp, kKv, 0.0, kDt, kTicks, true);
  Trajectory r;
  double x = 1.0, v = 0.0;
  for (int k = 0; k <= kTicks; ++k) {
    r.x.push_back(x);
    r.v.push_back(v);
    const double vn = v - kDt * (kKp * x + kKv * v);
    x = x + kDt * 0.5 * (vn + v);
    v = vn;
  }
  EXPECT_LE(maxDiff(c, r), 1e-12);
  // It matches the acceleration-domain positions (eq. 75 = eq. 58) for the same velocities.
  EXPECT_GT(maxDiff(c, runController("gn", kKp, kKv, 0.0, kDt, kTicks)), 1e-4);
}

TEST(PointMass, VelocityDomainDampingDoesNotSpoilTheCriticallyDampedBehaviour) {
  // No overshoot for any damping: the emulated PD keeps converging monotonically (Fig. 1).
  for (double mu : {0.0, 0.1, 0.5, 1.0, 3.0}) {
    const Trajectory c = runController("gn", kKp, kKv, mu, kDt, kTicks);
    EXPECT_GE(minX(c), -1e-12) << "mu " << mu;
    for (size_t k = 1; k < c.x.size(); ++k) ASSERT_LE(c.x[k], c.x[k - 1] + 1e-15) << "mu " << mu << " tick " << k;
  }
}

TEST(PointMass, AccelerationDomainReproducesEq51And52) {
  for (double mu : {0.0, 0.5, 1.0, 3.0}) {
    const Trajectory c = runController("wls", kKp, kKv, mu, kDt, kTicks);
    const Trajectory r = accelerationRecursion(kKp, kKv, mu, kDt, kTicks);
    EXPECT_LE(maxDiff(c, r), 1e-12) << "mu " << mu;
  }
}

TEST(PointMass, AccelerationDomainDampingOvershootsWithKvOfKp) {
  // With kv = kv(kp) the damping makes the system under-damped: overshoot (Fig. 1, dashed).
  const Trajectory c = runController("wls", kKp, kKv, 1.0, kDt, kTicks);
  EXPECT_LT(minX(c), -0.01);
  // Re-tuned kv = 2 sqrt(m (1 + mu^2) kp) restores critical damping: no overshoot.
  const Trajectory d = runController("wls", kKp, 2.0 * std::sqrt(2.0 * kKp), 1.0, kDt, kTicks);
  EXPECT_GE(minX(d), -1e-9);
  // Without damping no overshoot either.
  EXPECT_GE(minX(runController("wls", kKp, kKv, 0.0, kDt, kTicks)), -1e-9);
}

TEST(PointMass, BothDomainsConvergeToTheClosedFormEq49) {
  // Without damping both schemes are first-order discretisations of eq. 48: the error to the
  // closed form eq. 49 halves with dt. The acceleration domain with damping converges to eq. 51.
  struct Case {
    std::string method;
    double mu;
  };
  for (const Case& cs : {Case{"gn", 0.0}, Case{"wls", 0.0}, Case{"wls", 1.0}}) {
    const double a = kKv / (1.0 + cs.mu * cs.mu), b = kKp / (1.0 + cs.mu * cs.mu);
    double err[2];
    for (int i = 0; i < 2; ++i) {
      const double dt = (i == 0) ? 0.01 : 0.005;
      const int ticks = static_cast<int>(std::lround(10.0 / dt));
      const Trajectory c = runController(cs.method, kKp, kKv, cs.mu, dt, ticks);
      err[i] = 0.0;
      for (int k = 0; k <= ticks; ++k) err[i] = std::max(err[i], std::abs(c.x[static_cast<size_t>(k)] - closedForm(a, b, k * dt)));
    }
    EXPECT_LT(err[1], 0.01) << cs.method << " mu " << cs.mu;
    const double ratio = err[1] / err[0];
    EXPECT_GT(ratio, 0.4) << cs.method;
    EXPECT_LT(ratio, 0.6) << cs.method;
  }
}

// A fifth method, registered here and written against the public interface
// (lexdyn/control/method.hpp) only: velocity domain; every geometric level reserves nv rows and
// carries mu u(k+1) = 0 on every dof (eq. 81, mu = ControllerParams::damping). On the point mass
// (one dof, occupied by the position task) this is pure Gauss-Newton with the same damping.
class ToyDamped final : public ControlMethod {
 public:
  explicit ToyDamped(const ControllerParams& p) : p_(p) {}
  tasks::Domain domain() const override { return tasks::Domain::Velocity; }
  bool separatesLevels() const override { return true; }
  bool reservesRows(size_t, bool geometric) const override { return geometric; }
  void setup(const MethodSetup& s) override {
    model_ = &s.model;
    nv_ = s.model.nv();
    ng_ = s.layout.ng();
  }
  void reset() override { ++resets; }
  void addRows(const MethodTick& t, solver::Problem& problem, TickRecord& rec) override {
    for (const SolverLevel& L : t.levels) {
      if (!L.augmentable) continue;
      solver::Level& pl = problem.level(L.problem_level);
      pl.A.middleRows(L.spare_row, nv_).setZero();
      for (int i = 0; i < nv_; ++i) {
        pl.A(L.spare_row + i, i) = p_.damping;
        pl.lower(L.spare_row + i) = pl.upper(L.spare_row + i) = 0.0;
      }
      rec.level_augmented[static_cast<size_t>(L.config_level)] = 1;
    }
  }
  void command(const RobotState& s, const Eigen::VectorXd& x, Command& cmd) override {
    cmd.u = x.head(nv_);
    cmd.udot = (cmd.u - s.u) / p_.dt;
    cmd.gamma = x.tail(ng_) / p_.dt;
    model_->integrate(s.q, cmd.u, p_.dt, cmd.q);  // eq. 32
  }
  void afterSolve(const MethodTick&) override { ++ticks; }

  static int resets, ticks;

 private:
  ControllerParams p_;
  const model::RobotModel* model_ = nullptr;
  int nv_ = 0, ng_ = 0;
};
int ToyDamped::resets = 0;
int ToyDamped::ticks = 0;

TEST(PointMass, AFifthMethodRegisteredByTheTestRunsIt) {
  registerMethod({"toy", "constant damping on every dof of the geometric levels (test)", false, &makeMethodOf<ToyDamped>});
  EXPECT_EQ(methodNames().back(), "toy");
  const Trajectory toy = runController("toy", kKp, kKv, 0.5, kDt, 400);
  EXPECT_EQ(ToyDamped::resets, 1);
  EXPECT_EQ(ToyDamped::ticks, 400);
  // Pure Gauss-Newton with the same damping gives the same trajectory, bit for bit, and both
  // follow eq. 82-83.
  const Trajectory gn = runController("gn", kKp, kKv, 0.5, kDt, 400);
  EXPECT_EQ(toy.x, gn.x);
  EXPECT_EQ(toy.v, gn.v);
  EXPECT_LE(maxDiff(toy, velocityRecursion(kKp, kKv, 0.5, kDt, 400)), 1e-12);
  EXPECT_LT(toy.x.back(), 1.0);
}

TEST(PointMass, IndicesOfTheControllersAccessorsAreChecked) {
  const model::RobotModel m = model::RobotModel::fromFiles(kDir + "point_mass.urdf", kDir + "point_mass.yaml");
  ControllerConfig cfg;
  tasks::PositionParams pp;
  pp.frame = "mass";
  pp.target = Eigen::Vector3d::Zero();
  pp.gains.kp = 1.0;
  cfg.tasks.push_back(std::make_unique<tasks::PositionTask>("position", m, pp));
  cfg.levels = {{"position", {0}, {}}};
  Controller c(m, std::move(cfg));
  EXPECT_EQ(c.task(0).name(), "position");
  EXPECT_EQ(lexdyn::testing::exceptionMessage<std::out_of_range>([&] { (void)c.task(1); }),
            "Controller::task: index 1 out of range [0, 1)");
  EXPECT_THROW((void)c.taskData(-1), std::out_of_range);
  EXPECT_THROW(c.setContactActive(0, true), std::out_of_range);  // no contacts
  EXPECT_THROW((void)c.contactActive(0), std::out_of_range);
}

}  // namespace
}  // namespace lexdyn::control
