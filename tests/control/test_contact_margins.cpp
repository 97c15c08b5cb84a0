// Contact margins (docs/controller.md, "Contact margins"): the support polygon shrunk inward, the
// reduced friction pyramid and the minimum normal force per point, and the humanoid's plan under
// an out-of-reach target keeping every point's force inside them at every tick (and, without
// margins, the same plan using the contacts to their edges, so that the test can fail).
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "humanoid_config.hpp"
#include "lexdyn/tasks/contact_margins.hpp"

namespace lexdyn::control {
namespace {

using tasks::ContactMargins;
using tasks::ContactSpec;

std::vector<Eigen::Vector3d> sole() {  // 0.216 x 0.140 m, the humanoid's
  return {{0.108, 0.070, 0}, {0.108, -0.070, 0}, {-0.108, -0.070, 0}, {-0.108, 0.070, 0}};
}

TEST(ContactMargins, RectangleCornersMoveInwardByTheMarginOnBothAxes) {
  std::vector<Eigen::Vector3d> p = sole();
  double room = 0.0;
  ASSERT_TRUE(tasks::shrinkSupport(p, Eigen::Vector3d::UnitZ(), 0.02, room));
  const std::vector<Eigen::Vector3d> expected = {{0.088, 0.050, 0}, {0.088, -0.050, 0}, {-0.088, -0.050, 0}, {-0.088, 0.050, 0}};
  for (size_t k = 0; k < p.size(); ++k) EXPECT_LT((p[k] - expected[k]).norm(), 1e-15) << k;
  // A margin the sole cannot give (half its width is 0.07 m) is refused, points unchanged.
  p = sole();
  EXPECT_FALSE(tasks::shrinkSupport(p, Eigen::Vector3d::UnitZ(), 0.07, room));
  EXPECT_NEAR(room, 0.07, 1e-15);
  EXPECT_EQ(p, sole());
}

TEST(ContactMargins, TiltedPolygonInteriorPointsAndSegments) {
  // A pentagon in a plane with normal (0, 1, 1)/sqrt(2), plus an interior point near one edge:
  // every resulting point is at least the margin from every edge of the original hull.
  const Eigen::Vector3d n = Eigen::Vector3d(0, 1, 1).normalized();
  const Eigen::Vector3d a = Eigen::Vector3d::UnitX(), b = n.cross(a);
  const std::vector<Eigen::Vector2d> p2 = {{0.1, 0.0}, {0.03, 0.09}, {-0.08, 0.05}, {-0.08, -0.05}, {0.03, -0.09}, {0.07, 0.0}};
  std::vector<Eigen::Vector3d> p;
  for (const auto& q : p2) p.push_back(q.x() * a + q.y() * b + 0.01 * n);
  double room = 0.0;
  const double d = 0.015;
  ASSERT_TRUE(tasks::shrinkSupport(p, n, d, room));
  for (size_t k = 0; k < p.size(); ++k) {
    EXPECT_NEAR(p[k].dot(n), 0.01, 1e-15);  // stays in its plane
    const Eigen::Vector2d q(p[k].dot(a), p[k].dot(b));
    for (size_t e = 0; e < 5; ++e) {
      const Eigen::Vector2d v0 = p2[e], v1 = p2[(e + 1) % 5];
      const Eigen::Vector2d t = (v1 - v0).normalized();
      const double inside = t.x() * (q - v0).y() - t.y() * (q - v0).x();  // left of the counter-clockwise edge
      EXPECT_GT(inside, d - 1e-12) << "point " << k << " edge " << e;
    }
  }
  // The hull's vertices lie on the offset edges: exactly d from their two edges.
  // Two points (a line contact): the ends move toward each other.
  std::vector<Eigen::Vector3d> seg = {{0.05, 0, 0}, {-0.05, 0, 0}};
  ASSERT_TRUE(tasks::shrinkSupport(seg, Eigen::Vector3d::UnitZ(), 0.01, room));
  EXPECT_NEAR(seg[0].x(), 0.04, 1e-15);
  EXPECT_NEAR(seg[1].x(), -0.04, 1e-15);
  EXPECT_FALSE(tasks::shrinkSupport(seg, Eigen::Vector3d::UnitZ(), 0.05, room));
}

TEST(ContactMargins, ApplyScalesFrictionAndRefusesBadValues) {
  ContactSpec c;
  c.name = "RIGHT_FOOT";
  c.points = sole();
  c.friction = 0.7;
  EXPECT_TRUE(tasks::applyContactMargins(c, {0.2, 0.01, 12.0}).empty());
  EXPECT_NEAR(c.friction, 0.56, 1e-15);
  EXPECT_EQ(c.min_normal_force, 12.0);
  EXPECT_NEAR(c.points[0].x(), 0.098, 1e-15);
  // A fixed (grasp) contact has no sign bound: no margin applies.
  ContactSpec g = c;
  g.fixed = true;
  g.points = sole();
  g.friction = 0.7;
  g.min_normal_force = 0.0;
  EXPECT_TRUE(tasks::applyContactMargins(g, {0.2, 0.01, 12.0}).empty());
  EXPECT_EQ(g.friction, 0.7);
  EXPECT_EQ(g.points, sole());
  EXPECT_EQ(g.min_normal_force, 0.0);
  // Every problem at once.
  ContactSpec bad;
  bad.name = "LEFT_FOOT";
  bad.points = sole();
  const std::vector<std::string> problems = tasks::applyContactMargins(bad, {1.0, -0.01, std::nan("")});
  ASSERT_EQ(problems.size(), 3u);
  EXPECT_NE(problems[0].find("friction"), std::string::npos);
  EXPECT_NE(problems[1].find("cop_m"), std::string::npos);
  EXPECT_NE(problems[2].find("min_normal_N"), std::string::npos);
  const std::vector<std::string> wide = tasks::applyContactMargins(bad, {0.0, 0.08, 0.0});
  ASSERT_EQ(wide.size(), 1u);
  EXPECT_NE(wide[0].find("leaves no support polygon of contact LEFT_FOOT"), std::string::npos) << wide[0];
}

struct Extremes {
  bool ok = true;
  double min_point_normal = std::numeric_limits<double>::infinity();  // N
  double max_friction_use = 0.0;                                      // (|f_t1| + |f_t2|) / (mu f_n) of the real coefficient
  double min_cop_to_edge = std::numeric_limits<double>::infinity();   // m, of the real sole
};

// The humanoid's exp. 1-like plan with both hands' targets out of reach, closed on its own
// integrated state for `ticks` ticks; the extremes of its per-point forces and foot CoPs.
Extremes runPlan(const std::string& method, const ContactMargins& margins, int ticks) {
  const model::RobotModel m = test::loadHumanoid();
  ControllerConfig cfg = test::exp1Config(m, method, 0.3);
  const double mu = cfg.contacts[0].friction;
  for (auto& c : cfg.contacts) EXPECT_TRUE(tasks::applyContactMargins(c, margins).empty());
  Controller ctl(m, std::move(cfg));
  RobotState s = test::halfSitting(m);
  ctl.reset(s);
  ctl.setTaskTarget(ctl.taskIndex("right_hand"), Eigen::Vector3d(0.4, -2.0, 2.0));
  ctl.setTaskTarget(ctl.taskIndex("left_hand"), Eigen::Vector3d(1.5, 1.0, 0.6));
  model::ModelData d = m.createData();
  Extremes x;
  for (int k = 0; k < ticks; ++k) {
    const Command& cmd = ctl.tick(s);
    if (!cmd.ok()) {
      x.ok = false;
      ADD_FAILURE() << method << ": tick " << k << ": " << toString(cmd.status);
      break;
    }
    m.update(d, s.q, s.u);
    const tasks::ContactLayout& layout = ctl.contacts();
    for (int c = 0; c < layout.count(); ++c) {
      const ContactSpec& spec = layout.contact(c);
      const Eigen::Isometry3d X = m.framePlacement(d, spec.frame);
      Eigen::Matrix<double, 3, 4> D;
      tasks::ContactLayout::generators(spec, X.linear(), D);
      Eigen::Vector3d f_sum = Eigen::Vector3d::Zero(), m_sum = Eigen::Vector3d::Zero();
      for (size_t p = 0; p < spec.points.size(); ++p) {
        const Eigen::Vector3d f = X.linear().transpose() * (D * cmd.gamma.segment(layout.offset(c) + 4 * static_cast<int>(p), 4));
        x.min_point_normal = std::min(x.min_point_normal, f.z());
        x.max_friction_use = std::max(x.max_friction_use, (std::abs(f.x()) + std::abs(f.y())) / (mu * f.z()));
        f_sum += f;
        m_sum += spec.points[p].cross(f);
      }
      // The CoP in the sole frame against the real sole's edges (0.108, 0.070).
      const double cx = -m_sum.y() / f_sum.z(), cy = m_sum.x() / f_sum.z();
      x.min_cop_to_edge = std::min({x.min_cop_to_edge, 0.108 - std::abs(cx), 0.070 - std::abs(cy)});
    }
    s.q = cmd.q;
    s.u = cmd.u;
    s.time += 0.005;
  }
  return x;
}

TEST(ContactMargins, ThePlanKeepsEveryPointInsideItsMargins) {
  const ContactMargins margins{0.1, 0.01, 5.0};
  for (const std::string method : {"bfgs", "ah", "wls"}) {
    const Extremes x = runPlan(method, margins, 400);  // 2 s
    ASSERT_TRUE(x.ok) << method;
    EXPECT_GE(x.min_point_normal, 5.0 - 1e-6) << method;
    // The pyramid of 0.8 mu holds |f_t1| + |f_t2| <= 0.8 mu f_n.
    EXPECT_LE(x.max_friction_use, 0.9 + 1e-9) << method;
    EXPECT_GE(x.min_cop_to_edge, 0.01 - 1e-9) << method;
  }
  // Without margins the same plan takes the contacts to their limits: some point carries no
  // force, a CoP reaches within 1 cm of an edge and a force reaches the pyramid's edge (the
  // margins above are what kept them; measured: 0 N, 0 m, 1.00003).
  const Extremes none = runPlan("bfgs", {0.0, 0.0, 0.0}, 400);
  ASSERT_TRUE(none.ok);
  EXPECT_LT(none.min_point_normal, 1.0);
  EXPECT_LT(none.min_cop_to_edge, 0.01);
  EXPECT_GT(none.max_friction_use, 0.95);
}

}  // namespace
}  // namespace lexdyn::control
