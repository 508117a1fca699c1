#pragma once
// The event-driven hybrid integrator: reference solutions computed event by event.
//
// A run is a sequence of phases (free, slip+, slip-, stick). Each phase is a smooth ODE
// integrated by CVODE with error control and root finding on the witnesses that end it:
//   free:    d_N / g0 (closing: contact onset), v_N / v_ref (rising: a gap minimum, for grazing)
//   slip s:  F_N / F_ref (falling: lift-off), v_t / v_ref (towards 0: stick or reversal;
//            not built when mu = 0)
//   stick:   F_N / F_ref (lift-off), (mu F_N -+ F_T) / F_ref (falling: stick -> slip)
//   all:     (omega - omega_lim) / omega_lim (rising: the crossing time, no event)
// Contact phases (ContactFormulation):
//   reduced (default): the ODE in the model's minimal coordinates (contact/contact_chart.hpp):
//            slip in 6 coordinates (the rotor centre on the clearance circle, phi free), stick in
//            5 (phi tied to theta by rolling). The right-hand side is the constrained
//            acceleration of the full model (contact_problem.hpp, which also gives F_N, F_T for
//            the witnesses) reduced to p''. The constraints hold to round-off by construction:
//            no projection, nothing taken out of the energy. CVODE Adams with fixed-point
//            iteration (measured on the rolling regime: 4.4x fewer steps than BDF, no Jacobian);
//            an angle's error is weighted by the displacement it causes (phi: g0 per radian,
//            theta - theta0 in stick: R_r per radian), at the gap's scale.
//            With several contacts (event_multi.cpp): the K-contact chart of
//            contact/ring_chart.hpp (each closed contact's ring replaced by one angle, or tied
//            to the spin in stick; a fixed ring's two equations solved for two of the rotor's
//            coordinates) wherever it applies; the projection formulation for the other
//            phases (rank-deficient fixed rings, a shared ring, stick at a prescribed speed).
//   projection: the index-reduced DAE in full coordinates, CVODE-BDF with projection after
//            every step (positions onto d_N = 0, velocities onto v_N = 0 and v_t = 0 in stick,
//            mass-weighted). Kept as an in-house cross-check; also the fallback for a model
//            without a chart.
// The works of the applied loads, the dampers and friction are integrated with the state.
// Per-phase cost (steps, wall seconds) is measured and reported in the summary.
// At an event: contact onset with v_N < 0 -> impact map; any other switch -> the contact problem
// at acceleration level decides the next phase. Both are the one Coulomb-Signorini solver of
// contact/coulomb_signorini.hpp (impulse and acceleration level) with its one tie rule; the phase
// whose witness fired is not a candidate while another mode is consistent.
// Every event is localised to the last time its witness has the ending phase's sign, to a few
// ulps, on the interpolant of the step that found it (one localiser for all witnesses).
// Painleve situations are logged; an inconsistent one ends the run (Termination::Painleve).
// Impacts accumulating (e_n > 0) are detected by the bounce height falling below the position
// tolerance; the remaining sequence is truncated by a plastic impact (logged as zeno with the
// extrapolated accumulation time). Bounds on events at one instant and per simulated second end
// runs whose mode switching loops or chatters (Termination::Chattering).
// Output: dense samples on the output grid (CV_NORMAL interpolation), plus samples before and
// after each event.
//
// Structure (src/hybrid/): event_driven.cpp is the loop advance -> classify -> dispatch ->
// restart; phase_system.* holds the phase dynamics (one object and one CVODE session per
// formulation and mode) and the witnesses; event_locator.hpp the localiser; mode_switching.* the
// decisions at events (impact map, Zeno truncation, mode selection, gap minima); cvode_session.*
// is the only file that touches SUNDIALS.
//
// What a scene does not need is not built:
//   - mu = 0: no tangential witness and no stick mode (Integrator::build_witnesses; the contact
//     problem has no stick candidate without friction);
//   - a scene that never closes the gap never builds contact quantities: the free-flight
//     right-hand side uses only M and f (FreeFlight::rhs);
//   - e_n = 0 never enters accumulation handling (ModeSwitcher::gap_closed);
//   - output thinning costs no integration: samples are interpolated (CV_NORMAL);
//   - omega_lim's witness is removed once crossed (main loop).
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
  /// (an in-house cross-check of the reduced formulation).
  Projection
};

/// The integrator's own options, beside the run controls every solver shares (output_dt,
/// omega_lim, progress, stop, max_wall: core/run_envelope.hpp).
struct EventDrivenOptions : RunControls {
  double rtol = 1e-10;
  double atol = 1e-12;  ///< absolute tolerance on positions [m]; velocities: atol * 1e3 [m/s]
  /// Free flight with Adams-Moulton (fixed-point iteration) instead of BDF. Measured on the
  /// reference case at rtol 1e-10: 3324 steps at 0.9 us vs 4801 at 1.9 us, orbit error
  /// 3.6e-11 m vs 2.1e-10 m.
  bool adams = true;
  ContactFormulation contact_phases = ContactFormulation::Reduced;
  bool contact_adams = true;  ///< reduced contact phases with Adams (false: BDF)
  /// Adams phases solve their implicit corrector by fixed-point iteration (no Jacobian, no
  /// linear algebra) instead of Newton with a difference-quotient Jacobian.
  bool fixed_point = true;
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
/// or for a model without a contact or with more than 8 (several contacts run the K-contact
/// integrator of src/hybrid/event_multi.hpp; one contact this one). omega (monitor, omega_lim) is
/// the rate of the model's spin_coordinate(); a model without one has no omega_lim witness.
RunSummary run_event_driven(const LagrangianModel& model, const MechanicalState& initial,
                            double t_end, const EventDrivenOptions& opt, OutputSink& sink);

}  // namespace rubdyn
