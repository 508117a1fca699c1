#pragma once
// The event-driven hybrid integrator: reference solutions computed event by event.
//
// One engine for one contact and for K (up to kMaxContacts): the hybrid state is the tuple of
// the contacts' modes (free, slip+, slip-, stick each), one contact the smallest case. A run is
// a sequence of phases; each is a smooth ODE integrated by CVODE with error control and root
// finding on the witnesses that end it, per contact k:
//   free:    d_N,k / g0 (closing: contact onset), v_N,k / v_ref (rising: a gap minimum, for
//            grazing)
//   slip s:  F_N,k / F_ref (falling: lift-off), v_t,k / v_ref (towards 0: stick or reversal;
//            not built when mu_k = 0)
//   stick:   F_N,k / F_ref (lift-off), (mu F_N,k -+ F_T,k) / F_ref (falling: stick -> slip)
//   all:     (omega - omega_lim) / omega_lim (rising: the crossing time, no event)
// The witnesses of a phase are set when it (re)starts and never between steps; those that start
// degenerate (after a release on the constraint, a slip from rest) begin in a banded form and
// are armed by their value (docs/events-and-sundials.md 3.2).
// Contact phases (ContactFormulation):
//   reduced (default): the ODE in minimal coordinates: the model's ContactChart with one
//            contact (contact/contact_chart.hpp; the rigid rotor: slip in 6 coordinates, stick in
//            5), its RingChart with K (contact/ring_chart.hpp: each closed contact's ring replaced
//            by one angle, or tied to the spin in stick; fixed rings eliminate rotor
//            coordinates), wherever it applies. The right-hand side is the constrained
//            acceleration of the full model reduced to p''; the constraints hold to round-off by
//            construction. CVODE Adams with fixed-point iteration (measured on the rolling
//            regime: 4.4x fewer steps than BDF, no Jacobian); an angle's error is weighted by the
//            displacement it causes, at the gap's scale. The projection formulation where the
//            chart does not apply (a shared ring, rank-deficient fixed rings, a model without
//            a chart). At a prescribed speed the RingChart charts one contact too, its stick
//            constraint rheonomic (the chart takes the time).
//   projection: the index-reduced DAE in full coordinates, CVODE-BDF with projection after
//            every step (positions onto d_N,k = 0, velocities onto v_N,k = 0 and v_t,k = 0 in
//            stick, mass-weighted). Kept as an in-house cross-check.
// The works of the applied loads, the dampers and friction are integrated with the state.
// Per-phase cost (steps, wall seconds) is measured and reported in the summary.
// At an event the contact problem of every contact at the constraint decides (contact/
// contact_set.hpp, the one-contact kernel of coulomb_signorini.hpp at K = 1, with its one tie
// rule): an onset closing faster than the velocity tolerance -> the impulse problem; any other
// switch -> the acceleration-level problem, the phase whose witness fired excluded while another
// mode is consistent, and where no combination is strictly consistent the next order (a zero
// margin that falls along its mode's flow drops that mode). Every velocity projection at an
// event obeys the law (the slip friction at a sliding contact). A cascade of impacts between
// coupled contacts, and a bounce sequence, are integrated while their flights are resolved and
// collapsed by impulses of the law below that (their error is of the order of the flight).
// Every event is localised to the last time its witness has the ending phase's sign, to a few
// ulps, on the interpolant of the step that found it (one localiser for all witnesses).
// Painleve situations are logged; an inconsistent one ends the run (Termination::Painleve).
// Every sample and event is checked against the law (F_N >= 0, |F_T| <= mu F_N, to ten
// decision bands): a breach ends the run (Termination::LawViolation). Bounds on events at one
// instant and per simulated second end runs whose mode switching loops or chatters
// (Termination::Chattering). The same input gives the same bits: nothing decided depends on
// the clock, the load, the addresses or the thread.
// Output: dense samples on the output grid (CV_NORMAL interpolation), plus samples before and
// after each event.
//
// Structure (src/hybrid/, docs/architecture.md section 7): event_driven.cpp is the engine (the
// loop advance -> classify -> dispatch -> restart); phase_session.* the phases (one CVODE session
// per formulation) and their witnesses; phase_eval.* the contacts' mechanics at a state;
// phase_chart.* the charts; contact_decisions.* the decisions at events; event_locator.hpp the
// localiser; cvode_session.* is the only file that touches SUNDIALS.
//
// What a scene does not need is not built:
//   - mu = 0: no tangential witness and no stick mode (the contact problem has no stick
//     candidate without friction);
//   - a scene that never closes the gap never builds contact quantities: the free-flight
//     right-hand side uses only M and f;
//   - e_n = 0 never enters accumulation handling;
//   - output thinning costs no integration: samples are interpolated (CV_NORMAL);
//   - omega_lim's witness is left out of every phase that starts after it was crossed.
#include <atomic>
#include <functional>
#include <vector>

#include "rubdyn/core/run_envelope.hpp"
#include "rubdyn/core/run_types.hpp"
#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn {

/// How contact phases are integrated.
enum class ContactFormulation {
  /// Minimal coordinates of the model's ContactChart (slip: 6, stick: 5 coordinates): the
  /// constraints hold by construction, no projection. Models without a chart fall back to the
  /// projection formulation (the summary's options say which one ran).
  Reduced,
  /// The index-reduced DAE in the full coordinates, CVODE-BDF with projection after every step
  /// (an in-house cross-check of the reduced formulation, and the formulation of wide models).
  Projection,
  /// Reduced (its Newton systems under BDF the projected DAE's, lifted by the chart's tangent
  /// map: banded in O(n w^2) where the model is, hybrid/phase_session.hpp). Until the structured
  /// solve, wide banded models (40 coordinates and more) were projected: their minimal
  /// coordinates' Newton systems were dense difference quotients (docs/fe-rotors.md section 10).
  Auto
};

/// A CVODE multistep family, or the choice left to the model's stiffness (hybrid/method_choice.hpp:
/// BDF when the ratio of its fastest to its slowest time scale exceeds kStiffRatio, else Adams).
enum class MultistepMethod { Auto, Adams, BDF };

/// The integrator's own options, beside the run controls every solver shares (output_dt,
/// omega_lim, progress, stop, max_wall: core/run_envelope.hpp).
struct EventDrivenOptions : RunControls {
  double rtol = 1e-10;
  double atol = 1e-12;  ///< absolute tolerance on positions [m]; velocities: atol * 1e3 [m/s]
  /// Free flight. Adams-Moulton (fixed-point iteration) where the model is not stiff: measured on
  /// the reference case at rtol 1e-10, 3324 steps at 0.9 us vs BDF's 4801 at 1.9 us, orbit error
  /// 3.6e-11 m vs 2.1e-10 m; BDF where it is (a finite-element shaft: 5016 steps vs Adams'
  /// 289k, docs/fe-rotors.md). Auto decides by the model (summary.json says which and why).
  MultistepMethod method = MultistepMethod::Auto;
  ContactFormulation contact_phases = ContactFormulation::Auto;
  MultistepMethod contact_method = MultistepMethod::Auto;  ///< reduced contact phases
  /// Adams phases solve their implicit corrector by fixed-point iteration (no Jacobian, no
  /// linear algebra) instead of Newton with a difference-quotient Jacobian.
  bool fixed_point = true;
  /// Reduced contact phases integrated with Newton solve their systems by CVODE's dense
  /// difference-quotient Jacobian (size 2 dim + 3) instead of the structured solve in the full
  /// model's coordinates (hybrid/phase_session.hpp, lsys_reduced): the reference the structured
  /// solve is tested against (tests/events/test_structured_newton.cpp). Not a case option.
  bool dense_reduced_newton = false;
  double max_events_per_second = 1e6;
  /// The step limit per advance (per output interval or event), not per phase; reaching it
  /// ends the run (solver_failure). CVODE's own calls are cut at kCheckSteps steps and
  /// continued (core/run_envelope.hpp), so that the loop sees the stop flag between steps.
  long max_steps_per_call = 10'000'000;
  // (run controls: progress acts at output samples; the stop flag, the wall-time budget and the
  // step-rate guard between steps, at least every kCheckSteps steps: core/run_envelope.hpp)
};

/// Every rule that `opt` breaks (empty: valid): rtol and atol finite and > 0; output_dt finite
/// and > 0; omega_lim finite and >= 0; max_events_per_second > 0; max_steps_per_call >= 1;
/// max_wall finite and >= 0. The one
/// statement of these rules: run_event_driven and the case-file validation (io/case_toml.cpp)
/// both call it.
std::vector<OptionProblem> event_driven_option_problems(const EventDrivenOptions& opt);

/// Integrates from `initial` to t_end; hands samples, events and the summary to `sink`.
/// Never throws from inside the time loop: numerical trouble ends the run with a typed
/// termination, a message, and everything produced so far. Throws std::invalid_argument, before
/// anything reaches the sink, listing every rule the options break (event_driven_option_problems)
/// or for a model without a contact or with more than kMaxContacts. omega (monitor, omega_lim) is
/// the rate of the model's spin_coordinate(); a model without one has no omega_lim witness.
RunSummary run_event_driven(const LagrangianModel& model, const MechanicalState& initial,
                            double t_end, const EventDrivenOptions& opt, OutputSink& sink);

}  // namespace rubdyn
