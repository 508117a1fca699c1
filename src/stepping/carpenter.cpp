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

#include "rubdyn/stepping/stepper.hpp"
#include "simplified_newton.hpp"

namespace rubdyn {

namespace {

class Carpenter final : public Stepper {
 public:
  Carpenter(const LagrangianModel& m, const FixedStepOptions& o)
      : m_(m),
        law_(m.contact_law()),
        o_(o),
        qn_(o.scheme == FixedStepScheme::CarpQN),
        spin_(m.spin_coordinate()),
        newton_(30) {}

  std::string_view name() const override { return qn_ ? "carp-qn" : "carp-onevc"; }
  std::string options_json() const override {
    return fmt::format("{{\"h\": {:.6g}, \"itmax\": {}, \"qn_tol\": {:.3g}}}", o_.h, o_.itmax,
                       o_.qn_tol);
  }

  void start(double t0, const Vec7& q0, const Vec7& v0) override {
    // Start-up: q_1 = q_0 + h v_0 + h^2/2 a_0 with a_0 the contact-free acceleration, i.e. the
    // scheme applied at i = 0 with a fictitious q_{-1} = q_0 - h v_0 + h^2/2 a_0: then the
    // central velocity at t_0 is exactly v_0. The spin acceleration history (Algorithm 1's
    // linear guess) starts at a_0's.
    Mat7 M;
    Vec7 f;
    m_.mass_matrix(q0, M);
    m_.smooth_forces(t0, q0, v0, f);
    const Vec7 a0 = M.ldlt().solve(f);
    q_ = q0;
    v_ = v0;
    dq_prev_ = o_.h * v0 - 0.5 * o_.h * o_.h * a0;
    acc_prev_ = acc_prev2_ = spin_ >= 0 ? a0[spin_] : 0.0;
    index_ = 0;
  }

  StepOutcome step(double t, StepReport& r, std::string& message) override;

 private:
  const LagrangianModel& m_;
  const ContactLaw law_;
  const FixedStepOptions o_;
  const bool qn_;
  const int spin_;
  detail::SimplifiedNewton newton_;
  Vec7 q_ = Vec7::Zero(), v_ = Vec7::Zero();  // q_i; the central velocity of the last report
  Vec7 dq_prev_ = Vec7::Zero();               // Delta_i = q_i - q_{i-1}
  double acc_prev_ = 0.0, acc_prev2_ = 0.0;   // spin acceleration at t_{i-1}, t_{i-2}
  long index_ = 0;
};

StepOutcome Carpenter::step(double t, StepReport& r, std::string& message) {
  const double h = o_.h, h2 = h * h;
  const ContactKinematics c_start = m_.contact(q_, v_);
  Mat7 M, dfdq, dfdv, J, Mbar;
  Vec7 f;
  m_.mass_matrix(q_, M);
  auto residual = [&](const Vec7& d, Vec7& R, bool with_jacobians) {
    const Vec7 v = (d + dq_prev_) / (2.0 * h);
    m_.smooth_forces(t, q_, v, f);
    R = M * (d - dq_prev_) / h2 - f;
    if (with_jacobians) {
      m_.smooth_force_jacobians(t, q_, v, dfdq, dfdv);
      J = M / h2 - dfdv / (2.0 * h);
      Mbar = J;
      if (spin_ >= 0) Mbar.col(spin_) = M.col(spin_) / h2;
    }
  };
  // Algorithm 1's contactless first guess: linear spin acceleration.
  Vec7 d = dq_prev_;
  if (spin_ >= 0) d[spin_] = (2.0 * acc_prev_ - acc_prev2_) * h2 + dq_prev_[spin_];
  Vec7 R;
  bool painleve = false;
  // solve_mbar(b) returns M-bar^{-1} b for the correction
  auto correct = [&](Vec7& dd, const auto& solve_mbar, double& FN, double& FT, Phase& ph) {
    const Vec7 qp = q_ + dd;
    const Vec7 vp = (dd + dq_prev_) / (2.0 * h);
    const ContactKinematics c = m_.contact(qp, vp);
    FN = FT = 0.0;
    ph = Phase::Free;
    if (!(c.d_N < 0.0)) return;
    const double s = law_.mu > 0.0 ? (c.v_t > 0.0 ? 1.0 : (c.v_t < 0.0 ? -1.0 : 0.0)) : 0.0;
    const Vec7 CNT = c.W_N - law_.mu * s * c.W_T;
    const Vec7 x = solve_mbar(CNT);
    const double den = c.W_N.dot(x);
    if (!(den > 0.0)) {
      // the correction along C_NT would need F_N < 0 to close the gap: with this friction
      // coefficient the sliding contact of the scheme is ill-posed (Painleve-type)
      painleve = true;
      return;
    }
    FN = -c.d_N / den;
    FT = -law_.mu * s * FN;
    dd += x * FN;
    ph = s < 0.0 ? Phase::SlipNeg : Phase::SlipPos;
  };
  double FN = 0, FT = 0;
  Phase ph = Phase::Free;
  r = StepReport{};
  if (!qn_) {
    // Prediction: simplified Newton on R(Delta) = 0 (simplified_newton.hpp), the Jacobian
    // J = M/h^2 - dfdv/(2h). Scaled change: 1e-14 of the increment plus 1e-16 h (a velocity of
    // 1e-16: round-off).
    newton_.begin_step();
    for (;;) {
      const bool refresh = newton_.needs_matrix();
      residual(d, R, refresh);
      if (refresh) newton_.set_matrix(J);
      const Vec7 step = newton_.inverse() * R;
      d -= step;
      ++r.newton_iters;
      if (!d.allFinite()) {
        message = fmt::format("{}: non-finite iterate at t = {:.17g}", name(), t);
        return StepOutcome::NonFinite;
      }
      const auto next =
          newton_.after((step.array().abs() / (1e-14 * d.array().abs() + 1e-16 * h)).maxCoeff());
      if (next == detail::SimplifiedNewton::Next::Converged) break;
      if (next == detail::SimplifiedNewton::Next::Failed) {
        message =
            fmt::format("carp-onevc: the prediction Newton did not converge at t = {:.17g}", t);
        return StepOutcome::NewtonFailed;
      }
    }
    // Verification, and the correction with M-bar at the predicted spin (Algorithm 1) only
    // when the prediction penetrates.
    if (m_.contact(q_ + d, (d + dq_prev_) / (2.0 * h)).d_N < 0.0) {
      residual(d, R, true);
      // M-bar differs from the prediction Jacobian only in the spin column (by G v / 2h, ~1e-7
      // of M / h^2 here): solve with M-bar by Richardson iteration preconditioned with the
      // kept inverse Jacobian, to round-off (2-3 iterations), instead of factorising M-bar.
      const Mat7& Ji = newton_.inverse();
      auto solve_mbar = [&](const Vec7& b) {
        Vec7 x = Ji * b;
        for (int k = 0; k < 20; ++k) {
          const Vec7 dx = Ji * (b - Mbar * x);
          x += dx;
          if (dx.norm() <= 1e-15 * x.norm()) break;
        }
        return x;
      };
      correct(d, solve_mbar, FN, FT, ph);
    }
  } else {
    // Quasi-Newton loop (Roques et al. 2010): prediction (one solve with M-bar at the current
    // spin), verification, correction, repeated until the increment settles.
    int it = 0;
    for (; it < o_.itmax; ++it) {
      residual(d, R, true);
      const Eigen::PartialPivLU<Mat7> lu(Mbar);
      // each pass predicts the contact-free solution at the current spin from the last iterate
      // (exact in one solve, R being affine in Delta at fixed spin) and corrects it
      Vec7 dn = d - lu.solve(R);
      correct(
          dn, [&lu](const Vec7& b) { return Vec7(lu.solve(b)); }, FN, FT, ph);
      const Vec7 change = dn - d;
      d = dn;
      ++r.newton_iters;
      if (!d.allFinite()) {
        message = fmt::format("{}: non-finite iterate at t = {:.17g}", name(), t);
        return StepOutcome::NonFinite;
      }
      if ((change.array().abs() <= o_.qn_tol * d.array().abs() + 1e-16 * h).all()) break;
    }
    r.unconverged = it == o_.itmax;
  }
  if (painleve) {
    message = fmt::format(
        "{} at t = {:.17g}: C_N^T M-bar^-1 C_NT <= 0, the correction would need F_N < 0 "
        "(sliding friction mu = {} is ill-posed for the scheme here)",
        name(), t, law_.mu);
    return StepOutcome::Painleve;
  }
  if (!d.allFinite()) {
    message = fmt::format("non-finite state at t = {:.17g}", t + h);
    return StepOutcome::NonFinite;
  }
  // the state at t_i with its central velocity; then q_{i+1} = q_i + Delta
  v_ = (d + dq_prev_) / (2.0 * h);
  r.index = index_++;
  r.q = q_;
  r.v = v_;
  r.F_N = FN;
  r.F_T = FT;
  r.P_N = FN * h;
  r.P_T = FT * h;
  r.phase = ph;
  r.v_N_before = c_start.v_N;
  if (FN != 0.0) {
    const ContactKinematics c = m_.contact(q_, v_);
    r.contact_work = (FN * c.v_N + FT * c.v_t) * h;
  }
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
  return std::make_unique<Carpenter>(m, opt);
}

}  // namespace rubdyn
