#pragma once
// The phases of the event-driven engine: one CVODE session (cvode_session.hpp, the only place
// that touches SUNDIALS) per formulation, each with its own right-hand side, so that no
// right-hand side branches on the formulation:
//   Free       free flight in (q, v): a = M^{-1} f (one structured solve); Adams (fixed-point)
//              or BDF with the analytic Jacobian, its Newton systems reduced to n x n (lsys_free)
//   Projected  the closed contacts' index-reduced DAE in (q, v): BDF, CVODE's projection after
//              every step (positions onto d_N,k = 0, velocities mass-weighted onto v_N,k = 0 and
//              v_t,k = 0 in stick); its Newton systems free flight's, bordered by the closed
//              contacts' constraints (lsys_projected)
//   Reduced    a contact phase in minimal coordinates (phase_chart.hpp) of one dimension: every
//              mode tuple whose chart has it; the constraints hold by construction; with
//              Newton, its systems the Projected session's, lifted by the chart's tangent map
//              (lsys_reduced)
// A session state is the mechanical part ((q, v) or (p, p')) followed by the kNw works of the
// applied loads, the dampers and friction, integrated with the state and error-controlled like
// it. The witnesses of the running phase (the engine's list, contact_modes.hpp) are evaluated
// here, on the phase's own state. Every buffer is sized when the session is built; each
// callback (right-hand side, Jacobian, projection, witnesses, the engine's queries) has its own
// scratch, so that none overwrites another's.
#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <array>
#include <memory>
#include <span>
#include <vector>

#include "contact_modes.hpp"
#include "cvode_session.hpp"
#include "phase_chart.hpp"
#include "phase_eval.hpp"
#include "rubdyn/core/bordered_band.hpp"

namespace rubdyn::detail {

inline constexpr int kNw = 3;  // works: applied loads, dampers, friction
/// The works' absolute tolerance in a session's error weights [J] (rtol |W| + this).
inline constexpr double kWorkAtol = 1e-9;
using Works = std::array<double, kNw>;

/// Tolerances and limits shared by the sessions.
struct SessionSettings {
  double rtol = 1e-10;
  double atol_q = 1e-12;  ///< positions [m]
  double atol_v = 1e-9;   ///< velocities [m/s]
  double g0 = 1.0;        ///< the gap's scale [m] (angles of reduced coordinates)
  bool adams = true;      ///< Adams (else BDF); a Projected session is always BDF
  bool fixed_point = true;
  /// A Reduced session's Newton systems by CVODE's dense difference quotients (the reference of
  /// tests/events/test_structured_newton.cpp) instead of the structured solve (lsys_reduced).
  bool dense_reduced_newton = false;
  long max_steps = 10'000'000;
};

/// What the sessions share with the engine: the contacts' modes, laws and tolerances, the
/// witnesses of the running phase and how they are armed, the scales. Owned by the engine, read
/// by every session's callbacks.
struct PhaseContext {
  PhaseContext(const LagrangianModel& m, double rtol, double atol, double omega_lim);
  const LagrangianModel& m;
  const int K;
  Modes modes;
  std::vector<ContactLaw> laws;
  std::vector<SwitchTolerances> tol;
  WitnessList witnesses;
  Arming arming;
  double F_ref = 1.0, omega_lim = 0.0;
  const ContactLaw& law(int k) const { return laws[static_cast<std::size_t>(k)]; }
  const SwitchTolerances& tl(int k) const { return tol[static_cast<std::size_t>(k)]; }
  /// The value of a witness (unscaled) from an evaluation of the phase at (t, q, v).
  double witness_value(const WitnessRef& w, const PhaseEval& e, double t, VecIn q, VecIn v) const;
};

enum class SessionKind { Free, Projected, Reduced };

class PhaseSession {
 public:
  /// A Reduced session integrates the mode tuples whose chart has dimension `dim`.
  PhaseSession(const PhaseContext& ctx, const SessionSettings& s, SessionKind kind,
               std::unique_ptr<PhaseChart> chart = nullptr, int dim = 0);
  PhaseSession(const PhaseSession&) = delete;
  PhaseSession& operator=(const PhaseSession&) = delete;

  SessionKind kind() const { return kind_; }
  CvodeSession& session() { return *session_; }
  const CvodeSession& session() const { return *session_; }
  /// Start of the last internal step (the interpolant covers [step_start, current_time]).
  double step_start() const { return session_->current_time() - session_->last_step(); }

  /// (Re)starts at t from (q, v) with the works w, the context's modes and witnesses: a
  /// Projected session projects (q, v) onto the constraints first, a Reduced one starts from
  /// the chart of (q, v); (q, v) become the state it starts from (equal to the input to
  /// round-off).
  void restart(double t, Vec& q, Vec& v, const Works& w, double t_stop);
  /// Advances (CvodeSession::advance) and returns the full state at t.
  CvodeSession::Status advance(double tout, double& t, Vec& q, Vec& v, bool one_step);
  /// The full state at t inside the last step (projected onto the constraints in a Projected
  /// session, whose interpolant is not; on them by construction in a Reduced one).
  void interpolate(double t, Vec& q, Vec& v) const;
  /// Works at the last state advance returned, or interpolated at t in the last step.
  Works works() const;
  Works works_at(double t) const;

  /// Evaluates the phase at a state of it (projected first in a Projected session): forces,
  /// accelerations and kinematics in eval(). False: the closed set is singular.
  bool evaluate(double t, Vec& q, Vec& v) const;
  /// What the witnesses need: evaluate() in a contact phase; in free flight the contacts'
  /// kinematics only (no solve with M; forces 0).
  void evaluate_witnesses(double t, Vec& q, Vec& v) const;
  const PhaseEval& eval() const { return query_; }

  // Free flight's Newton systems (BDF), user = this session: the CVODE callbacks lsys and
  // lsolve (cvode_session.hpp) of the structured solve, and the dense Jacobian it reduces (the
  // state's 2n + 3 components, column-major), kept as its reference (tests/events/
  // test_structured_newton.cpp).
  static int jac_free(double t, const double* y, const double* yd, double* J, void* user);
  static int lsys_free(double t, const double* y, double gamma, int jok, int* jcur, void* user);
  static int lsolve_free(const double* b, double* x, void* user);
  // The Projected session's Newton systems (BDF), user = this session. The constrained
  // acceleration solves M a = f + W_f lambda, H a + wdot = 0 (W_f: the closed contacts' force
  // directions, W_N - mu s W_T in slip, W_N and W_T in stick; H: their constraint rows W_N^T,
  // and W_T^T in stick). Its Jacobian with W_f, H and wdot held fixed (their derivatives act on
  // the contact's own coordinates only, by about lambda / g0 and v / g0:
  // tests/events/test_structured_newton.cpp) turns the Newton system into free flight's S
  // bordered by them,
  //   [S  -W_f] [x_v]   [M b_v + gamma (df/dq - d(M a)/dq) b_q]
  //   [H    0 ] [mu ] = [H b_v                               ],   x_q = b_q + gamma x_v,
  // with d(M a)/dq at the constrained a: S factored once, then a Schur complement of at most
  // 2K rows. CVODE's Newton iteration converges on the exact residual; the Jacobian only sets
  // its rate.
  static int lsys_projected(double t, const double* y, double gamma, int jok, int* jcur,
                            void* user);
  static int lsolve_projected(const double* b, double* x, void* user);
  // A Reduced session's Newton systems (BDF, or Adams with Newton), user = this session. The
  // chart's q = Q(p), v = T(p) p' (+ a rheonomic term), T = dQ/dp, and p'' = L a (L T = I)
  // for the constrained acceleration a of the full model at the embedded state. With T, L and
  // the constrained a's Jacobian held as in lsys_projected (W_f, H, wdot fixed; and T, L at
  // the Jacobian's p: the terms dropped are T's and L's derivatives, acting on the angles and
  // the contact's coordinates only), the reduced Jacobian is [[0, I], [L A_q T, L A_v T]]
  // with A_x the constrained acceleration's. Since T L is the identity on H's null space,
  // where A_x's values lie, y = T x_p' solves the Projected session's bordered system with
  // b_q = T b_p, b_v = T b_p' (H T = 0: its second row is H y = 0):
  //   [S  -W_f] [y ]   [M T b_p' + gamma (df/dq - d(M a)/dq) T b_p]
  //   [H    0 ] [mu] = [0                                          ],
  // x_p' = L y, x_p = b_p + gamma x_p': S banded where the model is, no dense 2n system.
  static int lsys_reduced(double t, const double* y, double gamma, int jok, int* jcur, void* user);
  static int lsolve_reduced(const double* b, double* x, void* user);
  /// The absolute tolerances of the session's state (p, p', works) as CVODE weighs it (a chart
  /// session's: since its last restart).
  std::span<const double> absolute_tolerances() const { return atol_; }
  /// The unscaled value of a witness after evaluate() or evaluate_witnesses().
  double witness_value(const WitnessRef& w, double t, const Vec& q, const Vec& v) const {
    return ctx_.witness_value(w, query_, t, q, v);
  }

 private:
  void to_full(double t, const double* y, Vec& q, Vec& v) const;
  /// Coordinate::length of the model's coordinate i: its error weight's length.
  double length_of(int i) const {
    const auto& c = m_.coordinates();
    return i >= 0 && static_cast<std::size_t>(i) < c.size() ? c[static_cast<std::size_t>(i)].length
                                                            : 1.0;
  }
  /// Free flight's Jacobian blocks at y: M, df/dv and df/dq - d(M a)/dq (in dfdq_) with a
  /// the given acceleration (null: free flight's M^-1 f, into a_), and their band (band_). As
  /// the model's entry lists (ne_, entries_ true) where it gives them and `lists` allows, in
  /// O(entries) instead of O(n^2); else dense.
  void free_jacobians(double t, const double* y, const Vec* a = nullptr, bool lists = true);
  /// Sizes M_, dfdq_, dfdv_, dMa_ (n x n) unless they are: the first dense Jacobian's.
  void size_dense_blocks();
  /// Factors S = M - gamma df/dv - gamma^2 (df/dq - d(M a)/dq) of the last Jacobian.
  bool factor_newton(double gamma);
  /// dv_ = S^-1 (M b_v + gamma (df/dq - d(M a)/dq) b_q), b = (b_q, b_v, ...).
  void newton_velocities(const double* b);
  /// The constrained Jacobian's blocks at the full state y = (q, v): free_jacobians at the
  /// constrained acceleration, W_f and H^T of the closed contacts (lsys_projected). False: the
  /// closed set is singular.
  bool constrained_jacobians(double t, const double* y);
  /// Factors S and the Schur complement H S^-1 W_f for gamma (lsys_projected).
  bool factor_bordered(double gamma);
  /// dv_ = x_v of the bordered system with b = (b_q, b_v, ...) (lsolve_projected).
  void solve_bordered(const double* b);
  void powers(double t, VecIn q, VecIn v, const PhaseEval& e, double* w) const;
  static int rhs_free(double t, const double* y, double* yd, void* user);
  static int rhs_projected(double t, const double* y, double* yd, void* user);
  static int rhs_reduced(double t, const double* y, double* yd, void* user);
  static int proj(double t, const double* y, double* corr, void* user);
  static int roots(double t, const double* y, double* g, void* user);

  const PhaseContext& ctx_;
  const LagrangianModel& m_;
  const int n_, K_;
  const SessionKind kind_;
  const bool rheonomic_;
  std::unique_ptr<PhaseChart> chart_;  ///< Reduced: the chart of the running phase
  const int dim_;                      ///< coordinates of the session state (n_ unless Reduced)
  SessionSettings settings_;
  // scratch of each callback: right-hand side, projection, witnesses, the engine's queries
  mutable PhaseEval rhs_, proj_, roots_, query_;
  mutable Vec q_rhs_, v_rhs_, q_proj_, v_proj_, q_roots_, v_roots_;
  mutable std::vector<ContactForce> forces_;
  Vec p_, pd_;
  std::vector<double> lengths_;
  std::vector<int> copies_;  ///< the full coordinate each chart coordinate copies (-1: an angle)
  std::vector<double> rtol_, atol_, ys_;
  mutable std::vector<double> scratch_;
  // free flight's Jacobian (BDF): M, df/dq - d(M a)/dq, df/dv at its state, and the Newton
  // system reduced to the n x n S = M - gamma df/dv - gamma^2 (df/dq - d(M a)/dq) (lsys_free)
  Mat M_, dfdq_, dfdv_, dMa_;
  NewtonEntries ne_;      ///< the same as entry lists (entries_)
  bool entries_ = false;  ///< the last Jacobian is in ne_ (else in the dense blocks)
  Vec f_, a_, rhs_n_, dv_;
  double gamma_ = 0.0;
  std::unique_ptr<BorderedBand> band_;  ///< S, banded with the spin as its border
  // the Projected session's constraints at its Jacobian's state: W_f, H^T (n x mc), S^-1 W_f,
  // and the Schur complement H S^-1 W_f (lsys_projected)
  std::unique_ptr<PhaseEval> jac_eval_;
  Mat Wf_, Ht_, Y_;
  int mc_ = 0;
  SmallMat E_;
  Eigen::FullPivLU<SmallMat> E_lu_;
  SmallVec res_, mu_;
  // a Reduced session's Newton systems (lsys_reduced): the Jacobian's time, p, p' and full
  // state (q, v), the lifted right-hand side (T b_p, T b_p'), scratch
  double t_jac_ = 0.0;
  Vec p_jac_, pd_jac_, y_jac_, b_full_, q_tan_, x_red_;
  std::unique_ptr<CvodeSession> session_;
};

}  // namespace rubdyn::detail
