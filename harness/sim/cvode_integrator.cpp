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
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <dlfcn.h>

#include <cmath>
#include <cstring>
#include <exception>
#include <stdexcept>

namespace lexdyn::sim {

const char* toString(CvodeStatus s) {
  switch (s) {
    case CvodeStatus::Success: return "success";
    case CvodeStatus::TooMuchWork: return "too_much_work";
    case CvodeStatus::TooMuchAccuracy: return "too_much_accuracy";
    case CvodeStatus::ErrorTestFailures: return "error_test_failures";
    case CvodeStatus::ConvergenceFailures: return "convergence_failures";
    case CvodeStatus::RhsFailure: return "rhs_failure";
    case CvodeStatus::OtherFailure: return "other_failure";
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
  void* mem = nullptr;
  double t = 0.0;
  std::string message;       // last failure
  std::string rhs_error;     // exception text from the right-hand side
  std::string cvode_error;   // text from CVODE's error handler

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

  static void errorHandler(int code, const char* module, const char* function, char* msg, void* user) {
    Impl& self = *static_cast<Impl*>(user);
    self.cvode_error = std::string(module ? module : "CVODE") + "::" + (function ? function : "?") + " (" +
                       std::to_string(code) + "): " + (msg ? msg : "");
  }

  void check(int flag, const char* what) {
    if (flag < 0) throw std::runtime_error(std::string("CVODE setup failed in ") + what + " (flag " + std::to_string(flag) + ")");
  }
};

CvodeIntegrator::CvodeIntegrator(OdeSystem& system, const CvodeSettings& settings)
    : impl_(std::make_unique<Impl>(system, settings)) {
  Impl& m = *impl_;
  // Guard against the link-order trap: our SUNDIALS must be the static one linked into this
  // program, not the old copy exported by libSimTKmath.so.
  Dl_info info;
  if (dladdr(reinterpret_cast<void*>(&N_VNew_Serial), &info) != 0 && info.dli_fname &&
      std::strstr(info.dli_fname, "SimTK") != nullptr) {
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
  m.LS = SUNLinSol_Dense(m.y, m.A, m.ctx);
  if (!m.A || !m.LS) throw std::runtime_error("dense matrix / linear solver creation failed");
  m.check(CVodeSetLinearSolver(m.mem, m.LS, m.A), "CVodeSetLinearSolver");  // Newton iteration
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
    case CV_TOO_MUCH_WORK: s = CvodeStatus::TooMuchWork; break;
    case CV_TOO_MUCH_ACC: s = CvodeStatus::TooMuchAccuracy; break;
    case CV_ERR_FAILURE: s = CvodeStatus::ErrorTestFailures; break;
    case CV_CONV_FAILURE: s = CvodeStatus::ConvergenceFailures; break;
    case CV_RHSFUNC_FAIL:
    case CV_REPTD_RHSFUNC_ERR:
    case CV_UNREC_RHSFUNC_ERR:
    case CV_FIRST_RHSFUNC_ERR: s = CvodeStatus::RhsFailure; break;
    default: break;
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
  realtype h = 0.0;
  if (CVodeGetLastStep(m.mem, &h) == CV_SUCCESS) s.last_step = h;
  int q = 0;
  if (CVodeGetLastOrder(m.mem, &q) == CV_SUCCESS) s.last_order = q;
  return s;
}

std::string CvodeIntegrator::sundialsVersion() { return SUNDIALS_VERSION; }

}  // namespace lexdyn::sim
