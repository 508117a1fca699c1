#pragma once
// The single-contact problem at acceleration and impulse level, shared by the event-driven
// integrator (mode selection at events, contact-phase dynamics, impact map).
//
// Phase dynamics at (t, q, v), with W = [W_N W_T], A = W^T M^{-1} W (2x2 Delassus matrix),
// b = W^T M^{-1} f + (wdot_N, wdot_T):
//   free:    a = M^{-1} f,                     F_N = F_T = 0
//   slip s:  F_T = -mu s F_N,  C = W_N - mu s W_T,  d_N'' = 0:
//            F_N = -b_N / (A_NN - mu s A_NT),  a = M^{-1}(f + C F_N)
//   stick:   d_N'' = 0 and v_t' = 0:  (F_N, F_T) = -A^{-1} b,  a = M^{-1}(f + W (F_N, F_T))
// Painleve: the slip normal "mass" A_NN - mu s A_NT <= 0 makes the slip problem ill-posed
// (no solution, or several): detected and reported, never silently picked.
//
// Mode selection and the impact map are the Coulomb-Signorini problem of
// rubdyn/contact/coulomb_signorini.hpp at acceleration and impulse level, with its one tie rule.
// Impact (v_N- < 0): Newton's law v_N+ = -e_n v_N- and v_t+ = -e_t v_t- while the impulse stays
// in the Coulomb cone, a sliding impulse P_T = -mu s P_N otherwise. Exact for one contact.
#include <optional>
#include <string>

#include "rubdyn/core/run_types.hpp"
#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn {

/// M^{-1} applied to f, W_N and W_T, and the quantities every phase needs; computed once per
/// evaluation (one solve with M(q) for three right-hand sides: the model's structured solve when
/// it has one). Sized for the model when built (ContactOperators(n)); computing into it then
/// allocates nothing.
struct ContactOperators {
  ContactOperators() = default;
  explicit ContactOperators(int n) : c(n), B(Mat::Zero(n, 3)) {}
  ContactKinematics c;
  /// M^{-1} f, M^{-1} W_N, M^{-1} W_T: the columns of B, solved in place (no copies).
  auto Minv_f() const { return B.col(0); }
  auto Minv_WN() const { return B.col(1); }
  auto Minv_WT() const { return B.col(2); }
  int size() const { return static_cast<int>(B.rows()); }
  double A_NN = 0, A_NT = 0, A_TT = 0;  ///< Delassus matrix entries
  double b_N = 0, b_T = 0;              ///< free normal/tangential accelerations d_N'', v_t'
  Mat B;                                ///< (f, W_N, W_T), then M^{-1} applied to them in place
};
void compute_contact_operators(const LagrangianModel& m, double t, VecIn q, VecIn v,
                               ContactOperators& op);
/// The constraint parts only (kinematics, M^{-1} W_N, M^{-1} W_T, the Delassus entries): M^{-1} f
/// and b are left as they were, for update_contact_velocity to set (a velocity projection needs
/// the constraints, not the forces, and changes v). The same bits in what it sets as
/// compute_contact_operators (the models' mass solves take their columns one by one).
void compute_constraint_operators(const LagrangianModel& m, double t, VecIn q, VecIn v,
                                  ContactOperators& op);
/// Updates the velocity-dependent parts (kinematic rates, M^{-1} f, b) for a new v at the same
/// q: one solve with M(q) instead of three.
void update_contact_velocity(const LagrangianModel& m, double t, VecIn q, VecIn v,
                             ContactOperators& op);

struct PhaseDynamics {
  PhaseDynamics() = default;
  explicit PhaseDynamics(int n) : a(Vec::Zero(n)) {}
  Vec a;
  double F_N = 0.0, F_T = 0.0;
  double normal_mass = 0.0;  ///< slip: A_NN - mu s A_NT; stick: det(A) / A_TT; free: A_NN
  bool well_posed = true;    ///< false for a Painleve slip (normal_mass <= 0) or singular stick
};
/// Acceleration and contact forces in `phase`, into d (d.a of the model's size).
void phase_dynamics(const ContactOperators& op, Phase phase, double mu, PhaseDynamics& d);

/// Result of the mode selection at an event on the constraint (d_N = 0, v_N = 0).
struct ModeDecision {
  Phase phase = Phase::Free;
  PhaseDynamics dyn;
  int n_consistent = 0;   ///< 1 in a well-posed situation
  bool painleve = false;  ///< no candidate (inconsistent) or several (non-unique)
  std::string note;       ///< what was decided and why (logged with the event)
};
/// Solves the acceleration-level contact problem (coulomb_signorini.hpp) for the candidates
/// {free, stick, slip+, slip-} (only the sliding direction when |v_t| > v_t_eps; no stick and no
/// slip direction when mu = 0) and keeps the one its tie rule picks; rel_tol is the relative
/// band within which a margin counts as zero (the accuracy of the event location).
/// `ending`: the phase a witness has just ended, excluded while another mode is consistent.
/// force_scale [N]: the contact forces of that phase (0: none); margins within rel_tol of it are
/// zero.
ModeDecision select_mode(const ContactOperators& op, double mu, double v_t_eps,
                         double rel_tol = 1e-9, std::optional<Phase> ending = std::nullopt,
                         double force_scale = 0.0);

struct ImpactResult {
  Vec v_plus;
  double P_N = 0.0, P_T = 0.0;
  bool sticking = false;   ///< the impulse stayed inside the cone
  bool ok = true;          ///< false: no solution (a Painleve-type Delassus matrix)
  bool nonunique = false;  ///< several solutions (same cause); the tie rule picked one
};
/// Impact map at (q, v-) with the contact law of the model. Requires op computed at (q, v-).
ImpactResult impact_map(const ContactOperators& op, VecIn v_minus, const ContactLaw& law);

/// Puts q on d_N = 0 by steps along W_N (Euclidean metric): q <- q - W_N d_N / |W_N|^2, while
/// |d_N| > tol (at most 3 steps). For the circular clearance this moves the rotor and stator
/// centres apart along the normal and is exact in one step; for any model it is a Newton step.
/// `scratch` (sized for the model) holds the kinematics.
void project_position(const LagrangianModel& m, double t, VecOut q, VecIn v, double tol,
                      ContactKinematics& scratch);

/// Mass-weighted projection of v onto {v_N = 0} (n_constraints = 1) or {v_N = 0, v_t = 0}
/// (n_constraints = 2): v <- v - M^{-1} W (W^T M^{-1} W)^{-1} (W^T v + b) (v_N = v_t = 0 exactly
/// after, a prescribed motion's share b included).
void project_velocity(const ContactOperators& op, int n_constraints, VecOut v);

}  // namespace rubdyn
