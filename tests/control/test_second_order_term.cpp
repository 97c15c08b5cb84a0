// The size of the Newton rows against the Gauss-Newton term (TickRecord::level_second_order_ratio,
// level_curvature_ratio; trace channels level.<L>.second_order_ratio, .curvature_ratio) and the
// readings of eq. 87-89 (ControllerParams::bfgs_secant, ah_add_jtj, multiplier_scale), on the
// planar 3R arm driven to an out-of-reach target (trust region, position task, minimum
// velocity), in an ideal loop (the next state is the command).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "lexdyn/control/controller.hpp"
#include "lexdyn/tasks/position.hpp"
#include "lexdyn/tasks/trust_region.hpp"
#include "lexdyn/tasks/velocity_min.hpp"

namespace lexdyn::control {
namespace {

const std::string kDir = std::string(LEXDYN_SOURCE_DIR) + "/models/planar_3r/";
constexpr double kDt = 0.005;
constexpr int kToolLevel = 1;  // configured levels: trust, tool, velocity

struct Tick {
  bool augmented = false;
  double ratio = 0.0, curvature = 0.0;
  double recomputed = 0.0;  // trace(R^T R) / trace(J^T J) from the solver problem's rows
  int occupied = 0;         // rows of R written (occupied dofs)
  double jtj = 0.0;
};

std::vector<Tick> run(const ControllerParams& params, double seconds) {
  const model::RobotModel m = model::RobotModel::fromFiles(kDir + "planar_3r.urdf", kDir + "planar_3r.yaml");
  ControllerConfig cfg;
  cfg.params = params;
  tasks::PositionParams pp;
  pp.frame = "tool";
  pp.target = Eigen::Vector3d(2.0, 0.0, 0.5);
  pp.gains.kp = 10.0;
  cfg.tasks.push_back(std::make_unique<tasks::PositionTask>("tool", m, pp));
  cfg.tasks.push_back(std::make_unique<tasks::VelocityMinTask>("velocity", m));
  cfg.tasks.push_back(std::make_unique<tasks::TrustRegionTask>("trust", m));
  cfg.levels = {{"trust", {2}, {}}, {"tool", {0}, {}}, {"velocity", {1}, {}}};
  Controller c(m, std::move(cfg));
  RobotState s;
  s.q = m.neutralConfiguration();
  s.q.joints = m.posture("bent");
  s.u = Eigen::VectorXd::Zero(3);
  c.reset(s);
  const int nv = m.nv();
  std::vector<Tick> out;
  for (int k = 0; k < static_cast<int>(std::lround(seconds / kDt)); ++k) {
    const Command& cmd = c.tick(s);
    EXPECT_TRUE(cmd.ok());
    const TickRecord& r = c.record();
    Tick t;
    t.augmented = r.level_augmented[kToolLevel] != 0;
    t.ratio = r.level_second_order_ratio(kToolLevel);
    t.curvature = r.level_curvature_ratio(kToolLevel);
    // The tool level of the solver: 3 task rows, then nv reserved rows (the Newton rows).
    const solver::Problem& p = c.problem();
    for (int l = 0; l < p.levelCount(); ++l) {
      const solver::Level& pl = p.level(l);
      if (pl.rows() != 3 + nv) continue;
      t.jtj = pl.A.topRows(3).leftCols(nv).squaredNorm();
      const auto R = pl.A.middleRows(3, nv).leftCols(nv);
      t.recomputed = R.squaredNorm() / t.jtj;
      for (int i = 0; i < nv; ++i) t.occupied += R.row(i).squaredNorm() > 0.0 ? 1 : 0;
    }
    out.push_back(t);
    s.q = cmd.q;
    s.u = cmd.u;
    s.time += kDt;
  }
  return out;
}

ControllerParams params(const std::string& method) {
  ControllerParams p;
  p.method = method;
  return p;
}

int firstAugmented(const std::vector<Tick>& ticks) {
  for (size_t k = 0; k < ticks.size(); ++k)
    if (ticks[k].augmented) return static_cast<int>(k);
  return -1;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? std::nan("") : v[v.size() / 2];
}

double medianCurvature(const std::vector<Tick>& ticks) {
  std::vector<double> v;
  for (const Tick& t : ticks)
    if (t.augmented) v.push_back(t.curvature);
  return median(v);
}

TEST(SecondOrderTerm, RatioIsTraceOfTheNewtonRowsOverTraceOfJtJ) {
  for (const std::string method : {"bfgs", "ah"}) {
    ControllerParams p = params(method);
    p.newton_identity_weight = 1e-4;
    const std::vector<Tick> ticks = run(p, 6.0);
    int augmented = 0;
    for (const Tick& t : ticks) {
      if (!t.augmented) {
        // Not augmented: no value (the rows are free).
        EXPECT_TRUE(std::isnan(t.ratio)) << method;
        EXPECT_TRUE(std::isnan(t.curvature)) << method;
        continue;
      }
      ++augmented;
      ASSERT_GT(t.jtj, 0.0);
      EXPECT_NEAR(t.ratio, t.recomputed, 1e-12 * t.recomputed) << method;
      // The curvature term is what remains without the identity terms on the occupied dofs.
      const double identity = (method == "ah" ? 1e-3 * kDt * kDt : 0.0) + 1e-4;
      EXPECT_NEAR(t.curvature, t.ratio - t.occupied * identity / t.jtj, 1e-9 * t.ratio) << method;
      EXPECT_GE(t.curvature, -1e-12) << method;
    }
    EXPECT_GT(augmented, 500) << method;
  }
}

TEST(SecondOrderTerm, DefaultReadingsGiveATermFarBelowJtJ) {
  // eq. 37 with the multipliers of the last solve: the second-order term is tiny against J^T J.
  for (const std::string method : {"bfgs", "ah"}) {
    const std::vector<Tick> ticks = run(params(method), 6.0);
    ASSERT_GE(firstAugmented(ticks), 0) << method;
    EXPECT_LT(medianCurvature(ticks), 1e-3) << method;
  }
}

TEST(SecondOrderTerm, BfgsGaussNewtonSecantLearnsJtJ) {
  // y = J^T J s + sum (J - J_prev)^T lambda: B approximates J^T J + H, so its trace becomes of
  // the order of J^T J's (B s = y along the steps taken).
  ControllerParams p = params("bfgs");
  p.bfgs_secant = BfgsSecant::GaussNewton;
  const std::vector<Tick> gn = run(p, 6.0);
  const std::vector<Tick> base = run(params("bfgs"), 6.0);
  const double c = medianCurvature(gn);
  EXPECT_GT(c, 0.05);
  EXPECT_GT(c, 100.0 * medianCurvature(base));
}

TEST(SecondOrderTerm, BfgsFullDifferenceChangesTheUpdates) {
  // y = grad L(k) - grad L(k-1) with each gradient's own multipliers: the term J_prev^T
  // (lambda - lambda_prev) is added, so B (and the rows) differ from the default reading.
  ControllerParams p = params("bfgs");
  p.bfgs_secant = BfgsSecant::FullDifference;
  const std::vector<Tick> full = run(p, 6.0);
  const std::vector<Tick> base = run(params("bfgs"), 6.0);
  // Identical until the first augmented tick (B does not act before), different afterwards.
  const int k0 = firstAugmented(base);
  ASSERT_GE(k0, 0);
  EXPECT_EQ(firstAugmented(full), k0);
  bool differs = false;
  for (size_t k = static_cast<size_t>(k0); k < base.size(); ++k)
    differs = differs || (full[k].augmented && base[k].augmented && full[k].curvature != base[k].curvature);
  EXPECT_TRUE(differs);
}

TEST(SecondOrderTerm, MultiplierScaleOneScalesTheAnalyticHessianByOneOverDt) {
  // eq. 37: lambda_optim = dt lambda_ctrl. With lambda_ctrl itself the analytic term is 1/dt
  // times larger at the first augmented tick (the runs are identical up to it).
  ControllerParams p = params("ah");
  p.multiplier_scale = MultiplierScale::One;
  const std::vector<Tick> one = run(p, 6.0);
  const std::vector<Tick> base = run(params("ah"), 6.0);
  const int k0 = firstAugmented(base);
  ASSERT_GE(k0, 0);
  ASSERT_EQ(firstAugmented(one), k0);
  const Tick& a = one[static_cast<size_t>(k0)];
  const Tick& b = base[static_cast<size_t>(k0)];
  ASSERT_GT(b.curvature, 0.0);
  EXPECT_NEAR(a.curvature / b.curvature, 1.0 / kDt, 1e-6 / kDt);
  // And for BFGS the later term is larger too (its secant pairs carry the scale).
  ControllerParams pb = params("bfgs");
  pb.multiplier_scale = MultiplierScale::One;
  EXPECT_GT(medianCurvature(run(pb, 6.0)), 10.0 * medianCurvature(run(params("bfgs"), 6.0)));
}

TEST(SecondOrderTerm, AnalyticHessianWithJtJ) {
  // ah_add_jtj: H = J^T J + sum lambda H before Higham: the curvature term is J^T J's size.
  ControllerParams p = params("ah");
  p.ah_add_jtj = true;
  const std::vector<Tick> ticks = run(p, 6.0);
  const int k0 = firstAugmented(ticks);
  ASSERT_GE(k0, 0);
  EXPECT_NEAR(ticks[static_cast<size_t>(k0)].curvature, 1.0, 1e-2);
  EXPECT_NEAR(medianCurvature(ticks), 1.0, 1e-2);
}

TEST(SecondOrderTerm, DefaultOptionsAreTheDefaultReadings) {
  const ControllerParams p;
  EXPECT_EQ(p.bfgs_secant, BfgsSecant::CurrentMultipliers);
  EXPECT_EQ(p.multiplier_scale, MultiplierScale::Dt);
  EXPECT_FALSE(p.ah_add_jtj);
}

}  // namespace
}  // namespace lexdyn::control
