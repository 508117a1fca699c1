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
//   projection: the index-reduced DAE in full coordinates, CVODE-BDF with projection after
//            every step (positions onto d_N = 0, velocities onto v_N = 0 and v_t = 0 in stick,
//            mass-weighted). Kept as an in-house cross-check; also the fallback for a model
//            without a chart.
// The works of the applied loads, the dampers and friction are integrated with the state.
// Per-phase cost (steps, wall seconds) is measured and reported in the summary.
// At an event: contact onset with v_N < 0 -> impact map (Newton + Coulomb impulse); any other
// switch -> the contact problem at acceleration level decides the next phase (select_mode); the
// phase whose witness fired is not a candidate while another mode is consistent.
// Painleve situations are logged; an inconsistent one ends the run (Termination::Painleve).
// Impacts accumulating (e_n > 0) are detected by the bounce height falling below the position
// tolerance; the remaining sequence is truncated by a plastic impact (logged as zeno with the
// extrapolated accumulation time). A bound on events per simulated second ends chattering runs.
// Output: dense samples on the output grid (CV_NORMAL interpolation: the output interval never
// changes the steps), plus samples before and after each event.
//
// What a scene does not need is not built (event_driven.cpp):
//   - mu = 0: no tangential witness and no stick mode (build_witnesses; select_mode in
//     contact_problem.cpp has no stick candidate without friction);
//   - a scene that never closes the gap never builds a contact phase: the free-flight right-hand
//     side uses only M and f (eval_rhs), contact operators exist only in contact phases;
//   - e_n = 0 never enters accumulation handling (on_gap_closing: law_.has_restitution());
//   - output thinning costs no solver work: samples are interpolated (CV_NORMAL), never stepped to;
//   - omega_lim's witness is removed once crossed (main loop).
#include <atomic>
#include <functional>

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

struct EventDrivenOptions {
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
  double output_dt = 1e-4;
  double omega_lim = 0.0;  ///< crossing time reported (0: none)
  double max_events_per_second = 1e6;
  long max_steps_per_phase = 10'000'000;
  /// Called at output samples with (t, events so far, omega, phase); may be empty.
  std::function<void(double, long, double, Phase)> progress;
  /// When set and true (a signal handler sets it), the run ends right after its next output
  /// sample with Termination::Interrupted, keeping what it wrote.
  const std::atomic<bool>* stop = nullptr;
};

/// Integrates from `initial` to t_end; hands samples, events and the summary to `sink`.
/// Never throws from inside the time loop: numerical trouble ends the run with a typed
/// termination, a message, and everything produced so far.
RunSummary run_event_driven(const LagrangianModel& model, const MechanicalState& initial,
                            double t_end, const EventDrivenOptions& opt, OutputSink& sink);

}  // namespace rubdyn
