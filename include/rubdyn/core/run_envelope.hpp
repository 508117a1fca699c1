#pragma once
// The run envelope: what every solver does around its integration, written once for both
// families (the event-driven integrator and the fixed-step run loop). It opens the books
// (solver, options, times, initial energy), holds the run monitor (invariants, spin statistics)
// and the event counters, hands samples and events to the sink, reports progress, answers the
// stop flag and the wall-time budget with a typed termination, and closes the books (works,
// energy balance, monitor, wall time) by handing the summary to the sink.
// How a solver produces its samples (dense output on a grid, or the first step end past each
// grid point) stays its own; the output grid t_start + k output_dt is the envelope's.
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "rubdyn/core/run_monitor.hpp"
#include "rubdyn/core/run_types.hpp"

namespace rubdyn {

/// What every solver's options share: the output grid, the spin speed of the monitor, and the
/// controls of a running run.
struct RunControls {
  double output_dt = 1e-4;  ///< output interval [s]
  double omega_lim = 0.0;   ///< the summary reports the first time omega >= it (0: none)
  /// Called at output samples with (t, events so far, omega, phase); may be empty.
  std::function<void(double, long, double, Phase)> progress;
  /// When set and true (a signal handler sets it), the run ends with Termination::Interrupted,
  /// keeping what it wrote.
  const std::atomic<bool>* stop = nullptr;
  /// Wall-time budget [s], 0 = none: once spent, the run ends with Termination::TimeBudget,
  /// keeping what it wrote.
  double max_wall = 0.0;
};

/// The step-rate guard of a run with error control (the event-driven integrator). The steps are
/// watched in windows of kCheckSteps steps; a window is over the bound when, at its mean step
/// size, the run would need more than kMaxRunSteps steps in all. One such window proves nothing,
/// nor do many at a steady step: the onset of rolling at mu = 0.25 on the reference case holds
/// the step at 8e-8 s for 1e5 steps (about 100 windows, each over the bound of a 100 s run) before
/// it grows with the falling spin, and the run needs 2e7 steps for 28 s of rolling. A collapse (a
/// stiff or degenerate parameter: a tiny inertia, a huge stiffness, load or speed) is judged by
/// its persistence, and the run then ends with Termination::StepCollapse:
/// - a falling step: kCollapseWindows consecutive windows over the bound, the mean step of the
///   last at most 1 / kCollapseFall of the first's;
/// - a step below round-off: a window over the bound whose mean step is below kRoundoffSteps
///   ulps of the time the run must reach, max(|t|, |t_end|): there the time itself carries a
///   relative error of a percent per step (rotor.L = 1e30: 8e-20 s steps in a run of 1 ms);
/// - and in any case a run that has taken kMaxRunSteps steps: the bound of kMaxFixedSteps
///   (stepping/fixed_step.hpp), which a fixed-step run may not exceed either (at about 1 us a
///   step, a quarter of an hour of integration), so that every run ends in bounded time.
inline constexpr double kMaxRunSteps = 1e9;
/// Integrator steps between two readings of the clock (the wall-time budget) and of the step
/// rate: one window of the step-rate guard. The event-driven integrator hands control back to
/// its loop at least this often (a CVODE call takes at most this many steps), so that the stop
/// flag is seen between steps too.
inline constexpr long kCheckSteps = 1000;
/// Consecutive windows over the bound over which a falling step is judged (1e4 steps: a
/// hundredth of a second of wall time at 1 us a step).
inline constexpr int kCollapseWindows = 10;
/// How much the mean step must fall over kCollapseWindows windows to be a collapse: an order of
/// magnitude (the mean step of a steady phase scatters by tens of percent between windows; a
/// collapsing one falls geometrically, 1e-19 s within a few windows with rotor.L = 1e30).
inline constexpr double kCollapseFall = 10.0;
/// A window's mean step below this many ulps of the run's time (kRoundoffSteps x eps x
/// max(|t|, |t_end|)) is a collapse at once.
inline constexpr double kRoundoffSteps = 100.0;

/// The largest contact speed |v_N|, |v_t| [m/s] a run may reach. A rigid-body model assumes
/// that a push at the contact is felt at once by the whole rotor; elastic waves carry it at
/// about 6 km/s in steel and titanium and 13 km/s in beryllium, the fastest structural solid,
/// and rotors burst at rim speeds below 1 km/s. A contact point faster than 2e4 m/s is no
/// rigid rotor (a torque of 1e12 N m spun the reference rotor to 1e10 rad/s in half a
/// millisecond, at 1e11 integrator steps per simulated second): the run ends
/// (Termination::Implausible), and a case whose initial rim speed R_r |omega0| exceeds it is
/// refused (io/case_toml.cpp).
inline constexpr double kMaxContactSpeed = 2e4;

/// What a complete run must satisfy to be called complete (checked by RunEnvelope::finish; a
/// run that breaks a rule ends with Termination::Implausible or NonFinite instead):
/// - every number of the summary finite (t_omega_lim and min_F_N_in_contact: NaN means none);
/// - max_penetration <= max_penetration (the solver's own bound: the event solver's is the
///   round-off of the gap, fixed-step schemes have none, plain mj allows O(h));
/// - |energy_residual| <= energy_residual_rel x the largest flow of the balance (|E_initial|,
///   |E_final| and each work): a balance that leaves half the largest flow unaccounted for is
///   not an integration error but a broken model or scheme; a residual within
///   energy_residual_abs (the solver's resolution of its books) is never judged.
struct Plausibility {
  double max_penetration = std::numeric_limits<double>::infinity();  ///< [m]
  double energy_residual_rel = 0.5;
  double energy_residual_abs = 0.0;  ///< [J]
};

/// The default wall-time budget [s] of one run of a sweep point whose case sets none
/// (run.max_wall = 0), derived from the sweep's plan: ten times the run's expected cost, and
/// at least a minute. Expected cost: a fixed-step run (fixed_steps > 0) 2 us a step (measured:
/// 0.4 us mj to 1.1 us carp-qn on the rigid rotor), an event-driven one 10 s per simulated
/// second (measured: 0.2 s/s on the reference case, about 5 s/s in the rolling regime at
/// mu = 0.25). A degenerate point then ends with time_budget instead of holding its thread.
double default_wall_budget(double simulated_seconds, double fixed_steps = 0.0);

/// The works of a run [J]: the energy balance's terms.
struct RunWorks {
  double torque = 0.0, damping = 0.0, friction = 0.0, impacts = 0.0;
};

class RunEnvelope {
 public:
  /// Opens the books of a run of `solver` (its options as a JSON object text) from t_start to
  /// t_end, with the initial state's mechanical energy and the contact's friction coefficient
  /// (the monitor's cone). The output grid starts at k = first_output (the event-driven
  /// integrator writes the initial sample itself: 1; the fixed-step loop writes the first step
  /// end at or after each grid time, the initial time included: 0). Nothing here knows the
  /// model: core sits below it.
  RunEnvelope(const RunControls& c, OutputSink& sink, double t_start, double t_end,
              double energy_initial, double mu, std::string solver, std::string options,
              long first_output = 1);

  RunSummary& summary() { return sum_; }
  /// The rules a complete run must satisfy (Plausibility; the default: no penetration bound).
  void set_plausibility(const Plausibility& p) { plaus_ = p; }
  RunMonitor& monitor() { return mon_; }
  const RunControls& controls() const { return c_; }

  /// The output grid t_start + k output_dt: the next time to write, and past it.
  double next_output() const { return next_out_; }
  void advance_output() { next_out_ = t0_ + static_cast<double>(++k_out_) * c_.output_dt; }

  /// A sample: observed by the monitor (in_contact: a closed contact, whose gap and gap rate
  /// measure the constraint drift) and handed to the sink. A sample with a number that is not
  /// finite (a derived quantity such as v_t = R_r omega can overflow while the state is finite)
  /// is not written: the run ends (Termination::NonFinite, false).
  bool sample(const Sample& s, double omega, bool in_contact) {
    const ContactSample& k = s.contacts.front();
    mon_.observe(s.t, omega, k.d_N, k.v_N, k.F_N, k.F_T, in_contact);
    check_speed(s.t, k.v_N, k.v_t);
    return output(s);
  }
  /// A sample the solver's own loop has already shown the monitor: handed to the sink, unless a
  /// number in it is not finite (then the run ends, Termination::NonFinite, false).
  bool output(const Sample& s) {
    if (!finite_sample(s)) return false;
    sink_.sample(s);
    last_output_t_ = s.t;
    return true;
  }
  /// True when the next call of watch() with `steps` reads the clock and the step rate: the
  /// moment for a solver to check what costs a model evaluation (check_speed).
  bool check_due(long steps) const { return steps - check_steps_ >= kCheckSteps; }
  /// The contact speeds against kMaxContactSpeed: above it the run ends
  /// (Termination::Implausible, false).
  bool check_speed(double t, double v_N, double v_t) {
    if (std::abs(v_N) <= kMaxContactSpeed && std::abs(v_t) <= kMaxContactSpeed) return true;
    return speed_failure(t, v_N, v_t);
  }
  /// The time of the last sample written (NaN: none yet).
  double last_output_time() const { return last_output_t_; }
  /// An event: counted and handed to the sink.
  void event(const EventRecord& e) {
    ++sum_.events[static_cast<int>(e.kind)];
    sink_.event(e);
  }
  long event_count() const;
  /// Progress at an output sample (the callback's).
  void progress(double t, double omega, Phase phase) const {
    if (c_.progress) c_.progress(t, event_count(), omega, phase);
  }
  /// The stop flag is set: the run ends (Termination::Interrupted) at t. True: stop now.
  bool stop_requested(double t) {
    if (!(c_.stop && c_.stop->load(std::memory_order_relaxed))) return false;  // (every step)
    return interrupt(t);
  }
  /// The wall-time budget is spent: the run ends (Termination::TimeBudget) at t. True: stop.
  bool budget_spent(double t);
  /// Between integrator steps of a run with error control, with `steps` its steps so far and t
  /// the end of the last: the stop flag at every call; every kCheckSteps steps the wall-time
  /// budget and the step-rate guard (a persistent collapse, see kMaxRunSteps:
  /// Termination::StepCollapse, with the step size and the likely cause). True: stop now. Reads
  /// the clock once per kCheckSteps steps.
  bool watch(double t, long steps) {
    if (stop_requested(t)) return true;
    if (steps - check_steps_ < kCheckSteps) return false;
    return check_rate(t, steps);
  }
  /// Ends the run with a typed termination (the first reason is kept).
  void fail(Termination why, const std::string& message);

  /// Closes the books at t_reached with the final state's energy and the works: the energy
  /// balance, the monitor's invariants, the wall time; hands the summary to the sink.
  RunSummary finish(double t_reached, double energy_final, const RunWorks& w);

 private:
  bool interrupt(double t);
  bool check_rate(double t, long steps);
  bool speed_failure(double t, double v_N, double v_t);
  bool finite_sample(const Sample& s);
  void check_plausible();
  const RunControls& c_;
  OutputSink& sink_;
  RunMonitor mon_;
  RunSummary sum_;
  std::chrono::steady_clock::time_point wall0_;
  double t0_ = 0.0, t_end_ = 0.0, next_out_ = 0.0;
  long k_out_ = 1;
  Plausibility plaus_;
  double check_t_ = 0.0;  // the step-rate guard's last check: time and steps
  long check_steps_ = 0;
  // the step-rate guard's recent windows: mean steps, newest at over_h_[over_windows_ % N], and
  // how many consecutive windows were over the bound (kMaxRunSteps)
  std::array<double, kCollapseWindows> over_h_{};
  long over_windows_ = 0;
  double last_output_t_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace rubdyn
