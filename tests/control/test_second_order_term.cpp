// The size of the Newton rows against the Gauss-Newton term (TickRecord::level_second_order_ratio,
// level_curvature_ratio; trace channels level.<L>.second_order_ratio, .curvature_ratio) and the
// readings of eq. 87-89 (ControllerParams::bfgs_secant, ah_add_jtj, multiplier_scale), on the
// planar 3R arm driven to an out-of-reach target (trust region, position task, minimum
// velocity), in an ideal loop (the next state is the command).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "planar_arm.hpp"

namespace lexdyn::control {
namespace {

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
  const model::RobotModel m = testing::planarArm();
  Controller c(m, testing::planarArmConfig(m, params, true));
  RobotState s = testing::planarArmStart(m);
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

// A reading (params) and the default readings of the same method over 6 s. The readings act
// through the Newton rows only: both runs are the same up to the first augmented tick k0 (-1
// when either run has none or they differ there).
struct Variant {
  std::vector<Tick> ticks, base;
  int k0 = -1;
};

Variant runVariant(const ControllerParams& p) {
  Variant v;
  v.ticks = run(p, 6.0);
  v.base = run(params(p.method), 6.0);
  const int k0 = firstAugmented(v.base);
  EXPECT_EQ(firstAugmented(v.ticks), k0);
  if (k0 >= 0 && firstAugmented(v.ticks) == k0) v.k0 = k0;
  return v;
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
  // Identical until the first augmented tick (B does not act before), different afterwards.
  const Variant v = runVariant(p);
  ASSERT_GE(v.k0, 0);
  bool differs = false;
  for (size_t k = static_cast<size_t>(v.k0); k < v.base.size(); ++k)
    differs = differs || (v.ticks[k].augmented && v.base[k].augmented && v.ticks[k].curvature != v.base[k].curvature);
  EXPECT_TRUE(differs);
}

TEST(SecondOrderTerm, MultiplierScaleOneScalesTheAnalyticHessianByOneOverDt) {
  // eq. 37: lambda_optim = dt lambda_ctrl. With lambda_ctrl itself the analytic term is 1/dt
  // times larger at the first augmented tick (the runs are identical up to it).
  ControllerParams p = params("ah");
  p.multiplier_scale = MultiplierScale::One;
  const Variant v = runVariant(p);
  ASSERT_GE(v.k0, 0);
  const Tick& a = v.ticks[static_cast<size_t>(v.k0)];
  const Tick& b = v.base[static_cast<size_t>(v.k0)];
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
