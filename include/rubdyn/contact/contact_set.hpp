#pragma once
// K frictional contacts solved together: the Coulomb-Signorini problem of a set of contacts in
// the plane, as coulomb_signorini.hpp is for one. Exact enumeration of the contact modes for
// K <= kMaxEnumContacts, a projected (non-smooth) Gauss-Seidel iteration beyond. Called by
// Moreau-Jean with several contacts (the impulses of the active ones, docs/time-steppers.md 3.1)
// and by the event-driven engine (its impacts and mode decisions, for one contact and for K:
// src/hybrid/contact_decisions.cpp). Derivation, tie rule and tolerances:
// docs/contact-set.md.
//
// Contact i has rows 2i (normal) and 2i+1 (tangential) of the 2K x 2K Delassus operator
// W = H M^{-1} H^T (any square W is accepted: symmetric or not, singular or not). Find r (2K)
// with u = u0 + W r such that every contact obeys
//     Signorini:  0 <= u_N  _|_  r_N >= 0,
//     Coulomb:    u_T = 0 and |r_T| <= mu r_N (stick),  or  r_T = -mu s r_N with s u_T >= 0
//                 (slip in direction s = +-1); an open contact (r_N = 0) has r_T = 0.
// The level is the caller's, contact by contact as in coulomb_signorini.hpp:
//     acceleration:  u = (d_N'', v_t'),  r = (F_N, F_T), for the contacts with d_N = v_N = 0; a
//                    contact that slides (v_t != 0) has its direction fixed: `sliding` = sign v_t
//     impulse:       u = (v_N+ + e_n v_N-, v_t+ + e_t v_t-),  r = (P_N, P_T),
//                    u0 = ((1 + e_n) v_N-, (1 + e_t) v_t-) (impulse_free_velocity)
//     Moreau-Jean:   u = (v_N + e_n v_N(start), v_t + e_t v_t(start)),  r = the step's impulse.
//
// ENUMERATION (K <= kMaxEnumContacts = 4: at most 4^4 = 256 linear solves of size <= 8).
// Each contact's candidates are those of the one-contact kernel: free, stick, slip+, slip-
// (free and the one slip direction when `sliding`; free and frictionless contact, labelled
// SlipPos, when mu = 0). For each combination of modes the equations (free: r_i = 0; stick:
// u_i = 0; slip s: u_Ni = 0, r_Ti = -mu s r_Ni) are solved by Gaussian elimination with full
// pivoting; a combination whose reduced matrix has a pivot below kSingularPivot times its largest
// entry is ill-posed and not a candidate. Each contact's margins, as in the one-contact kernel:
//     free: u_N;  stick: r_N, mu r_N - |r_T|;  slip s: r_N and, unless sliding or mu = 0, s u_T,
// are Strict (> tol), Boundary (within +-tol) or Violated (< -tol), with tol = the data's band
// (SetBand: tol_u on u, tol_r on r, times mu for the cone) or, when larger, the round-off of the
// mode's solve: m kappa eps (|u0| + |W| |r|) on u and m kappa eps |r| on r (m the system's size,
// kappa its largest over smallest pivot, inf norms), so that a margin that is zero in exact
// arithmetic (redundant contacts) is not decided by the noise of an ill-conditioned solve. A
// combination's level is its weakest margin's.
//
// THE TIE RULE. K = 1 gives the one-contact kernel's modes, forces and flags with the same band
// (contact_set_band): they could differ only where the round-off term exceeds the kernel's band
// and a margin falls between the two (never in the tests' 20000 random problems).
//   1. Contact by contact in index order: the combinations with contact i in its `excluded`
//      mode are dropped while a consistent combination with contact i in another mode remains
//      (for decoupled contacts: each contact's own rule 1); then, the same way, each mode of its
//      `excluded_modes`, one after the other.
//   2. The first Strict combination, else the first Boundary one, in the order of least contact
//      effort: fewest closed contacts (not free), then fewest slipping contacts with mu > 0
//      (dissipating ones), then contact 0's mode first, contact 1's next, ... in the order free,
//      stick, slip+, slip- (the one-contact order; only this last key depends on the numbering).
//   3. Outcome: Unique (one Strict combination), NonUnique (more than one: Painleve-type
//      non-uniqueness), Boundary (none Strict, some Boundary: solutions that coincide to the band,
//      or redundant contacts whose forces are indeterminate: see r_spread and u_spread),
//      NoSolution (none consistent: Painleve inconsistency; r = 0, every contact free).
//   Contacts involved: NonUnique, those whose mode differs among the Strict combinations;
//   Boundary, those whose mode differs among the consistent ones or that have a margin in the
//   band; NoSolution, the contacts whose law fails in the combination with the fewest failing
//   contacts (then the least total violation in units of the band, then rule 2's order): a
//   smallest set of contacts that cannot obey the law while the others do.
//
// PROJECTED GAUSS-SEIDEL (K > kMaxEnumContacts, or SetMethod::Pgs): sweeps over the contacts in
// index order, each solving its own 2x2 problem (the enumeration above with K = 1) with the
// others' current r, from r = 0. Converged when a sweep changes no r by more than
// PgsOptions::rel_tol times max(|r|_inf, tol_r); NotConverged after max_sweeps sweeps, or when a
// contact's own problem has no solution (its last r kept, marked involved). It finds a solution
// when it converges; it does not tell whether that solution is unique.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "rubdyn/contact/contact_law.hpp"
#include "rubdyn/core/run_types.hpp"
#include "rubdyn/core/types.hpp"

namespace rubdyn {

/// Largest K solved by enumeration (4^K mode combinations; K = 4: 256 solves of size <= 8).
inline constexpr int kMaxEnumContacts = 4;
/// A mode's reduced matrix is singular when its largest pivot (full pivoting) falls below this
/// fraction of its largest entry: the mode's solution would keep fewer than 4 digits.
inline constexpr double kSingularPivot = 1e-12;

/// One contact of the set.
struct SetContact {
  double mu = 0.0;                ///< Coulomb coefficient, >= 0
  int sliding = 0;                ///< 0, or +-1: slides in that direction (acceleration level)
  std::optional<Phase> excluded;  ///< tie rule 1
  /// More modes dropped by tie rule 1 after `excluded`, in the order free, stick, slip+, slip-
  /// (bit 1 << Phase): the event-driven engine's modes whose margin, zero at an event, falls
  /// (decided by the next order, contact_decisions.hpp).
  std::uint8_t excluded_modes = 0;
  bool excludes_any() const { return excluded.has_value() || excluded_modes != 0; }
};

enum class SetOutcome : int {
  Unique = 0,    ///< enumeration: exactly one strictly consistent mode combination
  Boundary,      ///< enumeration: none strict, some consistent within the band
  NonUnique,     ///< enumeration: several strict combinations (Painleve: non-unique)
  NoSolution,    ///< enumeration: no consistent combination (Painleve: inconsistent)
  Converged,     ///< Gauss-Seidel: a solution to its tolerance (uniqueness not known)
  NotConverged,  ///< Gauss-Seidel: iteration cap, or a contact without a local solution
  NonFinite,     ///< W or u0 not finite: nothing solved (r = 0, every contact free)
};
std::string_view to_string(SetOutcome o);
/// A solution was found (Unique, Boundary, NonUnique or Converged).
inline bool has_solution(SetOutcome o) {
  return o == SetOutcome::Unique || o == SetOutcome::Boundary || o == SetOutcome::NonUnique ||
         o == SetOutcome::Converged;
}

enum class SetMethod : int { Auto = 0, Enumeration, Pgs };

struct PgsOptions {
  double rel_tol = 1e-12;  ///< converged: no r changed by more than this times max(|r|, tol_r)
  int max_sweeps = 2000;   ///< then NotConverged
};

/// The bands of round-off within which a margin counts as zero.
struct SetBand {
  double tol_u = 0.0;  ///< on margins of u
  double tol_r = 0.0;  ///< on margins of r
};
/// tol_u = rel_band sum |u0|, tol_r = tol_u / min_i W_{N_i N_i}: for K = 1 exactly
/// make_local_problem's band (coulomb_signorini.hpp).
SetBand contact_set_band(MatIn W, VecIn u0, double rel_band = 1e-13);

/// A sufficient condition for the problem to have at most one solution whatever u0 (the
/// Coulomb-Signorini law without a fixed sliding direction: impulse and Moreau-Jean levels;
/// docs/contact-set.md, "Uniqueness certificate"). With the De Saxce velocity
/// u^ = (u_N + mu |u_T|, u_T) the law of each contact reads -u^ in N_K(r) (K the friction cone),
/// a monotone relation; two solutions r1, r2 (dr = r1 - r2) then give
///     dr^T W dr <= sum_k mu_k |w_Tk . dr| |dr_Nk|     (w_Tk: row 2k+1 of W),
/// and by Young's inequality (any a_k > 0)
///     dr^T [sym(W) - sum_k (mu_k / 2) (a_k w_Tk w_Tk^T + e_Nk e_Nk^T / a_k)] dr <= 0,
/// so dr = 0 when the bracket is positive definite. True when the bracket less
/// 1e-10 (2K) max|bracket| I is positive definite (by Gershgorin's discs, else by an LDL^T
/// factorisation; the shift covers their round-off) for one of a_k = t / |w_Tk|, t in {1, 1/2,
/// 2, 1/4, 4}. False for a contact with a fixed
/// sliding direction, for K > kMaxEnumContacts and for non-finite W. Allocates nothing.
bool unique_by_monotonicity(MatIn W, std::span<const SetContact> contacts);

/// Impulse level: u0 = ((1 + e_n) v_N-, (1 + e_t) v_t-) per contact, from v_minus = (v_N-, v_t-)
/// per contact (2K) and each contact's law. u0 must have 2K entries.
void impulse_free_velocity(VecIn v_minus, std::span<const ContactLaw> laws, VecOut u0);

/// The solver: workspaces sized for up to max_contacts contacts at construction; solve()
/// allocates nothing. Results stay until the next solve.
class ContactSetSolver {
 public:
  explicit ContactSetSolver(int max_contacts, PgsOptions pgs = {});

  /// Solves the problem (W: 2K x 2K, u0: 2K, contacts: K <= max_contacts entries).
  SetOutcome solve(MatIn W, VecIn u0, std::span<const SetContact> contacts, SetBand band,
                   SetMethod method = SetMethod::Auto);

  /// The enumeration with a first guess (a time-stepper's last modes): when no contact has an
  /// `excluded` mode, unique_by_monotonicity(W) holds and the combination `guess` (one mode per
  /// contact) is strictly consistent, that combination is the answer, Unique, and nothing else is
  /// solved: it is the enumeration's own answer, the same r and u to the bit (the same solve of
  /// the same system; a second strict combination would be a second solution, which the
  /// certificate excludes). The counts are then those of the one combination (1, 1, 1) and the
  /// spreads 0. Otherwise solve(W, u0, contacts, band). guess_taken() says which.
  /// `known_unique`, when given, is the caller's unique_by_monotonicity(W, contacts) for this
  /// very W and these contacts (a time-stepper that keeps W over its Newton iterates computes it
  /// once per W).
  SetOutcome solve_guess(MatIn W, VecIn u0, std::span<const SetContact> contacts, SetBand band,
                         std::span<const Phase> guess,
                         std::optional<bool> known_unique = std::nullopt);
  bool guess_taken() const { return guess_taken_; }

  int size() const { return K_; }
  SetOutcome outcome() const { return outcome_; }
  SetMethod method_used() const { return method_; }
  Phase mode(int i) const { return mode_[i]; }
  double r_N(int i) const { return r_(2 * i); }
  double r_T(int i) const { return r_(2 * i + 1); }
  double u_N(int i) const { return u_(2 * i); }
  double u_T(int i) const { return u_(2 * i + 1); }
  auto r() const { return r_.head(2 * K_); }
  auto u() const { return u_.head(2 * K_); }
  /// Contact i is involved in the outcome (NonUnique, Boundary, NoSolution, NotConverged).
  bool involved(int i) const { return involved_[i] != 0; }
  int n_involved() const;

  // enumeration
  int n_candidates() const { return n_candidates_; }  ///< well-posed mode combinations
  int n_strict() const { return n_strict_; }
  int n_consistent() const { return n_consistent_; }
  /// Largest |r - r_chosen|_inf and |u - u_chosen|_inf over the consistent combinations: at a
  /// true boundary of the order of the band; redundant contacts give a large r_spread with a
  /// u_spread of the order of the band (the motion is determinate, the forces are not).
  double r_spread() const { return r_spread_; }
  double u_spread() const { return u_spread_; }
  /// NonUnique: another strict solution (the next in rule 2's order), a certificate.
  Phase other_mode(int i) const { return other_mode_[i]; }
  auto other_r() const { return other_r_.head(2 * K_); }

  // Gauss-Seidel
  int sweeps() const { return sweeps_; }
  double last_change() const { return last_change_; }  ///< largest change of r in the last sweep

 private:
  struct EnumWork;  // the enumeration's fixed-capacity workspace (contact_set.cpp)
  SetOutcome enumerate(MatIn W, VecIn u0, std::span<const SetContact> contacts, SetBand band);
  SetOutcome gauss_seidel(MatIn W, VecIn u0, std::span<const SetContact> contacts, SetBand band);
  void all_free(VecIn u0);

  int max_contacts_;
  PgsOptions pgs_;
  int K_ = 0;
  SetOutcome outcome_ = SetOutcome::Unique;
  SetMethod method_ = SetMethod::Enumeration;
  Vec r_, u_, other_r_;
  std::vector<Phase> mode_, other_mode_;
  std::vector<std::uint8_t> involved_;
  int n_candidates_ = 0, n_strict_ = 0, n_consistent_ = 0;
  double r_spread_ = 0.0, u_spread_ = 0.0;
  int sweeps_ = 0;
  double last_change_ = 0.0;
  bool guess_taken_ = false;
  std::unique_ptr<EnumWork> work_;
  Vec dr_;       // Gauss-Seidel: each contact's change of r in the last sweep
  Mat local_W_;  // Gauss-Seidel: one contact's 2x2 block and free u
  Vec local_u0_;

 public:
  ~ContactSetSolver();
  ContactSetSolver(ContactSetSolver&&) noexcept;
  ContactSetSolver& operator=(ContactSetSolver&&) noexcept;
};

}  // namespace rubdyn
