// SUNDIALS CVODE adapter. The only translation unit of lexdyn that includes SUNDIALS.
//
// SUNDIALS is linked statically with its symbols hidden (LINKER:--exclude-libs,
// libsundials_cvode.a): libSimTKmath.so exports an old embedded SUNDIALS whose symbols would
// otherwise interpose ours (docs/simulator.md, "Linking").
#include "harness/sim/cvode_integrator.hpp"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_config.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Core>
#include <Eigen/LU>

#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <exception>
#include <stdexcept>
#include <utility>
#include <vector>

// CVODE's difference-quotient Jacobian (cvode_ls.c). Not declared in SUNDIALS' public headers,
// but an external symbol of the static library linked here (a SUNDIALS without it fails to
// link). The block-elimination solver calls it from its own linear-system function, so that the
// Jacobian has exactly the increments and bits of CVODE's own (docs/simulator.md, "Integrator").
extern "C" int cvLsDQJac(realtype t, N_Vector y, N_Vector fy, SUNMatrix Jac, void* cvode_mem, N_Vector tmp1, N_Vector tmp2, N_Vector tmp3);
static_assert(SUNDIALS_VERSION_MAJOR == 6, "cvLsDQJac's signature and CVODE's linear-system function are those of SUNDIALS 6: check them");

namespace lexdyn::sim {

namespace {

// The direct solver of CVODE's Newton systems A x = b, A = I - gamma J (n x n), from CVODE's
// Jacobian J (difference quotients or the system's; column-major, kept in CVODE's system matrix)
// and gamma.
//
// With a kinematic block of size p (y = [q; u], q the first p components) A is split as
//   [A11 A12]   A11 = I - gamma dqdot/dq   (p x p: identity but for the rows whose rates
//   [A21 A22]   A12 = -gamma dqdot/du       depend on q, e.g. Euler-angle rates; sparse)
// and solved by block elimination: A11 = P^T L U by a partial-pivoting LU that skips zeros,
// X = A11^-1 A12 (sparse as A12 is), the Schur complement S = A22 - A21 X (m x m, m = n - p,
// dense) by a dense partial-pivoting LU. For the humanoid (p = m = 38) that is about an eighth
// of the work of the dense LU of A. Pivoting does not cross the blocks, so the elimination is
// used only when every pivot of A11 is at least kMinBlockPivot (A11 is then close to the
// identity); otherwise, and without a kinematic block, A is factorised whole.
class NewtonSolver {
 public:
  NewtonSolver(int n, int p) : n_(n), p_(std::clamp(p, 0, n)), m_(n - p_) {
    full_.resize(n_, n_);
    full_lu_ = Eigen::PartialPivLU<Eigen::MatrixXd>(n_);
    rhs_.resize(n_);
    if (p_ > 0) {
      const size_t pp = static_cast<size_t>(p_);
      rows_.reserve(pp);
      lrow_.reserve(pp * pp);
      lval_.reserve(pp * pp);
      urow_.reserve(pp * pp);
      uval_.reserve(pp * pp);
      xrow_.reserve(pp * static_cast<size_t>(m_));
      xval_.reserve(pp * static_cast<size_t>(m_));
      a11_.resize(p_, p_);
      perm_.resize(static_cast<size_t>(p_));
      udiag_.resize(static_cast<size_t>(p_));
      lstart_.resize(static_cast<size_t>(p_) + 1);
      ustart_.resize(static_cast<size_t>(p_) + 1);
      xstart_.resize(static_cast<size_t>(m_) + 1);
      a21_.resize(m_, p_);
      s_.resize(m_, m_);
      s_lu_ = Eigen::PartialPivLU<Eigen::MatrixXd>(m_);
      z_.resize(p_);
      r_.resize(m_);
      x2_.resize(m_);
      col_.resize(p_);
    }
  }

  long fullSetups() const { return full_setups_; }
  void resetCounters() { full_setups_ = 0; }

  // The gamma of the next factorisation (set by the integrator's linear-system function).
  void setGamma(double gamma) { gamma_ = gamma; }
  // false: factor() receives I - gamma J as CVODE formed it (CVODE's own linear-system function).
  void setFormsSystem(bool forms) { forms_system_ = forms; }

  // Factorises A = I - gamma J for the Jacobian J (column-major n x n) and the gamma last set.
  // Each entry of A is formed once, where it is read, as (-gamma) J_ij plus 1 on the diagonal:
  // the same operations, in the same order, as CVODE's SUNMatScaleAddI on a copy of J, so the
  // factors have the same bits without CVODE's copy and scaling of the whole matrix. Returns false
  // when A is singular (a zero pivot).
  bool factor(const double* J) {
    const Eigen::Map<const Eigen::MatrixXd> jac(J, n_, n_);
    blocked_ = p_ > 0 && factorBlocked(jac);
    if (blocked_) return true;
    ++full_setups_;
    full_ = scale() * jac;
    addIdentity(full_);
    full_lu_.compute(full_);
    return nonsingular(full_lu_.matrixLU());
  }

  // Overwrites b (n) with A^-1 b.
  void solve(double* b) {
    Eigen::Map<Eigen::VectorXd> x(b, n_);
    if (!blocked_) {
      rhs_ = x;
      x.noalias() = full_lu_.solve(rhs_);
      return;
    }
    z_ = x.head(p_);
    solveA11(z_.data());
    r_.noalias() = x.tail(m_) - a21_ * z_;
    x2_.noalias() = s_lu_.solve(r_);
    for (int j = 0; j < m_; ++j) {
      const double xj = x2_[j];
      for (int e = xstart_[static_cast<size_t>(j)]; e < xstart_[static_cast<size_t>(j) + 1]; ++e) {
        z_[xrow_[static_cast<size_t>(e)]] -= xval_[static_cast<size_t>(e)] * xj;
      }
    }
    x.head(p_) = z_;
    x.tail(m_) = x2_;
  }

 private:
  static constexpr double kMinBlockPivot = 0.25;

  // With CVODE's own linear-system function the matrix handed to factor() already is A.
  double scale() const { return forms_system_ ? -gamma_ : 1.0; }
  void addIdentity(Eigen::MatrixXd& a) const {
    if (forms_system_) a.diagonal().array() += 1.0;
  }

  static bool nonsingular(const Eigen::MatrixXd& lu) {
    for (Eigen::Index k = 0; k < lu.rows(); ++k) {
      if (!(lu(k, k) != 0.0) || !std::isfinite(lu(k, k))) return false;
    }
    return true;
  }

  // A = I - gamma J is formed blockwise as scale() J plus the identity on the diagonal blocks
  // (addIdentity); the off-diagonal blocks of A have no identity part.
  bool factorBlocked(const Eigen::Map<const Eigen::MatrixXd>& jac) {
    const double c = scale();
    // LU of A11 with partial pivoting, skipping the zero entries of the multiplier column and
    // of the pivot row (for a near-identity A11 almost everything is skipped).
    a11_ = c * jac.topLeftCorner(p_, p_);
    addIdentity(a11_);
    for (int k = 0; k < p_; ++k) {
      int r = k;
      double best = std::abs(a11_(k, k));
      for (int i = k + 1; i < p_; ++i) {
        const double v = std::abs(a11_(i, k));
        if (v > best) {
          best = v;
          r = i;
        }
      }
      if (!(best >= kMinBlockPivot) || !std::isfinite(best)) return false;
      perm_[static_cast<size_t>(k)] = r;
      if (r != k) a11_.row(k).swap(a11_.row(r));
      const double pivot = a11_(k, k);
      rows_.clear();
      for (int i = k + 1; i < p_; ++i) {
        if (a11_(i, k) != 0.0) {
          a11_(i, k) /= pivot;
          rows_.push_back(i);
        }
      }
      if (rows_.empty()) continue;
      for (int j = k + 1; j < p_; ++j) {
        const double akj = a11_(k, j);
        if (akj == 0.0) continue;
        for (const int i : rows_) a11_(i, j) -= a11_(i, k) * akj;
      }
    }
    // L (unit, strictly below the diagonal) and U (strictly above) by columns, nonzeros only.
    lrow_.clear();
    lval_.clear();
    urow_.clear();
    uval_.clear();
    for (int k = 0; k < p_; ++k) {
      lstart_[static_cast<size_t>(k)] = static_cast<int>(lrow_.size());
      ustart_[static_cast<size_t>(k)] = static_cast<int>(urow_.size());
      for (int i = 0; i < k; ++i) {
        if (a11_(i, k) != 0.0) {
          urow_.push_back(i);
          uval_.push_back(a11_(i, k));
        }
      }
      udiag_[static_cast<size_t>(k)] = a11_(k, k);
      for (int i = k + 1; i < p_; ++i) {
        if (a11_(i, k) != 0.0) {
          lrow_.push_back(i);
          lval_.push_back(a11_(i, k));
        }
      }
    }
    lstart_[static_cast<size_t>(p_)] = static_cast<int>(lrow_.size());
    ustart_[static_cast<size_t>(p_)] = static_cast<int>(urow_.size());
    // X = A11^-1 A12, kept by columns (nonzeros only).
    xrow_.clear();
    xval_.clear();
    for (int j = 0; j < m_; ++j) {
      xstart_[static_cast<size_t>(j)] = static_cast<int>(xrow_.size());
      col_ = c * jac.block(0, p_ + j, p_, 1);
      solveA11(col_.data());
      for (int i = 0; i < p_; ++i) {
        if (col_[i] != 0.0) {
          xrow_.push_back(i);
          xval_.push_back(col_[i]);
        }
      }
    }
    xstart_[static_cast<size_t>(m_)] = static_cast<int>(xrow_.size());
    // S = A22 - A21 X.
    a21_ = c * jac.bottomLeftCorner(m_, p_);
    s_ = c * jac.bottomRightCorner(m_, m_);
    addIdentity(s_);
    for (int j = 0; j < m_; ++j) {
      for (int e = xstart_[static_cast<size_t>(j)]; e < xstart_[static_cast<size_t>(j) + 1]; ++e) {
        s_.col(j) -= a21_.col(xrow_[static_cast<size_t>(e)]) * xval_[static_cast<size_t>(e)];
      }
    }
    s_lu_.compute(s_);
    if (!nonsingular(s_lu_.matrixLU())) {
      return false;  // factorised whole instead (and reported singular there if it is)
    }
    return true;
  }

  // v (p) := A11^-1 v.
  void solveA11(double* v) const {
    for (int k = 0; k < p_; ++k) {
      const int r = perm_[static_cast<size_t>(k)];
      if (r != k) std::swap(v[k], v[r]);
    }
    for (int k = 0; k < p_; ++k) {
      const double vk = v[k];
      if (vk == 0.0) continue;
      for (int e = lstart_[static_cast<size_t>(k)]; e < lstart_[static_cast<size_t>(k) + 1]; ++e) {
        v[lrow_[static_cast<size_t>(e)]] -= lval_[static_cast<size_t>(e)] * vk;
      }
    }
    for (int k = p_ - 1; k >= 0; --k) {
      v[k] /= udiag_[static_cast<size_t>(k)];
      const double vk = v[k];
      if (vk == 0.0) continue;
      for (int e = ustart_[static_cast<size_t>(k)]; e < ustart_[static_cast<size_t>(k) + 1]; ++e) {
        v[urow_[static_cast<size_t>(e)]] -= uval_[static_cast<size_t>(e)] * vk;
      }
    }
  }

  int n_, p_, m_;
  double gamma_ = 0.0;
  bool forms_system_ = true;
  bool blocked_ = false;
  long full_setups_ = 0;
  Eigen::MatrixXd full_;
  Eigen::PartialPivLU<Eigen::MatrixXd> full_lu_;
  // Block elimination.
  Eigen::MatrixXd a11_;    // LU of A11 in place
  std::vector<int> perm_;  // row k was interchanged with row perm_[k]
  std::vector<double> udiag_;
  std::vector<int> lstart_, lrow_, ustart_, urow_, xstart_, xrow_, rows_;
  std::vector<double> lval_, uval_, xval_;
  Eigen::MatrixXd a21_, s_;
  Eigen::PartialPivLU<Eigen::MatrixXd> s_lu_;
  Eigen::VectorXd z_, r_, x2_, col_, rhs_;
};

// CVODE's view of a NewtonSolver: a matrix-based direct SUNLinearSolver.
SUNLinearSolver_Type lsGetType(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
SUNLinearSolver_ID lsGetId(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
int lsSetup(SUNLinearSolver S, SUNMatrix A) {
  return static_cast<NewtonSolver*>(S->content)->factor(SUNDenseMatrix_Data(A)) ? SUNLS_SUCCESS : SUNLS_LUFACT_FAIL;
}
int lsSolve(SUNLinearSolver S, SUNMatrix, N_Vector x, N_Vector b, realtype) {
  N_VScale(1.0, b, x);
  static_cast<NewtonSolver*>(S->content)->solve(N_VGetArrayPointer(x));
  return SUNLS_SUCCESS;
}
int lsFree(SUNLinearSolver S) {
  S->content = nullptr;  // owned by the integrator
  SUNLinSolFreeEmpty(S);
  return SUNLS_SUCCESS;
}

}  // namespace

const char* toString(LinearSolver s) {
  switch (s) {
    case LinearSolver::BlockElimination:
      return "block_elimination";
    case LinearSolver::DenseLU:
      return "dense_lu";
  }
  return "unknown";
}

void OdeSystem::jacobian(double, const double*, const double*, double*) {
  throw std::logic_error("this system provides no Jacobian: integrate it with difference quotients");
}

const char* toString(JacobianSource s) {
  switch (s) {
    case JacobianSource::DifferenceQuotient:
      return "difference_quotient";
    case JacobianSource::System:
      return "system";
  }
  return "unknown";
}

const char* toString(CvodeStatus s) {
  switch (s) {
    case CvodeStatus::Success:
      return "success";
    case CvodeStatus::TooMuchWork:
      return "too_much_work";
    case CvodeStatus::TooMuchAccuracy:
      return "too_much_accuracy";
    case CvodeStatus::ErrorTestFailures:
      return "error_test_failures";
    case CvodeStatus::ConvergenceFailures:
      return "convergence_failures";
    case CvodeStatus::RhsFailure:
      return "rhs_failure";
    case CvodeStatus::OtherFailure:
      return "other_failure";
  }
  return "unknown";
}

struct CvodeIntegrator::Impl {
  OdeSystem& system;
  CvodeSettings settings;
  int n = 0;
  SUNContext ctx = nullptr;
  N_Vector y = nullptr;
  N_Vector atol = nullptr;
  SUNMatrix A = nullptr;
  SUNLinearSolver LS = nullptr;
  std::unique_ptr<NewtonSolver> newton;
  bool jacobian_incomplete = false;  // the last Jacobian failed part-way (or had non-finite entries)
  void* mem = nullptr;
  double t = 0.0;
  std::string message;      // last failure
  std::string rhs_error;    // exception text from the right-hand side
  std::string cvode_error;  // text from CVODE's error handler

  Impl(OdeSystem& s, const CvodeSettings& st) : system(s), settings(st) {}

  ~Impl() {
    if (mem) CVodeFree(&mem);
    if (LS) SUNLinSolFree(LS);
    if (A) SUNMatDestroy(A);
    if (atol) N_VDestroy(atol);
    if (y) N_VDestroy(y);
    if (ctx) SUNContext_Free(&ctx);
  }

  static int rhsCallback(realtype t, N_Vector yv, N_Vector ydotv, void* user) {
    Impl& self = *static_cast<Impl*>(user);
    try {
      self.system.rhs(t, N_VGetArrayPointer(yv), N_VGetArrayPointer(ydotv));
    } catch (const std::exception& e) {
      self.rhs_error = e.what();
      return -1;  // unrecoverable: CVode returns CV_RHSFUNC_FAIL
    } catch (...) {
      self.rhs_error = "unknown exception in the right-hand side";
      return -1;
    }
    const double* yd = N_VGetArrayPointer(ydotv);
    for (int i = 0; i < self.n; ++i) {
      if (!std::isfinite(yd[i])) return 1;  // recoverable: CVODE retries with a smaller step
    }
    return 0;
  }

  // The system's Jacobian into the dense matrix J. A throwing jacobian() stops the integration as
  // a throwing rhs() does; a non-finite entry is recoverable (CVODE retries with a smaller step).
  int systemJacobian(realtype t, N_Vector yv, N_Vector fy, SUNMatrix J) {
    double* data = SUNDenseMatrix_Data(J);
    try {
      system.jacobian(t, N_VGetArrayPointer(yv), N_VGetArrayPointer(fy), data);
    } catch (const std::exception& e) {
      rhs_error = std::string("Jacobian: ") + e.what();
      return -1;
    } catch (...) {
      rhs_error = "unknown exception in the Jacobian";
      return -1;
    }
    const long entries = static_cast<long>(n) * n;
    for (long i = 0; i < entries; ++i) {
      if (!std::isfinite(data[i])) return 1;
    }
    return 0;
  }

  // CVODE's Jacobian function (CVodeSetJacFn), for the solvers that let CVODE form I - gamma J.
  static int jacobianCallback(realtype t, N_Vector yv, N_Vector fy, SUNMatrix J, void* user, N_Vector, N_Vector, N_Vector) {
    return static_cast<Impl*>(user)->systemJacobian(t, yv, fy, J);
  }

  static void errorHandler(int code, const char* module, const char* function, char* msg, void* user) {
    Impl& self = *static_cast<Impl*>(user);
    self.cvode_error = std::string(module ? module : "CVODE") + "::" + (function ? function : "?") + " (" + std::to_string(code) +
                       "): " + (msg ? msg : "");
  }

  // CVODE's linear-system function for the block-elimination solver: where CVODE's own copies its
  // saved Jacobian into the system matrix and scales it to I - gamma J at every setup, this one
  // keeps the Jacobian in the system matrix (a new one, difference quotients or the system's,
  // when CVODE asks for one, !jok) and hands gamma to the solver, which forms I - gamma J only
  // where it reads it.
  static int linearSystem(realtype t, N_Vector yv, N_Vector fy, SUNMatrix J, booleantype jok, booleantype* jcur, realtype gamma, void* user,
                          N_Vector tmp1, N_Vector tmp2, N_Vector tmp3) {
    Impl& self = *static_cast<Impl*>(user);
    // A Jacobian that failed part-way leaves J with columns of two Jacobians (CVODE's
    // own function would still hold its last saved one): the next setup forms a new one.
    const bool fresh = !jok || self.jacobian_incomplete;
    *jcur = fresh ? SUNTRUE : SUNFALSE;
    if (fresh) {
      self.jacobian_incomplete = true;
      const int flag = self.settings.jacobian == JacobianSource::System ? self.systemJacobian(t, yv, fy, J)
                                                                        : cvLsDQJac(t, yv, fy, J, self.mem, tmp1, tmp2, tmp3);
      if (flag != 0) return flag;
      self.jacobian_incomplete = false;
    }
    self.newton->setGamma(gamma);
    return 0;
  }

  void check(int flag, const char* what) {
    if (flag < 0) throw std::runtime_error(std::string("CVODE setup failed in ") + what + " (flag " + std::to_string(flag) + ")");
  }
};

CvodeIntegrator::CvodeIntegrator(OdeSystem& system, const CvodeSettings& settings) : impl_(std::make_unique<Impl>(system, settings)) {
  Impl& m = *impl_;
  // Guard against the link-order trap: our SUNDIALS must be the static one linked into this
  // program, not the old copy exported by libSimTKmath.so.
  Dl_info info;
  if (dladdr(reinterpret_cast<void*>(&N_VNew_Serial), &info) != 0 && info.dli_fname && std::strstr(info.dli_fname, "SimTK") != nullptr) {
    throw std::runtime_error(std::string("SUNDIALS symbols resolve to ") + info.dli_fname +
                             " (Simbody's embedded copy): link libsundials_cvode.a before the Simbody libraries");
  }
  m.n = system.size();
  if (static_cast<int>(settings.atol.size()) != m.n) {
    throw std::invalid_argument("CvodeIntegrator: atol must have one entry per state component");
  }
  if (SUNContext_Create(nullptr, &m.ctx) != 0) throw std::runtime_error("SUNContext_Create failed");
  m.y = N_VNew_Serial(m.n, m.ctx);
  m.atol = N_VNew_Serial(m.n, m.ctx);
  if (!m.y || !m.atol) throw std::runtime_error("N_VNew_Serial failed");
  for (int i = 0; i < m.n; ++i) NV_Ith_S(m.atol, i) = settings.atol[static_cast<size_t>(i)];
  m.mem = CVodeCreate(CV_BDF, m.ctx);
  if (!m.mem) throw std::runtime_error("CVodeCreate failed");
  N_VConst(0.0, m.y);
  m.check(CVodeInit(m.mem, &Impl::rhsCallback, 0.0, m.y), "CVodeInit");
  m.check(CVodeSetUserData(m.mem, &m), "CVodeSetUserData");
  m.check(CVodeSetErrHandlerFn(m.mem, &Impl::errorHandler, &m), "CVodeSetErrHandlerFn");
  m.check(CVodeSVtolerances(m.mem, settings.rtol, m.atol), "CVodeSVtolerances");
  m.A = SUNDenseMatrix(m.n, m.n, m.ctx);
  if (!m.A) throw std::runtime_error("dense matrix creation failed");
  if (settings.linear_solver == LinearSolver::DenseLU) {
    m.LS = SUNLinSol_Dense(m.y, m.A, m.ctx);
    if (!m.LS) throw std::runtime_error("SUNLinSol_Dense creation failed");
  } else {
    m.newton = std::make_unique<NewtonSolver>(m.n, settings.kinematic_block);
    m.LS = SUNLinSolNewEmpty(m.ctx);
    if (!m.LS) throw std::runtime_error("linear solver creation failed");
    m.LS->content = m.newton.get();
    m.LS->ops->gettype = lsGetType;
    m.LS->ops->getid = lsGetId;
    m.LS->ops->setup = lsSetup;
    m.LS->ops->solve = lsSolve;
    m.LS->ops->free = lsFree;
  }
  m.check(CVodeSetLinearSolver(m.mem, m.LS, m.A), "CVodeSetLinearSolver");  // Newton iteration
  const bool own_linear_system = m.newton && settings.own_linear_system;
  if (own_linear_system) {
    m.check(CVodeSetLinSysFn(m.mem, &Impl::linearSystem), "CVodeSetLinSysFn");
  } else if (m.newton) {
    m.newton->setFormsSystem(false);
  }
  if (!own_linear_system && settings.jacobian == JacobianSource::System) {
    m.check(CVodeSetJacFn(m.mem, &Impl::jacobianCallback), "CVodeSetJacFn");
  }
  m.check(CVodeSetMaxOrd(m.mem, settings.max_order), "CVodeSetMaxOrd");
  m.check(CVodeSetMaxNumSteps(m.mem, settings.max_steps), "CVodeSetMaxNumSteps");
  if (settings.max_step > 0.0) m.check(CVodeSetMaxStep(m.mem, settings.max_step), "CVodeSetMaxStep");
  if (settings.initial_step > 0.0) m.check(CVodeSetInitStep(m.mem, settings.initial_step), "CVodeSetInitStep");
}

CvodeIntegrator::~CvodeIntegrator() = default;

void CvodeIntegrator::initialize(double t0, const double* y0) {
  Impl& m = *impl_;
  std::memcpy(N_VGetArrayPointer(m.y), y0, sizeof(double) * static_cast<size_t>(m.n));
  m.check(CVodeReInit(m.mem, t0, m.y), "CVodeReInit");
  if (m.newton) m.newton->resetCounters();  // CVodeReInit resets CVODE's counters
  m.t = t0;
  m.message.clear();
}

CvodeStatus CvodeIntegrator::advance(double t_out, double* y_out) {
  Impl& m = *impl_;
  m.rhs_error.clear();
  m.cvode_error.clear();
  m.check(CVodeSetStopTime(m.mem, t_out), "CVodeSetStopTime");
  realtype t_reached = m.t;
  const int flag = CVode(m.mem, t_out, m.y, &t_reached, CV_NORMAL);
  std::memcpy(y_out, N_VGetArrayPointer(m.y), sizeof(double) * static_cast<size_t>(m.n));
  m.t = t_reached;
  if (flag >= 0) return CvodeStatus::Success;
  CvodeStatus s = CvodeStatus::OtherFailure;
  switch (flag) {
    case CV_TOO_MUCH_WORK:
      s = CvodeStatus::TooMuchWork;
      break;
    case CV_TOO_MUCH_ACC:
      s = CvodeStatus::TooMuchAccuracy;
      break;
    case CV_ERR_FAILURE:
      s = CvodeStatus::ErrorTestFailures;
      break;
    case CV_CONV_FAILURE:
      s = CvodeStatus::ConvergenceFailures;
      break;
    case CV_RHSFUNC_FAIL:
    case CV_REPTD_RHSFUNC_ERR:
    case CV_UNREC_RHSFUNC_ERR:
    case CV_FIRST_RHSFUNC_ERR:
      s = CvodeStatus::RhsFailure;
      break;
    case CV_LSETUP_FAIL:  // a throwing OdeSystem::jacobian(), or rhs() within a difference quotient
      if (!m.rhs_error.empty()) s = CvodeStatus::RhsFailure;
      break;
    default:
      break;
  }
  m.message = std::string("CVODE stopped at t = ") + std::to_string(t_reached) + " s (" + toString(s) + ")";
  if (!m.rhs_error.empty()) m.message += ": " + m.rhs_error;
  if (!m.cvode_error.empty()) m.message += "; " + m.cvode_error;
  return s;
}

double CvodeIntegrator::time() const { return impl_->t; }
const std::string& CvodeIntegrator::message() const { return impl_->message; }

CvodeStats CvodeIntegrator::stats() const {
  const Impl& m = *impl_;
  CvodeStats s;
  long v = 0;
  if (CVodeGetNumSteps(m.mem, &v) == CV_SUCCESS) s.steps = v;
  if (CVodeGetNumRhsEvals(m.mem, &v) == CV_SUCCESS) s.rhs_evals = v;
  if (CVodeGetNumJacEvals(m.mem, &v) == CV_SUCCESS) s.jac_evals = v;
  if (CVodeGetNumLinRhsEvals(m.mem, &v) == CV_SUCCESS) s.jac_rhs_evals = v;
  if (CVodeGetNumNonlinSolvIters(m.mem, &v) == CV_SUCCESS) s.nonlin_iters = v;
  if (CVodeGetNumNonlinSolvConvFails(m.mem, &v) == CV_SUCCESS) s.nonlin_conv_fails = v;
  if (CVodeGetNumErrTestFails(m.mem, &v) == CV_SUCCESS) s.err_test_fails = v;
  if (CVodeGetNumLinSolvSetups(m.mem, &v) == CV_SUCCESS) s.lin_setups = v;
  s.lin_full_setups = m.newton ? m.newton->fullSetups() : 0;
  realtype h = 0.0;
  if (CVodeGetLastStep(m.mem, &h) == CV_SUCCESS) s.last_step = h;
  int q = 0;
  if (CVodeGetLastOrder(m.mem, &q) == CV_SUCCESS) s.last_order = q;
  return s;
}

std::string CvodeIntegrator::sundialsVersion() { return SUNDIALS_VERSION; }

}  // namespace lexdyn::sim
