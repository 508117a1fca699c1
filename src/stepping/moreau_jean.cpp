// Moreau-Jean theta-method (paper eq. 27-33: mj) and its projected version (Acary, CMAME 256,
// 2013: mj-proj), with our f on the right-hand side (M a = f):
//   M(q_{i+eta}) (v_{i+1} - v_i) - h [(1-theta) f(t_i, q_i, v_i) + theta f(t_{i+1}, q_{i+1},
//   v_{i+1})] = W_N r_N + W_T r_T,   q_{i+1} = q_i + h [(1-theta) v_i + theta v_{i+1}].
// Simplified Newton on v_{i+1} (simplified_newton.hpp) with the iteration matrix
//   Mt = M(q_eta) + eta h theta d(M a)/dq|_{a = v - v_i} - h theta (dfdv + h theta dfdq),
// the contact problem being solved at every Newton iterate (so the converged pair (v, r) solves
// the coupled problem). Contact is active (index set) when the predicted gap
// d_N(q_i) + h/2 v_N(q_i, v_i) <= 0. W_N, W_T are taken at q_i (the relation is linearised at
// the start of the step; Siconos' MoreauJeanOSI re-evaluates them at every Newton iterate, which
// changes the scheme at O(h), see validation/siconos). Newton's law at velocity level:
// u_N = v_N(i+1) + e_n v_N(i), u_T = v_t(i+1) + e_t v_t(i), with the 2D Coulomb cone solved
// exactly (contact/coulomb_signorini.hpp). Reported forces are impulse / h.
// mj-proj: after the step, if d_N(q_{i+1}) < 0 the positions are projected back onto d_N = 0
// along M^{-1} W_N (mass-weighted metric, default) or along W_N (Euclidean metric,
// solver.projection = "identity", as Siconos' MLCPProjectOnConstraints); velocities are not
// changed.
#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <span>
#include <vector>

#include "rubdyn/contact/contact_set.hpp"
#include "rubdyn/contact/coulomb_signorini.hpp"
#include "rubdyn/stepping/stepper.hpp"
#include "simplified_newton.hpp"

namespace rubdyn {

namespace {

/// N: the model's dofs, fixed (a fast path) or Eigen::Dynamic (simplified_newton.hpp).
template <int N>
class MoreauJean final : public Stepper {
  using V = detail::SVec<N>;
  using M = detail::SMat<N>;

 public:
  MoreauJean(const LagrangianModel& m, const FixedStepOptions& o)
      : m_(m),
        n_(m.num_dofs()),
        law_(m.contact_law(0)),
        o_(o),
        project_(o.scheme == FixedStepScheme::MoreauJeanProjected),
        rheonomic_(m.rheonomic()),
        newton_(n_, 50),
        q_(V::Zero(n_)),
        v_(V::Zero(n_)),
        v_prev_(V::Zero(n_)),
        M_(n_, n_),
        dfdq_(n_, n_),
        dfdv_(n_, n_),
        dMa_(n_, n_),
        Mt_(n_, n_),
        X_(n_, 1),
        fi_(V::Zero(n_)),
        f_(V::Zero(n_)),
        v_it_(V::Zero(n_)),
        q_it_(V::Zero(n_)),
        qe_(V::Zero(n_)),
        dv_(V::Zero(n_)),
        Phi_(V::Zero(n_)),
        vfree_(V::Zero(n_)),
        vn_(V::Zero(n_)),
        change_(V::Zero(n_)),
        xN_(V::Zero(n_)),
        xT_(V::Zero(n_)),
        WN_(V::Zero(n_)),
        WT_(V::Zero(n_)),
        ci_(n_),
        kin_(n_),
        K_(m.contact_count()),
        set_(std::max(K_, 1)) {
    if (K_ > 1) {  // the K-contact workspaces (sized here: a step allocates nothing)
      const auto K = static_cast<std::size_t>(K_);
      cik_.assign(K, ContactKinematics(n_));
      pk_.assign(K, ContactKinematics(n_));
      WNk_.assign(K, V::Zero(n_));
      WTk_.assign(K, V::Zero(n_));
      XNk_.assign(K, V::Zero(n_));
      XTk_.assign(K, V::Zero(n_));
      bN1k_.assign(K, 0.0);
      bT1k_.assign(K, 0.0);
      act_.reserve(K);
      pen_.reserve(K);
      sc_.assign(K, SetContact{});
      Wd_ = Mat::Zero(2 * K_, 2 * K_);
      u0_ = Vec::Zero(2 * K_);
      Xp_ = Mat::Zero(n_, K_);
    }
  }

  std::string_view name() const override { return project_ ? "mj-proj" : "mj"; }
  std::string options_json() const override {
    if (project_)
      return fmt::format(
          "{{\"h\": {:.6g}, \"theta\": {:.6g}, \"eta\": {:.6g}, \"projection\": \"{}\"}}", o_.h,
          o_.theta, o_.eta, o_.project_with_mass ? "mass" : "identity");
    return fmt::format("{{\"h\": {:.6g}, \"theta\": {:.6g}, \"eta\": {:.6g}}}", o_.h, o_.theta,
                       o_.eta);
  }

  void start(double, const Vec& q0, const Vec& v0) override {
    q_ = q0;
    v_ = v_prev_ = v0;
    prev_impulse_free_ = false;
    index_ = 0;
  }

  StepOutcome step(double t, StepReport& r, std::string& message) override;

 private:
  const LagrangianModel& m_;
  const int n_;
  const ContactLaw law_;
  const FixedStepOptions o_;
  const bool project_;
  const bool rheonomic_;
  detail::SimplifiedNewton<N> newton_;
  V q_, v_;
  V v_prev_;                        // v_{i-1}, for the predictor
  bool prev_impulse_free_ = false;  // the last step had no impulse (and exists)
  long index_ = 0;
  // workspaces
  M M_, dfdq_, dfdv_, dMa_, Mt_;
  Mat X_;  // (n x 1) the projection direction, solved with the model's mass solve
  V fi_, f_, v_it_, q_it_, qe_, dv_, Phi_, vfree_, vn_, change_, xN_, xT_, WN_, WT_;
  ContactKinematics ci_, kin_;
  // K > 1 contacts (docs/time-steppers.md): each contact's kinematics at q_i (cik_) and at the
  // projection (pk_), the active contacts' W_N, W_T and Mt^-1 W (in act_ order), the joint
  // impulse problem (Delassus Wd_, free velocities u0_, ContactSetSolver set_) and the joint
  // position projection (Xp_, a small dense solve)
  const int K_;
  ContactSetSolver set_;
  std::vector<ContactKinematics> cik_, pk_;
  std::vector<V> WNk_, WTk_, XNk_, XTk_;
  std::vector<double> bN1k_, bT1k_;
  std::vector<int> act_, pen_;
  std::vector<SetContact> sc_;
  Mat Wd_, Xp_;
  Vec u0_;
  /// One step of the K-contact path (step() for K = 1 keeps its own arithmetic).
  StepOutcome step_multi(double t, StepReport& r, std::string& message);
};

/// The most contacts Moreau-Jean takes (the joint projection's system lives on the stack).
constexpr int kMaxMjContacts = 16;
/// Solves G x = b in place (m x m, partial pivoting) for the small systems of the K-contact
/// projection (m <= kMaxMjContacts): false when G is singular.
using SmallMat =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxMjContacts, kMaxMjContacts>;
using SmallVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxMjContacts, 1>;
inline bool solve_small(SmallMat& G, SmallVec& b) {
  const Eigen::Index m = G.rows();
  for (Eigen::Index k = 0; k < m; ++k) {
    Eigen::Index p = k;
    for (Eigen::Index i = k + 1; i < m; ++i)
      if (std::abs(G(i, k)) > std::abs(G(p, k))) p = i;
    if (G(p, k) == 0.0) return false;
    if (p != k) {
      G.row(p).swap(G.row(k));
      std::swap(b[p], b[k]);
    }
    for (Eigen::Index i = k + 1; i < m; ++i) {
      const double f = G(i, k) / G(k, k);
      for (Eigen::Index j = k; j < m; ++j) G(i, j) -= f * G(k, j);
      b[i] -= f * b[k];
    }
  }
  for (Eigen::Index k = m - 1; k >= 0; --k) {
    double x = b[k];
    for (Eigen::Index j = k + 1; j < m; ++j) x -= G(k, j) * b[j];
    b[k] = x / G(k, k);
  }
  return true;
}

template <int N>
StepOutcome MoreauJean<N>::step(double t, StepReport& r, std::string& message) {
  if (K_ > 1) return step_multi(t, r, message);
  const double h = o_.h, th = o_.theta, eta = o_.eta;
  m_.smooth_forces(t, q_, v_, fi_);
  m_.compute_contact(0, t, q_, v_, ci_);
  const ContactKinematics& ci = ci_;
  // A prescribed motion's share of the contact speeds (b_N, b_T: zero for a scleronomic model)
  // is taken at the step's end, t_{i+1}, where the velocity-level law holds, with W at q_i
  // like the rest of the relation; the impulse's work uses the mean of its two ends.
  double bN1 = ci.b_N, bT1 = ci.b_T;
  if (rheonomic_) {
    m_.compute_contact(0, t + h, q_, v_, kin_);
    bN1 = kin_.b_N;
    bT1 = kin_.b_T;
  }
  const bool active = ci.normal_defined && ci.d_N + 0.5 * h * ci.v_N <= 0.0;
  // W_N, W_T at q_i in the stepper's vectors (fixed-size on the fast path)
  V& WN = WN_;
  V& WT = WT_;
  WN = ci.W_N;
  WT = ci.W_T;
  // The predictor extrapolates the last acceleration unless the last step had an impulse.
  V& v = v_it_;
  v = v_;
  if (prev_impulse_free_) v += v_ - v_prev_;
  newton_.begin_step();
  double A_NN = 0, A_NT = 0, A_TT = 0;
  auto delassus = [&] {  // W^T Mt^{-1} W with the current iteration matrix
    newton_.apply_inverse(WN, xN_);
    newton_.apply_inverse(WT, xT_);
    A_NN = WN.dot(xN_);
    A_NT = WN.dot(xT_);
    A_TT = WT.dot(xT_);
  };
  if (!newton_.needs_matrix() && active) delassus();
  double rN = 0.0, rT = 0.0;
  Phase ph = Phase::Free;
  r.reset();
  for (;;) {
    q_it_ = q_ + h * ((1.0 - th) * v_ + th * v);
    qe_ = (1.0 - eta) * q_ + eta * q_it_;
    m_.smooth_forces(t + h, q_it_, v, f_);
    dv_ = v - v_;
    m_.mass_product(qe_, dv_, Phi_);  // M(q_{i+eta}) (v - v_i), structured
    Phi_ -= h * ((1.0 - th) * fi_ + th * f_);
    if (newton_.needs_matrix()) {
      m_.mass_matrix(qe_, M_);
      m_.smooth_force_jacobians(t + h, q_it_, v, dfdq_, dfdv_);
      m_.mass_matrix_product_jacobian(qe_, dv_, dMa_);
      Mt_ = M_ + eta * h * th * dMa_ - h * th * (dfdv_ + h * th * dfdq_);
      newton_.set_matrix(Mt_);
      if (active) delassus();
    }
    newton_.apply_inverse(Phi_, vfree_);
    vfree_ = v - vfree_;
    V& vn = vn_;
    vn = vfree_;
    rN = rT = 0.0;
    ph = Phase::Free;
    if (active) {
      // the velocity-level Coulomb-Signorini problem, band: round-off on the velocities
      const LocalSolution sol = solve_coulomb_signorini(
          make_local_problem(A_NN, A_NT, A_TT, WN.dot(vfree_) + bN1 + law_.e_n * ci.v_N,
                             WT.dot(vfree_) + bT1 + law_.e_t * ci.v_t, law_.mu));
      if (!sol.ok()) {
        message = fmt::format(
            "mj: the contact problem has no solution at t = {:.17g} "
            "(Painleve-type Delassus matrix)",
            t);
        return StepOutcome::Painleve;
      }
      r.nonunique = r.nonunique || sol.nonunique();
      rN = sol.r_N;
      rT = sol.r_T;
      ph = sol.phase;
      vn = vfree_ + xN_ * rN + xT_ * rT;
    }
    change_ = vn - v;
    v = vn;
    ++r.newton_iters;
    if (!all_finite(v)) {
      message = fmt::format("mj: non-finite iterate at t = {:.17g}", t);
      return StepOutcome::NonFinite;
    }
    // scaled change: 1e-14 relative plus 1e-15 m/s (or rad/s)
    const auto next =
        newton_.after((change_.array().abs() / (1e-14 * v.array().abs() + 1e-15)).maxCoeff());
    if (next == detail::SimplifiedNewton<N>::Next::Converged) break;
    if (next == detail::SimplifiedNewton<N>::Next::Failed) {
      message = fmt::format("mj: Newton did not converge in {} iterations at t = {:.17g}",
                            newton_.max_iterations(), t);
      return StepOutcome::NewtonFailed;
    }
  }
  V& q = q_it_;
  q = q_ + h * ((1.0 - th) * v_ + th * v);
  if (project_) {
    for (int k = 0; k < 3; ++k) {
      m_.compute_contact(0, t + h, q, v, kin_);
      const ContactKinematics& c = kin_;
      if (!c.normal_defined || c.d_N >= 0.0) break;
      X_.col(0) = c.W_N;
      if (o_.project_with_mass) m_.solve_mass(q, X_);
      q += X_.col(0) * (-c.d_N / c.W_N.dot(X_.col(0)));
    }
  }
  if (!all_finite(q) || !all_finite(v)) {
    message = fmt::format("non-finite state at t = {:.17g}", t + h);
    return StepOutcome::NonFinite;
  }
  // work of the impulse with the mid-step velocity: r . W^T (v_i + v_{i+1}) / 2
  if (rN != 0.0 || rT != 0.0) {
    dv_ = 0.5 * (v_ + v);
    r.contact_work =
        rN * (WN.dot(dv_) + 0.5 * (ci.b_N + bN1)) + rT * (WT.dot(dv_) + 0.5 * (ci.b_T + bT1));
  }
  r.a = (v - v_) / h;
  v_prev_ = v_;
  q_ = q;
  v_ = v;
  prev_impulse_free_ = rN == 0.0 && rT == 0.0;
  r.index = ++index_;
  r.q = q_;
  r.v = v_;
  r.P_N = rN;
  r.P_T = rT;
  r.F_N = rN / h;
  r.F_T = rT / h;
  r.phase = ph;
  r.v_N_before = ci.v_N;
  return StepOutcome::Ok;
}

template <int N>
StepOutcome MoreauJean<N>::step_multi(double t, StepReport& r, std::string& message) {
  // The scheme of step() with K contacts: every contact's index set by its predicted gap, the
  // impulses of the active ones solved jointly at every Newton iterate (contact_set.hpp: the
  // Delassus matrix W^T Mt^-1 W of all active contacts, Newton's law per contact), and with
  // mj-proj every penetrating contact projected jointly.
  const double h = o_.h, th = o_.theta, eta = o_.eta;
  m_.smooth_forces(t, q_, v_, fi_);
  act_.clear();
  for (int k = 0; k < K_; ++k) {
    ContactKinematics& c = cik_[static_cast<std::size_t>(k)];
    m_.compute_contact(k, t, q_, v_, c);
    bN1k_[static_cast<std::size_t>(k)] = c.b_N;
    bT1k_[static_cast<std::size_t>(k)] = c.b_T;
    if (rheonomic_) {
      m_.compute_contact(k, t + h, q_, v_, kin_);
      bN1k_[static_cast<std::size_t>(k)] = kin_.b_N;
      bT1k_[static_cast<std::size_t>(k)] = kin_.b_T;
    }
    if (c.normal_defined && c.d_N + 0.5 * h * c.v_N <= 0.0) act_.push_back(k);
  }
  const int na = static_cast<int>(act_.size());
  for (int a = 0; a < na; ++a) {
    const auto k = static_cast<std::size_t>(act_[static_cast<std::size_t>(a)]);
    WNk_[static_cast<std::size_t>(a)] = cik_[k].W_N;
    WTk_[static_cast<std::size_t>(a)] = cik_[k].W_T;
    sc_[static_cast<std::size_t>(a)] = SetContact{m_.contact_law(static_cast<int>(k)).mu, 0, {}};
  }
  V& v = v_it_;
  v = v_;
  if (prev_impulse_free_) v += v_ - v_prev_;
  newton_.begin_step();
  auto delassus = [&] {  // W^T Mt^{-1} W of the active contacts, with the current matrix
    for (int a = 0; a < na; ++a) {
      const auto ia = static_cast<std::size_t>(a);
      newton_.apply_inverse(WNk_[ia], XNk_[ia]);
      newton_.apply_inverse(WTk_[ia], XTk_[ia]);
    }
    for (int a = 0; a < na; ++a)
      for (int b = 0; b < na; ++b) {
        const auto ia = static_cast<std::size_t>(a), ib = static_cast<std::size_t>(b);
        Wd_(2 * a, 2 * b) = WNk_[ia].dot(XNk_[ib]);
        Wd_(2 * a, 2 * b + 1) = WNk_[ia].dot(XTk_[ib]);
        Wd_(2 * a + 1, 2 * b) = WTk_[ia].dot(XNk_[ib]);
        Wd_(2 * a + 1, 2 * b + 1) = WTk_[ia].dot(XTk_[ib]);
      }
  };
  if (!newton_.needs_matrix() && na > 0) delassus();
  bool solved = false;  // the last iterate solved a contact problem (set_ holds it)
  r.reset();
  for (;;) {
    q_it_ = q_ + h * ((1.0 - th) * v_ + th * v);
    qe_ = (1.0 - eta) * q_ + eta * q_it_;
    m_.smooth_forces(t + h, q_it_, v, f_);
    dv_ = v - v_;
    m_.mass_product(qe_, dv_, Phi_);
    Phi_ -= h * ((1.0 - th) * fi_ + th * f_);
    if (newton_.needs_matrix()) {
      m_.mass_matrix(qe_, M_);
      m_.smooth_force_jacobians(t + h, q_it_, v, dfdq_, dfdv_);
      m_.mass_matrix_product_jacobian(qe_, dv_, dMa_);
      Mt_ = M_ + eta * h * th * dMa_ - h * th * (dfdv_ + h * th * dfdq_);
      newton_.set_matrix(Mt_);
      if (na > 0) delassus();
    }
    newton_.apply_inverse(Phi_, vfree_);
    vfree_ = v - vfree_;
    V& vn = vn_;
    vn = vfree_;
    solved = false;
    if (na > 0) {
      for (int a = 0; a < na; ++a) {
        const auto ia = static_cast<std::size_t>(a);
        const int k = act_[ia];
        const ContactKinematics& c = cik_[static_cast<std::size_t>(k)];
        const ContactLaw& law = m_.contact_law(k);
        u0_[2 * a] = WNk_[ia].dot(vfree_) + bN1k_[static_cast<std::size_t>(k)] + law.e_n * c.v_N;
        u0_[2 * a + 1] =
            WTk_[ia].dot(vfree_) + bT1k_[static_cast<std::size_t>(k)] + law.e_t * c.v_t;
      }
      const auto W = Wd_.topLeftCorner(2 * na, 2 * na);
      const auto u0 = u0_.head(2 * na);
      const SetOutcome o =
          set_.solve(W, u0, std::span<const SetContact>(sc_.data(), static_cast<std::size_t>(na)),
                     contact_set_band(W, u0));
      if (!has_solution(o)) {
        std::string who;
        for (int a = 0; a < na; ++a)
          if (set_.involved(a))
            who +=
                fmt::format("{}{}", who.empty() ? "" : ", ", act_[static_cast<std::size_t>(a)] + 1);
        message = fmt::format(
            "mj: the joint contact problem has no solution at t = {:.17g} ({}; contacts "
            "involved: {})",
            t, to_string(o), who.empty() ? "none named" : who);
        return StepOutcome::Painleve;
      }
      r.nonunique = r.nonunique || o == SetOutcome::NonUnique;
      for (int a = 0; a < na; ++a) {
        const auto ia = static_cast<std::size_t>(a);
        vn += XNk_[ia] * set_.r_N(a) + XTk_[ia] * set_.r_T(a);
      }
      solved = true;
    }
    change_ = vn - v;
    v = vn;
    ++r.newton_iters;
    if (!all_finite(v)) {
      message = fmt::format("mj: non-finite iterate at t = {:.17g}", t);
      return StepOutcome::NonFinite;
    }
    const auto next =
        newton_.after((change_.array().abs() / (1e-14 * v.array().abs() + 1e-15)).maxCoeff());
    if (next == detail::SimplifiedNewton<N>::Next::Converged) break;
    if (next == detail::SimplifiedNewton<N>::Next::Failed) {
      message = fmt::format("mj: Newton did not converge in {} iterations at t = {:.17g}",
                            newton_.max_iterations(), t);
      return StepOutcome::NewtonFailed;
    }
  }
  V& q = q_it_;
  q = q_ + h * ((1.0 - th) * v_ + th * v);
  if (project_) {
    // every penetrating contact onto d_N = 0 at once: q += X lambda with X = M^-1 W_N (or W_N,
    // identity metric) of those contacts and W_N^T X lambda = -d_N (a Newton step; at most 3)
    for (int it = 0; it < 3; ++it) {
      pen_.clear();
      for (int k = 0; k < K_; ++k) {
        ContactKinematics& c = pk_[static_cast<std::size_t>(k)];
        m_.compute_contact(k, t + h, q, v, c);
        if (c.normal_defined && c.d_N < 0.0) pen_.push_back(k);
      }
      const int np = static_cast<int>(pen_.size());
      if (np == 0) break;
      for (int a = 0; a < np; ++a)
        Xp_.col(a) = pk_[static_cast<std::size_t>(pen_[static_cast<std::size_t>(a)])].W_N;
      if (o_.project_with_mass) m_.solve_mass(q, Xp_.leftCols(np));
      SmallMat G(np, np);
      SmallVec rhs(np);
      for (int a = 0; a < np; ++a) {
        const ContactKinematics& ca =
            pk_[static_cast<std::size_t>(pen_[static_cast<std::size_t>(a)])];
        rhs[a] = -ca.d_N;
        for (int b = 0; b < np; ++b) G(a, b) = ca.W_N.dot(Xp_.col(b));
      }
      if (!solve_small(G, rhs)) break;  // redundant constraints: left as they are
      for (int a = 0; a < np; ++a) q += Xp_.col(a) * rhs[a];
    }
  }
  if (!all_finite(q) || !all_finite(v)) {
    message = fmt::format("non-finite state at t = {:.17g}", t + h);
    return StepOutcome::NonFinite;
  }
  // the impulses' work with the mid-step velocity, contact by contact
  dv_ = 0.5 * (v_ + v);
  bool impulse_free = true;
  for (int k = 0; k < K_; ++k) {
    ContactStep& cs = r.contacts[static_cast<std::size_t>(k)];
    cs.v_N_before = cik_[static_cast<std::size_t>(k)].v_N;
  }
  if (solved) {
    for (int a = 0; a < na; ++a) {
      const auto ia = static_cast<std::size_t>(a);
      const int k = act_[ia];
      const ContactKinematics& c = cik_[static_cast<std::size_t>(k)];
      const double rN = set_.r_N(a), rT = set_.r_T(a);
      ContactStep& cs = r.contacts[static_cast<std::size_t>(k)];
      cs.P_N = rN;
      cs.P_T = rT;
      cs.F_N = rN / h;
      cs.F_T = rT / h;
      cs.phase = rN != 0.0 || rT != 0.0 ? set_.mode(a) : Phase::Free;
      if (rN != 0.0 || rT != 0.0) {
        impulse_free = false;
        r.contact_work +=
            rN * (WNk_[ia].dot(dv_) + 0.5 * (c.b_N + bN1k_[static_cast<std::size_t>(k)])) +
            rT * (WTk_[ia].dot(dv_) + 0.5 * (c.b_T + bT1k_[static_cast<std::size_t>(k)]));
      }
    }
  }
  r.a = (v - v_) / h;
  v_prev_ = v_;
  q_ = q;
  v_ = v;
  prev_impulse_free_ = impulse_free;
  r.index = ++index_;
  r.q = q_;
  r.v = v_;
  return StepOutcome::Ok;
}

}  // namespace

std::unique_ptr<Stepper> make_moreau_jean(const LagrangianModel& m, const FixedStepOptions& opt) {
  if (m.contact_count() > kMaxMjContacts)
    throw std::invalid_argument(fmt::format("{}: at most {} contacts; model '{}' has {}",
                                            to_string(opt.scheme), kMaxMjContacts, m.name(),
                                            m.contact_count()));
  if (m.num_dofs() == 7) return std::make_unique<MoreauJean<7>>(m, opt);  // the rigid rotor
  return std::make_unique<MoreauJean<Eigen::Dynamic>>(m, opt);
}

}  // namespace rubdyn
