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

#include "moreau_jean_class.hpp"
#include "rubdyn/contact/coulomb_signorini.hpp"

namespace rubdyn {

namespace detail {

template <int N, bool Multi>
StepOutcome MoreauJean<N, Multi>::step(double t, StepReport& r, std::string& message) {
  static_assert(!Multi, "MoreauJean<N, true>::step is moreau_jean_multi.cpp's");
  const double h = o_.h, th = o_.theta;
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
    free_velocity(t, v, [&] {
      if (active) delassus();
    });
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
    StepOutcome out = StepOutcome::Ok;
    const Iterate it = accept(t, v, vn, r, out, message);
    if (it == Iterate::Converged) break;
    if (it == Iterate::Failed) return out;
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

}  // namespace detail

std::unique_ptr<Stepper> make_moreau_jean(const LagrangianModel& m, const FixedStepOptions& opt) {
  if (m.contact_count() > detail::kMaxMjContacts)
    throw std::invalid_argument(fmt::format("{}: at most {} contacts; model '{}' has {}",
                                            to_string(opt.scheme), detail::kMaxMjContacts, m.name(),
                                            m.contact_count()));
  // several contacts: moreau_jean_multi.cpp (dynamic sizes)
  if (m.contact_count() > 1) return detail::make_moreau_jean_multi(m, opt);
  if (m.num_dofs() == 7) return std::make_unique<detail::MoreauJean<7>>(m, opt);  // rigid rotor
  return std::make_unique<detail::MoreauJean<Eigen::Dynamic>>(m, opt);
}

}  // namespace rubdyn
