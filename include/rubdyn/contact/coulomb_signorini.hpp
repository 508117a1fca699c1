#pragma once
// The Coulomb-Signorini problem of one contact in the plane, solved exactly by enumeration. It is
// the one contact law of every solver: the event-driven integrator's mode selection
// (acceleration level) and impact map (impulse level), and the Moreau-Jean step (velocity level).
//
// With W = [W_N W_T] and the 2x2 Delassus matrix A = W^T M^{-1} W, find r = (r_N, r_T) such that
//     u = u0 + A r,
//     Signorini:  0 <= u_N  _|_  r_N >= 0,
//     Coulomb:    u_T = 0 and |r_T| <= mu r_N (stick),  or  r_T = -mu s r_N with s u_T >= 0 (slip
//                 in direction s = +-1).
// The level is the caller's:
//     acceleration:  u = (d_N'', v_t'),  r = (F_N, F_T)            (d_N = v_N = 0)
//     impulse:       u = (v_N+ + e_n v_N-, v_t+ + e_t v_t-),  r = (P_N, P_T)
//     Moreau-Jean:   u = (v_N + e_n v_N(start), v_t + e_t v_t(start)),  r = the step's impulse.
// At acceleration level a contact that already slides (v_t != 0) has its slip direction fixed by
// v_t, not by u_T: `sliding` = sign(v_t) leaves free and that one slip mode as candidates.
// Without friction (mu = 0) the candidates are free and frictionless contact (labelled SlipPos).
//
// Candidates and their conditions (each a margin that must be >= 0):
//     free:    u0_N
//     stick:   det A > 0; r_N; mu r_N - |r_T|            (A r = -u0)
//     slip s:  A_NN - mu s A_NT != 0; r_N; unless sliding, s u_T   (u_N = 0, r_T = -mu s r_N)
// Each margin is Strict (> tol), Boundary (within +-tol: zero to the accuracy of the data) or
// Violated (< -tol); tol_u applies to margins on u, tol_r to margins on r (times mu for the cone).
// A candidate's level is that of its weakest margin.
//
// THE TIE RULE (the only one, for every caller):
//   1. `excluded` (the mode whose witness has just ended it) is dropped while another candidate
//      is consistent: it cannot continue although its margin is zero at the event.
//   2. The first Strict candidate in the order free, stick, slip+, slip- is taken; if none is
//      Strict, the first Boundary candidate in the same order. The order is that of least
//      contact effort: no force before a force that dissipates nothing before a dissipating one.
//      At a boundary the candidates' r coincide to tol, so the order only names the mode.
//   3. More than one Strict candidate is a genuine non-uniqueness (a Painleve-type A with
//      mu |A_NT| > A_NN): flagged (nonunique), the rule above still picks one.
//   4. No consistent candidate (the same cause): flagged (!ok), r = 0, phase Free.
#include <optional>

#include "rubdyn/core/run_types.hpp"

namespace rubdyn {

struct LocalProblem {
  double A_NN = 0, A_NT = 0, A_TT = 0;  ///< Delassus matrix (symmetric)
  double u_N = 0, u_T = 0;              ///< u0: u with r = 0
  double mu = 0;
  int sliding = 0;   ///< 0, or +-1: the contact slides in that direction (acceleration level)
  double tol_u = 0;  ///< band on margins of u
  double tol_r = 0;  ///< band on margins of r
  std::optional<Phase> excluded;  ///< tie rule 1
};

/// The problem (A, u0, mu) with the band of round-off on data of velocity or impulse level:
/// tol_u = rel_band (|u_N| + |u_T|), tol_r = tol_u / A_NN (the impact map, Moreau-Jean).
LocalProblem make_local_problem(double A_NN, double A_NT, double A_TT, double u_N, double u_T,
                                double mu, double rel_band = 1e-13);

enum class Consistency : int { Violated = 0, Boundary = 1, Strict = 2 };

/// r and the normal "mass" of the problem in one mode (no consistency check).
struct ModeSolution {
  double r_N = 0, r_T = 0;
  double normal_mass = 0;  ///< free: A_NN; slip s: A_NN - mu s A_NT; stick: det A / A_TT
  bool well_posed = true;  ///< false: slip with normal_mass <= 0 (Painleve), singular stick
};
/// Solves the equations of `mode` (free: r = 0; slip: u_N = 0; stick: u = 0).
ModeSolution solve_in_mode(const LocalProblem& p, Phase mode);

struct LocalSolution {
  Phase phase = Phase::Free;
  double r_N = 0, r_T = 0;
  double normal_mass = 0;
  int n_strict = 0;      ///< strictly consistent candidates
  int n_consistent = 0;  ///< strict + boundary
  bool ok() const { return n_consistent > 0; }
  bool nonunique() const { return n_strict > 1; }
  bool boundary() const { return n_strict == 0 && n_consistent > 0; }
};
/// Enumerates the candidates and applies the tie rule. Allocates nothing.
LocalSolution solve_coulomb_signorini(const LocalProblem& p);

}  // namespace rubdyn
