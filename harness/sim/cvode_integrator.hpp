// The one adapter to SUNDIALS CVODE (the only file that includes SUNDIALS headers is
// cvode_integrator.cpp). Integrates ydot = f(t, y) with BDF and a Newton nonlinear solver whose
// dense Jacobian CVODE approximates by difference quotients (or the system provides,
// CvodeSettings::jacobian). The Newton systems
// (I - gamma J) x = b are solved by our own direct linear solver (cvode_integrator.cpp,
// NewtonSolver): for a system y = [q; u] whose q block is kinematic (CvodeSettings::
// kinematic_block) by eliminating the q block, otherwise by a dense LU of the whole matrix; or,
// on request (CvodeSettings::linear_solver), by SUNDIALS' own dense LU (SUNLinSol_Dense).
// The block-elimination solver forms I - gamma J itself, from CVODE's difference-quotient
// Jacobian, instead of CVODE's copy and scaling of the whole matrix at every setup.
// Integration is advanced to a given time with CVodeSetStopTime + CV_NORMAL, so CVODE never
// steps past a control tick and keeps its history (order, step size, Jacobian) across ticks.
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace lexdyn::sim {

/// The system of ordinary differential equations. rhs() may throw: the exception's message is
/// kept and the integration stops with CvodeStatus::RhsFailure.
class OdeSystem {
 public:
  virtual ~OdeSystem() = default;
  virtual int size() const = 0;
  virtual void rhs(double t, const double* y, double* ydot) = 0;
  /// The Jacobian d ydot / d y at (t, y) (n x n, column-major, every entry written: J may hold
  /// the previous Jacobian; fy = rhs(t, y), may be null outside CVODE), used with
  /// CvodeSettings::jacobian = JacobianSource::System. It may be an approximation: CVODE's
  /// error test, not the Jacobian, decides the accuracy; a poorer Jacobian only makes the Newton
  /// iterations converge more slowly. It may throw, as rhs() may (CvodeStatus::RhsFailure, with
  /// the exception's message). The default throws: a system
  /// without one must be integrated with difference quotients.
  virtual void jacobian(double t, const double* y, const double* fy, double* J);
};

/// Where the Jacobian of CVODE's Newton matrix comes from.
enum class JacobianSource {
  DifferenceQuotient,  ///< CVODE's difference quotients: n right-hand sides per Jacobian (the default)
  System               ///< OdeSystem::jacobian
};

const char* toString(JacobianSource s);  ///< "difference_quotient" | "system"

/// Who solves the Newton systems (I - gamma J) x = b.
enum class LinearSolver {
  BlockElimination,  ///< NewtonSolver: block elimination of the kinematic block (the default)
  DenseLU            ///< SUNDIALS' SUNLinSol_Dense on the SUNDenseMatrix (LU of the whole matrix)
};

const char* toString(LinearSolver s);  ///< "block_elimination" | "dense_lu"

struct CvodeSettings {
  double rtol = 1e-4;         ///< relative tolerance
  std::vector<double> atol;   ///< absolute tolerance per component (size of the system)
  int max_order = 5;          ///< BDF order limit (1..5)
  long max_steps = 20000;     ///< per advance() call
  double max_step = 0.0;      ///< 0: no limit
  double initial_step = 0.0;  ///< 0: CVODE's estimate
  /// Size p of a leading block q of y = [q; u] whose rates depend on u through a sparse map
  /// (qdot = N(q) u, e.g. joint rates = joint speeds): the Newton matrix is then factorised by
  /// eliminating the q block (its blocks I - gamma dqdot/dq and -gamma N are sparse) and a
  /// dense LU of the (n - p) x (n - p) Schur complement. Only the cost depends on the
  /// structure: any matrix is solved correctly, and the whole matrix is factorised instead
  /// when the q block is not safely invertible without pivoting across the blocks. 0: always
  /// the dense LU of the whole matrix.
  int kinematic_block = 0;
  /// DenseLU ignores kinematic_block.
  LinearSolver linear_solver = LinearSolver::BlockElimination;
  /// BlockElimination only: true (the default) hands the solver CVODE's Jacobian and gamma, and
  /// the solver forms I - gamma J where it reads it; false lets CVODE copy its saved Jacobian and
  /// scale it to I - gamma J at every setup. The same bits either way (a test compares them);
  /// true saves the copy and the scaling of the whole n x n matrix.
  bool own_linear_system = true;
  JacobianSource jacobian = JacobianSource::DifferenceQuotient;
};

struct CvodeStats {
  long steps = 0;
  long rhs_evals = 0;      ///< by the integrator (not counting the Jacobian's)
  long jac_evals = 0;      ///< Jacobians (difference quotients or the system's)
  long jac_rhs_evals = 0;  ///< rhs evaluations spent on those Jacobians
  long nonlin_iters = 0;
  long nonlin_conv_fails = 0;
  long err_test_fails = 0;
  long lin_setups = 0;       ///< Newton-matrix factorisations
  long lin_full_setups = 0;  ///< of which of the whole matrix by NewtonSolver (kinematic block not used; 0 with DenseLU)
  double last_step = 0.0;
  int last_order = 0;
};

enum class CvodeStatus { Success, TooMuchWork, TooMuchAccuracy, ErrorTestFailures, ConvergenceFailures, RhsFailure, OtherFailure };

const char* toString(CvodeStatus s);

class CvodeIntegrator {
 public:
  CvodeIntegrator(OdeSystem& system, const CvodeSettings& settings);
  ~CvodeIntegrator();
  CvodeIntegrator(const CvodeIntegrator&) = delete;
  CvodeIntegrator& operator=(const CvodeIntegrator&) = delete;

  /// Starts (or restarts) at t0 from y0 (size of the system).
  void initialize(double t0, const double* y0);
  /// Integrates to exactly t_out (stop time) and writes y(t_out). On failure, y_out holds the
  /// last successful state, time() its time, and message() says what happened.
  CvodeStatus advance(double t_out, double* y_out);
  double time() const;
  const std::string& message() const;
  CvodeStats stats() const;

  /// "6.4.1": the SUNDIALS version compiled in.
  static std::string sundialsVersion();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lexdyn::sim
