// Carpenter's scheme (paper, Algorithm 1: carp-onevc) and its quasi-Newton version (Roques et
// al., JSV 329, 2010: carp-qn).
//
// Central differences (eq. 22-23) on the increments Delta_{i+1} = q_{i+1} - q_i:
//   R(Delta) = M(q_i) (Delta - Delta_i) / h^2 - f(t_i, q_i, (Delta + Delta_i) / (2h)) = 0,
// which for the rotor is exactly eq. (24). Working with increments instead of absolute positions
// keeps the spin angle (tens of radians) from eating the digits of h^2 theta''.
// M-bar is the paper's matrix M(q_i)/h^2 + (theta' G + D)/(2h): the Jacobian of R without the
// column of the spin velocity inside the gyroscopic term, i.e. M/h^2 - dfdv/(2h) with the spin
// column of dfdv removed (the spin is the model's spin_coordinate(); a model without one has
// M-bar = the Jacobian). The Newton Jacobian of the prediction keeps that column.
// Correction (eq. 25-26): d_N < 0 at the prediction -> one multiplier along
// C_NT = W_N - mu sign(v_t) W_T (W and v_t at the prediction, v_t central), F_N from
// d_N(q^p) + W_N^T M-bar^{-1} C_NT F_N = 0. The multiplier is a force acting at t_i.
// The state at t_i is complete once Delta_{i+1} is known (its velocity is central): step i
// reports t_i.
#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <vector>

#include "rubdyn/stepping/stepper.hpp"
#include "simplified_newton.hpp"

namespace rubdyn {

namespace {

/// The K-contact workspaces of Carpenter<N, true> (docs/time-steppers.md, 3.1): each contact's
/// kinematics at the prediction, the penetrating contacts' correction directions C_NT,k and
/// M-bar^-1 C_NT,k, and the forces found. Empty for one contact.
template <int N, bool Multi>
struct CarpMulti {
  CarpMulti(int /*n*/, int /*K*/) {}
};
template <int N>
struct CarpMulti<N, true> {
  using V = detail::SVec<N>;
  CarpMulti(int n, int K)
      : kin(static_cast<std::size_t>(K), ContactKinematics(n)),
        C(static_cast<std::size_t>(K), V::Zero(n)),
        X(static_cast<std::size_t>(K), V::Zero(n)),
        s(static_cast<std::size_t>(K), 0.0),
        FN(static_cast<std::size_t>(K), 0.0),
        FT(static_cast<std::size_t>(K), 0.0),
        vN0(static_cast<std::size_t>(K), 0.0),
        phase(static_cast<std::size_t>(K), Phase::Free) {
    pen.reserve(static_cast<std::size_t>(K));
    act.reserve(static_cast<std::size_t>(K));
  }
  std::vector<ContactKinematics> kin;
  std::vector<V> C, X;
  std::vector<double> s, FN, FT, vN0;
  std::vector<Phase> phase;
  std::vector<int> pen, act;  // penetrating contacts; those kept by the active-set loop
};

/// N: the model's dofs, fixed (a fast path) or Eigen::Dynamic (simplified_newton.hpp). Multi:
/// several contacts (a class instance of its own, so that the one-contact step is compiled as
/// before).
template <int N, bool Multi = false>
class Carpenter final : public Stepper {
  using V = detail::SVec<N>;
  using M = detail::SMat<N>;

 public:
  Carpenter(const LagrangianModel& m, const FixedStepOptions& o)
      : m_(m),
        n_(m.num_dofs()),
        law_(m.contact_law(0)),
        o_(o),
        qn_(o.scheme == FixedStepScheme::CarpQN),
        spin_(m.spin_coordinate()),
        newton_(n_, 30, m.spin_coordinate()),
        q_(V::Zero(n_)),
        v_(V::Zero(n_)),
        dq_prev_(V::Zero(n_)),
        M_(n_, n_),
        dfdq_(n_, n_),
        dfdv_(n_, n_),
        J_(n_, n_),
        Mbar_(n_, n_),
        f_(V::Zero(n_)),
        d_(V::Zero(n_)),
        dn_(V::Zero(n_)),
        R_(V::Zero(n_)),
        w_(V::Zero(n_)),
        vc_(V::Zero(n_)),
        qp_(V::Zero(n_)),
        step_(V::Zero(n_)),
        CNT_(V::Zero(n_)),
        x_(V::Zero(n_)),
        dx_(V::Zero(n_)),
        lu_(n_),
        kin_(n_),
        K_(m.contact_count()),
        mw_(n_, K_) {}

  std::string_view name() const override { return qn_ ? "carp-qn" : "carp-onevc"; }
  std::string options_json() const override {
    return fmt::format("{{\"h\": {:.6g}, \"itmax\": {}, \"qn_tol\": {:.3g}}}", o_.h, o_.itmax,
                       o_.qn_tol);
  }

  void start(double t0, const Vec& q0, const Vec& v0) override {
    // Start-up: q_1 = q_0 + h v_0 + h^2/2 a_0 with a_0 the contact-free acceleration, i.e. the
    // scheme applied at i = 0 with a fictitious q_{-1} = q_0 - h v_0 + h^2/2 a_0: then the
    // central velocity at t_0 is exactly v_0. The spin acceleration history (Algorithm 1's
    // linear guess) starts at a_0's.
    m_.mass_matrix(q0, M_);
    m_.smooth_forces(t0, q0, v0, f_);
    const V a0 = M_.ldlt().solve(f_);
    q_ = q0;
    v_ = v0;
    dq_prev_ = o_.h * v0 - 0.5 * o_.h * o_.h * a0;
    acc_prev_ = acc_prev2_ = spin_ >= 0 ? a0[spin_] : 0.0;
    index_ = 0;
  }

  StepOutcome step(double t, StepReport& r, std::string& message) override;

 private:
  /// R(Delta) at d_ (into R_), and with_jacobians: the prediction Jacobian J_ and M-bar.
  void residual(double t, const V& d, bool with_jacobians);
  /// The correction of the increment dd along C_NT (Algorithm 1, eq. 25-26) when the
  /// prediction penetrates; solve_mbar(b, x) sets x = M-bar^{-1} b. kin_ready: kin_ already
  /// holds the kinematics at the prediction (q_i + dd, central velocity).
  template <class SolveMbar>
  void correct(double t, V& dd, const SolveMbar& solve_mbar, double& FN, double& FT, Phase& ph,
               bool kin_ready = false);

  const LagrangianModel& m_;
  const int n_;
  const ContactLaw law_;
  const FixedStepOptions o_;
  const bool qn_;
  const int spin_;
  detail::SimplifiedNewton<N> newton_;
  V q_, v_;                                  // q_i; the central velocity of the last report
  V dq_prev_;                                // Delta_i = q_i - q_{i-1}
  double acc_prev_ = 0.0, acc_prev2_ = 0.0;  // spin acceleration at t_{i-1}, t_{i-2}
  long index_ = 0;
  bool painleve_ = false;
  // workspaces
  M M_, dfdq_, dfdv_, J_, Mbar_;
  V f_, d_, dn_, R_, w_, vc_, qp_, step_, CNT_, x_, dx_;
  Eigen::PartialPivLU<M> lu_;
  ContactKinematics kin_;
  const int K_;
  CarpMulti<N, Multi> mw_;
  /// Multi: the correction of dd for every contact that the prediction penetrates, jointly
  /// (docs/time-steppers.md, 3.1); kin_ready: mw_.kin holds the prediction's kinematics.
  template <class SolveMbar>
  void correct_multi(double t, V& dd, const SolveMbar& solve_mbar, bool kin_ready = false);
  /// Multi: the kinematics of every contact at the prediction q_i + dd (with the central
  /// velocity, at t = t_i, where the multiplier acts); true if one penetrates.
  bool predict_contacts(double t, const V& dd);
};

template <int N, bool Multi>
void Carpenter<N, Multi>::residual(double t, const V& d, bool with_jacobians) {
  const double h = o_.h, h2 = h * h;
  vc_ = (d + dq_prev_) / (2.0 * h);
  m_.smooth_forces(t, q_, vc_, f_);
  w_ = d - dq_prev_;
  m_.mass_product(q_, w_, R_);  // M(q_i) (Delta - Delta_i), structured
  R_ = R_ / h2 - f_;
  if (with_jacobians) {
    m_.mass_matrix(q_, M_);
    m_.smooth_force_jacobians(t, q_, vc_, dfdq_, dfdv_);
    J_ = M_ / h2 - dfdv_ / (2.0 * h);
    Mbar_ = J_;
    if (spin_ >= 0) Mbar_.col(spin_) = M_.col(spin_) / h2;
  }
}

template <int N, bool Multi>
template <class SolveMbar>
void Carpenter<N, Multi>::correct(double t, V& dd, const SolveMbar& solve_mbar, double& FN,
                                  double& FT, Phase& ph, bool kin_ready) {
  const double h = o_.h;
  if (!kin_ready) {
    qp_ = q_ + dd;
    vc_ = (dd + dq_prev_) / (2.0 * h);
    // at t_i (not 0: a prescribed spin's share of the slip speed, b_T = -R omega(t), sets the
    // friction's direction)
    m_.compute_contact(0, t, qp_, vc_, kin_);
  }
  const ContactKinematics& c = kin_;
  FN = FT = 0.0;
  ph = Phase::Free;
  if (!(c.d_N < 0.0)) return;
  const double s = law_.mu > 0.0 ? (c.v_t > 0.0 ? 1.0 : (c.v_t < 0.0 ? -1.0 : 0.0)) : 0.0;
  CNT_ = c.W_N - law_.mu * s * c.W_T;
  solve_mbar(CNT_, x_);
  const double den = c.W_N.dot(x_);
  if (!(den > 0.0)) {
    // the correction along C_NT would need F_N < 0 to close the gap: with this friction
    // coefficient the sliding contact of the scheme is ill-posed (Painleve-type)
    painleve_ = true;
    return;
  }
  FN = -c.d_N / den;
  FT = -law_.mu * s * FN;
  dd += x_ * FN;
  ph = s < 0.0 ? Phase::SlipNeg : Phase::SlipPos;
}

template <int N, bool Multi>
bool Carpenter<N, Multi>::predict_contacts(double t, const V& dd) {
  qp_ = q_ + dd;
  vc_ = (dd + dq_prev_) / (2.0 * o_.h);
  bool any = false;
  for (int k = 0; k < K_; ++k) {
    ContactKinematics& c = mw_.kin[static_cast<std::size_t>(k)];
    m_.compute_contact(k, t, qp_, vc_, c);
    any = any || c.d_N < 0.0;
  }
  return any;
}

template <int N, bool Multi>
template <class SolveMbar>
void Carpenter<N, Multi>::correct_multi(double t, V& dd, const SolveMbar& solve_mbar,
                                        bool kin_ready) {
  // One multiplier per penetrating contact along its C_NT,k = W_N,k - mu_k s_k W_T,k (s_k the
  // sign of its slip at the prediction), all found together: d_N,j(q^p) + sum_k W_N,j^T
  // M-bar^-1 C_NT,k F_k = 0 over the set; a contact whose F comes out negative leaves the set
  // (the most negative first) and the rest is solved again.
  auto& w = mw_;
  if (!kin_ready) predict_contacts(t, dd);
  w.pen.clear();
  for (int k = 0; k < K_; ++k) {
    const auto ik = static_cast<std::size_t>(k);
    w.FN[ik] = w.FT[ik] = 0.0;
    w.phase[ik] = Phase::Free;
    if (w.kin[ik].d_N < 0.0) w.pen.push_back(k);
  }
  if (w.pen.empty()) return;
  for (const int k : w.pen) {
    const auto ik = static_cast<std::size_t>(k);
    const ContactKinematics& c = w.kin[ik];
    const double mu = m_.contact_law(k).mu;
    w.s[ik] = mu > 0.0 ? (c.v_t > 0.0 ? 1.0 : (c.v_t < 0.0 ? -1.0 : 0.0)) : 0.0;
    w.C[ik] = c.W_N - mu * w.s[ik] * c.W_T;
    solve_mbar(w.C[ik], w.X[ik]);
  }
  w.act.assign(w.pen.begin(), w.pen.end());
  while (!w.act.empty()) {
    const auto m = static_cast<Eigen::Index>(w.act.size());
    detail::SmallMat G(m, m);
    detail::SmallVec F(m);
    for (Eigen::Index a = 0; a < m; ++a) {
      const ContactKinematics& ca =
          w.kin[static_cast<std::size_t>(w.act[static_cast<std::size_t>(a)])];
      F[a] = -ca.d_N;
      for (Eigen::Index b = 0; b < m; ++b)
        G(a, b) = ca.W_N.dot(w.X[static_cast<std::size_t>(w.act[static_cast<std::size_t>(b)])]);
    }
    if (!detail::solve_small(G, F)) break;  // singular: reported below
    Eigen::Index worst = -1;
    for (Eigen::Index a = 0; a < m; ++a)
      if (F[a] < 0.0 && (worst < 0 || F[a] < F[worst])) worst = a;
    if (worst < 0) {
      for (Eigen::Index a = 0; a < m; ++a) {
        const auto k = static_cast<std::size_t>(w.act[static_cast<std::size_t>(a)]);
        const double mu = m_.contact_law(static_cast<int>(k)).mu;
        w.FN[k] = F[a];
        w.FT[k] = -mu * w.s[k] * F[a];
        w.phase[k] = w.s[k] < 0.0 ? Phase::SlipNeg : Phase::SlipPos;
        dd += w.X[k] * F[a];
      }
      return;
    }
    w.act.erase(w.act.begin() + worst);
  }
  // no set of the penetrating contacts closes with forces >= 0: as for one contact, the
  // scheme's sliding correction is ill-posed here (Painleve-type)
  painleve_ = true;
}

template <int N, bool Multi>
StepOutcome Carpenter<N, Multi>::step(double t, StepReport& r, std::string& message) {
  const double h = o_.h, h2 = h * h;
  if constexpr (Multi) {
    for (int k = 0; k < K_; ++k) {
      const auto ik = static_cast<std::size_t>(k);
      m_.compute_contact(k, t, q_, v_, kin_);
      mw_.vN0[ik] = kin_.v_N;
      // no force until this step's correction finds one: carp-onevc corrects only when the
      // prediction penetrates, and a step without correction must not report (nor book the
      // work of) the forces of the last step that had one
      mw_.FN[ik] = mw_.FT[ik] = 0.0;
      mw_.phase[ik] = Phase::Free;
    }
    mw_.pen.clear();
  } else {
    m_.compute_contact(0, t, q_, v_, kin_);
  }
  const double v_N_start = kin_.v_N;
  // Algorithm 1's contactless first guess: linear spin acceleration.
  V& d = d_;
  d = dq_prev_;
  if (spin_ >= 0) d[spin_] = (2.0 * acc_prev_ - acc_prev2_) * h2 + dq_prev_[spin_];
  painleve_ = false;
  double FN = 0, FT = 0;
  Phase ph = Phase::Free;
  r.reset();
  if (!qn_) {
    // Prediction: simplified Newton on R(Delta) = 0 (simplified_newton.hpp), the Jacobian
    // J = M/h^2 - dfdv/(2h). Scaled change: 1e-14 of the increment plus 1e-16 h (a velocity of
    // 1e-16: round-off).
    newton_.begin_step();
    for (;;) {
      const bool refresh = newton_.needs_matrix();
      residual(t, d, refresh);
      if (refresh) newton_.set_matrix(J_);
      newton_.apply_inverse(R_, step_);
      d -= step_;
      ++r.newton_iters;
      if (!all_finite(d)) {
        message = fmt::format("{}: non-finite iterate at t = {:.17g}", name(), t);
        return StepOutcome::NonFinite;
      }
      const auto next =
          newton_.after((step_.array().abs() / (1e-14 * d.array().abs() + 1e-16 * h)).maxCoeff());
      if (next == detail::SimplifiedNewton<N>::Next::Converged) break;
      if (next == detail::SimplifiedNewton<N>::Next::Failed) {
        message =
            fmt::format("carp-onevc: the prediction Newton did not converge at t = {:.17g}", t);
        return StepOutcome::NewtonFailed;
      }
    }
    // Verification, and the correction with M-bar at the predicted spin (Algorithm 1) only
    // when the prediction penetrates.
    bool penetrates = false;
    if constexpr (Multi) {
      penetrates = predict_contacts(t, d);
    } else {
      qp_ = q_ + d;
      vc_ = (d + dq_prev_) / (2.0 * h);
      m_.compute_contact(0, t, qp_, vc_, kin_);
      penetrates = kin_.d_N < 0.0;
    }
    if (penetrates) {
      residual(t, d, true);  // (kin_ stays: residual does not touch it)
      // M-bar differs from the prediction Jacobian only in the spin column (by G v / 2h, ~1e-7
      // of M / h^2 here): solve with M-bar by Richardson iteration preconditioned with the
      // kept inverse Jacobian, to round-off (2-3 iterations), instead of factorising M-bar.
      auto solve_mbar = [this](const V& b, V& x) {
        newton_.apply_inverse(b, x);
        for (int k = 0; k < 20; ++k) {
          detail::mat_vec<N>(Mbar_, x, w_);
          w_ = b - w_;
          newton_.apply_inverse(w_, dx_);
          x += dx_;
          if (dx_.norm() <= 1e-15 * x.norm()) break;
        }
      };
      if constexpr (Multi) {
        correct_multi(t, d, solve_mbar, true);
      } else {
        correct(t, d, solve_mbar, FN, FT, ph, true);
      }
    }
  } else {
    // Quasi-Newton loop (Roques et al. 2010): prediction (one solve with M-bar at the current
    // spin), verification, correction, repeated until the increment settles.
    int it = 0;
    for (; it < o_.itmax; ++it) {
      residual(t, d, true);
      lu_.compute(Mbar_);
      // each pass predicts the contact-free solution at the current spin from the last iterate
      // (exact in one solve, R being affine in Delta at fixed spin) and corrects it
      step_ = lu_.solve(R_);
      dn_ = d - step_;
      auto solve_mbar = [this](const V& b, V& x) { x = lu_.solve(b); };
      if constexpr (Multi) {
        correct_multi(t, dn_, solve_mbar);
      } else {
        correct(t, dn_, solve_mbar, FN, FT, ph);
      }
      step_ = dn_ - d;  // the change of the iterate
      d = dn_;
      ++r.newton_iters;
      if (!all_finite(d)) {
        message = fmt::format("{}: non-finite iterate at t = {:.17g}", name(), t);
        return StepOutcome::NonFinite;
      }
      if ((step_.array().abs() <= o_.qn_tol * d.array().abs() + 1e-16 * h).all()) break;
    }
    r.unconverged = it == o_.itmax;
  }
  if (painleve_) {
    if constexpr (Multi) {
      std::string who;
      for (const int k : mw_.pen) who += fmt::format("{}{}", who.empty() ? "" : ", ", k + 1);
      message = fmt::format(
          "{} at t = {:.17g}: no set of the penetrating contacts ({}) closes with forces >= 0 "
          "along C_NT (the sliding correction is ill-posed for the scheme here)",
          name(), t, who);
    } else {
      message = fmt::format(
          "{} at t = {:.17g}: C_N^T M-bar^-1 C_NT <= 0, the correction would need F_N < 0 "
          "(sliding friction mu = {} is ill-posed for the scheme here)",
          name(), t, law_.mu);
    }
    return StepOutcome::Painleve;
  }
  if (!all_finite(d)) {
    message = fmt::format("non-finite state at t = {:.17g}", t + h);
    return StepOutcome::NonFinite;
  }
  // the state at t_i with its central velocity; then q_{i+1} = q_i + Delta
  v_ = (d + dq_prev_) / (2.0 * h);
  // The work of a contact's force over the step: the force the correction applied, C_NT F_N =
  // W_N F_N + W_T F_T with W_N, W_T at the prediction (the kinematics `c` it was found with),
  // along the central velocity. It is exact: with M (Delta_{i+1} - Delta_i) / h^2 = f + C_NT F_N,
  // the work (C_NT F_N)^T v_i h is the change of the half-step kinetic energy the force causes.
  // (The kinematics at q_i instead rotate the force by the step's turn of the normal: with the
  // rotor thrown at 20 m/s into a ring of 1e-4 m clearance, 4.2e3 J of 2.9e4 J went unbooked.)
  const auto work = [&](const ContactKinematics& c, double F_N, double F_T) {
    const double v_N = c.W_N.dot(v_) + c.b_N, v_t = c.W_T.dot(v_) + c.b_T;
    return (F_N * v_N + F_T * v_t) * h;
  };
  r.index = index_++;
  r.q = q_;
  r.v = v_;
  r.F_N = FN;
  r.F_T = FT;
  r.P_N = FN * h;
  r.P_T = FT * h;
  r.phase = ph;
  r.v_N_before = v_N_start;
  if constexpr (Multi) {
    for (int k = 0; k < K_; ++k) {
      const auto ik = static_cast<std::size_t>(k);
      ContactStep& cs = r.contacts[ik];
      cs.F_N = mw_.FN[ik];
      cs.F_T = mw_.FT[ik];
      cs.P_N = mw_.FN[ik] * h;
      cs.P_T = mw_.FT[ik] * h;
      cs.phase = mw_.phase[ik];
      cs.v_N_before = mw_.vN0[ik];
      if (mw_.FN[ik] != 0.0) r.contact_work += work(mw_.kin[ik], mw_.FN[ik], mw_.FT[ik]);
    }
  } else if (FN != 0.0) {
    r.contact_work = work(kin_, FN, FT);
  }
  r.a = (d - dq_prev_) / h2;
  if (spin_ >= 0) {
    acc_prev2_ = acc_prev_;
    acc_prev_ = (d[spin_] - dq_prev_[spin_]) / h2;
  }
  q_ += d;
  dq_prev_ = d;
  return StepOutcome::Ok;
}

}  // namespace

std::unique_ptr<Stepper> make_carpenter(const LagrangianModel& m, const FixedStepOptions& opt) {
  if (m.contact_count() > detail::kMaxSmall)
    throw std::invalid_argument(fmt::format("{}: at most {} contacts; model '{}' has {}",
                                            to_string(opt.scheme), detail::kMaxSmall, m.name(),
                                            m.contact_count()));
  if (m.contact_count() > 1) {
    // the rigid rotor with two planes on sprung rings (9 dofs): fixed-size vectors, as the
    // one-plane rotor's 7
    if (m.num_dofs() == 9) return std::make_unique<Carpenter<9, true>>(m, opt);
    return std::make_unique<Carpenter<Eigen::Dynamic, true>>(m, opt);
  }
  if (m.num_dofs() == 7) return std::make_unique<Carpenter<7>>(m, opt);  // the rigid rotor
  return std::make_unique<Carpenter<Eigen::Dynamic>>(m, opt);
}

}  // namespace rubdyn
