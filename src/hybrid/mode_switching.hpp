#pragma once
// Mode switching of the event-driven integrator: what happens at an event, decided on the
// state at the event, apart from integration (nothing here touches a CVODE session or writes
// output; the integrator logs the events and restarts where a Transition says).
//   - contact onset: the impact map (Coulomb-Signorini at impulse level), a bounce or, when the
//     next bounce would be below the position tolerance, a Zeno truncation by a plastic impact;
//   - on the constraint: v_N = 0 exactly (and v_t = 0 at the end of a slip), then the contact
//     problem at acceleration level picks the next mode (select_mode, whose tie rule is that of
//     contact/coulomb_signorini.hpp);
//   - gap minima of free flight: clear, touch and go, grazing, or a crossing the root finder
//     could not see (the gap closed and reopened inside one step);
//   - the guard against mode switching that loops at one instant or chatters.
#include <array>
#include <optional>
#include <string>

#include "decision_tolerances.hpp"
#include "rubdyn/hybrid/contact_problem.hpp"

namespace rubdyn::detail {

/// The outcome of an event: what to log and where the run continues.
struct Transition {
  bool ok = true;  ///< false: the run ends with `why` and `message`
  Termination why = Termination::Completed;
  std::string message;
  Phase next = Phase::Free;
  Vec q, v;                           ///< the state the next phase starts from
  std::array<EventRecord, 2> events;  ///< to log, in order
  int n_events = 0;
  double impulse_work = 0.0;  ///< kinetic energy change by impulses and velocity projections
  bool release = false;       ///< free flight starting on the constraint with v_N = 0
  void log(const EventRecord& e) { events[n_events++] = e; }
};

class ModeSwitcher {
 public:
  ModeSwitcher(const LagrangianModel& m, const SwitchTolerances& tol);

  /// Puts q on d_N = 0 (to 1e-14 g0: 100x below the drift bound we promise, 1e-12 g0, and 1e6x
  /// above round-off).
  void project_position(double t, VecOut q, VecIn v) const;

  /// The gap closed at t with (q on d_N = 0, v-). Impact when v_N < -v_tol, then the contact
  /// problem decides (unless the impact is a bounce). `e` carries the event's time, phase and
  /// witness.
  Transition gap_closed(double t, VecIn q, VecIn v, EventRecord e) const;

  /// On the constraint (q on d_N = 0): v_N set to 0 exactly (v_t too when at_slip_zero or
  /// |v_t| <= v_tol, with friction), then select_mode with the relative band rel_tol and the
  /// ending phase excluded (force scale F_ref). With `ending`, the event's kind is set from the
  /// decision: liftoff, stick, slip (stick -> slip) or reversal (slip -> the other slip).
  Transition on_constraint(double t, VecIn q, VecIn v, EventRecord e, double rel_tol,
                           bool at_slip_zero = false, std::optional<Phase> ending = std::nullopt,
                           double F_ref = 0.0) const;

  enum class GapMinimum {
    Clear,       ///< above the grazing band: nothing happens
    TouchAndGo,  ///< within the band, the free normal acceleration >= 0: logged only
    Grazing,     ///< touching with the gap closing at acceleration level: contact problem
    Crossed      ///< below 0: the gap closed and reopened inside the step
  };
  GapMinimum classify_gap_minimum(double t, VecIn q, VecIn v) const;
  /// The grazing event record of a gap minimum (TouchAndGo: phase_after Free and its note).
  EventRecord grazing_record(double t, VecIn q, VecIn v, bool touch_and_go) const;

 private:
  const LagrangianModel& m_;
  const ContactLaw law_;
  const SwitchTolerances tol_;
  // workspaces of classify_gap_minimum, which runs at every gap minimum of free flight (once per
  // whirl turn), not only at events: sized here, so that it allocates nothing
  mutable ContactKinematics kin_;
  mutable ContactOperators op_;
};

/// The record of a gap minimum at t with the contact's kinematics c there (kind grazing, phase
/// free before; the caller sets what comes after): shared by both integrators.
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
