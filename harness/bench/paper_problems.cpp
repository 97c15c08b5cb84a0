#include "paper_problems.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "lexdyn/common/error.hpp"

namespace lexdyn::bench {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using solver::kInf;
using solver::Problem;

constexpr int kNq = 38;
constexpr int kNg = 36;
constexpr int kN = kNq + kNg;
constexpr double kDt = 0.005;
constexpr double kDelta = 0.01;
constexpr int kDims[5] = {6, 6, 3, 6, 3};

MatrixXd randn(std::mt19937_64& rng, int r, int c, double s = 1.0) {
  std::normal_distribution<double> nd(0.0, s);
  MatrixXd m(r, c);
  for (int j = 0; j < c; ++j)
    for (int i = 0; i < r; ++i) m(i, j) = nd(rng);
  return m;
}

MatrixXd orthonormal(std::mt19937_64& rng, int n) {
  Eigen::HouseholderQR<MatrixXd> qr(randn(rng, n, n));
  return qr.householderQ() * MatrixXd::Identity(n, n);
}

}  // namespace

Regime parseRegime(const std::string& name) {
  if (name == "nominal") return Regime::Nominal;
  if (name == "stress") return Regime::Stress;
  if (name == "near-singular") return Regime::NearSingular;
  throw InputError("--regime", "expected nominal, stress or near-singular, found \"" + name + "\"");
}

struct PaperProblemSequence::Data {
  MatrixXd L;        // M = L L^T + I
  MatrixXd Jc, dJc;  // contact generators (36 x 38) and their drift
  VectorXd h, dh;    // N and its drift
  MatrixXd J[5], dJ[5];
  VectorXd e[5], de[5];
  MatrixXd C, dC;  // 16 x 38 inequality rows
  VectorXd c;
};

PaperProblemSequence::PaperProblemSequence(Regime regime, std::uint64_t seed) : d_(std::make_unique<Data>()), regime_(regime) {
  Data& b = *d_;
  std::mt19937_64 rng(seed);
  const bool stress = regime == Regime::Stress;
  const bool singular = regime == Regime::NearSingular;
  // Inertia: M = L L^T + I (well conditioned, like a humanoid's joint-space inertia).
  b.L = randn(rng, kNq, kNq, 0.3);
  // Contact generators: a smooth map from 36 generator magnitudes to 38 generalized forces.
  b.Jc = randn(rng, kNg, kNq, 0.4);
  b.dJc = randn(rng, kNg, kNq, 0.02);
  // Gravity-like bias supported by the contacts, N = Jc^T gamma0. A few generators of gamma0
  // are negative, so that their bound gamma >= 0 is active at the optimum.
  VectorXd gamma0(kNg);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double pNeg = stress ? 0.25 : 0.12;
  for (int i = 0; i < kNg; ++i) gamma0(i) = (u01(rng) < pNeg) ? -(0.2 + u01(rng)) : 1.0 + u01(rng);
  b.h = b.Jc.transpose() * gamma0 * 100.0;
  b.dh = randn(rng, kNq, 1, 5.0);
  const double eScale = stress ? 2.5 : 0.3;
  for (int t = 0; t < 5; ++t) {
    b.J[t] = randn(rng, kDims[t], kNq, 0.5);
    b.dJ[t] = randn(rng, kDims[t], kNq, 0.02);
    b.e[t] = randn(rng, kDims[t], 1, eScale);
    b.de[t] = randn(rng, kDims[t], 1, 0.5 * eScale);
  }
  if (singular) {
    // Task 1 (6 rows): singular values 1, 1, 1, 1, 1e-3, 1e-7 relative.
    const MatrixXd U = orthonormal(rng, 6);
    const MatrixXd V = orthonormal(rng, kNq).leftCols(6);
    VectorXd s(6);
    s << 1, 1, 1, 1, 1e-3, 1e-7;
    b.J[0] = 2.0 * U * s.asDiagonal() * V.transpose();
    b.dJ[0].setZero();
    b.e[0] = randn(rng, 6, 1, 0.5);
    // Tasks 4 and 5 share their first 3 rows; task 5's targets are the opposite of task 4's.
    b.J[4] = b.J[3].topRows(3);
    b.dJ[4] = b.dJ[3].topRows(3);
  }
  b.C = randn(rng, 16, kNq, 0.5);
  b.dC = randn(rng, 16, kNq, 0.02);
  b.c = VectorXd::Constant(16, stress ? 0.2 : 1.0) + randn(rng, 16, 1, stress ? 0.2 : 0.5).cwiseAbs();
}

PaperProblemSequence::~PaperProblemSequence() = default;

Problem PaperProblemSequence::tick(int k) const {
  const Data& b = *d_;
  const bool singular = regime_ == Regime::NearSingular;
  const double t = k * kDt;
  const double w1 = std::sin(2.0 * M_PI * 0.13 * t), w2 = std::sin(2.0 * M_PI * 0.31 * t + 1.0);
  Problem p(kN);
  {
    std::vector<int> vars(kNg);
    for (int i = 0; i < kNg; ++i) vars[static_cast<size_t>(i)] = kNq + i;
    p.addBoundsLevel("contact wrench generators >= 0", vars, VectorXd::Ones(kNg), VectorXd::Zero(kNg), VectorXd::Constant(kNg, kInf));
  }
  {
    // Eq. 86: [M, -Jc^T] [qdot(k+1); dt gamma] = M qdot(k) - dt N.
    const MatrixXd Lk = b.L + 0.02 * w1 * MatrixXd::Identity(kNq, kNq);
    const MatrixXd M = Lk * Lk.transpose() + MatrixXd::Identity(kNq, kNq);
    const MatrixXd Jc = b.Jc + w2 * b.dJc;
    MatrixXd A(kNq, kN);
    A.leftCols(kNq) = M;
    A.rightCols(kNg) = -Jc.transpose();
    const VectorXd qdot = 0.2 * w2 * VectorXd::Ones(kNq);
    const VectorXd rhs = M * qdot - kDt * (b.h + w1 * b.dh);
    p.addLevel("equation of motion", A, rhs, rhs);
  }
  {
    MatrixXd A = MatrixXd::Zero(kNq, kN);
    A.leftCols(kNq).setIdentity();
    p.addLevel("trust region", A, VectorXd::Constant(kNq, -kDelta / kDt), VectorXd::Constant(kNq, kDelta / kDt));
  }
  for (int i = 0; i < 5; ++i) {
    MatrixXd A = MatrixXd::Zero(kDims[i], kN);
    A.leftCols(kNq) = b.J[i] + w1 * b.dJ[i];
    VectorXd e = b.e[i] + w2 * b.de[i];
    if (singular && i == 4) e = -(b.e[3] + w2 * b.de[3]).head(3);
    p.addLevel("task " + std::to_string(i + 1), A, e, e);
  }
  {
    MatrixXd A = MatrixXd::Zero(16, kN);
    A.leftCols(kNq) = b.C + w2 * b.dC;
    p.addLevel("inequalities", A, VectorXd::Constant(16, -kInf), b.c);
  }
  {
    MatrixXd A = MatrixXd::Zero(kNq, kN);
    A.leftCols(kNq).setIdentity();
    p.addLevel("minimum velocity", A, VectorXd::Zero(kNq), VectorXd::Zero(kNq));
  }
  return p;
}

}  // namespace lexdyn::bench
