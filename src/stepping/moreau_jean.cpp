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

#include "rubdyn/contact/coulomb_signorini.hpp"
#include "rubdyn/stepping/stepper.hpp"
#include "simplified_newton.hpp"

namespace rubdyn {

namespace {

class MoreauJean final : public Stepper {
 public:
  MoreauJean(const LagrangianModel& m, const FixedStepOptions& o)
      : m_(m),
        law_(m.contact_law()),
        o_(o),
        project_(o.scheme == FixedStepScheme::MoreauJeanProjected),
        newton_(50) {}

  std::string_view name() const override { return project_ ? "mj-proj" : "mj"; }
  std::string options_json() const override {
    if (project_)
      return fmt::format(
          "{{\"h\": {:.6g}, \"theta\": {:.6g}, \"eta\": {:.6g}, \"projection\": \"{}\"}}", o_.h,
          o_.theta, o_.eta, o_.project_with_mass ? "mass" : "identity");
    return fmt::format("{{\"h\": {:.6g}, \"theta\": {:.6g}, \"eta\": {:.6g}}}", o_.h, o_.theta,
                       o_.eta);
  }

  void start(double, const Vec7& q0, const Vec7& v0) override {
    q_ = q0;
    v_ = v_prev_ = v0;
    prev_impulse_free_ = false;
    index_ = 0;
  }

  StepOutcome step(double t, StepReport& r, std::string& message) override;

 private:
  const LagrangianModel& m_;
  const ContactLaw law_;
  const FixedStepOptions o_;
  const bool project_;
  detail::SimplifiedNewton newton_;
  Vec7 q_ = Vec7::Zero(), v_ = Vec7::Zero();
  Vec7 v_prev_ = Vec7::Zero();      // v_{i-1}, for the predictor
  bool prev_impulse_free_ = false;  // the last step had no impulse (and exists)
  long index_ = 0;
};

StepOutcome MoreauJean::step(double t, StepReport& r, std::string& message) {
  const double h = o_.h, th = o_.theta, eta = o_.eta;
  Vec7 fi;
  m_.smooth_forces(t, q_, v_, fi);
  const ContactKinematics ci = m_.contact(q_, v_);
  const bool active = ci.normal_defined && ci.d_N + 0.5 * h * ci.v_N <= 0.0;
  // The predictor extrapolates the last acceleration unless the last step had an impulse.
  Vec7 v = v_;
  if (prev_impulse_free_) v += v_ - v_prev_;
  Mat7 M, dfdq, dfdv, dMa;
  Vec7 f;
  newton_.begin_step();
  Vec7 xN = Vec7::Zero(), xT = Vec7::Zero();
  double A_NN = 0, A_NT = 0, A_TT = 0;
  auto delassus = [&] {  // W^T Mt^{-1} W with the current iteration matrix
    const Mat7& Li = newton_.inverse();
    xN = Li * ci.W_N;
    xT = Li * ci.W_T;
    A_NN = ci.W_N.dot(xN);
    A_NT = ci.W_N.dot(xT);
    A_TT = ci.W_T.dot(xT);
  };
  if (!newton_.needs_matrix() && active) delassus();
  double rN = 0.0, rT = 0.0;
  Phase ph = Phase::Free;
  r = StepReport{};
  for (;;) {
    const Vec7 q = q_ + h * ((1.0 - th) * v_ + th * v);
    const Vec7 qe = (1.0 - eta) * q_ + eta * q;
    m_.mass_matrix(qe, M);
    m_.smooth_forces(t + h, q, v, f);
    const Vec7 Phi = M * (v - v_) - h * ((1.0 - th) * fi + th * f);
    if (newton_.needs_matrix()) {
      m_.smooth_force_jacobians(t + h, q, v, dfdq, dfdv);
      m_.mass_matrix_product_jacobian(qe, v - v_, dMa);
      newton_.set_matrix(M + eta * h * th * dMa - h * th * (dfdv + h * th * dfdq));
      if (active) delassus();
    }
    const Vec7 vfree = v - newton_.inverse() * Phi;
    Vec7 vn = vfree;
    rN = rT = 0.0;
    ph = Phase::Free;
    if (active) {
      // the velocity-level Coulomb-Signorini problem, band: round-off on the velocities
      const LocalSolution sol = solve_coulomb_signorini(
          make_local_problem(A_NN, A_NT, A_TT, ci.W_N.dot(vfree) + law_.e_n * ci.v_N,
                             ci.W_T.dot(vfree) + law_.e_t * ci.v_t, law_.mu));
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
      vn = vfree + xN * rN + xT * rT;
    }
    const Vec7 change = vn - v;
    v = vn;
    ++r.newton_iters;
    if (!v.allFinite()) {
      message = fmt::format("mj: non-finite iterate at t = {:.17g}", t);
      return StepOutcome::NonFinite;
    }
    // scaled change: 1e-14 relative plus 1e-15 m/s (or rad/s)
    const auto next =
        newton_.after((change.array().abs() / (1e-14 * v.array().abs() + 1e-15)).maxCoeff());
    if (next == detail::SimplifiedNewton::Next::Converged) break;
    if (next == detail::SimplifiedNewton::Next::Failed) {
      message = fmt::format("mj: Newton did not converge in {} iterations at t = {:.17g}",
                            newton_.max_iterations(), t);
      return StepOutcome::NewtonFailed;
    }
  }
  Vec7 q = q_ + h * ((1.0 - th) * v_ + th * v);
  if (project_) {
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
  if (!q.allFinite() || !v.allFinite()) {
    message = fmt::format("non-finite state at t = {:.17g}", t + h);
    return StepOutcome::NonFinite;
  }
  // work of the impulse with the mid-step velocity: r . W^T (v_i + v_{i+1}) / 2
  if (rN != 0.0 || rT != 0.0) {
    const Vec7 vmid = 0.5 * (v_ + v);
    r.contact_work = rN * ci.W_N.dot(vmid) + rT * ci.W_T.dot(vmid);
  }
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

}  // namespace

std::unique_ptr<Stepper> make_moreau_jean(const LagrangianModel& m, const FixedStepOptions& opt) {
  return std::make_unique<MoreauJean>(m, opt);
}

}  // namespace rubdyn
