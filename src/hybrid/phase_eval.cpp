#include "phase_eval.hpp"

#include <cmath>

#include "rubdyn/contact/contact_set.hpp"
#include "rubdyn/contact/min_norm.hpp"

namespace rubdyn::detail {

bool solve_small(const SmallMat& G, SmallVec& b) {
  SmallVec x;
  const MinNormResult r = min_norm_solve<2 * kMaxContacts>(G, b, x, kSingularPivot);
  if (!r.consistent) return false;
  b = x;
  return true;
}

// ---- MultiOps ---------------------------------------------------------------------------------

MultiOps::MultiOps(int n, int K_)
    : K(K_),
      c(static_cast<std::size_t>(K_), ContactKinematics(n)),
      B(Mat::Zero(n, 1 + 2 * K_)),
      W(Mat::Zero(2 * K_, 2 * K_)),
      b(Vec::Zero(2 * K_)) {}

void MultiOps::kinematics(const LagrangianModel& m, double t, VecIn q, VecIn v) {
  for (int k = 0; k < K; ++k) m.compute_contact(k, t, q, v, c[static_cast<std::size_t>(k)]);
}

void MultiOps::compute(const LagrangianModel& m, double t, VecIn q, VecIn v) {
  m.smooth_forces(t, q, v, B.col(0));
  for (int k = 0; k < K; ++k) {
    ContactKinematics& ck = c[static_cast<std::size_t>(k)];
    m.compute_contact(k, t, q, v, ck);
    B.col(1 + 2 * k) = ck.W_N;
    B.col(2 + 2 * k) = ck.W_T;
  }
  m.solve_mass(q, B);
  for (int i = 0; i < 2 * K; ++i) {
    const Vec& h = row(i);
    for (int j = 0; j < 2 * K; ++j) W(i, j) = h.dot(B.col(1 + j));
    const ContactKinematics& ck = at(i / 2);
    b(i) = h.dot(B.col(0)) + (i % 2 == 0 ? ck.wdot_N : ck.wdot_T);
  }
}

// ---- ModeSolve --------------------------------------------------------------------------------

ModeSolve::ModeSolve(int n, int K) : r(Vec::Zero(2 * K)), a(Vec::Zero(n)) {}

bool ModeSolve::solve(const MultiOps& op, const Modes& modes, std::span<const ContactLaw> laws) {
  // unknowns: r_N,k of a slipping contact (r_T,k = -mu s r_N,k), r_N,k and r_T,k of a sticking
  // one; equations: u_N,k = 0 (and u_T,k = 0 in stick), u = b + W r
  int m = 0;
  for (int k = 0; k < op.K; ++k) {
    const Phase p = modes[k];
    if (!closed(p)) continue;
    rows[m] = 2 * k;
    cols[m++] = 2 * k;
    if (p == Phase::Stick) {
      rows[m] = 2 * k + 1;
      cols[m++] = 2 * k + 1;
    }
  }
  r.setZero();
  a = op.B.col(0);
  if (m == 0) return true;
  G.resize(m, m);
  x.resize(m);
  for (int i = 0; i < m; ++i) {
    x[i] = -op.b(rows[i]);
    for (int j = 0; j < m; ++j) {
      const int c = cols[j];
      const int k = c / 2;
      const Phase p = modes[k];
      double g = op.W(rows[i], c);
      if (c % 2 == 0 && p != Phase::Stick)
        g -= laws[static_cast<std::size_t>(k)].mu * slip_sign(p) * op.W(rows[i], c + 1);
      G(i, j) = g;
    }
  }
  if (!solve_small(G, x)) return false;
  for (int j = 0; j < m; ++j) r(cols[j]) = x[j];
  for (int k = 0; k < op.K; ++k) {
    const Phase p = modes[k];
    if (slipping(p)) r(2 * k + 1) = -laws[static_cast<std::size_t>(k)].mu * slip_sign(p) * r(2 * k);
  }
  a.noalias() += op.B.rightCols(2 * op.K) * r;
  return true;
}

// ---- Projector --------------------------------------------------------------------------------

Projector::Projector(int n, int K) : op(n, K), J(Mat::Zero(K, n)), d(Vec::Zero(K)) {}

void Projector::positions(const LagrangianModel& m, double t, Vec& q, VecIn v, ContactSet set,
                          std::span<const SwitchTolerances> tol) {
  const int K = op.K;
  const int nc = set.count();
  for (int it = 0; nc > 0 && it < 3; ++it) {
    bool done = true;
    int i = 0;
    for (int k = 0; k < K; ++k) {
      if (!set.test(k)) continue;
      ContactKinematics& ck = op.c[static_cast<std::size_t>(k)];
      m.compute_contact(k, t, q, v, ck);
      if (!ck.normal_defined) {
        op.compute(m, t, q, v);
        return;
      }
      d[i] = ck.d_N;
      J.row(i) = ck.W_N.transpose();
      if (std::abs(ck.d_N) > kProjectionRel * tol[static_cast<std::size_t>(k)].g0) done = false;
      ++i;
    }
    if (done) break;
    G.resize(nc, nc);
    x.resize(nc);
    for (int a = 0; a < nc; ++a) {
      x[a] = d[a];
      for (int b = 0; b < nc; ++b) G(a, b) = J.row(a).dot(J.row(b));
    }
    if (!solve_small(G, x)) break;
    for (int a = 0; a < nc; ++a) q.noalias() -= J.row(a).transpose() * x[a];
  }
  op.compute(m, t, q, v);
}

bool Projector::velocities(const LagrangianModel& m, double t, VecIn q, Vec& v, ContactSet set,
                           std::span<const ContactLaw> laws) {
  // unknowns: one normal impulse per contact of the set (its direction W_N - mu s W_T for a
  // sliding one, W_N otherwise) and a tangential one per sticking contact; equations: the
  // speeds of those rows vanish after the impulse
  int mr = 0;
  for (int k = 0; k < op.K; ++k) {
    if (!set.test(k)) continue;
    rows[mr] = 2 * k;
    cols[mr++] = 2 * k;
    if (kind[static_cast<std::size_t>(k)] == RowKind::Stick) {
      rows[mr] = 2 * k + 1;
      cols[mr++] = 2 * k + 1;
    }
  }
  if (mr == 0) return true;
  auto slip_mu = [&](int k) {  // mu s of a sliding contact's impulse, 0 otherwise
    if (kind[static_cast<std::size_t>(k)] != RowKind::Sliding) return 0.0;
    const double vt = op.at(k).v_t;
    return laws[static_cast<std::size_t>(k)].mu * (vt > 0.0 ? 1.0 : -1.0);
  };
  G.resize(mr, mr);
  x.resize(mr);
  for (int a = 0; a < mr; ++a) {
    x[a] = op.speed(rows[a]);
    for (int b = 0; b < mr; ++b) {
      const int c = cols[b];
      double g = op.W(rows[a], c);
      if (c % 2 == 0) g -= slip_mu(c / 2) * op.W(rows[a], c + 1);
      G(a, b) = g;
    }
  }
  if (!solve_small(G, x)) return false;
  for (int b = 0; b < mr; ++b) {
    const int c = cols[b];
    v.noalias() -= op.B.col(1 + c) * x[b];
    if (c % 2 == 0) {
      const double smu = slip_mu(c / 2);
      if (smu != 0.0) v.noalias() += op.B.col(2 + c) * (smu * x[b]);
    }
  }
  op.compute(m, t, q, v);
  return true;
}

// ---- PhaseEval --------------------------------------------------------------------------------

PhaseEval::PhaseEval(const LagrangianModel& m, int K)
    : m_(m),
      K_(K),
      op1_(m.num_dofs()),
      dyn1_(m.num_dofs()),
      ops_(m.num_dofs(), K == 1 ? 0 : K),
      ms_(m.num_dofs(), K == 1 ? 0 : K),
      pr_(m.num_dofs(), K == 1 ? 0 : K) {}

void PhaseEval::zero_forces() {
  if (K_ == 1) {
    dyn1_.F_N = dyn1_.F_T = 0.0;
  } else {
    ms_.r.setZero();
  }
}

void PhaseEval::kinematics(double t, VecIn q, VecIn v) {
  if (K_ == 1) {
    m_.compute_contact(0, t, q, v, op1_.c);
  } else {
    ops_.kinematics(m_, t, q, v);
    cur_ = &ops_;
  }
  zero_forces();
}

bool PhaseEval::dynamics(double t, VecIn q, VecIn v, const Modes& modes,
                         std::span<const ContactLaw> laws) {
  if (K_ == 1) {
    compute_contact_operators(m_, t, q, v, op1_);
    phase_dynamics(op1_, modes[0], laws[0].mu, dyn1_);
    return dyn1_.well_posed;
  }
  ops_.compute(m_, t, q, v);
  cur_ = &ops_;
  return ms_.solve(ops_, modes, laws);
}

bool PhaseEval::place(double t, Vec& q, Vec& v, const Modes& modes,
                      std::span<const ContactLaw> laws, std::span<const SwitchTolerances> tol) {
  if (K_ == 1) {
    // positions onto d_N = 0, then the operators there, velocities onto v_N = 0 (and v_t = 0
    // in stick): one structured solve with M(q) for three right-hand sides, then one
    if (closed(modes[0])) {
      project_position(m_, t, q, v, kProjectionRel * tol[0].g0, op1_.c);
      compute_constraint_operators(m_, t, q, v, op1_);  // (M^-1 f comes at the new v)
      project_velocity(op1_, modes[0] == Phase::Stick ? 2 : 1, v);
      update_contact_velocity(m_, t, q, v, op1_);
    } else {
      compute_contact_operators(m_, t, q, v, op1_);
    }
    phase_dynamics(op1_, modes[0], laws[0].mu, dyn1_);
    return dyn1_.well_posed;
  }
  const ContactSet set = modes.closed_set();
  pr_.positions(m_, t, q, v, set, tol);
  for (int k = 0; k < K_; ++k)
    pr_.kind[static_cast<std::size_t>(k)] =
        modes[k] == Phase::Stick ? RowKind::Stick : RowKind::Normal;
  pr_.velocities(m_, t, q, v, set, laws);
  cur_ = &pr_.op;
  return ms_.solve(pr_.op, modes, laws);
}

}  // namespace rubdyn::detail
