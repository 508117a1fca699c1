#include "rubdyn/hybrid/contact_problem.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "rubdyn/contact/coulomb_signorini.hpp"

namespace rubdyn {

void compute_contact_operators(const LagrangianModel& m, double t, const Vec7& q, const Vec7& v,
                               ContactOperators& op) {
  Mat7x3 B;
  Vec7 f;
  m.smooth_forces(t, q, v, f);
  B.col(0) = f;
  op.c = m.contact(q, v);
  B.col(1) = op.c.W_N;
  B.col(2) = op.c.W_T;
  m.solve_mass(q, B, 3);
  op.Minv_f = B.col(0);
  op.Minv_WN = B.col(1);
  op.Minv_WT = B.col(2);
  op.A_NN = op.c.W_N.dot(op.Minv_WN);
  op.A_NT = op.c.W_N.dot(op.Minv_WT);
  op.A_TT = op.c.W_T.dot(op.Minv_WT);
  op.b_N = op.c.W_N.dot(op.Minv_f) + op.c.wdot_N;
  op.b_T = op.c.W_T.dot(op.Minv_f) + op.c.wdot_T;
}

void update_contact_velocity(const LagrangianModel& m, double t, const Vec7& q, const Vec7& v,
                             ContactOperators& op) {
  Mat7x3 B;
  Vec7 f;
  m.smooth_forces(t, q, v, f);
  B.col(0) = f;
  op.c = m.contact(q, v);
  m.solve_mass(q, B, 1);
  op.Minv_f = B.col(0);
  op.b_N = op.c.W_N.dot(op.Minv_f) + op.c.wdot_N;
  op.b_T = op.c.W_T.dot(op.Minv_f) + op.c.wdot_T;
}

namespace {

/// The acceleration-level problem at a contact point: u0 = (b_N, b_T), r = (F_N, F_T).
LocalProblem acceleration_problem(const ContactOperators& op, double mu) {
  return make_local_problem(op.A_NN, op.A_NT, op.A_TT, op.b_N, op.b_T, mu);
}

PhaseDynamics dynamics_of(const ContactOperators& op, const ModeSolution& m) {
  PhaseDynamics d;
  d.F_N = m.r_N;
  d.F_T = m.r_T;
  d.normal_mass = m.normal_mass;
  d.well_posed = m.well_posed;
  d.a = op.Minv_f + op.Minv_WN * d.F_N + op.Minv_WT * d.F_T;
  return d;
}

}  // namespace

PhaseDynamics phase_dynamics(const ContactOperators& op, Phase phase, double mu) {
  if (phase == Phase::Free) {
    PhaseDynamics d;
    d.a = op.Minv_f;
    d.normal_mass = op.A_NN;
    return d;
  }
  return dynamics_of(op, solve_in_mode(acceleration_problem(op, mu), phase));
}

ModeDecision select_mode(const ContactOperators& op, double mu, double v_t_eps, double rel_tol,
                         std::optional<Phase> ending, double force_scale) {
  // The acceleration-level Coulomb-Signorini problem (coulomb_signorini.hpp, with its tie rule)
  // at d_N = 0, v_N = 0; a contact sliding faster than v_t_eps keeps its direction.
  // The band is relative to the accelerations at the event and to the ending phase's force
  // scale: at a lift-off both F_N and b_N vanish, and a margin that is zero to the accuracy of
  // the root location (relative to the forces the phase had) must count as zero.
  LocalProblem p = acceleration_problem(op, mu);
  if (mu > 0.0 && std::abs(op.c.v_t) > v_t_eps) p.sliding = op.c.v_t > 0.0 ? 1 : -1;
  const double acc_scale = std::abs(op.b_N) + std::abs(op.b_T) + force_scale * op.A_NN;
  p.tol_u = rel_tol * acc_scale + 1e-300;
  p.tol_r = p.tol_u / std::max(op.A_NN, 1e-300);
  p.excluded = ending;
  const LocalSolution s = solve_coulomb_signorini(p);
  ModeDecision out;
  out.n_consistent = s.n_consistent;
  out.phase = s.phase;
  out.dyn = out.phase == Phase::Free ? phase_dynamics(op, Phase::Free, mu)
                                     : dynamics_of(op, solve_in_mode(p, out.phase));
  if (!s.ok()) {
    out.painleve = true;
    out.note =
        fmt::format("no consistent contact mode (b_N = {:.6g}, v_t = {:.6g})", op.b_N, op.c.v_t);
  } else if (s.nonunique()) {
    out.painleve = true;
    out.note = fmt::format("{} strictly consistent modes; rule: least contact effort ({} kept)",
                           s.n_strict, to_string(s.phase));
  } else if (s.boundary()) {
    out.note = "boundary case: mode chosen by the order free, stick, slip";
  }
  return out;
}

ImpactResult impact_map(const ContactOperators& op, const Vec7& v_minus, const ContactLaw& law) {
  // The impulse-level Coulomb-Signorini problem (coulomb_signorini.hpp): with
  // v+ = v- + M^{-1} W P, u = (v_N+ + e_n v_N-, v_t+ + e_t v_t-) = u0 + A P,
  // u0 = ((1 + e_n) v_N-, (1 + e_t) v_t-). The band is round-off on the velocities.
  const LocalProblem p = make_local_problem(op.A_NN, op.A_NT, op.A_TT, (1.0 + law.e_n) * op.c.v_N,
                                            (1.0 + law.e_t) * op.c.v_t, law.mu);
  const LocalSolution s = solve_coulomb_signorini(p);
  ImpactResult r;
  r.ok = s.ok() && s.phase != Phase::Free;
  r.nonunique = s.nonunique();
  if (!r.ok) return r;
  r.P_N = s.r_N;
  r.P_T = s.r_T;
  r.sticking = s.phase == Phase::Stick;
  r.v_plus = v_minus + op.Minv_WN * r.P_N + op.Minv_WT * r.P_T;
  return r;
}

void project_position(const LagrangianModel& m, Vec7& q, const Vec7& v, double tol) {
  for (int it = 0; it < 3; ++it) {
    const ContactKinematics c = m.contact(q, v);
    if (!c.normal_defined || std::abs(c.d_N) <= tol) return;
    q -= c.W_N * (c.d_N / c.W_N.squaredNorm());
  }
}

void project_velocity(const ContactOperators& op, int n_constraints, Vec7& v) {
  const double gN = op.c.W_N.dot(v);
  if (n_constraints == 1) {
    v -= op.Minv_WN * (gN / op.A_NN);
    return;
  }
  const double gT = op.c.W_T.dot(v);
  const double det = op.A_NN * op.A_TT - op.A_NT * op.A_NT;
  const double lN = (op.A_TT * gN - op.A_NT * gT) / det;
  const double lT = (-op.A_NT * gN + op.A_NN * gT) / det;
  v -= op.Minv_WN * lN + op.Minv_WT * lT;
}

}  // namespace rubdyn
