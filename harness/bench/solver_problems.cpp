// lexdyn-bench-solver-problems: writes drifting sequences of paper-shaped hierarchical problems
// (docs/performance.md, "Solver"). 74 variables x = [qdot (38); gamma (36)], 10 levels, 190 rows:
//   1  bounds gamma >= 0                                  36 (bounds level)
//   2  [M, -Jc^T] x = -h                                  38 equality
//   3  trust box |qdot_i| <= Delta / dt                   38 two-sided
//   4-8 equality tasks on qdot                            6, 6, 3, 6, 3
//   9  one-sided inequality on qdot                       16
//   10 minimum norm qdot = 0                              38
// Regimes: nominal (a few active inequalities), stress (many), near-singular (a task with singular
// values 1e-3 and 1e-7 relative, and two tasks sharing rows with opposite targets).
// Everything is generated from a fixed seed: the same command writes the same files.
#include <CLI/CLI.hpp>
#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include "lexdyn/common/error.hpp"
#include "lexdyn/solver/problem.hpp"
#include "lexdyn/solver/problem_io.hpp"

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using lexdyn::solver::kInf;
using lexdyn::solver::Problem;

constexpr int kNq = 38;
constexpr int kNg = 36;
constexpr int kN = kNq + kNg;
constexpr double kDt = 0.005;

struct Base {
  MatrixXd L;       // M = L L^T + I
  MatrixXd Jc, dJc; // contact generators (36 x 38) and their drift direction
  VectorXd h, dh;
  MatrixXd J[5], dJ[5];
  VectorXd e[5], de[5];
  MatrixXd C, dC;   // 16 x 38 inequality rows
  VectorXd c;
  MatrixXd Wsing;   // near-singular task basis
};

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

int main(int argc, char** argv) {
  CLI::App app{"Writes drifting sequences of paper-shaped hierarchical least-squares problems"};
  std::string regime = "nominal", out;
  int ticks = 1000;
  std::uint64_t seed = 20200710;
  app.add_option("--regime", regime, "nominal | stress | near-singular")
      ->check(CLI::IsMember({"nominal", "stress", "near-singular"}));
  app.add_option("--ticks", ticks, "number of ticks")->check(CLI::PositiveNumber);
  app.add_option("--seed", seed, "generator seed");
  app.add_option("--out", out, "output directory (tick_0000.json, ...)")->required();
  CLI11_PARSE(app, argc, argv);

  std::mt19937_64 rng(seed);
  Base b;
  const bool stress = regime == "stress";
  const bool singular = regime == "near-singular";
  // Inertia: M = L L^T + I (well conditioned, like a humanoid's joint-space inertia in SI units).
  b.L = randn(rng, kNq, kNq, 0.3);
  // Contact generators: a smooth map from 36 generator magnitudes to 38 generalized forces.
  b.Jc = randn(rng, kNg, kNq, 0.4);
  b.dJc = randn(rng, kNg, kNq, 0.02);
  // Gravity-like bias supported by the contacts: N = Jc^T gamma0 / dt-free units. A few
  // generators of gamma0 are negative, so that their bound gamma >= 0 is active at the optimum.
  VectorXd gamma0(kNg);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double pNeg = stress ? 0.25 : 0.12;
  for (int i = 0; i < kNg; ++i) gamma0(i) = (u01(rng) < pNeg) ? -(0.2 + u01(rng)) : 1.0 + u01(rng);
  b.h = b.Jc.transpose() * gamma0 * 100.0;  // N (forces of ~100 N per generator)
  b.dh = randn(rng, kNq, 1, 5.0);
  const int dims[5] = {6, 6, 3, 6, 3};
  const double eScale = stress ? 2.5 : 0.3;
  for (int t = 0; t < 5; ++t) {
    b.J[t] = randn(rng, dims[t], kNq, 0.5);
    b.dJ[t] = randn(rng, dims[t], kNq, 0.02);
    b.e[t] = randn(rng, dims[t], 1, eScale);
    b.de[t] = randn(rng, dims[t], 1, 0.5 * eScale);
  }
  if (singular) {
    // Task 1 (6 rows): singular values 1, 1, 1, 1, 1e-3, 1e-7 relative.
    const MatrixXd U = orthonormal(rng, 6);
    const MatrixXd V = orthonormal(rng, kNq).leftCols(6);
    VectorXd s(6);
    s << 1, 1, 1, 1, 1e-3, 1e-7;
    b.J[0] = 2.0 * U * s.asDiagonal() * V.transpose();
    b.dJ[0].setZero();
    b.Wsing = V;
    b.e[0] = randn(rng, 6, 1, 0.5);
    // Tasks 4 and 5 share their first 3 rows with opposite targets.
    b.J[4] = b.J[3].topRows(3);
    b.dJ[4] = b.dJ[3].topRows(3);
  }
  b.C = randn(rng, 16, kNq, 0.5);
  b.dC = randn(rng, 16, kNq, 0.02);
  b.c = VectorXd::Constant(16, stress ? 0.2 : 1.0) + randn(rng, 16, 1, stress ? 0.2 : 0.5).cwiseAbs();

  std::filesystem::create_directories(out);
  const double delta = 0.01;
  for (int k = 0; k < ticks; ++k) {
    const double t = k * kDt;
    const double w1 = std::sin(2.0 * M_PI * 0.13 * t), w2 = std::sin(2.0 * M_PI * 0.31 * t + 1.0);
    Problem p(kN);
    {
      std::vector<int> vars(kNg);
      for (int i = 0; i < kNg; ++i) vars[static_cast<size_t>(i)] = kNq + i;
      p.addBoundsLevel("contact wrench generators >= 0", vars, VectorXd::Ones(kNg), VectorXd::Zero(kNg),
                       VectorXd::Constant(kNg, kInf));
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
      p.addLevel("trust region", A, VectorXd::Constant(kNq, -delta / kDt), VectorXd::Constant(kNq, delta / kDt));
    }
    for (int i = 0; i < 5; ++i) {
      MatrixXd A = MatrixXd::Zero(dims[i], kN);
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
    char name[64];
    std::snprintf(name, sizeof(name), "/tick_%04d.json", k);
    lexdyn::solver::writeProblemJson(p, out + name);
    if ((k + 1) % 200 == 0) std::fprintf(stderr, "lexdyn-bench-solver-problems: %s %d/%d\n", regime.c_str(), k + 1, ticks);
  }
  return 0;
}
