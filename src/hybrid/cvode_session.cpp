#include "cvode_session.hpp"

#include <cvodes/cvodes.h>
#include <cvodes/cvodes_proj.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "decision_tolerances.hpp"

namespace rubdyn::detail {

namespace {

/// CVodeGetReturnFlagName returns a malloc'ed string: copy and free it.
std::string flag_name(int flag) {
  char* name = CVodeGetReturnFlagName(flag);
  std::string s = name ? name : "unknown flag";
  std::free(name);
  return s;
}

void check(int flag, const char* what) {
  if (flag < 0) {
    throw std::runtime_error(std::string("CVODE: ") + what + " failed: " + flag_name(flag));
  }
}

// ---- vector operations for small states ----
// CVODE works on states of 13 to 17 components here, and spends most of a step in generic
// vector operations (the Nordsieck predictor alone is q(q+1)/2 linear sums at order q, up to 12):
// with the serial vector each one is two calls deep and branches on its coefficients, and the
// fused operations are emulated by loops of such calls. These replace the hot operations by one
// plain loop each (the same sums; only the rounding order of a few cases differs, e.g. a x + a y
// for the serial a (x + y)); every vector CVODE clones from the template inherits them.
// Measured on the rolling regime (mu = 0.25, 0.5 s): 2.8 -> 1.05 us per step.
namespace small {

// The loops below are element-wise: z[i] depends on x[i], y[i] only. CVODE calls them on
// vectors that are either distinct allocations or the very same vector (the Nordsieck predictor
// adds in place, z == x), never on partly overlapping ones; either way a vectorised loop computes
// the same numbers (the same IEEE operation per element, no reassociation). Without the hint the
// compiler guards its vector loop by an overlap test that the in-place case fails, and the
// predictor's additions ran the scalar loop (callgrind, mu = 0.25 rolling regime).
#define RUBDYN_ELEMENTWISE _Pragma("GCC ivdep")

inline double* data(N_Vector v) {
  return NV_DATA_S(v);
}
inline sunindextype size(N_Vector v) {
  return NV_LENGTH_S(v);
}

void linear_sum(realtype a, N_Vector x, realtype b, N_Vector y, N_Vector z) {
  const double *xd = data(x), *yd = data(y);
  double* zd = data(z);
  const sunindextype n = size(x);
  if (a == 1.0 && b == 1.0) {
    RUBDYN_ELEMENTWISE
    for (sunindextype i = 0; i < n; ++i) zd[i] = xd[i] + yd[i];
  } else if (a == 1.0 && b == -1.0) {
    RUBDYN_ELEMENTWISE
    for (sunindextype i = 0; i < n; ++i) zd[i] = xd[i] - yd[i];
  } else if (a == -1.0 && b == 1.0) {
    RUBDYN_ELEMENTWISE
    for (sunindextype i = 0; i < n; ++i) zd[i] = yd[i] - xd[i];
  } else if (a == 1.0) {
    RUBDYN_ELEMENTWISE
    for (sunindextype i = 0; i < n; ++i) zd[i] = xd[i] + b * yd[i];
  } else if (b == 1.0) {
    RUBDYN_ELEMENTWISE
    for (sunindextype i = 0; i < n; ++i) zd[i] = a * xd[i] + yd[i];
  } else {
    RUBDYN_ELEMENTWISE
    for (sunindextype i = 0; i < n; ++i) zd[i] = a * xd[i] + b * yd[i];
  }
}

void scale(realtype c, N_Vector x, N_Vector z) {
  const double* xd = data(x);
  double* zd = data(z);
  const sunindextype n = size(x);
  RUBDYN_ELEMENTWISE
  for (sunindextype i = 0; i < n; ++i) zd[i] = c * xd[i];
}

realtype wsqrsum(N_Vector x, N_Vector w) {
  const double *xd = data(x), *wd = data(w);
  const sunindextype n = size(x);
  double sum = 0.0;
  for (sunindextype i = 0; i < n; ++i) {
    const double p = xd[i] * wd[i];
    sum += p * p;
  }
  return sum;
}

realtype wrmsnorm(N_Vector x, N_Vector w) {
  return std::sqrt(wsqrsum(x, w) / static_cast<double>(size(x)));
}

/// z = sum_j c_j X_j
int linear_combination(int nv, realtype* c, N_Vector* X, N_Vector z) {
  double* zd = data(z);
  const sunindextype n = size(z);
  const double* x0 = data(X[0]);
  if (X[0] == z) {
    if (c[0] != 1.0)
      for (sunindextype i = 0; i < n; ++i) zd[i] *= c[0];
  } else {
    for (sunindextype i = 0; i < n; ++i) zd[i] = c[0] * x0[i];
  }
  for (int j = 1; j < nv; ++j) {
    const double* xj = data(X[j]);
    for (sunindextype i = 0; i < n; ++i) zd[i] += c[j] * xj[i];
  }
  return 0;
}

/// Z_j = c_j x + Y_j
int scale_add_multi(int nv, realtype* c, N_Vector x, N_Vector* Y, N_Vector* Z) {
  const double* xd = data(x);
  const sunindextype n = size(x);
  for (int j = 0; j < nv; ++j) {
    const double* yd = data(Y[j]);
    double* zd = data(Z[j]);
    RUBDYN_ELEMENTWISE
    for (sunindextype i = 0; i < n; ++i) zd[i] = c[j] * xd[i] + yd[i];
  }
  return 0;
}

void install(N_Vector v) {
  v->ops->nvlinearsum = linear_sum;
  v->ops->nvscale = scale;
  v->ops->nvwrmsnorm = wrmsnorm;
  v->ops->nvwsqrsumlocal = wsqrsum;
  v->ops->nvlinearcombination = linear_combination;
  v->ops->nvscaleaddmulti = scale_add_multi;
}

}  // namespace small

}  // namespace

struct CvodeSession::Impl {
  int n = 0;
  SUNContext ctx = nullptr;
  N_Vector y = nullptr;
  N_Vector out = nullptr;  // an empty vector that wraps the caller's array in dky()
  SUNMatrix A = nullptr;
  SUNLinearSolver LS = nullptr;
  SUNNonlinearSolver NLS = nullptr;
  void* mem = nullptr;
  std::vector<double> rtol, atol;  // per component (error weights)
  std::vector<double> y0;          // the state of the last restart
  double t0 = 0.0;
  double t_stop = 0.0;
  CvodeCallbacks cb;
  CvodeStats acc;  // counters of previous restarts
  bool started = false;
  int n_roots = 0;
  std::vector<int> root_dirs;  // CVodeSetRootDirection's argument (it takes a non-const array)
  /// The last message CVODES reported (error or warning), without its "[CVODES ERROR]"
  /// framing. CVODES prints nothing itself: its messages become part of the typed result.
  std::string message;

  static void on_message(int code, const char* module, const char* function, char* msg, void* ud) {
    auto* self = static_cast<Impl*>(ud);
    self->message = std::string(code < 0 ? "" : "warning: ") + (function ? function : "?") + ": " +
                    (msg ? msg : "") + " (" + (module ? module : "?") + ")";
  }

  static int rhs(realtype t, N_Vector y, N_Vector yd, void* ud) {
    auto* self = static_cast<Impl*>(ud);
    return self->cb.rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yd), self->cb.user);
  }
  static int jac(realtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* ud, N_Vector, N_Vector,
                 N_Vector) {
    auto* self = static_cast<Impl*>(ud);
    return self->cb.jac(t, N_VGetArrayPointer(y), N_VGetArrayPointer(fy), SM_DATA_D(J),
                        self->cb.user);
  }
  // The structured Newton systems (cb.lsys, cb.lsolve): CVODE calls linsys when it would form
  // I - gamma J (its own heuristics decide when J is re-evaluated: jok), then the linear
  // solver's setup (nothing left to do) and solve. The custom matrix is an empty handle: with a
  // user linsys CVODE calls none of its operations but getid.
  static int linsys(realtype t, N_Vector y, N_Vector, SUNMatrix, booleantype jok, booleantype* jcur,
                    realtype gamma, void* ud, N_Vector, N_Vector, N_Vector) {
    auto* self = static_cast<Impl*>(ud);
    int cur = 0;
    const int r = self->cb.lsys(t, N_VGetArrayPointer(y), gamma, jok ? 1 : 0, &cur, self->cb.user);
    *jcur = cur ? SUNTRUE : SUNFALSE;
    if (cur) ++self->structured_jacs;
    return r;
  }
  static SUNMatrix_ID custom_matrix_id(SUNMatrix) { return SUNMATRIX_CUSTOM; }
  static SUNLinearSolver_Type custom_ls_type(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
  static SUNLinearSolver_ID custom_ls_id(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
  static int custom_ls_setup(SUNLinearSolver, SUNMatrix) { return SUNLS_SUCCESS; }
  static int custom_ls_solve(SUNLinearSolver S, SUNMatrix, N_Vector x, N_Vector b, realtype) {
    auto* self = static_cast<Impl*>(S->content);
    return self->cb.lsolve(N_VGetArrayPointer(b), N_VGetArrayPointer(x), self->cb.user) == 0
               ? SUNLS_SUCCESS
               : SUNLS_PACKAGE_FAIL_REC;
  }
  static int custom_ls_free(SUNLinearSolver S) {
    S->content = nullptr;
    SUNLinSolFreeEmpty(S);
    return SUNLS_SUCCESS;
  }
  long structured_jacs = 0;  // since the restart (CVODE counts only its own linsys' Jacobians)

  static int roots(realtype t, N_Vector y, realtype* g, void* ud) {
    auto* self = static_cast<Impl*>(ud);
    return self->cb.roots(t, N_VGetArrayPointer(y), g, self->cb.user);
  }
  static int proj(realtype t, N_Vector y, N_Vector corr, realtype /*eps*/, N_Vector /*err*/,
                  void* ud) {
    auto* self = static_cast<Impl*>(ud);
    return self->cb.proj(t, N_VGetArrayPointer(y), N_VGetArrayPointer(corr), self->cb.user);
  }
  static int weights(N_Vector y, N_Vector ewt, void* ud) {
    auto* self = static_cast<Impl*>(ud);
    const double* yy = N_VGetArrayPointer(y);
    double* w = N_VGetArrayPointer(ewt);
    for (int i = 0; i < self->n; ++i) {
      // never below the state's own round-off (decision_tolerances.hpp, kRoundoffFloor): an
      // absolute weight on a chart angle that grows through a long phase would otherwise ask
      // for more digits than a double holds, and CVODE stops (CV_TOO_MUCH_ACC)
      const double a = std::abs(yy[i]);
      const double tol = std::max(self->rtol[i] * a + self->atol[i], kRoundoffFloor * kEps * a);
      if (!(tol > 0.0)) return -1;
      w[i] = 1.0 / tol;
    }
    return 0;
  }

  /// Adds the counters of the current integration (since the last restart) to s.
  void add_current(CvodeStats& s) const {
    if (!started) return;
    long v = 0;
    CVodeGetNumSteps(mem, &v);
    s.steps += v;
    CVodeGetNumRhsEvals(mem, &v);
    s.rhs_evals += v;
    if (LS) {  // a fixed-point session has no linear solver (and no Jacobian)
      CVodeGetNumJacEvals(mem, &v);
      s.jac_evals += v + structured_jacs;
    }
    CVodeGetNumGEvals(mem, &v);
    s.root_evals += v;
    CVodeGetNumNonlinSolvIters(mem, &v);
    s.newton_iters += v;
    CVodeGetNumErrTestFails(mem, &v);
    s.err_test_fails += v;
    CVodeGetNumNonlinSolvConvFails(mem, &v);
    s.conv_fails += v;
  }
  void collect() { add_current(acc); }  // before a restart resets CVODE's counters

  ~Impl() {
    if (mem) CVodeFree(&mem);
    if (LS) SUNLinSolFree(LS);
    if (NLS) SUNNonlinSolFree(NLS);
    if (A) SUNMatDestroy(A);
    if (out) N_VDestroy(out);
    if (y) N_VDestroy(y);
    if (ctx) SUNContext_Free(&ctx);
  }
};

CvodeSession::CvodeSession(const CvodeConfig& cfg, const CvodeCallbacks& cb)
    : impl_(std::make_unique<Impl>()) {
  auto& I = *impl_;
  const int n = cfg.n;
  I.n = n;
  I.cb = cb;
  I.rtol.assign(cfg.rtol, cfg.rtol + n);
  I.atol.assign(cfg.atol, cfg.atol + n);
  check(SUNContext_Create(nullptr, &I.ctx), "SUNContext_Create");
  I.y = N_VNew_Serial(n, I.ctx);
  if (!I.y) throw std::runtime_error("CVODE: N_VNew_Serial failed (out of memory)");
  small::install(I.y);
  N_VConst(0.0, I.y);
  I.out = N_VNewEmpty_Serial(n, I.ctx);
  if (!I.out) throw std::runtime_error("CVODE: N_VNewEmpty_Serial failed (out of memory)");
  I.mem = CVodeCreate(cfg.method == CvodeMethod::BDF ? CV_BDF : CV_ADAMS, I.ctx);
  if (!I.mem) throw std::runtime_error("CVODE: CVodeCreate failed");
  check(CVodeSetErrHandlerFn(I.mem, &Impl::on_message, &I), "CVodeSetErrHandlerFn");
  check(CVodeInit(I.mem, &Impl::rhs, 0.0, I.y), "CVodeInit");
  check(CVodeSetUserData(I.mem, &I), "CVodeSetUserData");
  check(CVodeWFtolerances(I.mem, &Impl::weights), "CVodeWFtolerances");
  check(CVodeSetMaxNumSteps(I.mem, cfg.max_steps), "CVodeSetMaxNumSteps");
  if (cfg.fixed_point && cfg.method == CvodeMethod::Adams) {
    I.NLS = SUNNonlinSol_FixedPoint(I.y, 0, I.ctx);
    if (!I.NLS) throw std::runtime_error("CVODE: SUNNonlinSol_FixedPoint failed");
    check(CVodeSetNonlinearSolver(I.mem, I.NLS), "CVodeSetNonlinearSolver");
  } else if (cb.lsys && cb.lsolve) {
    I.A = SUNMatNewEmpty(I.ctx);
    if (!I.A) throw std::runtime_error("CVODE: SUNMatNewEmpty failed (out of memory)");
    I.A->ops->getid = &Impl::custom_matrix_id;
    I.LS = SUNLinSolNewEmpty(I.ctx);
    if (!I.LS) throw std::runtime_error("CVODE: SUNLinSolNewEmpty failed (out of memory)");
    I.LS->content = &I;
    I.LS->ops->gettype = &Impl::custom_ls_type;
    I.LS->ops->getid = &Impl::custom_ls_id;
    I.LS->ops->setup = &Impl::custom_ls_setup;
    I.LS->ops->solve = &Impl::custom_ls_solve;
    I.LS->ops->free = &Impl::custom_ls_free;
    check(CVodeSetLinearSolver(I.mem, I.LS, I.A), "CVodeSetLinearSolver");
    check(CVodeSetLinSysFn(I.mem, &Impl::linsys), "CVodeSetLinSysFn");
  } else {
    I.A = SUNDenseMatrix(n, n, I.ctx);
    if (!I.A) throw std::runtime_error("CVODE: SUNDenseMatrix failed (out of memory)");
    I.LS = SUNLinSol_Dense(I.y, I.A, I.ctx);
    if (!I.LS) throw std::runtime_error("CVODE: SUNLinSol_Dense failed");
    check(CVodeSetLinearSolver(I.mem, I.LS, I.A), "CVodeSetLinearSolver");
    if (cb.jac) check(CVodeSetJacFn(I.mem, &Impl::jac), "CVodeSetJacFn");
  }
  if (cb.proj) {
    check(CVodeSetProjFn(I.mem, &Impl::proj), "CVodeSetProjFn");
    check(CVodeSetProjErrEst(I.mem, SUNFALSE), "CVodeSetProjErrEst");
  }
}

CvodeSession::~CvodeSession() = default;

void CvodeSession::restart(double t0, const double* y0, int n_roots, const int* directions,
                           bool projection, double h_init, double t_stop) {
  auto& I = *impl_;
  I.collect();
  I.structured_jacs = 0;  // (counted since the restart, as CVODE's own counters)
  std::memcpy(N_VGetArrayPointer(I.y), y0, sizeof(double) * I.n);
  I.y0.assign(y0, y0 + I.n);
  I.t0 = t0;
  I.t_stop = t_stop;
  check(CVodeReInit(I.mem, t0, I.y), "CVodeReInit");
  set_roots(n_roots, directions);
  if (I.cb.proj) check(CVodeSetProjFrequency(I.mem, projection ? 1 : 0), "CVodeSetProjFrequency");
  check(CVodeSetInitStep(I.mem, h_init), "CVodeSetInitStep");
  check(CVodeSetStopTime(I.mem, t_stop), "CVodeSetStopTime");
  I.started = true;
}

void CvodeSession::set_tolerances(const double* rtol, const double* atol) {
  auto& I = *impl_;
  std::copy(rtol, rtol + I.n, I.rtol.begin());
  std::copy(atol, atol + I.n, I.atol.begin());
}

void CvodeSession::set_roots(int n_roots, const int* directions) {
  auto& I = *impl_;
  check(CVodeRootInit(I.mem, n_roots, n_roots > 0 ? &Impl::roots : nullptr), "CVodeRootInit");
  if (n_roots > 0) {
    I.root_dirs.assign(directions, directions + n_roots);
    check(CVodeSetRootDirection(I.mem, I.root_dirs.data()), "CVodeSetRootDirection");
    // CVODE warns when a witness is zero at t0 and keeps it inactive until it moves away:
    // that is the half-open interval rule we rely on; the warning itself is not useful.
    check(CVodeSetNoInactiveRootWarn(I.mem), "CVodeSetNoInactiveRootWarn");
  }
  I.n_roots = n_roots;
}

CvodeSession::Status CvodeSession::advance(double tout, double& t, double* y, bool one_step) {
  auto& I = *impl_;
  realtype tret = 0.0;
  if (I.started && steps_since_restart() == 0) {
    // The first step after a restart. CVODE estimates it from the distance to the tout of the
    // call (cvHin starts from a tenth of it), so the output grid, or the end time, would change
    // the steps taken. It is taken towards t0 + kFirstStepHorizon instead (the step itself is
    // still cut at t_stop); tout is then interpolated, or reached by the call below.
    const int flag = CVode(I.mem, I.t0 + kFirstStepHorizon, I.y, &tret, CV_ONE_STEP);
    t = tret;
    std::memcpy(y, N_VGetArrayPointer(I.y), sizeof(double) * I.n);
    if (flag == CV_ROOT_RETURN) return Status::Root;
    if (flag != CV_SUCCESS && flag != CV_TSTOP_RETURN) {
      last_error_ = flag_name(flag);
      return Status::Failure;
    }
    if (tret >= tout) {
      t = tout;
      dky(tout, 0, y);
      return Status::Reached;
    }
    if (one_step) return Status::Step;
  }
  if (one_step && I.started) {
    // After a root return the integrator may already be past tout (the root lies before tout,
    // the step that found it ended after it). A further single step would leave tout outside
    // the interpolation interval [tcur - hu, tcur]; in normal mode CVODE first searches the rest
    // of the current step for roots, then interpolates at tout without stepping.
    realtype tcur = 0.0;
    if (CVodeGetCurrentTime(I.mem, &tcur) == CV_SUCCESS && tcur >= tout) one_step = false;
  }
  const int flag = CVode(I.mem, tout, I.y, &tret, one_step ? CV_ONE_STEP : CV_NORMAL);
  t = tret;
  std::memcpy(y, N_VGetArrayPointer(I.y), sizeof(double) * I.n);
  if (flag == CV_ROOT_RETURN) return Status::Root;
  if (flag == CV_TSTOP_RETURN) return Status::Reached;
  if (flag == CV_SUCCESS) {
    if (one_step && tret < tout) return Status::Step;
    if (one_step && tret > tout) {  // stepped past tout: interpolate back to it
      t = tout;
      dky(tout, 0, y);
    }
    return Status::Reached;
  }
  last_error_ = flag_name(flag);
  if (!I.message.empty()) last_error_ += " (" + I.message + ")";
  return Status::Failure;
}

void CvodeSession::dky(double t, int k, double* out) const {
  auto& I = *impl_;
  long nst = 0;
  CVodeGetNumSteps(I.mem, &nst);
  if (nst == 0 && k == 0 && t == I.t0) {
    // no step since the restart: CVODE has no interpolant yet (an event at the very start of a
    // phase, e.g. an impact in the initial state); the state is the restart state
    std::memcpy(out, I.y0.data(), sizeof(double) * I.n);
    return;
  }
  N_VSetArrayPointer(out, I.out);  // the caller's array, wrapped without allocating
  const int flag = CVodeGetDky(I.mem, t, k, I.out);
  if (flag < 0) {
    throw std::runtime_error("CVODE: CVodeGetDky failed: " + flag_name(flag) +
                             (I.message.empty() ? "" : " (" + I.message + ")"));
  }
}

void CvodeSession::root_info(int* info) const {
  check(CVodeGetRootInfo(impl_->mem, info), "CVodeGetRootInfo");
}

double CvodeSession::last_step() const {
  realtype h = 0.0;
  CVodeGetLastStep(impl_->mem, &h);
  return h;
}

double CvodeSession::current_time() const {
  realtype t = 0.0;
  CVodeGetCurrentTime(impl_->mem, &t);
  return t;
}

long CvodeSession::steps_since_restart() const {
  long nst = 0;
  CVodeGetNumSteps(impl_->mem, &nst);
  return nst;
}

CvodeStats CvodeSession::stats() const {
  CvodeStats s = impl_->acc;
  impl_->add_current(s);
  return s;
}

}  // namespace rubdyn::detail
