#pragma once
// What happens at an event of the event-driven engine, decided on the state at the event by the
// contact problem of every contact at the constraint (contact/contact_set.hpp; K = 1 is the
// one-contact problem of coulomb_signorini.hpp with its band and tie rule), apart from
// integration: nothing here touches a CVODE session or writes output. A decision returns a
// Transition (the events to log, the next modes, the restart state, the impulse work, how the
// switched contacts' witnesses start) that the engine applies.
//   - contact onset: every contact at the constraint enters one impulse problem (Newton's law
//     for the impacting ones, plastic for the others); a bounce too low to resolve is truncated
//     by a plastic impact (Zeno, per contact); a contact pushed off by the others' impulses
//     whose flight is too low to matter is kept on the constraint by the collapse of the
//     cascade (below);
//   - on the constraint: velocities onto the closed contacts' constraints, then the
//     acceleration-level problem picks every contact's mode; where it is degenerate (no
//     strictly consistent combination: a margin zero at the event) the next order decides: a
//     mode whose zero margin falls along its own flow is not a candidate (entering stick with
//     the cone margin at 0 and falling, keeping a contact whose normal force is 0 and falling).
//
// THE LAW AT IMPULSES. Every impulse a decision applies obeys Coulomb's law at its contact:
// the impacts' (the impulse-level problem), and the velocity projections onto the constraints,
// which carry the slip friction of a sliding contact (P_T = -mu s P_N, s = sign v_t) and are
// tangential too at a sticking one.
//
// CASCADES. With two coupled contacts a plastic impact at one pushes the other off its ring, the
// free acceleration closes it again, its impact pushes the first off, and so on: a geometric
// accumulation onto the state where both are closed. While each contact keeps its sliding
// direction, the total normal impulse until the accumulation time solves
// D_eff P = -(v_N0 + int b_N dt), D_eff = W_N^T M^{-1} (W_N - mu s W_T), whether the cascade is
// resolved or collapsed; so the collapse applies, at the impact, the impulse of the slip law
// that brings the pushed-off contacts' normal speeds to 0 with the others', and the contact phase
// that follows supplies the integral of b_N. What it changes is only when the impulses act:
// a flight of height h = v_N^2 / (2 |b_N|) lasts 2 v_N / |b_N|, so the collapse's error is of
// the order of h, second order in the push-off speed. A flight is collapsed when h is below
// collapse_height (decision_tolerances.hpp: the integrator's position resolution), i.e. when
// the push-off speed is below sqrt(2 |b_N| collapse_height); higher flights are integrated. A
// bounce of an impact with restitution is truncated by the same criterion.
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "contact_modes.hpp"
#include "phase_eval.hpp"
#include "rubdyn/contact/contact_set.hpp"

namespace rubdyn::detail {

struct PhaseContext;

/// The outcome of an event: what to log and where the run continues.
struct Transition {
  bool ok = true;  ///< false: the run ends with `why` and `message`
  Termination why = Termination::Completed;
  std::string message;
  /// Written as a sample before the events: the state at the event before any impulse (an
  /// arrival's, positions on the constraint).
  bool pre_sample = false;
  Vec q_pre, v_pre;
  Modes next;
  Vec q, v;  ///< the state the next phase starts from
  /// To log, in order. The contact events (one per contact whose mode changed or that took
  /// part) come last; their forces after the event are the next phase's (the engine sets them).
  std::vector<EventRecord> events;
  int first_contact_event = 0;  ///< index in `events` of the first contact event
  double impulse_work = 0.0;    ///< kinetic energy change by impulses and velocity projections
  /// The contacts the decision covered, and how their witnesses start (the others keep theirs).
  ContactSet decided;
  Arming arming;
};

class ContactDecider {
 public:
  ContactDecider(const LagrangianModel& m, const PhaseContext& ctx);

  /// Contact onset at time t of the contacts `arriving` (q at the onset, v = v-), in the modes
  /// `modes`; every other contact at the constraint joins. Impact of those closing, then the
  /// decision on the constraint. `dt_ref`: a step of the flow, for the next order.
  Transition arrive(double t, const Vec& q, const Vec& v, const Modes& modes, ContactSet arriving,
                    const std::string& witness, double dt_ref);

  /// One contact's event being built.
  struct Pending {
    bool active = false;
    EventRecord e;
  };
  using PendingList = std::array<Pending, kMaxContacts>;

  /// The contacts `C` on the constraint at (q, v) in `modes` (the closed ones and any that
  /// joins): velocities projected onto their constraints, then the acceleration-level problem
  /// of the set picks every contact's mode. `ending`: (contact, mode) a witness ended (that mode
  /// is tie rule 1's exclusion); `at_slip_zero`: the ending contact's v_t is 0 (its slip
  /// witness fired); rel_tol: the relative band of the decision; F_ref: the contact forces'
  /// scale; `ev`: the contacts' events built so far.
  Transition on_constraint(double t, const Vec& q, const Vec& v, const Modes& modes, ContactSet C,
                           std::optional<std::pair<int, Phase>> ending, bool at_slip_zero,
                           double rel_tol, double F_ref, PendingList& ev, double dt_ref,
                           const std::string& ending_witness = "", ContactSet band_on_release = {});

 private:
  const SwitchTolerances& tol(int k) const;
  const ContactLaw& law(int k) const;
  /// Adds the contacts within the position tolerance of 0 that are not opening.
  void constraint_set(const MultiOps& op, const Modes& modes, ContactSet& S) const;
  void painleve_record(Transition& tr, double t, const std::vector<int>& idx,
                       const std::string& what) const;
  Transition painleve(double t, const std::vector<int>& idx, const std::string& what) const;
  /// Velocities of `set` onto their constraints, with the slip friction at sliding contacts and
  /// both rows at those in `stick_rows`; the kinetic energy change is the impulse work.
  bool project_velocities(double t, const Vec& q, Vec& v, ContactSet set, ContactSet stick_rows,
                          double& work);
  /// The next order at a degenerate decision: for each contact of idx whose chosen mode has a
  /// margin within the band, whether that margin falls along the chosen modes' flow (central
  /// differences over +-dt). Sets the falling modes in `falling` (bit 1 << Phase per contact).
  bool falling_margins(double t, const Vec& q, const Vec& v, const Modes& chosen,
                       const std::vector<int>& idx, double tol_u, double tol_r, double dt,
                       std::array<std::uint8_t, kMaxContacts>& falling);

  const LagrangianModel& m_;
  const PhaseContext& ctx_;
  const int n_, K_;
  Projector set_;
  MultiOps fd_op_;
  ModeSolve fd_ms_;
  ContactSetSolver solver_;
};

/// A sample or event obeys the contact law when no normal force is negative and no friction
/// force leaves the Coulomb cone by more than kLawBreachRel of the contact forces' scale (the
/// engine's F_ref: the largest normal force since the contacts closed). A decision takes a margin
/// within its band as a zero (kWitnessBandRel of the force scale at a witness's event; the next
/// order then drops a zero margin that falls), so a phase may begin with a margin that small on
/// the wrong side, rising; beyond ten bands it is a broken law, not the decision's accuracy.
/// Measured (validation/contacts/table.md): no sample or event of the K-contact scenes has a
/// margin below 0 at all.
inline constexpr double kLawBreachRel = 10.0 * kWitnessBandRel;
inline bool law_holds(double F_N, double F_T, double mu, double scale) {
  return F_N >= -kLawBreachRel * scale && std::abs(F_T) - mu * F_N <= kLawBreachRel * scale;
}

/// The record of a gap minimum at t with the contact's kinematics c there (kind grazing, phase
/// free before; the caller sets what comes after).
EventRecord grazing_event(double t, const ContactKinematics& c);

/// Bounds on events: more than kMaxSameInstant at one instant (mode switching that loops) or
/// more than max_per_second per unit of simulated time over the last kChatterWindow
/// (chattering) end the run (decision_tolerances.hpp).
class EventGuard {
 public:
  explicit EventGuard(double max_per_second) : max_per_second_(max_per_second) {}
  /// Registers an event at t; returns the reason to stop, or nullopt.
  std::optional<std::string> record(double t);

 private:
  double max_per_second_;
  std::array<double, kChatterWindow> times_{};
  long n_ = 0;
  int same_time_ = 0;
  double last_t_ = -1e300;
};

}  // namespace rubdyn::detail
