#pragma once
// CvodeSession: RAII over one CVODES integrator (SUNDIALS 6.4.1) with dense linear algebra, the
// caller's structured Newton solves (a SUNDIALS custom matrix and linear solver) or fixed-point
// iteration, root finding and optional projection. This file and
// cvode_session.cpp are the ONLY ones that include SUNDIALS headers; SUNDIALS return flags become
// exceptions or statuses here.
//
// The problem is given as plain callbacks on double arrays (y of size n)
// with a user pointer; a callback returns 0 on success, > 0 for a recoverable failure (CVODE
// retries with a smaller step), < 0 for an unrecoverable one.
#include <memory>
#include <string>

namespace rubdyn::detail {

struct CvodeCallbacks {
  int (*rhs)(double t, const double* y, double* ydot, void* user) = nullptr;
  /// Dense Jacobian d(ydot)/dy, column-major n x n (ld = n). Null: difference quotients.
  int (*jac)(double t, const double* y, const double* ydot, double* J, void* user) = nullptr;
  int (*roots)(double t, const double* y, double* g, void* user) = nullptr;
  /// Structured Newton systems instead of the dense matrix (both or neither; then `jac` is not
  /// used): lsys prepares the solves with I - gamma J at (t, y), re-evaluating J unless jok (then
  /// setting *jcur = 1, else 0), as CVODE decides; lsolve solves (I - gamma J) x = b (x and b
  /// distinct, of size n).
  int (*lsys)(double t, const double* y, double gamma, int jok, int* jcur, void* user) = nullptr;
  int (*lsolve)(const double* b, double* x, void* user) = nullptr;
  /// Projection: fill corr so that y + corr satisfies the constraints (BDF only).
  int (*proj)(double t, const double* y, double* corr, void* user) = nullptr;
  void* user = nullptr;
};

struct CvodeStats {
  long steps = 0, rhs_evals = 0, jac_evals = 0, root_evals = 0, newton_iters = 0;
  long err_test_fails = 0, conv_fails = 0;
};

enum class CvodeMethod { BDF, Adams };

/// What a session integrates and how. Error weights are per component:
/// ewt_i = 1 / (rtol_i |y_i| + atol_i).
struct CvodeConfig {
  int n = 0;
  CvodeMethod method = CvodeMethod::BDF;
  /// Adams only: fixed-point (functional) iteration instead of Newton. A non-stiff system then
  /// needs no Jacobian and no linear solve.
  bool fixed_point = false;
  const double* rtol = nullptr;  ///< size n
  const double* atol = nullptr;  ///< size n
  long max_steps = 500;
};

class CvodeSession {
 public:
  CvodeSession(const CvodeConfig& cfg, const CvodeCallbacks& cb);
  ~CvodeSession();
  CvodeSession(const CvodeSession&) = delete;
  CvodeSession& operator=(const CvodeSession&) = delete;

  /// (Re)starts at t0 from y0, with n_roots witnesses (directions: -1
  /// decreasing only, +1 increasing only, 0 both), projection on or off, analytic Jacobian if
  /// the callbacks have one, and an initial step (0: CVODE's estimate). Counters accumulate.
  void restart(double t0, const double* y0, int n_roots, const int* directions, bool projection,
               double h_init, double t_stop);
  /// Replaces the per-component tolerances (n entries each; copied, nothing allocated): a
  /// session reused for states whose components mean different things (the K-contact charts),
  /// before its restart.
  void set_tolerances(const double* rtol, const double* atol);

  enum class Status { Reached, Step, Root, Failure };
  /// Advances towards tout (CV_NORMAL: steps are never shortened to hit tout; y is interpolated).
  /// On Root, t is the root time and y the interpolated state there. With one_step, returns
  /// after one internal step (Status::Step, t = t_n) unless tout or a root comes first.
  Status advance(double tout, double& t, double* y, bool one_step = false);
  /// k-th derivative of the interpolant at t (inside the last step).
  void dky(double t, int k, double* out) const;
  /// Which witnesses fired: +1 / -1 (rising / falling), 0 (none). Size n_roots.
  void root_info(int* info) const;
  double last_step() const;
  double current_time() const;  ///< t_n, the end of the last internal step
  long steps_since_restart() const;
  CvodeStats stats() const;  ///< accumulated over all restarts
  std::string last_error() const { return last_error_; }

 private:
  /// Sets the witnesses (CVodeRootInit): only at a restart, where CVODE evaluates them at t0
  /// before its first step. Called between steps, CVODE would compare their next values with
  /// the values at the last step end, which it never computed for new witnesses (uninitialised
  /// memory: measured with valgrind on the K-contact scenes, a source of runs that differed
  /// between processes). The witnesses of a phase therefore stay the same from its restart to
  /// the next; what changes between steps is only how the engine evaluates some of them.
  void set_roots(int n_roots, const int* directions);
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string last_error_;
};

}  // namespace rubdyn::detail
