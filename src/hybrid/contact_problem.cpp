#include "rubdyn/hybrid/contact_problem.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "rubdyn/contact/coulomb_signorini.hpp"

namespace rubdyn {

namespace {

/// The Delassus entries and free accelerations from the solved columns of op.B. N: the model's
/// dofs as a fixed size (the rigid rotor's 7: unrolled, measured 2x cheaper than the runtime-size
/// loops in the contact phases) or Eigen::Dynamic; the same sums in the same order either way.
/// Which of them: the Delassus entries (from M^-1 W_N, M^-1 W_T), the free accelerations (from
/// M^-1 f), or both.
enum class Parts { Both, Velocity, Constraint };

template <int N>
void delassus(ContactOperators& op, Parts parts) {
  using V = Eigen::Matrix<double, N, 1>;
  const Eigen::Index n = op.B.rows();
  const Eigen::Map<const V> WN(op.c.W_N.data(), n), WT(op.c.W_T.data(), n);
  if (parts != Parts::Velocity) {
    const Eigen::Map<const V> MN(op.B.col(1).data(), n), MT(op.B.col(2).data(), n);
    op.A_NN = WN.dot(MN);
    op.A_NT = WN.dot(MT);
    op.A_TT = WT.dot(MT);
  }
  if (parts != Parts::Constraint) {
    const Eigen::Map<const V> Mf(op.B.col(0).data(), n);
    op.b_N = WN.dot(Mf) + op.c.wdot_N;
    op.b_T = WT.dot(Mf) + op.c.wdot_T;
  }
}

void delassus(ContactOperators& op, Parts parts) {
  if (op.size() == 7) {
    delassus<7>(op, parts);
  } else {
    delassus<Eigen::Dynamic>(op, parts);
  }
}

}  // namespace

void compute_contact_operators(const LagrangianModel& m, double t, VecIn q, VecIn v,
                               ContactOperators& op) {
  Mat& B = op.B;
  m.smooth_forces(t, q, v, B.col(0));
  m.compute_contact(0, t, q, v, op.c);
  const Eigen::Index n = B.rows();
  std::copy_n(op.c.W_N.data(), n, B.col(1).data());
  std::copy_n(op.c.W_T.data(), n, B.col(2).data());
  m.solve_mass(q, B);
  delassus(op, Parts::Both);
}

void compute_constraint_operators(const LagrangianModel& m, double t, VecIn q, VecIn v,
                                  ContactOperators& op) {
  Mat& B = op.B;
  m.compute_contact(0, t, q, v, op.c);
  const Eigen::Index n = B.rows();
  std::copy_n(op.c.W_N.data(), n, B.col(1).data());
  std::copy_n(op.c.W_T.data(), n, B.col(2).data());
  m.solve_mass(q, B.middleCols(1, 2));
  delassus(op, Parts::Constraint);
}

void update_contact_velocity(const LagrangianModel& m, double t, VecIn q, VecIn v,
                             ContactOperators& op) {
  Mat& B = op.B;
  m.smooth_forces(t, q, v, B.col(0));
  m.compute_contact(0, t, q, v, op.c);
  m.solve_mass(q, B.leftCols(1));
  delassus(op, Parts::Velocity);
}

namespace {

/// The acceleration-level problem at a contact point: u0 = (b_N, b_T), r = (F_N, F_T).
LocalProblem acceleration_problem(const ContactOperators& op, double mu) {
  return make_local_problem(op.A_NN, op.A_NT, op.A_TT, op.b_N, op.b_T, mu);
}

template <int N>
void combine(const ContactOperators& op, double F_N, double F_T, Vec& a) {
  using V = Eigen::Matrix<double, N, 1>;
  const Eigen::Index n = op.B.rows();
  Eigen::Map<V> out(a.data(), n);
  out = Eigen::Map<const V>(op.B.col(0).data(), n) +
        Eigen::Map<const V>(op.B.col(1).data(), n) * F_N +
        Eigen::Map<const V>(op.B.col(2).data(), n) * F_T;
}

void dynamics_of(const ContactOperators& op, const ModeSolution& m, PhaseDynamics& d) {
  d.F_N = m.r_N;
  d.F_T = m.r_T;
  d.normal_mass = m.normal_mass;
  d.well_posed = m.well_posed;
  // a = M^{-1} f + M^{-1} W_N F_N + M^{-1} W_T F_T (fixed size on the rigid rotor's fast path)
  if (op.size() == 7) {
    combine<7>(op, d.F_N, d.F_T, d.a);
  } else {
    combine<Eigen::Dynamic>(op, d.F_N, d.F_T, d.a);
  }
}

}  // namespace

void phase_dynamics(const ContactOperators& op, Phase phase, double mu, PhaseDynamics& d) {
  if (phase == Phase::Free) {
    d.a = op.Minv_f();
    d.F_N = d.F_T = 0.0;
    d.normal_mass = op.A_NN;
    d.well_posed = true;
    return;
  }
  dynamics_of(op, solve_in_mode(acceleration_problem(op, mu), phase), d);
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
  out.dyn = PhaseDynamics(static_cast<int>(op.size()));
  if (out.phase == Phase::Free) {
    phase_dynamics(op, Phase::Free, mu, out.dyn);
  } else {
    dynamics_of(op, solve_in_mode(p, out.phase), out.dyn);
  }
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

ImpactResult impact_map(const ContactOperators& op, VecIn v_minus, const ContactLaw& law) {
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
  r.v_plus = v_minus + op.Minv_WN() * r.P_N + op.Minv_WT() * r.P_T;
  return r;
}

void project_position(const LagrangianModel& m, double t, VecOut q, VecIn v, double tol,
                      ContactKinematics& c) {
  for (int it = 0; it < 3; ++it) {
    m.compute_contact(0, t, q, v, c);
    if (!c.normal_defined || std::abs(c.d_N) <= tol) return;
    q -= c.W_N * (c.d_N / c.W_N.squaredNorm());
  }
}

void project_velocity(const ContactOperators& op, int n_constraints, VecOut v) {
  const double gN = op.c.W_N.dot(v) + op.c.b_N;
  if (n_constraints == 1) {
    v -= op.Minv_WN() * (gN / op.A_NN);
    return;
  }
  const double gT = op.c.W_T.dot(v) + op.c.b_T;
  const double det = op.A_NN * op.A_TT - op.A_NT * op.A_NT;
  const double lN = (op.A_TT * gN - op.A_NT * gT) / det;
  const double lT = (-op.A_NT * gN + op.A_NN * gT) / det;
  v -= op.Minv_WN() * lN + op.Minv_WT() * lT;
}

}  // namespace rubdyn
