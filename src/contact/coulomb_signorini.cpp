#include "rubdyn/contact/coulomb_signorini.hpp"

#include <algorithm>
#include <cmath>

namespace rubdyn {

LocalProblem make_local_problem(double A_NN, double A_NT, double A_TT, double u_N, double u_T,
                                double mu, double rel_band) {
  LocalProblem p;
  p.A_NN = A_NN;
  p.A_NT = A_NT;
  p.A_TT = A_TT;
  p.u_N = u_N;
  p.u_T = u_T;
  p.mu = mu;
  p.tol_u = rel_band * (std::abs(u_N) + std::abs(u_T)) + 1e-300;
  p.tol_r = p.tol_u / std::max(A_NN, 1e-300);
  return p;
}

ModeSolution solve_in_mode(const LocalProblem& p, Phase mode) {
  ModeSolution m;
  switch (mode) {
    case Phase::Free: m.normal_mass = p.A_NN; break;
    case Phase::SlipPos:
    case Phase::SlipNeg: {
      const double s = mode == Phase::SlipPos ? 1.0 : -1.0;
      m.normal_mass = p.A_NN - p.mu * s * p.A_NT;
      m.well_posed = m.normal_mass > 0.0;
      // with normal_mass < 0 (Painleve) the slip equations may still have a solution r_N >= 0:
      // it is computed, so that the enumeration sees the non-uniqueness
      m.r_N = m.normal_mass != 0.0 ? -p.u_N / m.normal_mass : 0.0;
      m.r_T = -p.mu * s * m.r_N;
      break;
    }
    case Phase::Stick: {
      const double det = p.A_NN * p.A_TT - p.A_NT * p.A_NT;
      m.normal_mass = p.A_TT > 0.0 ? det / p.A_TT : 0.0;
      m.well_posed = det > 0.0;
      if (m.well_posed) {
        m.r_N = -(p.A_TT * p.u_N - p.A_NT * p.u_T) / det;
        m.r_T = -(-p.A_NT * p.u_N + p.A_NN * p.u_T) / det;
      }
      break;
    }
  }
  return m;
}

namespace {

Consistency level(double margin, double tol) {
  return margin > tol ? Consistency::Strict
                      : (margin >= -tol ? Consistency::Boundary : Consistency::Violated);
}

}  // namespace

LocalSolution solve_coulomb_signorini(const LocalProblem& p) {
  struct Cand {
    Phase phase;
    ModeSolution sol;
    Consistency lv;
  };
  // candidates in the order of the tie rule: free, stick, slip+, slip-
  Cand cands[4];
  int n = 0;
  cands[n++] = {Phase::Free, solve_in_mode(p, Phase::Free), level(p.u_N, p.tol_u)};
  auto slip = [&](Phase mode) {
    const ModeSolution m = solve_in_mode(p, mode);
    Consistency lv = m.normal_mass == 0.0 ? Consistency::Violated : level(m.r_N, p.tol_r);
    if (p.sliding == 0 && p.mu > 0.0) {
      const double s = mode == Phase::SlipPos ? 1.0 : -1.0;
      const double u_T = p.u_T + p.A_NT * m.r_N + p.A_TT * m.r_T;
      lv = std::min(lv, level(s * u_T, p.tol_u));
    }
    cands[n++] = {mode, m, lv};
  };
  if (p.mu == 0.0) {
    slip(Phase::SlipPos);  // frictionless contact: r_T = 0, no direction
  } else if (p.sliding != 0) {
    slip(p.sliding > 0 ? Phase::SlipPos : Phase::SlipNeg);
  } else {
    const ModeSolution m = solve_in_mode(p, Phase::Stick);
    const Consistency lv =
        m.well_posed
            ? std::min(level(m.r_N, p.tol_r), level(p.mu * m.r_N - std::abs(m.r_T), p.mu * p.tol_r))
            : Consistency::Violated;
    cands[n++] = {Phase::Stick, m, lv};
    slip(Phase::SlipPos);
    slip(Phase::SlipNeg);
  }
  // tie rule 1
  if (p.excluded) {
    bool other = false;
    for (int i = 0; i < n; ++i)
      other |= cands[i].phase != *p.excluded && cands[i].lv != Consistency::Violated;
    if (other)
      for (int i = 0; i < n; ++i)
        if (cands[i].phase == *p.excluded) cands[i].lv = Consistency::Violated;
  }
  // tie rules 2-4
  LocalSolution out;
  int first_strict = -1, first_boundary = -1;
  for (int i = 0; i < n; ++i) {
    if (cands[i].lv == Consistency::Strict) {
      if (first_strict < 0) first_strict = i;
      ++out.n_strict;
    } else if (cands[i].lv == Consistency::Boundary && first_boundary < 0) {
      first_boundary = i;
    }
    out.n_consistent += cands[i].lv != Consistency::Violated;
  }
  const int pick = first_strict >= 0 ? first_strict : first_boundary;
  if (pick < 0) {
    out.normal_mass = cands[0].sol.normal_mass;
    return out;  // phase Free, r = 0, !ok()
  }
  out.phase = cands[pick].phase;
  out.r_N = cands[pick].sol.r_N;
  out.r_T = cands[pick].sol.r_T;
  out.normal_mass = cands[pick].sol.normal_mass;
  return out;
}

}  // namespace rubdyn
