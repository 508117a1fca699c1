// Fixed-step schemes: Carpenter (one-VC, QN) and Moreau-Jean (plain, projected).
// Decisions left open by the paper are stated where they are taken (see also
// include/rubdyn/stepping/fixed_step.hpp).
#include "rubdyn/stepping/fixed_step.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "rubdyn/core/demand.hpp"
#include "rubdyn/core/run_monitor.hpp"

namespace rubdyn {

std::string_view to_string(FixedStepScheme s) {
  switch (s) {
    case FixedStepScheme::CarpOneVC: return "carp-onevc";
    case FixedStepScheme::CarpQN: return "carp-qn";
    case FixedStepScheme::MoreauJean: return "mj";
    case FixedStepScheme::MoreauJeanProjected: return "mj-proj";
  }
  return "?";
}

bool parse_fixed_step_scheme(std::string_view name, FixedStepScheme& out) {
  for (auto s : {FixedStepScheme::CarpOneVC, FixedStepScheme::CarpQN, FixedStepScheme::MoreauJean,
                 FixedStepScheme::MoreauJeanProjected}) {
    if (name == to_string(s)) {
      out = s;
      return true;
    }
  }
  return false;
}

namespace {

/// The local 2D contact problem of one step, solved exactly by enumeration:
///   u = u_free + A r,  r = (r_N, r_T), A the 2x2 Delassus matrix,
///   0 <= u_N  _|_  r_N >= 0,  Coulomb: u_T = 0 and |r_T| <= mu r_N (stick), or
///   r_T = -mu s r_N with s = sign(u_T) (slip).
/// Returns the phase (Free, Stick, SlipPos, SlipNeg) and r. When several candidates are
/// consistent (possible only for a Painleve-type Delassus matrix) the first of free, stick,
/// slip+, slip- is kept and `ambiguous` is set; when none is (same cause) r = 0 and `ok` false.
struct LocalSolution {
  Phase phase = Phase::Free;
  double r_N = 0.0, r_T = 0.0;
  bool ok = true, ambiguous = false;
};

LocalSolution solve_local(double A_NN, double A_NT, double A_TT, double uN, double uT, double mu) {
  LocalSolution sol;
  const double scale = std::abs(uN) + std::abs(uT) + 1e-300;
  const double tol = 1e-13 * scale;  // round-off band on velocities
  int found = 0;
  auto take = [&](Phase p, double rN, double rT) {
    if (found++ == 0) {
      sol.phase = p;
      sol.r_N = rN;
      sol.r_T = rT;
    } else {
      sol.ambiguous = true;
    }
  };
  if (uN >= -tol) take(Phase::Free, 0.0, 0.0);
  if (mu == 0.0) {
    if (A_NN > 0.0) {
      const double rN = -uN / A_NN;
      if (rN > 0.0) take(Phase::SlipPos, rN, 0.0);
    }
  } else {
    const double det = A_NN * A_TT - A_NT * A_NT;
    if (det > 0.0) {
      const double rN = -(A_TT * uN - A_NT * uT) / det;
      const double rT = -(-A_NT * uN + A_NN * uT) / det;
      if (rN > 0.0 && std::abs(rT) <= mu * rN) take(Phase::Stick, rN, rT);
    }
    for (double s : {1.0, -1.0}) {
      const double m = A_NN - mu * s * A_NT;
      if (m == 0.0) continue;
      const double rN = -uN / m;
      if (!(rN > 0.0)) continue;
      const double rT = -mu * s * rN;
      const double uT_after = uT + A_NT * rN + A_TT * rT;
      if (s * uT_after > tol) take(s > 0 ? Phase::SlipPos : Phase::SlipNeg, rN, rT);
    }
  }
  // "free" found together with a contact candidate whose impulse is ~0 is the boundary case
  if (found > 1 && sol.phase == Phase::Free) sol.ambiguous = sol.ambiguous && uN > tol;
  sol.ok = found > 0;
  return sol;
}

class FixedStepRunner {
 public:
  FixedStepRunner(const LagrangianModel& m, const FixedStepOptions& o, OutputSink& sink)
      : m_(m), o_(o), sink_(sink), law_(m.contact_law()), mon_(law_.mu, o.omega_lim) {}

  RunSummary run(const MechanicalState& init, double t_end);

 private:
  // --- helpers shared by the schemes ---
  double energy(const Vec7& q, const Vec7& v) const {
    return m_.kinetic_energy(q, v) + m_.potential_energy(q);
  }
  bool finite(const Vec7& a, const Vec7& b) const { return a.allFinite() && b.allFinite(); }

  /// Records the end of a step: monitor, events between steps, output.
  void record(long i, double t, const Vec7& q, const Vec7& v, double FN, double FT, Phase phase,
              double vN_before, double PN, double PT);

  // --- schemes: each advances one step; false on numerical failure (message set) ---
  bool carpenter_step(double t, bool qn);
  bool moreau_jean_step(double t, bool project);

  const LagrangianModel& m_;
  const FixedStepOptions& o_;
  OutputSink& sink_;
  const ContactLaw law_;
  RunMonitor mon_;
  RunSummary sum_;
  double h_ = 0;
  // state: q_i (positions; theta grows, so differences are kept separately), increments
  Vec7 q_ = Vec7::Zero(), v_ = Vec7::Zero();
  Vec7 dq_prev_ = Vec7::Zero();                    // Carpenter: Delta_i = q_i - q_{i-1}
  double acc_th_prev_ = 0.0, acc_th_prev2_ = 0.0;  // Carpenter: theta'' at t_{i-1}, t_{i-2}
  Vec7 q_next_ = Vec7::Zero(), v_next_ = Vec7::Zero();
  double FN_ = 0, FT_ = 0, PN_ = 0, PT_ = 0;
  Phase phase_ = Phase::Free, prev_phase_ = Phase::Free;
  std::string fail_;
  long qn_unconverged_ = 0;  // carp-qn steps that reached itmax (the run goes on; reported)
  long mj_ambiguous_ = 0;
  bool painleve_ = false;           // Carpenter's correction needs F_N < 0 (ends the run)
  ContactKinematics c_start_;       // contact kinematics at the start of the current step
  Vec7 v_prev_ = Vec7::Zero();      // MJ: v_{i-1}, for the predictor
  bool prev_impulse_free_ = false;  // MJ: the last step had no impulse (and exists)
  Mat7 mj_inv_ = Mat7::Zero();      // MJ: inverse iteration matrix, reused across steps
  Mat7 carp_inv_ = Mat7::Zero();    // carp-onevc: inverse prediction Jacobian, reused
  bool carp_lu_valid_ = false;
  int carp_lu_age_ = 0;
  bool mj_lu_valid_ = false;
  int mj_lu_age_ = 0;  // local problems with several consistent solutions (reported)
  long next_sample_ = 0;
  double next_t_out_ = 0;
};

void FixedStepRunner::record(long i, double t, const Vec7& q, const Vec7& v, double FN, double FT,
                             Phase phase, double vN_before, double PN, double PT) {
  const ContactKinematics c = m_.contact(q, v);
  const bool in_contact = phase != Phase::Free;
  mon_.observe(t, v[TH], c.d_N, c.v_N, FN, FT, in_contact);
  sum_.phase_time[static_cast<int>(phase)] += i > 0 ? h_ : 0.0;
  if (i > 0 && phase != prev_phase_) {
    EventRecord e;
    e.t = t;
    e.phase_before = prev_phase_;
    e.phase_after = phase;
    e.d_N = c.d_N;
    e.v_N_minus = vN_before;
    e.v_N_plus = c.v_N;
    e.v_t_plus = c.v_t;
    e.P_N = PN;
    e.P_T = PT;
    e.F_N = FN;
    e.F_T = FT;
    e.witness = "between steps";
    if (prev_phase_ == Phase::Free) {
      e.kind = vN_before < 0.0 ? EventKind::Impact : EventKind::Contact;
    } else if (phase == Phase::Free) {
      e.kind = EventKind::Release;
    } else if (phase == Phase::Stick) {
      e.kind = EventKind::Stick;
    } else if (prev_phase_ == Phase::Stick) {
      e.kind = EventKind::Slip;
    } else {
      e.kind = EventKind::Reversal;
    }
    ++sum_.events[static_cast<int>(e.kind)];
    sink_.event(e);
  }
  prev_phase_ = phase;
  // output: every N-th step, or the first step end at or after each point of the output grid
  bool out = false;
  if (o_.output_every > 0) {
    out = i % o_.output_every == 0;
  } else if (t >= next_t_out_ - 1e-9 * h_) {
    out = true;
    while (next_t_out_ <= t + 1e-9 * h_)
      next_t_out_ = sum_.t_start + (++next_sample_) * o_.output_dt;
  }
  if (out) {
    Sample s;
    s.t = t;
    s.q = q;
    s.v = v;
    s.d_N = c.d_N;
    s.v_N = c.v_N;
    s.v_t = c.v_t;
    s.F_N = FN;
    s.F_T = FT;
    s.phase = phase;
    sink_.sample(s);
  }
}

// ---------------------------------------------------------------------------------------------
// Carpenter: central differences (eq. 22-23) on the increments Delta_{i+1} = q_{i+1} - q_i:
//   R(Delta) = M(q_i) (Delta - Delta_i) / h^2 - f(t_i, q_i, (Delta + Delta_i) / (2h)) = 0,
// which for the rotor is exactly eq. (24). Working with increments instead of absolute positions
// keeps theta (tens of radians) from eating the digits of h^2 theta'' (time-steppers.md).
// M-bar is the paper's matrix M(q_i)/h^2 + (theta' G + D)/(2h): the Jacobian of R without the
// column of the spin velocity inside the gyroscopic term, i.e. M/h^2 - dfdv/(2h) with the spin
// column of dfdv removed. The Newton Jacobian of the prediction keeps that column.
// Correction (eq. 25-26): d_N < 0 at the prediction -> one multiplier along
// C_NT = W_N - mu sign(v_t) W_T (W and v_t at the prediction, v_t central), F_N from
// d_N(q^p) + W_N^T M-bar^{-1} C_NT F_N = 0. The multiplier is a force acting at t_i.
// The sample at t_i is written once Delta_{i+1} is known (its velocity is central).
// ---------------------------------------------------------------------------------------------
bool FixedStepRunner::carpenter_step(double t, bool qn) {
  const double h = h_, h2 = h * h;
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
      Mat7 dfdv_fixed_spin = dfdv;
      dfdv_fixed_spin.col(TH).setZero();
      Mbar = M / h2 - dfdv_fixed_spin / (2.0 * h);
      Mbar.col(TH) = M.col(TH) / h2;
    }
  };
  // Algorithm 1's contactless first guess: linear angular acceleration.
  const double acc_guess = 2.0 * acc_th_prev_ - acc_th_prev2_;
  Vec7 d = dq_prev_;
  d[TH] = acc_guess * h2 + dq_prev_[TH];
  Vec7 R;
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
      painleve_ = true;
      return;
    }
    FN = -c.d_N / den;
    FT = -law_.mu * s * FN;
    dd += x * FN;
    ph = s > 0.0 ? Phase::SlipPos : (s < 0.0 ? Phase::SlipNeg : Phase::SlipPos);
  };
  double FN = 0, FT = 0;
  Phase ph = Phase::Free;
  if (!qn) {
    // Prediction: Newton on R(Delta) = 0. The Jacobian J = M/h^2 - dfdv/(2h) is factorised
    // and reused across steps (refreshed every 32 steps, or when the iteration contracts
    // slowly): the converged Delta solves R = 0 whatever the iteration matrix. Converged when
    // the estimated remaining error (r / (1 - r) times the last step, r the contraction ratio)
    // is below 1e-14 of the increment plus 1e-16 h (a velocity of 1e-16: round-off).
    bool fresh = carp_lu_valid_ && ++carp_lu_age_ < 32;
    int it = 0;
    double prev = 0.0;
    for (; it < 30; ++it) {
      residual(d, R, !fresh);
      if (!fresh) {
        carp_inv_ = J.partialPivLu().inverse();  // explicit inverse: see moreau_jean_step
        carp_lu_valid_ = fresh = true;
        carp_lu_age_ = 0;
      }
      const Vec7 step = carp_inv_ * R;
      d -= step;
      ++sum_.newton_iters;
      const double norm = (step.array().abs() / (1e-14 * d.array().abs() + 1e-16 * h)).maxCoeff();
      if (norm <= 1.0) break;
      if (it >= 1) {
        const double r = norm / prev;
        if (r < 1.0 && r / (1.0 - r) * norm <= 1.0) break;
        if (r > 0.1) fresh = false;      // slow contraction: refresh the Jacobian
        if (it >= 3 && r >= 0.5) break;  // round-off reached
      }
      prev = norm;
    }
    if (it == 30) {
      fail_ = fmt::format("carp-onevc: the prediction Newton did not converge at t = {:.17g}", t);
      return false;
    }
    // Verification, and the correction with M-bar at the predicted theta (Algorithm 1) only
    // when the prediction penetrates.
    if (m_.contact(q_ + d, (d + dq_prev_) / (2.0 * h)).d_N < 0.0) {
      residual(d, R, true);
      // M-bar differs from the prediction Jacobian only in the spin column (by G v / 2h, ~1e-7
      // of M / h^2 here): solve with M-bar by Richardson iteration preconditioned with the
      // cached inverse Jacobian, to round-off (2-3 iterations), instead of factorising M-bar.
      auto solve_mbar = [&](const Vec7& b) {
        Vec7 x = carp_inv_ * b;
        for (int k = 0; k < 20; ++k) {
          const Vec7 dx = carp_inv_ * (b - Mbar * x);
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
      Vec7 dn = d - lu.solve(R);  // the contact-free solution at this spin (R is affine)
      correct(
          dn, [&lu](const Vec7& b) { return Vec7(lu.solve(b)); }, FN, FT, ph);
      const Vec7 change = dn - d;
      d = dn;
      ++sum_.newton_iters;
      if ((change.array().abs() <= o_.qn_tol * d.array().abs() + 1e-16 * h).all()) break;
    }
    if (it == o_.itmax) ++qn_unconverged_;
  }
  if (painleve_) {
    fail_ = fmt::format(
        "{} at t = {:.17g}: C_N^T M-bar^-1 C_NT <= 0, the correction would need F_N < 0 "
        "(sliding friction mu = {} is ill-posed for the scheme here)",
        qn ? "carp-qn" : "carp-onevc", t, law_.mu);
    return false;
  }
  if (!d.allFinite()) {
    fail_ = fmt::format("non-finite state at t = {:.17g}", t + h);
    return false;
  }
  // state update: q_{i+1} = q_i + Delta; central velocity at t_i
  v_ = (d + dq_prev_) / (2.0 * h);
  acc_th_prev2_ = acc_th_prev_;
  acc_th_prev_ = (d[TH] - dq_prev_[TH]) / h2;
  q_next_ = q_ + d;
  dq_prev_ = d;
  FN_ = FN;
  FT_ = FT;
  PN_ = FN * h;
  PT_ = FT * h;
  phase_ = ph;
  return true;
}

// ---------------------------------------------------------------------------------------------
// Moreau-Jean theta-method (eq. 27-33), our f on the right-hand side (M a = f):
//   M(q_{i+eta}) (v_{i+1} - v_i) - h [(1-theta) f(t_i, q_i, v_i) + theta f(t_{i+1}, q_{i+1},
//   v_{i+1})] = W_N r_N + W_T r_T,   q_{i+1} = q_i + h [(1-theta) v_i + theta v_{i+1}].
// Newton on v_{i+1} with the iteration matrix
//   Mt = M(q_eta) + eta h theta d(M a)/dq|_{a = v - v_i} - h theta (dfdv + h theta dfdq),
// the contact problem being solved at every Newton iterate (so the converged pair (v, r) solves
// the coupled problem). Contact is active (index set) when the predicted gap
// d_N(q_i) + h/2 v_N(q_i, v_i) <= 0. W_N, W_T are taken at q_i (the relation is linearised at
// the start of the step; Siconos' MoreauJeanOSI re-evaluates them at every Newton iterate, which
// changes the scheme at O(h), see validation/siconos). Newton's law at
// velocity level: u_N = v_N(i+1) + e_n v_N(i), u_T = v_t(i+1) + e_t v_t(i), with the 2D Coulomb
// cone solved exactly (solve_local). Reported forces are impulse / h.
// mj-proj (Acary 2013): after the step, if d_N(q_{i+1}) < 0 the positions are projected back
// onto d_N = 0 along M^{-1} W_N (mass-weighted metric, default) or along W_N (Euclidean metric,
// solver.projection = "identity", as Siconos' MLCPProjectOnConstraints); velocities are not
// changed.
// ---------------------------------------------------------------------------------------------
bool FixedStepRunner::moreau_jean_step(double t, bool project) {
  const double h = h_, th = o_.theta, eta = o_.eta;
  Vec7 fi;
  m_.smooth_forces(t, q_, v_, fi);
  const ContactKinematics& ci = c_start_ = m_.contact(q_, v_);
  const bool active = ci.normal_defined && ci.d_N + 0.5 * h * ci.v_N <= 0.0;
  // Simplified Newton: the iteration matrix is factorised once per step (at the predictor) and
  // kept while the iteration contracts fast; it is refreshed when the contraction ratio exceeds
  // 0.1. The predictor extrapolates the last acceleration unless the last step had an impulse.
  Vec7 v = v_;
  if (prev_impulse_free_) v += v_ - v_prev_;
  Mat7 M, dfdq, dfdv, dMa;
  Vec7 f;
  // the factorisation is kept across steps and refreshed every 32 steps or when the iteration
  // contracts slowly: the converged (v, r) solves the step whatever the iteration matrix is
  // (kept as an explicit inverse: a 7x7 product is cheaper than two triangular solves, and the
  // converged solution does not depend on the iteration matrix)
  const Mat7& Li = mj_inv_;
  bool factorised = mj_lu_valid_ && ++mj_lu_age_ < 32;
  Vec7 xN = Vec7::Zero(), xT = Vec7::Zero();
  double A_NN = 0, A_NT = 0, A_TT = 0;
  auto delassus = [&] {
    xN = Li * ci.W_N;
    xT = Li * ci.W_T;
    A_NN = ci.W_N.dot(xN);
    A_NT = ci.W_N.dot(xT);
    A_TT = ci.W_T.dot(xT);
  };
  if (factorised && active) delassus();
  double rN = 0.0, rT = 0.0;
  Phase ph = Phase::Free;
  int it = 0;
  double prev = 0.0;
  for (; it < 50; ++it) {
    const Vec7 q = q_ + h * ((1.0 - th) * v_ + th * v);
    const Vec7 qe = (1.0 - eta) * q_ + eta * q;
    m_.mass_matrix(qe, M);
    m_.smooth_forces(t + h, q, v, f);
    const Vec7 Phi = M * (v - v_) - h * ((1.0 - th) * fi + th * f);
    if (!factorised) {
      m_.smooth_force_jacobians(t + h, q, v, dfdq, dfdv);
      m_.mass_matrix_product_jacobian(qe, v - v_, dMa);
      mj_inv_ = (M + eta * h * th * dMa - h * th * (dfdv + h * th * dfdq)).partialPivLu().inverse();
      if (active) delassus();
      factorised = mj_lu_valid_ = true;
      mj_lu_age_ = 0;
    }
    const Vec7 vfree = v - Li * Phi;
    Vec7 vn = vfree;
    rN = rT = 0.0;
    ph = Phase::Free;
    if (active) {
      const double uN = ci.W_N.dot(vfree) + law_.e_n * ci.v_N;
      const double uT = ci.W_T.dot(vfree) + law_.e_t * ci.v_t;
      const LocalSolution sol = solve_local(A_NN, A_NT, A_TT, uN, uT, law_.mu);
      if (!sol.ok) {
        fail_ = fmt::format(
            "mj: the contact problem has no solution at t = {:.17g} "
            "(Painleve-type Delassus matrix)",
            t);
        return false;
      }
      if (sol.ambiguous) ++mj_ambiguous_;
      rN = sol.r_N;
      rT = sol.r_T;
      ph = sol.phase;
      vn = vfree + xN * rN + xT * rT;
    }
    const Vec7 change = vn - v;
    v = vn;
    ++sum_.newton_iters;
    // Converged when every component of the remaining error is below 1e-14 relative plus
    // 1e-15 m/s (or rad/s). The remaining error of a contracting iteration with ratio r is
    // estimated by r / (1 - r) times the last change.
    const double norm = (change.array().abs() / (1e-14 * v.array().abs() + 1e-15)).maxCoeff();
    if (norm <= 1.0) break;
    if (it >= 1) {
      const double r = norm / prev;
      if (r < 1.0 && r / (1.0 - r) * norm <= 1.0) break;
      if (r > 0.1) factorised = false;  // slow contraction: refresh the iteration matrix
      if (it >= 3 && r >= 0.5) break;   // round-off reached
    }
    prev = norm;
  }
  if (it == 50) {
    fail_ = fmt::format("mj: Newton did not converge in 50 iterations at t = {:.17g}", t);
    return false;
  }
  Vec7 q = q_ + h * ((1.0 - th) * v_ + th * v);
  if (project) {
    for (int k = 0; k < 3; ++k) {
      const ContactKinematics c = m_.contact(q, v);
      if (!c.normal_defined || c.d_N >= 0.0) break;
      Vec7 x = c.W_N;
      if (o_.project_with_mass) {
        Mat7 Mq;
        m_.mass_matrix(q, Mq);
        x = Mq.ldlt().solve(c.W_N);
      }
      q += x * (-c.d_N / c.W_N.dot(x));
    }
  }
  q_next_ = q;
  v_next_ = v;
  v_prev_ = v_;
  prev_impulse_free_ = rN == 0.0 && rT == 0.0;
  PN_ = rN;
  PT_ = rT;
  FN_ = rN / h;
  FT_ = rT / h;
  phase_ = ph;
  return true;
}

RunSummary FixedStepRunner::run(const MechanicalState& init, double t_end) {
  const auto wall0 = std::chrono::steady_clock::now();
  h_ = o_.h;
  const bool carpenter =
      o_.scheme == FixedStepScheme::CarpOneVC || o_.scheme == FixedStepScheme::CarpQN;
  sum_.solver = std::string(to_string(o_.scheme));
  if (carpenter) {
    sum_.options = fmt::format("{{\"h\": {:.6g}, \"itmax\": {}, \"qn_tol\": {:.3g}}}", o_.h,
                               o_.itmax, o_.qn_tol);
  } else if (o_.scheme == FixedStepScheme::MoreauJeanProjected) {
    sum_.options =
        fmt::format("{{\"h\": {:.6g}, \"theta\": {:.6g}, \"eta\": {:.6g}, \"projection\": \"{}\"}}",
                    o_.h, o_.theta, o_.eta, o_.project_with_mass ? "mass" : "identity");
  } else {
    sum_.options = fmt::format("{{\"h\": {:.6g}, \"theta\": {:.6g}, \"eta\": {:.6g}}}", o_.h,
                               o_.theta, o_.eta);
  }
  sum_.t_start = init.t;
  sum_.t_end_requested = t_end;
  next_t_out_ = init.t;
  q_ = init.q;
  v_ = init.v;
  sum_.energy_initial = energy(q_, v_);
  // fixed_step_option_problems (checked by run_fixed_step) makes the span a whole number of
  // steps: with h the span over that number the last step ends at t_end (to round-off).
  const long n_steps = std::max(1L, std::lround((t_end - init.t) / h_));
  h_ = (t_end - init.t) / static_cast<double>(n_steps);
  RUBDYN_DEMAND(h_ > 0.0 && n_steps <= kMaxFixedSteps);  // run_fixed_step checked the options
  if (carpenter) {
    // Start-up: q_1 = q_0 + h v_0 + h^2/2 a_0 with a_0 the contact-free acceleration, i.e. the
    // scheme applied at i = 0 with a fictitious q_{-1} = q_0 - h v_0 + h^2/2 a_0: then the
    // central velocity at t_0 is exactly v_0. gamma_0 = gamma_1 = a_0[theta] seed the guess.
    Mat7 M;
    Vec7 f;
    m_.mass_matrix(q_, M);
    m_.smooth_forces(init.t, q_, v_, f);
    const Vec7 a0 = M.ldlt().solve(f);
    dq_prev_ = h_ * v_ - 0.5 * h_ * h_ * a0;
    acc_th_prev_ = acc_th_prev2_ = a0[TH];
  }
  double work_smooth_ext = 0.0, work_smooth_damp = 0.0, work_contact = 0.0;
  SmoothPower p0 = m_.smooth_power(init.t, q_, v_);
  // Carpenter's sample at t_i needs Delta_{i+1}: one more step gives the sample at t_end.
  const long last = carpenter ? n_steps + 1 : n_steps;
  Vec7 q_rec = q_, v_rec = v_;  // the last recorded state (Carpenter)
  long i = 0;
  double t = init.t;
  for (; i < last; ++i) {
    t = init.t + static_cast<double>(i) * h_;
    if (o_.stop && o_.stop->load(std::memory_order_relaxed)) {
      sum_.termination = Termination::Interrupted;
      sum_.message = fmt::format("interrupted at t = {:.17g}", t);
      break;
    }
    if (carpenter) c_start_ = m_.contact(q_, v_);  // (Moreau-Jean computes it in its step)
    const bool ok = carpenter
                        ? carpenter_step(t, o_.scheme == FixedStepScheme::CarpQN)
                        : moreau_jean_step(t, o_.scheme == FixedStepScheme::MoreauJeanProjected);
    if (!ok) {
      sum_.termination = painleve_ ? Termination::Painleve
                         : fail_.find("non-finite") != std::string::npos
                             ? Termination::NonFinite
                             : Termination::SolverFailure;
      sum_.message = fail_;
      break;
    }
    ++sum_.steps;
    if (carpenter) {
      // v_ is now the central velocity at t_i; the sample at t_i is complete
      if (!finite(q_, v_)) {
        sum_.termination = Termination::NonFinite;
        sum_.message = fmt::format("non-finite state at t = {:.17g}", t);
        break;
      }
      record(i, t, q_, v_, FN_, FT_, phase_, c_start_.v_N, PN_, PT_);
      q_rec = q_;
      v_rec = v_;
      const SmoothPower p1 = m_.smooth_power(t, q_, v_);
      if (i > 0) {
        work_smooth_ext += 0.5 * h_ * (p0.external + p1.external);
        work_smooth_damp += 0.5 * h_ * (p0.damping + p1.damping);
      }
      p0 = p1;
      if (FN_ != 0.0) {
        const ContactKinematics c = m_.contact(q_, v_);
        work_contact += (FN_ * c.v_N + FT_ * c.v_t) * h_;
      }
      q_ = q_next_;
    } else {
      if (!finite(q_next_, v_next_)) {
        sum_.termination = Termination::NonFinite;
        sum_.message = fmt::format("non-finite state at t = {:.17g}", t + h_);
        break;
      }
      // work of the impulse with the mid-step velocity: r . W^T (v_i + v_{i+1}) / 2
      if (PN_ != 0.0 || PT_ != 0.0) {
        const Vec7 vmid = 0.5 * (v_ + v_next_);
        work_contact += PN_ * c_start_.W_N.dot(vmid) + PT_ * c_start_.W_T.dot(vmid);
      }
      q_ = q_next_;
      v_ = v_next_;
      const SmoothPower p1 = m_.smooth_power(t + h_, q_, v_);
      work_smooth_ext += 0.5 * h_ * (p0.external + p1.external);
      work_smooth_damp += 0.5 * h_ * (p0.damping + p1.damping);
      p0 = p1;
      record(i + 1, t + h_, q_, v_, FN_, FT_, phase_, c_start_.v_N, PN_, PT_);
    }
  }
  sum_.t_reached = init.t + static_cast<double>(carpenter ? std::max(0L, i - 1) : i) * h_;
  sum_.energy_final = carpenter ? energy(q_rec, v_rec) : energy(q_, v_);
  sum_.work_torque = work_smooth_ext;
  sum_.work_damping = work_smooth_damp;
  // contact work: friction and normal impulses together (the split is not defined for impulses
  // of a time-stepping scheme); it is written as friction work, impacts 0
  sum_.work_friction = work_contact;
  sum_.work_impacts = 0.0;
  sum_.close_energy_balance();
  mon_.fill(sum_);
  if (qn_unconverged_ > 0 && sum_.message.empty())
    sum_.message = fmt::format("carp-qn: {} steps reached itmax = {}", qn_unconverged_, o_.itmax);
  if (mj_ambiguous_ > 0 && sum_.message.empty())
    sum_.message = fmt::format("{} steps had several consistent contact solutions (first kept)",
                               mj_ambiguous_);
  sum_.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  sink_.end(sum_);
  return sum_;
}

}  // namespace

std::vector<OptionProblem> fixed_step_option_problems(const FixedStepOptions& o) {
  std::vector<OptionProblem> bad;
  auto num = [](double x) { return fmt::format("{:.17g}", x); };
  if (!(std::isfinite(o.h) && o.h > 0.0)) bad.push_back({"h", num(o.h), "must be finite and > 0"});
  if (o.itmax < 1) bad.push_back({"itmax", fmt::format("{}", o.itmax), "must be >= 1"});
  if (!(o.qn_tol > 0.0)) bad.push_back({"qn_tol", num(o.qn_tol), "must be > 0"});
  if (!(o.theta >= 0.5 && o.theta <= 1.0))
    bad.push_back({"theta", num(o.theta), "must lie in [0.5, 1]"});
  if (!(o.eta >= 0.0 && o.eta <= 1.0)) bad.push_back({"eta", num(o.eta), "must lie in [0, 1]"});
  if (o.output_every < 0)
    bad.push_back(
        {"output_every", fmt::format("{}", o.output_every), "must be >= 0 (0: use output_dt)"});
  if (!(std::isfinite(o.output_dt) && o.output_dt > 0.0))
    bad.push_back({"output_dt", num(o.output_dt), "must be finite and > 0"});
  return bad;
}

std::vector<OptionProblem> fixed_step_count_problems(double h, double t_start, double t_end) {
  std::vector<OptionProblem> bad;
  const double span = t_end - t_start;
  if (!(std::isfinite(span) && span > 0.0)) {
    bad.push_back({"t_end", fmt::format("{:.17g}", t_end),
                   fmt::format("must be finite and > t_start = {:.17g}", t_start)});
    return bad;
  }
  if (!(std::isfinite(h) && h > 0.0)) return bad;  // reported by fixed_step_option_problems
  const double steps = span / h;
  if (!(steps <= static_cast<double>(kMaxFixedSteps))) {
    bad.push_back({"h", fmt::format("{:.17g}", h),
                   fmt::format("(t_end - t_start) / h = {:.6g} steps, above the limit of {} steps",
                               steps, kMaxFixedSteps)});
  } else if (std::abs(steps - std::round(steps)) > 1e-6 || std::round(steps) < 1.0) {
    // 1e-6 of a step: far above the round-off of a decimal ratio (0.01 / 1e-6 is
    // 10000.000000000002), far below any fraction of a step anyone means
    bad.push_back({"h", fmt::format("{:.17g}", h),
                   fmt::format("t_end - t_start = {:.17g} s is {:.9g} steps, not a whole number "
                               "(the schemes keep one step; take h = (t_end - t_start) / n)",
                               span, steps)});
  }
  return bad;
}

RunSummary run_fixed_step(const LagrangianModel& model, const MechanicalState& initial,
                          double t_end, const FixedStepOptions& opt, OutputSink& sink) {
  auto bad = fixed_step_option_problems(opt);
  for (auto& p : fixed_step_count_problems(opt.h, initial.t, t_end)) bad.push_back(std::move(p));
  if (!bad.empty()) {
    std::string text = "invalid fixed-step options:";
    for (const auto& b : bad) text += fmt::format("\n  {} = {}: {}", b.option, b.value, b.rule);
    throw std::invalid_argument(text);
  }
  FixedStepRunner r(model, opt, sink);
  return r.run(initial, t_end);
}

}  // namespace rubdyn
