#include "rubdyn/hybrid/contact_problem.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>

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

PhaseDynamics phase_dynamics(const ContactOperators& op, Phase phase, double mu) {
  PhaseDynamics d;
  switch (phase) {
    case Phase::Free:
      d.a = op.Minv_f;
      d.normal_mass = op.A_NN;
      break;
    case Phase::SlipPos:
    case Phase::SlipNeg: {
      const double s = phase == Phase::SlipPos ? 1.0 : -1.0;
      d.normal_mass = op.A_NN - mu * s * op.A_NT;
      d.well_posed = d.normal_mass > 0.0;
      // with normal_mass < 0 (Painleve) the slip equations may still have a solution F_N >= 0:
      // it is computed so that mode selection can see the non-uniqueness
      d.F_N = d.normal_mass != 0.0 ? -op.b_N / d.normal_mass : 0.0;
      d.F_T = -mu * s * d.F_N;
      d.a = op.Minv_f + op.Minv_WN * d.F_N + op.Minv_WT * d.F_T;
      break;
    }
    case Phase::Stick: {
      const double det = op.A_NN * op.A_TT - op.A_NT * op.A_NT;
      d.normal_mass = op.A_TT > 0.0 ? det / op.A_TT : 0.0;
      d.well_posed = det > 0.0;
      if (d.well_posed) {
        d.F_N = -(op.A_TT * op.b_N - op.A_NT * op.b_T) / det;
        d.F_T = -(-op.A_NT * op.b_N + op.A_NN * op.b_T) / det;
      }
      d.a = op.Minv_f + op.Minv_WN * d.F_N + op.Minv_WT * d.F_T;
      break;
    }
  }
  return d;
}

ModeDecision select_mode(const ContactOperators& op, double mu, double v_t_eps, double rel_tol,
                         std::optional<Phase> ending, double force_scale) {
  // Candidate consistency at acceleration level (d_N = 0 and v_N = 0 assumed):
  //   free:   b_N >= 0 (the gap does not close)
  //   slip s: well posed, F_N >= 0, and, when v_t = 0, sliding starts in direction s
  //           (s v_t' >= 0 with v_t' = A_TN F_N + A_TT F_T + b_T)
  //   stick:  F_N >= 0, |F_T| <= mu F_N
  // Each inequality is classified as strict (margin > rel_tol times its scale), boundary
  // (|margin| <= that) or violated. A unique strictly consistent candidate is taken. Otherwise:
  //   several strict:  non-unique (Painleve); the least-force candidate is kept (free, then
  //                    stick, then slip), and the decision is flagged;
  //   only boundary:   the regular case of an event exactly at a witness zero (lift-off,
  //                    stick -> slip): the continuation is the mode the witness leads into,
  //                    free before slip before stick;
  //   none:            inconsistent (Painleve); phase Free with n_consistent = 0.
  // `ending`: the phase whose witness just crossed zero (with a nonzero slope: the root finder
  // sees only sign changes). It cannot continue, although at the event its margin is zero and
  // thus "boundary": it is dropped from the candidates while another one is consistent.
  // Keeping it would restart the same phase with its witness falling through zero again (a
  // loop of events at one instant: stick -> stick at a lift-off whose cone margin and normal
  // force vanish together; slip -> slip at a lift-off with a stiff stator).
  // The band is relative to the accelerations at the event and to the phase's force scale: at
  // a lift-off both F_N and b_N vanish, and a margin that is zero to the accuracy of the root
  // location (relative to the forces the phase had) must count as zero.
  ModeDecision out;
  const double acc_scale = std::abs(op.b_N) + std::abs(op.b_T) + force_scale * op.A_NN;
  const double tol_acc = rel_tol * acc_scale + 1e-300;
  const double tol_F = tol_acc / std::max(op.A_NN, 1e-300);
  enum Level { Violated = 0, Boundary = 1, Strict = 2 };
  auto level = [](double margin, double tol) {
    return margin > tol ? Strict : (margin >= -tol ? Boundary : Violated);
  };
  struct Cand {
    Phase phase;
    PhaseDynamics dyn;
    Level lv;
  };
  Cand cands[4];
  int n = 0;
  const bool sliding = std::abs(op.c.v_t) > v_t_eps;
  cands[n++] = {Phase::Free, phase_dynamics(op, Phase::Free, mu), level(op.b_N, tol_acc)};
  auto slip_level = [&](Phase p, const PhaseDynamics& d) {
    if (d.normal_mass == 0.0) return Violated;
    Level lv = level(d.F_N, tol_F);
    if (!sliding && mu > 0.0) {
      const double s = p == Phase::SlipPos ? 1.0 : -1.0;
      const double vt_dot = op.A_NT * d.F_N + op.A_TT * d.F_T + op.b_T;
      lv = std::min(lv, level(s * vt_dot, tol_acc));
    }
    return lv;
  };
  if (mu == 0.0) {
    // No friction: no stick mode, and the slip direction is irrelevant (F_T = 0).
    PhaseDynamics d = phase_dynamics(op, Phase::SlipPos, 0.0);
    cands[n++] = {Phase::SlipPos, d, slip_level(Phase::SlipPos, d)};
  } else if (sliding) {
    const Phase p = op.c.v_t > 0.0 ? Phase::SlipPos : Phase::SlipNeg;
    PhaseDynamics d = phase_dynamics(op, p, mu);
    cands[n++] = {p, d, slip_level(p, d)};
  } else {
    for (Phase p : {Phase::SlipPos, Phase::SlipNeg}) {
      PhaseDynamics d = phase_dynamics(op, p, mu);
      cands[n++] = {p, d, slip_level(p, d)};
    }
    PhaseDynamics ds = phase_dynamics(op, Phase::Stick, mu);
    Level lv = ds.well_posed ? std::min(level(ds.F_N, tol_F),
                                        level(mu * ds.F_N - std::abs(ds.F_T), mu * tol_F))
                             : Violated;
    cands[n++] = {Phase::Stick, ds, lv};
  }
  if (ending) {
    bool other = false;
    for (int i = 0; i < n; ++i) other |= cands[i].phase != *ending && cands[i].lv != Violated;
    if (other) {
      for (int i = 0; i < n; ++i)
        if (cands[i].phase == *ending) cands[i].lv = Violated;
    }
  }
  int n_strict = 0, n_boundary = 0, first_strict = -1, first_boundary = -1;
  for (int i = 0; i < n; ++i) {
    if (cands[i].lv == Strict) {
      if (first_strict < 0) first_strict = i;
      ++n_strict;
    } else if (cands[i].lv == Boundary) {
      if (first_boundary < 0) first_boundary = i;
      ++n_boundary;
    }
  }
  out.n_consistent = n_strict + n_boundary;
  if (n_strict == 0 && n_boundary == 0) {
    out.painleve = true;
    out.phase = Phase::Free;
    out.dyn = cands[0].dyn;
    out.note =
        fmt::format("no consistent contact mode (b_N = {:.6g}, v_t = {:.6g})", op.b_N, op.c.v_t);
    return out;
  }
  int pick = first_strict;
  if (n_strict > 1) {
    // least force: free first, then stick, then slip
    pick = -1;
    for (int i = 0; i < n && pick < 0; ++i)
      if (cands[i].lv == Strict && cands[i].phase == Phase::Free) pick = i;
    for (int i = 0; i < n && pick < 0; ++i)
      if (cands[i].lv == Strict && cands[i].phase == Phase::Stick) pick = i;
    if (pick < 0) pick = first_strict;
    out.painleve = true;
    out.note = fmt::format("{} strictly consistent modes; rule: least force ({} kept)", n_strict,
                           to_string(cands[pick].phase));
  } else if (n_strict == 0) {
    pick = first_boundary;  // order of cands: free, slip+, slip-, stick
    out.note = "boundary case: mode chosen by the order free, slip, stick";
  }
  out.phase = cands[pick].phase;
  out.dyn = cands[pick].dyn;
  return out;
}

ImpactResult impact_map(const ContactOperators& op, const Vec7& v_minus, const ContactLaw& law) {
  ImpactResult r;
  const double vN = op.c.v_N, vt = op.c.v_t;
  // Sticking impulse: A (P_N, P_T) = (-(1 + e_n) v_N, -(1 + e_t) v_t).
  const double det = op.A_NN * op.A_TT - op.A_NT * op.A_NT;
  const double rN = -(1.0 + law.e_n) * vN, rT = -(1.0 + law.e_t) * vt;
  double PN = 0.0, PT = 0.0;
  bool stick = false;
  if (law.mu > 0.0 && det > 0.0) {
    PN = (op.A_TT * rN - op.A_NT * rT) / det;
    PT = (-op.A_NT * rN + op.A_NN * rT) / det;
    stick = PN >= 0.0 && std::abs(PT) <= law.mu * PN;
  }
  if (!stick) {
    // Sliding impulse P_T = sigma mu P_N, sigma = direction the sticking impulse wanted
    // (opposite to the tangential velocity when the stick solution is not available).
    const double sigma =
        law.mu == 0.0 ? 0.0
                      : (det > 0.0 && PT != 0.0 ? (PT > 0 ? 1.0 : -1.0) : (vt > 0 ? -1.0 : 1.0));
    const double mass = op.A_NN + sigma * law.mu * op.A_NT;
    if (!(mass > 0.0)) {
      r.ok = false;
      return r;
    }
    PN = rN / mass;
    PT = sigma * law.mu * PN;
  }
  r.P_N = PN;
  r.P_T = PT;
  r.sticking = stick;
  r.v_plus = v_minus + op.Minv_WN * PN + op.Minv_WT * PT;
  return r;
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
