// The CVODE adapter against closed-form solutions, and its failure reporting.
#include "harness/sim/cvode_integrator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace lexdyn::sim {
namespace {

// Damped oscillator x'' + 2 z w x' + w^2 x = 0 and a decoupled stiff decay y' = -lambda y.
class Oscillator : public OdeSystem {
 public:
  double w = 3.0, z = 0.1, lambda = 1e4;
  int calls = 0;
  double throw_after_t = 1e300;
  int size() const override { return 3; }
  void rhs(double t, const double* y, double* yd) override {
    ++calls;
    if (t > throw_after_t) throw std::runtime_error("model blew up on purpose");
    yd[0] = y[1];
    yd[1] = -2 * z * w * y[1] - w * w * y[0];
    yd[2] = -lambda * y[2];
  }
  // Closed form for x(0) = 1, x'(0) = 0.
  double x(double t) const {
    const double wd = w * std::sqrt(1 - z * z);
    return std::exp(-z * w * t) * (std::cos(wd * t) + z * w / wd * std::sin(wd * t));
  }
};

CvodeSettings tight(int n) {
  CvodeSettings s;
  s.rtol = 1e-10;
  s.atol.assign(static_cast<size_t>(n), 1e-12);
  return s;
}

TEST(CvodeIntegrator, MatchesClosedFormAcrossStopTimes) {
  Oscillator sys;
  CvodeIntegrator cv(sys, tight(3));
  const double y0[3] = {1.0, 0.0, 1.0};
  cv.initialize(0.0, y0);
  double y[3];
  for (int k = 1; k <= 400; ++k) {
    const double t = 0.005 * k;
    ASSERT_EQ(cv.advance(t, y), CvodeStatus::Success);
    EXPECT_EQ(cv.time(), t);  // stops exactly at the requested time
    EXPECT_NEAR(y[0], sys.x(t), 1e-8) << "t = " << t;
    EXPECT_NEAR(y[2], std::exp(-sys.lambda * t), 1e-10);
  }
  const CvodeStats st = cv.stats();
  EXPECT_GT(st.steps, 0);
  EXPECT_GT(st.jac_evals, 0);
}

// Advances a and b from the oscillator's initial state to each 5 ms tick up to `ticks`, calling
// check(t, ya, yb) after both reached t.
template <typename Check>
void advanceTogether(CvodeIntegrator& a, CvodeIntegrator& b, int ticks, Check check) {
  const double y0[3] = {1.0, 0.0, 1.0};
  a.initialize(0.0, y0);
  b.initialize(0.0, y0);
  double ya[3], yb[3];
  for (int k = 1; k <= ticks; ++k) {
    const double t = 0.005 * k;
    ASSERT_EQ(a.advance(t, ya), CvodeStatus::Success);
    ASSERT_EQ(b.advance(t, yb), CvodeStatus::Success);
    check(t, ya, yb);
  }
}

TEST(CvodeIntegrator, SundialsDenseLuMatchesTheClosedFormAndTheOwnSolver) {
  Oscillator a, b;
  CvodeSettings s = tight(3);
  s.kinematic_block = 1;  // x' = v: a kinematic block of size 1
  CvodeIntegrator own(a, s);
  s.linear_solver = LinearSolver::DenseLU;
  CvodeIntegrator dense(b, s);
  advanceTogether(own, dense, 200, [&](double t, const double* ya, const double* yb) {
    EXPECT_NEAR(yb[0], b.x(t), 1e-8) << "t = " << t;
    EXPECT_NEAR(ya[0], yb[0], 1e-9) << "t = " << t;
  });
  EXPECT_GT(dense.stats().lin_setups, 0);
  EXPECT_EQ(dense.stats().lin_full_setups, 0);
  EXPECT_STREQ(toString(LinearSolver::DenseLU), "dense_lu");
  EXPECT_STREQ(toString(LinearSolver::BlockElimination), "block_elimination");
}

// The solver's own I - gamma J (from CVODE's Jacobian and gamma) against CVODE's copy and
// scaling of its saved Jacobian: the same bits, step for step, with and without the kinematic
// block, at a tolerance loose enough for many setups with a reused Jacobian.
TEST(CvodeIntegrator, OwnLinearSystemHasTheBitsOfCvodes) {
  for (const int block : {0, 1}) {
    Oscillator a, b;
    CvodeSettings s;
    s.rtol = 1e-6;
    s.atol.assign(3, 1e-8);
    s.kinematic_block = block;
    CvodeIntegrator own(a, s);
    s.own_linear_system = false;
    CvodeIntegrator cvodes(b, s);
    int mismatches = 0;
    double first = -1.0;
    advanceTogether(own, cvodes, 400, [&](double t, const double* ya, const double* yb) {
      for (int i = 0; i < 3; ++i) {
        if (ya[i] == yb[i]) continue;
        if (mismatches++ == 0) first = t;
      }
    });
    EXPECT_EQ(mismatches, 0) << "block " << block << ": states differ from t = " << first << " s on";
    const CvodeStats p = own.stats(), q = cvodes.stats();
    EXPECT_EQ(p.steps, q.steps);
    EXPECT_EQ(p.jac_evals, q.jac_evals);
    EXPECT_EQ(p.jac_rhs_evals, q.jac_rhs_evals);
    EXPECT_EQ(p.lin_setups, q.lin_setups);
    EXPECT_GT(p.lin_setups, 2 * p.jac_evals) << "block " << block << ": the test needs setups with a reused Jacobian";
    EXPECT_EQ(p.lin_full_setups, block == 0 ? p.lin_setups : 0);
  }
}

TEST(CvodeIntegrator, LooseToleranceIsStillClose) {
  Oscillator sys;
  CvodeSettings s;
  s.rtol = 1e-4;
  s.atol.assign(3, 1e-6);
  CvodeIntegrator cv(sys, s);
  const double y0[3] = {1.0, 0.0, 1.0};
  cv.initialize(0.0, y0);
  double y[3];
  ASSERT_EQ(cv.advance(2.0, y), CvodeStatus::Success);
  EXPECT_NEAR(y[0], sys.x(2.0), 1e-3);
}

TEST(CvodeIntegrator, RightHandSideExceptionStopsWithItsMessage) {
  Oscillator sys;
  sys.throw_after_t = 0.0123;
  CvodeIntegrator cv(sys, tight(3));
  const double y0[3] = {1.0, 0.0, 1.0};
  cv.initialize(0.0, y0);
  double y[3];
  CvodeStatus s = CvodeStatus::Success;
  double t = 0.0;
  while (s == CvodeStatus::Success && t < 1.0) {
    t += 0.005;
    s = cv.advance(t, y);
  }
  EXPECT_EQ(s, CvodeStatus::RhsFailure);
  EXPECT_NE(cv.message().find("model blew up on purpose"), std::string::npos) << cv.message();
  EXPECT_LE(cv.time(), 0.0123 + 1e-12);
  EXPECT_NEAR(y[0], sys.x(cv.time()), 1e-6);  // the last good state is returned
}

TEST(CvodeIntegrator, TooMuchWorkIsReported) {
  Oscillator sys;
  CvodeSettings s = tight(3);
  s.max_steps = 3;
  CvodeIntegrator cv(sys, s);
  const double y0[3] = {1.0, 0.0, 1.0};
  cv.initialize(0.0, y0);
  double y[3];
  EXPECT_EQ(cv.advance(10.0, y), CvodeStatus::TooMuchWork);
  EXPECT_LT(cv.time(), 10.0);
  EXPECT_NE(cv.message().find("too_much_work"), std::string::npos) << cv.message();
}

// The oscillator with its Jacobian (column-major 3 x 3). `stiff_term` scales the entry of the
// stiff decay: 1 is exact, 0 leaves the stiff part out (a poor approximation).
class OscillatorWithJacobian : public Oscillator {
 public:
  int jacobians = 0;
  double stiff_term = 1.0;
  bool throw_in_jacobian = false;
  void jacobian(double, const double*, const double*, double* J) override {
    ++jacobians;
    if (throw_in_jacobian) throw std::runtime_error("Jacobian failed on purpose");
    for (int i = 0; i < 9; ++i) J[i] = 0.0;
    J[0 + 3 * 1] = 1.0;         // dx'/dv
    J[1 + 3 * 0] = -w * w;      // dv'/dx
    J[1 + 3 * 1] = -2 * z * w;  // dv'/dv
    J[2 + 3 * 2] = -lambda * stiff_term;
  }
};

// JacobianSource::System on each path into CVODE: the block elimination with its own linear
// system, the block elimination with CVODE's (CVodeSetJacFn), SUNDIALS' dense LU (CVodeSetJacFn).
TEST(CvodeIntegrator, SystemJacobianReplacesTheDifferenceQuotients) {
  struct Path {
    const char* name;
    LinearSolver solver;
    bool own;
  };
  for (const Path& path :
       {Path{"block elimination, own system", LinearSolver::BlockElimination, true},
        Path{"block elimination, CVODE's system", LinearSolver::BlockElimination, false}, Path{"dense LU", LinearSolver::DenseLU, true}}) {
    OscillatorWithJacobian a;
    Oscillator b;
    CvodeSettings s = tight(3);
    s.kinematic_block = 1;
    s.linear_solver = path.solver;
    s.own_linear_system = path.own;
    CvodeIntegrator dq(b, s);
    s.jacobian = JacobianSource::System;
    CvodeIntegrator own(a, s);
    advanceTogether(own, dq, 200, [&](double t, const double* ya, const double* yb) {
      EXPECT_NEAR(ya[0], a.x(t), 1e-8) << path.name << ", t = " << t;
      EXPECT_NEAR(ya[0], yb[0], 1e-8) << path.name << ", t = " << t;
      EXPECT_NEAR(ya[2], std::exp(-a.lambda * t), 1e-10) << path.name;
    });
    const CvodeStats p = own.stats(), q = dq.stats();
    EXPECT_GT(p.jac_evals, 0) << path.name;
    EXPECT_EQ(a.jacobians, p.jac_evals) << path.name;
    EXPECT_EQ(p.jac_rhs_evals, 0) << path.name;
    EXPECT_EQ(q.jac_rhs_evals, 3 * q.jac_evals) << path.name;  // one right-hand side per column
  }
  EXPECT_STREQ(toString(JacobianSource::System), "system");
  EXPECT_STREQ(toString(JacobianSource::DifferenceQuotient), "difference_quotient");
}

// A Jacobian without its stiff part costs steps (the Newton iterations diverge for
// h lambda > 1, so CVODE keeps h small: about 14 times as many here), while the error test still
// holds the solution to the order of the tolerance (2e-8 against 1.2e-9 with the exact Jacobian
// and 2.2e-10 with difference quotients over these 1 s; rtol 1e-10).
TEST(CvodeIntegrator, APoorSystemJacobianCostsStepsNotAccuracy) {
  OscillatorWithJacobian exact, poor;
  poor.stiff_term = 0.0;
  CvodeSettings s = tight(3);
  s.jacobian = JacobianSource::System;
  CvodeIntegrator a(exact, s), b(poor, s);
  advanceTogether(a, b, 200, [&](double t, const double*, const double* yb) {
    EXPECT_NEAR(yb[0], poor.x(t), 1e-7) << "t = " << t;
    EXPECT_NEAR(yb[2], std::exp(-poor.lambda * t), 1e-10) << "t = " << t;
  });
  EXPECT_GT(b.stats().steps, 5 * a.stats().steps) << "exact " << a.stats().steps << ", poor " << b.stats().steps;
}

TEST(CvodeIntegrator, SystemJacobianFailuresStopWithTheirMessage) {
  OscillatorWithJacobian throwing;
  throwing.throw_in_jacobian = true;
  Oscillator without;  // OdeSystem's default jacobian()
  CvodeSettings s = tight(3);
  s.jacobian = JacobianSource::System;
  for (const bool own : {true, false}) {
    s.own_linear_system = own;
    CvodeIntegrator a(throwing, s), b(without, s);
    const double y0[3] = {1.0, 0.0, 1.0};
    a.initialize(0.0, y0);
    b.initialize(0.0, y0);
    double y[3];
    EXPECT_EQ(a.advance(0.005, y), CvodeStatus::RhsFailure);
    EXPECT_NE(a.message().find("Jacobian: Jacobian failed on purpose"), std::string::npos) << a.message();
    EXPECT_EQ(b.advance(0.005, y), CvodeStatus::RhsFailure);
    EXPECT_NE(b.message().find("provides no Jacobian"), std::string::npos) << b.message();
  }
}

TEST(CvodeIntegrator, ReportsTheSundialsVersion) {
  EXPECT_EQ(CvodeIntegrator::sundialsVersion().rfind("6.", 0), 0u) << CvodeIntegrator::sundialsVersion();
}

}  // namespace
}  // namespace lexdyn::sim
