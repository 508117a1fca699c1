#pragma once
// CvodeSession: RAII over one CVODES integrator (SUNDIALS 6.4.1: CVODE plus quadratures) with dense
// linear algebra, root finding, optional projection and quadratures. This file and
// cvode_session.cpp are the ONLY ones that include SUNDIALS headers; SUNDIALS return flags become
// exceptions or statuses here.
//
// The problem is given as plain callbacks on double arrays (y of size n, quadratures of size nq)
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
  /// Projection: fill corr so that y + corr satisfies the constraints (BDF only).
  int (*proj)(double t, const double* y, double* corr, void* user) = nullptr;
  int (*quad)(double t, const double* y, double* qdot, void* user) = nullptr;
  void* user = nullptr;
};

struct CvodeStats {
  long steps = 0, rhs_evals = 0, jac_evals = 0, root_evals = 0, newton_iters = 0;
  long err_test_fails = 0, conv_fails = 0;
};

enum class CvodeMethod { BDF, Adams };

class CvodeSession {
 public:
  /// atol: per-component absolute tolerances (size n); qatol likewise (size nq).
  CvodeSession(int n, int nq, CvodeMethod method, double rtol, const double* atol,
               const double* qatol, const CvodeCallbacks& cb, long max_steps);
  ~CvodeSession();
  CvodeSession(const CvodeSession&) = delete;
  CvodeSession& operator=(const CvodeSession&) = delete;

  /// (Re)starts at t0 from y0 with quadratures q0, with n_roots witnesses (directions: -1
  /// decreasing only, +1 increasing only, 0 both), projection on or off, analytic Jacobian if
  /// the callbacks have one, and an initial step (0: CVODE's estimate). Counters accumulate.
  void restart(double t0, const double* y0, const double* q0, int n_roots, const int* directions,
               bool projection, double h_init, double t_stop);
  /// Changes the witnesses without restarting (same state, same history).
  void set_roots(int n_roots, const int* directions);

  enum class Status { Reached, Step, Root, Failure };
  /// Advances towards tout (CV_NORMAL: steps are never shortened to hit tout; y is interpolated).
  /// On Root, t is the root time and y the interpolated state there. With one_step, returns
  /// after one internal step (Status::Step, t = t_n) unless tout or a root comes first.
  Status advance(double tout, double& t, double* y, bool one_step = false);
  /// k-th derivative of the interpolant at t (inside the last step).
  void dky(double t, int k, double* out) const;
  /// Quadratures at the last returned time.
  void quadratures(double* q) const;
  /// Quadratures interpolated at t (inside the last step).
  void quadratures_at(double t, double* q) const;
  /// Which witnesses fired: +1 / -1 (rising / falling), 0 (none). Size n_roots.
  void root_info(int* info) const;
  double last_step() const;
  double current_time() const;  ///< t_n, the end of the last internal step
  CvodeStats stats() const;     ///< accumulated over all restarts
  std::string last_error() const { return last_error_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string last_error_;
};

}  // namespace rubdyn::detail
