// Shared helpers for the task tests: a per-tick fixture (model, data, state, M, N, contact
// layout, Hessian workspace, TickContext) and independent finite-difference references.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "../common/expect_text.hpp"
#include "../model/model_test_utils.hpp"
#include "lexdyn/hessian/kinematic_hessian.hpp"
#include "lexdyn/model/robot_model.hpp"
#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks::testing {

using lexdyn::testing::inputErrorWhere;

constexpr double kInf = std::numeric_limits<double>::infinity();

using model::Configuration;
using model::RobotModel;
using model::testing::RandomStates;

constexpr double kH = 1e-5;  // central differences: O(h^2) truncation

inline RobotModel loadModel(const std::string& name) {
  if (name == "hrp2kai_like") return model::testing::loadHumanoid();
  return model::testing::loadModel("models/" + name, name);
}

/// Contacts of the tests: the humanoid's two feet (friction, the data file's corners) and a
/// fixed one-point grasp at LGRASP; for a fixed-base arm, a fixed one-point contact at "tool".
inline std::vector<ContactSpec> testContacts(const RobotModel& model) {
  std::vector<ContactSpec> cs;
  for (const auto& s : model.description().contact_surfaces) {
    ContactSpec c;
    c.name = s.name;
    c.frame = s.frame;
    c.points = s.points;
    c.friction = model.description().friction_coefficient;
    cs.push_back(c);
  }
  ContactSpec g;
  g.fixed = true;
  g.friction = 0.5;
  g.points = {Eigen::Vector3d::Zero()};
  if (model.hasFreeFlyer()) {
    g.name = "LEFT_HAND";
    g.frame = model.frameId("LGRASP");
    g.normal_in_frame = Eigen::Vector3d(1.0, 0.0, 0.0);
  } else {
    g.name = "TOOL";
    g.frame = model.frameId("tool");
  }
  cs.push_back(g);
  return cs;
}

/// Everything a task needs for one tick.
struct TickFixture {
  explicit TickFixture(const std::string& model_name)
      : model(loadModel(model_name)), data(model.createData()), layout(model.nv(), testContacts(model)), ws(model) {
    q = model.neutralConfiguration();
    u = Eigen::VectorXd::Zero(model.nv());
    M.setZero(model.nv(), model.nv());
    N.setZero(model.nv());
    active.assign(static_cast<size_t>(layout.count()), 1);
    ctx.model = &model;
    ctx.data = &data;
    ctx.q = &q;
    ctx.u = &u;
    ctx.contacts = &layout;
    ctx.contact_active = &active;
    ctx.dt = 0.005;
    ctx.M = &M;
    ctx.N = &N;
    ctx.hessian = &ws;
    update();
  }
  /// model.update, M, N and the Hessian workspace at (q, u).
  void update() {
    model.update(data, q, u);
    model.massMatrix(data, M);
    model.nonlinearEffects(data, N);
    ws.update(model, data);
  }
  void set(const Configuration& qn, const Eigen::VectorXd& un) {
    q = qn;
    u = un;
    update();
  }

  RobotModel model;
  model::ModelData data;
  ContactLayout layout;
  hessian::KinematicHessianWorkspace ws;
  Configuration q;
  Eigen::VectorXd u;
  Eigen::MatrixXd M;
  Eigen::VectorXd N;
  std::vector<char> active;
  TickContext ctx;
};

/// Relative comparison with an absolute floor of 1.
inline ::testing::AssertionResult near(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double tol) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) {
    return ::testing::AssertionFailure() << "sizes " << a.rows() << "x" << a.cols() << " vs " << b.rows() << "x" << b.cols();
  }
  const double scale = std::max(1.0, std::max(a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff()));
  const double err = (a - b).cwiseAbs().maxCoeff();
  if (err <= tol * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "max error " << err << " > " << tol * scale << "\nA=\n" << a << "\nB=\n" << b;
}

/// f at q(h) and at q(-h), q(t) = integrate(q, v, t) (the fixture's u is kept). Restores the
/// fixture's state afterwards.
template <class F>
std::pair<Eigen::MatrixXd, Eigen::MatrixXd> valuesAround(TickFixture& fx, const Eigen::VectorXd& v, F f, double h) {
  const Configuration q0 = fx.q;
  Configuration qp = q0, qm = q0;
  fx.model.integrate(q0, v, h, qp);
  fx.model.integrate(q0, v, -h, qm);
  fx.q = qp;
  fx.update();
  const Eigen::MatrixXd fp = f();
  fx.q = qm;
  fx.update();
  const Eigen::MatrixXd fm = f();
  fx.q = q0;
  fx.update();
  return {fp, fm};
}

/// Central difference of f along q(t) = integrate(q, v, t) at t = 0 (the fixture's u is kept).
/// Restores the fixture's state afterwards.
template <class F>
Eigen::MatrixXd centralDifference(TickFixture& fx, const Eigen::VectorXd& v, F f, double h = kH) {
  const auto [fp, fm] = valuesAround(fx, v, f, h);
  return (fp - fm) / (2.0 * h);
}

/// Second derivative of f along q(t) = integrate(q, v, t) at t = 0.
template <class F>
Eigen::MatrixXd secondDifference(TickFixture& fx, const Eigen::VectorXd& v, F f, double h = 1e-4) {
  const Eigen::MatrixXd f0 = f();
  const auto [fp, fm] = valuesAround(fx, v, f, h);
  return (fp - 2.0 * f0 + fm) / (h * h);
}

/// Rotation vector log(R).
inline Eigen::Vector3d logRotation(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

inline Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return S;
}

}  // namespace lexdyn::tasks::testing
