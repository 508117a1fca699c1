#pragma once
// The run envelope: what every solver does around its integration, written once for both
// families (the event-driven integrator and the fixed-step run loop). It opens the books
// (solver, options, times, initial energy), holds the run monitor (invariants, spin statistics)
// and the event counters, hands samples and events to the sink, reports progress, answers the
// stop flag and the wall-time budget with a typed termination, and closes the books (works,
// energy balance, monitor, wall time) by handing the summary to the sink.
// How a solver produces its samples (dense output on a grid, or the first step end past each
// grid point) stays its own; the output grid t_start + k output_dt is the envelope's.
#include <atomic>
#include <chrono>
#include <functional>
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
  RunMonitor& monitor() { return mon_; }
  const RunControls& controls() const { return c_; }

  /// The output grid t_start + k output_dt: the next time to write, and past it.
  double next_output() const { return next_out_; }
  void advance_output() { next_out_ = t0_ + static_cast<double>(++k_out_) * c_.output_dt; }

  /// A sample: observed by the monitor (in_contact: a closed contact, whose gap and gap rate
  /// measure the constraint drift) and handed to the sink.
  void sample(const Sample& s, double omega, bool in_contact) {
    const ContactSample& k = s.contacts.front();
    mon_.observe(s.t, omega, k.d_N, k.v_N, k.F_N, k.F_T, in_contact);
    sink_.sample(s);
  }
  /// A sample the solver's own loop has already shown the monitor: handed to the sink.
  void output(const Sample& s) { sink_.sample(s); }
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
  /// Ends the run with a typed termination (the first reason is kept).
  void fail(Termination why, const std::string& message);

  /// Closes the books at t_reached with the final state's energy and the works: the energy
  /// balance, the monitor's invariants, the wall time; hands the summary to the sink.
  RunSummary finish(double t_reached, double energy_final, const RunWorks& w);

 private:
  bool interrupt(double t);
  const RunControls& c_;
  OutputSink& sink_;
  RunMonitor mon_;
  RunSummary sum_;
  std::chrono::steady_clock::time_point wall0_;
  double t0_ = 0.0, next_out_ = 0.0;
  long k_out_ = 1;
};

}  // namespace rubdyn
