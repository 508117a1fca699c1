#pragma once
// The Moreau-Jean stepper's class (moreau_jean.cpp: the scheme and its one-contact step;
// moreau_jean_multi.cpp: the step with several contacts). Internal to src/stepping.
#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <span>
#include <vector>

#include "rubdyn/contact/contact_set.hpp"
#include "rubdyn/stepping/stepper.hpp"
#include "simplified_newton.hpp"

namespace rubdyn::detail {

/// The K-contact workspaces of MoreauJean<N, true> (docs/time-steppers.md, 3.1), sized when the
/// stepper is built so that a step allocates nothing: each contact's kinematics at q_i (cik) and
/// at the projection (pk), the active contacts' W_N, W_T and Mt^-1 W (in act order), the joint
/// impulse problem (Delassus W, free velocities u0, ContactSetSolver set) and the joint position
/// projection (Xp). Empty for one contact: the one-contact stepper is the class it was.
template <int N, bool Multi>
struct MultiWork {
  MultiWork(int /*n*/, int /*K*/) {}
};
template <int N>
struct MultiWork<N, true> {
  using V = SVec<N>;
  MultiWork(int n, int K)
      : set(K),
        cik(static_cast<std::size_t>(K), ContactKinematics(n)),
        pk(static_cast<std::size_t>(K), ContactKinematics(n)),
        WNk(static_cast<std::size_t>(K), V::Zero(n)),
        WTk(static_cast<std::size_t>(K), V::Zero(n)),
        XNk(static_cast<std::size_t>(K), V::Zero(n)),
        XTk(static_cast<std::size_t>(K), V::Zero(n)),
        bN1k(static_cast<std::size_t>(K), 0.0),
        bT1k(static_cast<std::size_t>(K), 0.0),
        sc(static_cast<std::size_t>(K)),
        Wd(Mat::Zero(2 * K, 2 * K)),
        Xp(Mat::Zero(n, K)),
        u0(Vec::Zero(2 * K)),
        rN(static_cast<std::size_t>(K), 0.0),
        rT(static_cast<std::size_t>(K), 0.0),
        mode(static_cast<std::size_t>(K), Phase::Free),
        last_mode(static_cast<std::size_t>(K), Phase::Free),
        guess(static_cast<std::size_t>(K), Phase::Free) {
    act.reserve(static_cast<std::size_t>(K));
    pen.reserve(static_cast<std::size_t>(K));
  }
  ContactSetSolver set;
  std::vector<ContactKinematics> cik, pk;
  std::vector<V> WNk, WTk, XNk, XTk;
  std::vector<double> bN1k, bT1k;
  std::vector<int> act, pen;
  std::vector<SetContact> sc;
  Mat Wd, Xp;
  Vec u0;
  std::vector<double> rN, rT;  ///< the active contacts' impulses of the last solve
  std::vector<Phase> mode;     ///< and their modes
  /// each contact's mode in the last joint solve (Free when it was not active): the first guess
  /// of the next (ContactSetSolver::solve_guess), in act order in `guess`
  std::vector<Phase> last_mode, guess;
  bool unique = false;  ///< unique_by_monotonicity of the current Wd (set with it)
};

/// N: the model's dofs, fixed (a fast path) or Eigen::Dynamic (simplified_newton.hpp).
template <int N, bool Multi = false>
class MoreauJean final : public Stepper {
  using V = SVec<N>;
  using M = SMat<N>;

 public:
  MoreauJean(const LagrangianModel& m, const FixedStepOptions& o)
      : m_(m),
        n_(m.num_dofs()),
        law_(m.contact_law(0)),
        o_(o),
        project_(o.scheme == FixedStepScheme::MoreauJeanProjected),
        rheonomic_(m.rheonomic()),
        newton_(n_, 50, m.spin_coordinate()),
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
        mw_(n_, K_) {}

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
  SimplifiedNewton<N> newton_;
  V q_, v_;
  V v_prev_;                        // v_{i-1}, for the predictor
  bool prev_impulse_free_ = false;  // the last step had no impulse (and exists)
  long index_ = 0;
  // workspaces
  M M_, dfdq_, dfdv_, dMa_, Mt_;
  Mat X_;  // (n x 1) the projection direction, solved with the model's mass solve
  V fi_, f_, v_it_, q_it_, qe_, dv_, Phi_, vfree_, vn_, change_, xN_, xT_, WN_, WT_;
  ContactKinematics ci_, kin_;
  const int K_;
  MultiWork<N, Multi> mw_;  // the K-contact workspaces (empty for one contact)
  /// The free velocity of a Newton iterate at v, into vfree_: the residual
  /// Phi = M(q_eta) (v - v_i) - h [(1 - theta) f_i + theta f_{i+1}], the iteration matrix
  /// refreshed first when it is due (then `refreshed()`: the step's Delassus matrix depends on
  /// it), vfree = v - Mt^-1 Phi. Shared by both steps (inlined into each).
  template <class Refreshed>
  void free_velocity(double t, const V& v, Refreshed&& refreshed) {
    const double h = o_.h, th = o_.theta, eta = o_.eta;
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
      refreshed();
    }
    newton_.apply_inverse(Phi_, vfree_);
    vfree_ = v - vfree_;
  }
  enum class Iterate { Again, Converged, Failed };
  /// Takes the Newton iterate vn (v <- vn) and says what follows; on failure `out` and
  /// `message` say why. Shared by both steps.
  Iterate accept(double t, V& v, const V& vn, StepReport& r, StepOutcome& out,
                 std::string& message) {
    change_ = vn - v;
    v = vn;
    ++r.newton_iters;
    if (!all_finite(v)) {
      message = fmt::format("mj: non-finite iterate at t = {:.17g}", t);
      out = StepOutcome::NonFinite;
      return Iterate::Failed;
    }
    // scaled change: 1e-14 relative plus 1e-15 m/s (or rad/s)
    const auto next =
        newton_.after((change_.array().abs() / (1e-14 * v.array().abs() + 1e-15)).maxCoeff());
    if (next == SimplifiedNewton<N>::Next::Converged) return Iterate::Converged;
    if (next == SimplifiedNewton<N>::Next::Failed) {
      message = fmt::format("mj: Newton did not converge in {} iterations at t = {:.17g}",
                            newton_.max_iterations(), t);
      out = StepOutcome::NewtonFailed;
      return Iterate::Failed;
    }
    return Iterate::Again;
  }

  /// One step of the K-contact path: step() of MoreauJean<N, true> (moreau_jean_multi.cpp).
  /// Multi is a template parameter, not a branch in step(): a branch at its top, or the
  /// K-contact step compiled in the same unit, changed how GCC inlines the one-contact step's
  /// Eigen kernels (measured: 5-13 % more instructions per step on the reference case).
  StepOutcome step_multi(double t, StepReport& r, std::string& message);
};

/// The most contacts Moreau-Jean takes (the joint projection's system lives on the stack).
constexpr int kMaxMjContacts = kMaxSmall;

/// The stepper for a model with several contacts (moreau_jean_multi.cpp): dynamic sizes.
std::unique_ptr<Stepper> make_moreau_jean_multi(const LagrangianModel& m,
                                                const FixedStepOptions& o);

}  // namespace rubdyn::detail
