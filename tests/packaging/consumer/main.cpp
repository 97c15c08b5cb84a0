// Uses lexdyn as an installed package: solves a small hierarchy, then runs a controller on the
// point mass for a few ticks. Exits 0 when the results are right, 1 otherwise.
#include <lexdyn/control/controller.hpp>
#include <lexdyn/solver/problem.hpp>
#include <lexdyn/solver/solver.hpp>
#include <lexdyn/tasks/position.hpp>

#include <cmath>
#include <cstdio>
#include <memory>
#include <utility>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: lexdyn_consumer URDF DATA\n");
    return 2;
  }
  // Level 1: x0 + x1 = 1; level 2: x0 - x1 = 0.5 (both reachable: x = (0.75, 0.25)).
  lexdyn::solver::Problem p(2);
  Eigen::MatrixXd a1(1, 2), a2(1, 2);
  a1 << 1, 1;
  a2 << 1, -1;
  p.addLevel("sum", a1, Eigen::VectorXd::Constant(1, 1.0), Eigen::VectorXd::Constant(1, 1.0));
  p.addLevel("difference", a2, Eigen::VectorXd::Constant(1, 0.5), Eigen::VectorXd::Constant(1, 0.5));
  lexdyn::solver::Solver s;
  s.setup(p);
  const lexdyn::solver::Result& r = s.solve(p);
  if (r.status != lexdyn::solver::Status::Solved || std::abs(r.x(0) - 0.75) > 1e-12 || std::abs(r.x(1) - 0.25) > 1e-12) {
    std::fprintf(stderr, "solver: %s, x = (%g, %g)\n", lexdyn::solver::toString(r.status), r.x(0), r.x(1));
    return 1;
  }
  // The point mass at x = 1 driven to 0 by a position task.
  const lexdyn::model::RobotModel m = lexdyn::model::RobotModel::fromFiles(argv[1], argv[2]);
  lexdyn::control::ControllerConfig cfg;
  cfg.params.dt = 0.005;
  lexdyn::tasks::PositionParams pp;
  pp.frame = "mass";
  pp.target = Eigen::Vector3d::Zero();
  pp.gains.kp = 1.0;
  cfg.tasks.push_back(std::make_unique<lexdyn::tasks::PositionTask>("position", m, pp));
  cfg.levels = {{"position", {0}, {}}};
  lexdyn::control::Controller c(m, std::move(cfg));
  lexdyn::control::RobotState st;
  st.q = m.neutralConfiguration();
  st.q.joints(0) = 1.0;
  st.u = Eigen::VectorXd::Zero(1);
  c.reset(st);
  for (int k = 0; k < 100; ++k) {
    const lexdyn::control::Command& cmd = c.tick(st);
    if (!cmd.ok()) {
      std::fprintf(stderr, "controller: tick %d: %s\n", k, lexdyn::control::toString(cmd.status));
      return 1;
    }
    st.q = cmd.q;
    st.u = cmd.u;
    st.time += 0.005;
  }
  const double x = st.q.joints(0);
  if (!(x < 1.0 && x > 0.0)) {
    std::fprintf(stderr, "controller: the point mass did not move toward its target (x = %g)\n", x);
    return 1;
  }
  std::printf("lexdyn_consumer: solver x = (%g, %g); point mass from 1 to %.6f in 100 ticks\n", r.x(0), r.x(1), x);
  return 0;
}
