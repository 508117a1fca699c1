// The event-driven integrator: the loop advance -> classify -> dispatch -> restart.
// The pieces it drives live next to it:
//   phase_system.*    the phase dynamics (one object and one CVODE session per formulation and
//                     mode) and the witnesses;
//   event_locator.hpp the one localiser (every event at the last time its witness has the
//                     ending phase's sign);
//   mode_switching.*  what happens at an event (impact map, Zeno truncation, mode selection,
//                     gap minima) and the guard against switching loops and chattering.
#include "rubdyn/hybrid/event_driven.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numeric>
#include <optional>
#include <stdexcept>

#include "event_locator.hpp"
#include "event_multi.hpp"
#include "mode_switching.hpp"
#include "phase_system.hpp"
#include "rubdyn/core/run_envelope.hpp"

namespace rubdyn {

namespace {

using namespace detail;
using Status = CvodeSession::Status;

class Integrator {
 public:
  Integrator(const LagrangianModel& m, const EventDrivenOptions& opt, OutputSink& sink)
      : m_(m),
        n_(m.num_dofs()),
        opt_(opt),
        sink_(sink),
        law_(m.contact_law(0)),
        tol_(SwitchTolerances::derive(opt.rtol, opt.atol, m.gap_scale(0))),
        sw_(m, tol_),
        guard_(opt.max_events_per_second),
        sample_(n_, 1, static_cast<int>(m.observables().size())),
        op_(n_),
        dyn_(n_),
        kin_(n_),
        q_restart_(Vec::Zero(n_)),
        v_restart_(Vec::Zero(n_)),
        q_tmp_(Vec::Zero(n_)),
        v_tmp_(Vec::Zero(n_)),
        q_ev_(Vec::Zero(n_)),
        v_ev_(Vec::Zero(n_)),
        acc_(Vec::Zero(n_)) {
    wit_.g0 = tol_.g0;
    wit_.v_ref = tol_.v_ref;
    wit_.omega_lim = opt.omega_lim;
    omega_pending_ = opt.omega_lim > 0.0 && m.spin_coordinate() >= 0;
    if (opt.contact_phases == ContactFormulation::Reduced) chart_ = m.contact_chart();
  }

  RunSummary run(const MechanicalState& init, double t_end);

 private:
  // ---- phases ----
  void open_sessions() {
    SessionSettings s;
    s.rtol = opt_.rtol;
    s.atol_q = opt_.atol;
    s.atol_v = tol_.atol_v;
    s.g0 = tol_.g0;
    s.adams = opt_.adams;
    s.fixed_point = opt_.fixed_point;
    // A CVODE call takes at most kCheckSteps steps (run_envelope.hpp): the loop then sees the
    // stop flag, the clock and the step rate between steps, not only at samples and events. A
    // call cut there (CV_TOO_MUCH_WORK) is continued by the next one with the same steps, roots
    // and output: CVODE returns at a step end whose roots it has checked (run()).
    s.max_steps = std::min(opt_.max_steps_per_call, kCheckSteps);
    free_ = std::make_unique<FreeFlight>(m_, wit_, s);
    s.adams = opt_.contact_adams;
    if (chart_ == nullptr) {
      contact_ = std::make_unique<ProjectedContact>(m_, wit_, s);
    } else {
      slip_ = std::make_unique<ReducedContact>(m_, wit_, s, *chart_, ChartMode::Slip);
      stick_ = std::make_unique<ReducedContact>(m_, wit_, s, *chart_, ChartMode::Stick);
    }
  }
  PhaseSystem* system_for(Phase p) const {
    if (p == Phase::Free) return free_.get();
    if (chart_ == nullptr) return contact_.get();
    return p == Phase::Stick ? stick_.get() : slip_.get();
  }

  void build_witnesses() {
    wit_.clear();
    switch (phase_) {
      case Phase::Free:
        // After a release on the constraint (lift-off, v_N = 0 and F_N ~ 0, so d_N'' ~ 0 too)
        // the gap and its rate start at degenerate zeros. The gap opens as 0.5 d_N'' t^2, far
        // below the position tolerance for many steps, and the integrator's own error (atol on
        // coordinates whose difference is d_N) can cross d_N back through 0: a contact onset
        // that is an artefact (an arrival with |v_N| below the velocity tolerance that the
        // contact problem releases at once), and the same release again, in a loop. After such
        // an arrival, and until the gap has opened beyond the position tolerance, contact onset
        // is d_N = -graze_tol (a penetration the integrator can resolve); the gap-rate witness
        // waits until v_N is above the velocity tolerance after every release (arm).
        wit_.gap_offset = gap_banded_ ? tol_.graze_tol : 0.0;
        wit_.add(Witness::Gap, -1);
        if (!gap_rate_deferred_) wit_.add(Witness::GapRate, +1);
        break;
      case Phase::SlipPos:
      case Phase::SlipNeg:
        wit_.add(Witness::NormalForce, -1);
        // mu = 0: no tangential witness (the slip direction is irrelevant without friction)
        if (law_.has_friction()) wit_.add(Witness::SlipSpeed, phase_ == Phase::SlipPos ? -1 : +1);
        break;
      case Phase::Stick:
        wit_.add(Witness::NormalForce, -1);
        wit_.add(Witness::ConeUpper, -1);
        wit_.add(Witness::ConeLower, -1);
        break;
    }
    if (omega_pending_) wit_.add(Witness::Omega, +1);
  }

  /// Starts (or restarts) the current phase at (t, q, v). In minimal coordinates the state is
  /// mapped into the chart of the phase; the restart state is its embedding (equal to round-off).
  void start_phase(double t, const Vec& q, const Vec& v) {
    phase_start_ = t;
    build_witnesses();
    PhaseSystem* s = system_for(phase_);
    // (q, v may alias q_restart_, v_restart_: the embedding is computed from a copy)
    if (&q != &q_restart_) q_restart_ = q;
    if (&v != &v_restart_) v_restart_ = v;
    s->enter(phase_, q_restart_, v_restart_);
    const Vec& qs = q_restart_;
    const Vec& vs = v_restart_;
    // F_ref: the scale of the contact forces since the contact closed (witness scaling and the
    // decision band at contact witnesses); a phase that starts with a vanishing force, e.g. slip
    // at the instant stick ends with F_N -> 0, keeps the scale of the contact.
    if (phase_ == Phase::Free) {
      wit_.F_ref = 0.0;
    } else {
      double FN = 0, FT = 0;
      s->forces(t, qs, vs, FN, FT);
      wit_.F_ref = std::max({wit_.F_ref, std::abs(FN), kForceRefFloor});
    }
    t_restart_ = t;
    cur_ = s;
    s->restart(t, work_, t_end_);
  }

  /// A free phase after a release (build_witnesses): the gap-minimum witness is armed once the
  /// gap is clearly opening (v_N above the velocity tolerance; until then a closing gap is still
  /// seen by the d_N witness, and only a touch-and-go without any crossing could pass unlogged),
  /// contact onset at d_N = 0 once the gap is above the position tolerance.
  void arm(double t, const Vec& q, const Vec& v) {
    m_.compute_contact(0, t, q, v, kin_);
    const ContactKinematics& c = kin_;
    const bool rate = gap_rate_deferred_ && c.v_N > tol_.v_tol;
    const bool gap = gap_banded_ && c.d_N > tol_.graze_tol;
    if (!rate && !gap) return;
    gap_rate_deferred_ = gap_rate_deferred_ && !rate;
    gap_banded_ = gap_banded_ && !gap;
    build_witnesses();
    cur_->session().set_roots(wit_.size(), wit_.dirs.data());
  }

  /// Ends the current phase at t (inside its last step): outputs before t, works, time spent.
  void close_phase(double t) {
    emit_outputs_before(t);
    work_ = cur_->works_at(t);
    end_phase(t);
  }
  void end_phase(double t) {
    env_->summary().phase_time[static_cast<int>(phase_)] += t - phase_start_;
  }

  // ---- output ----
  void emit_sample(double t, const Vec& q, const Vec& v) {
    Sample& s = sample_;
    s.t = t;
    s.q = q;
    s.v = v;
    ContactSample& cs = s.contacts[0];
    cs.F_N = cs.F_T = 0.0;
    // Dense output inside a contact phase of the DAE formulation is CVODE's interpolant, which
    // is not projected: it is projected like a step end (contact_point), so that every output
    // state satisfies the constraints.
    if (phase_ != Phase::Free) {
      cur_->contact_point(t, s.q, s.v, op_);
      phase_dynamics(op_, phase_, law_.mu, dyn_);
      cs.F_N = dyn_.F_N;
      cs.F_T = dyn_.F_T;
    }
    m_.compute_contact(0, t, s.q, s.v, kin_);
    cs.d_N = kin_.d_N;
    cs.v_N = kin_.v_N;
    cs.v_t = kin_.v_t;
    cs.phase = phase_;
    if (s.observables.size() > 0) {
      // the model's observables need the accelerations: the phase's, or M^-1 f in free flight
      if (phase_ == Phase::Free) {
        compute_contact_operators(m_, t, s.q, s.v, op_);
        acc_ = op_.Minv_f();
      } else {
        acc_ = dyn_.a;
      }
      const ContactForce F{cs.F_N, cs.F_T};
      m_.compute_observables(t, s.q, s.v, acc_, &F, s.observables);
    }
    env_->sample(s, m_.spin(t, s.q, s.v), phase_ != Phase::Free);
  }

  /// Writes the output times before t, interpolated in the last step, before an event at t
  /// restarts the integration there: the step that found a root may have passed output times
  /// before it (single-step mode while the gap-rate witness is armed).
  void emit_outputs_before(double t) {
    while (env_->next_output() < t && env_->next_output() < t_end_) {
      const double tout = env_->next_output();
      cur_->interpolate(tout, q_tmp_, v_tmp_);
      emit_sample(tout, q_tmp_, v_tmp_);
      env_->advance_output();
    }
  }

  void fail(Termination why, const std::string& msg) { env_->fail(why, msg); }
  void log_event(const EventRecord& e) { env_->event(e); }

  // ---- events (false: the run ends) ----
  /// Logs a transition's events and restarts where it says.
  bool apply(double t, const Transition& tr) {
    for (int i = 0; i < tr.n_events; ++i) log_event(tr.events[i]);
    work_impacts_ += tr.impulse_work;
    if (!tr.ok) {
      fail(tr.why, tr.message);
      return false;
    }
    phase_ = tr.next;
    gap_rate_deferred_ = tr.release;
    gap_banded_ = tr.release && band_next_release_;
    band_next_release_ = false;
    start_phase(t, tr.q, tr.v);
    emit_sample(t, q_restart_, v_restart_);
    return guard(t);
  }
  bool guard(double t) {
    if (auto why = guard_.record(t)) {
      fail(Termination::Chattering, *why);
      return false;
    }
    return true;
  }

  /// The localised time of a witness's event in the current step (event_locator.hpp), and the
  /// interpolated state there. `hi`: the root finder's time (or the gap minimum's).
  double locate(Witness w, double hi, Vec& q, Vec& v) {
    auto g = [&](double t) {
      cur_->interpolate(t, q_tmp_, v_tmp_);
      return cur_->witness_value(w, t, q_tmp_, v_tmp_);
    };
    const double lo = cur_->step_start();
    const double t = last_time_with_sign(lo, hi, g(lo), g(hi), g);
    cur_->interpolate(t, q, v);
    return t;
  }

  /// The contact onset found by the d_N witness (or a gap minimum below 0) at hi: the last time
  /// with d_N > 0 in the step. After a release the witness is d_N + graze_tol (build_witnesses):
  /// the zero of d_N itself is still taken when the step holds it, so a slow re-contact is not
  /// dated by the band; only a crossing in an earlier step (inside the band, below what the
  /// integrator resolves) is dated by the band's witness.
  double locate_onset(double hi, Vec& q, Vec& v) {
    auto gap = [&](double t) {
      cur_->interpolate(t, q_tmp_, v_tmp_);
      m_.compute_contact(0, t, q_tmp_, v_tmp_, kin_);
      return kin_.d_N;
    };
    const double lo = cur_->step_start();
    const double g_lo = gap(lo);
    if (wit_.gap_offset == 0.0 || g_lo > 0.0) {
      const double t = last_time_with_sign(lo, hi, g_lo, gap(hi), gap);
      cur_->interpolate(t, q, v);
      return t;
    }
    return locate(Witness::Gap, hi, q, v);
  }

  /// Contact onset at t (free flight, q about to reach d_N = 0).
  bool arrive(double t, const Vec& q_in, const Vec& v, const char* witness) {
    Vec q = q_in;
    sw_.project_position(t, q, v);
    emit_sample(t, q, v);
    EventRecord e;
    e.t = t;
    e.phase_before = phase_;
    e.witness = witness;
    const Transition tr = sw_.gap_closed(t, q, v, e);
    // an arrival released at once: its d_N crossing was the integrator's error (build_witnesses)
    band_next_release_ =
        tr.release && tr.n_events > 0 && tr.events[tr.n_events - 1].kind == EventKind::Contact;
    return apply(t, tr);
  }

  bool on_gap_minimum(double t, const Vec& q, const Vec& v, bool& restarted) {
    if (t - phase_start_ <= kPhaseStartRel * std::max(1.0, std::abs(t))) {
      // Half-open interval rule: right after a release on the constraint (v_N = 0, and the
      // free normal acceleration ~ 0 at a lift-off) the gap rate may dip by round-off and come
      // back: that is the phase's own start, not a new gap minimum. Counted.
      ++env_->summary().suppressed_witnesses;
      return true;
    }
    switch (sw_.classify_gap_minimum(t, q, v)) {
      case ModeSwitcher::GapMinimum::Clear: return true;
      case ModeSwitcher::GapMinimum::TouchAndGo:
        log_event(sw_.grazing_record(t, q, v, true));
        return guard(t);
      case ModeSwitcher::GapMinimum::Grazing:
        restarted = true;
        close_phase(t);
        emit_sample(t, q, v);
        return apply(
            t, sw_.on_constraint(t, q, v, sw_.grazing_record(t, q, v, false), kDecisionBandRel));
      case ModeSwitcher::GapMinimum::Crossed: {
        // the gap closed and reopened inside the step: back to its first crossing
        restarted = true;
        const double tc = locate_onset(t, q_ev_, v_ev_);
        close_phase(tc);
        return arrive(tc, q_ev_, v_ev_, "v_N (gap minimum below 0: double crossing inside a step)");
      }
    }
    return true;
  }

  bool on_contact_witness(Witness w, double t_root) {
    Vec& q = q_ev_;
    Vec& v = v_ev_;
    const double t = locate(w, t_root, q, v);
    close_phase(t);
    emit_sample(t, q, v);
    const ContactKinematics c = m_.contact(0, t, q, v);
    EventRecord e;
    e.t = t;
    e.phase_before = phase_;
    e.d_N = c.d_N;
    e.v_N_minus = c.v_N;
    e.v_t_minus = c.v_t;
    e.witness = witness_name(w);  // the kind follows from the decision (on_constraint)
    // Decided with the witness band (kWitnessBandRel): the witness is zero at the event to the
    // accuracy of the root location on the interpolant, so a margin of that size is a zero, not
    // a sign. The phase whose witness fired cannot continue (tie rule 1 of
    // coulomb_signorini.hpp).
    return apply(t, sw_.on_constraint(t, q, v, e, kWitnessBandRel, w == Witness::SlipSpeed, phase_,
                                      wit_.F_ref));
  }

  /// One fired witness at t (the root finder's time, state (q, v)).
  bool on_root(Witness w, double t, const Vec& q, const Vec& v, bool& restarted) {
    if (w == Witness::Omega) {
      env_->monitor().set_omega_lim_time(t);
      omega_pending_ = false;
      return true;
    }
    if (phase_ == Phase::Free && w == Witness::GapRate) return on_gap_minimum(t, q, v, restarted);
    restarted = true;
    if (phase_ != Phase::Free) return on_contact_witness(w, t);
    const double tc = locate_onset(t, q_ev_, v_ev_);
    close_phase(tc);
    return arrive(tc, q_ev_, v_ev_, "d_N");
  }

  /// The initial phase: free unless the state is on the constraint.
  bool start(const MechanicalState& init) {
    const Vec& q = init.q;
    const Vec& v = init.v;
    const double t = init.t;
    const ContactKinematics c0 = m_.contact(0, t, q, v);
    phase_ = Phase::Free;
    phase_start_ = t;
    if (c0.d_N < -tol_.graze_tol) {
      fail(Termination::SolverFailure,
           fmt::format("initial state penetrates the stator: d_N = {:.6g} m", c0.d_N));
      return false;
    }
    if (!(c0.normal_defined && c0.d_N <= tol_.graze_tol && c0.v_N <= tol_.v_tol)) {
      start_phase(t, q, v);
      emit_sample(t, q_restart_, v_restart_);
      return true;
    }
    // starts in contact: impact if closing, else the contact problem decides
    if (c0.v_N < -tol_.v_tol) return arrive(t, q, v, "initial state on the constraint, closing");
    // (no sample before this event: the run starts in the phase the contact problem picks)
    EventRecord e;
    e.t = t;
    e.kind = EventKind::Contact;
    e.witness = "initial state on the constraint";
    return apply(t, sw_.on_constraint(t, q, v, e, kDecisionBandRel));
  }

  const LagrangianModel& m_;
  const int n_;
  const EventDrivenOptions& opt_;
  OutputSink& sink_;
  const ContactLaw law_;
  std::optional<RunEnvelope> env_;  // the books of the run (core/run_envelope.hpp)
  const SwitchTolerances tol_;      // decision_tolerances.hpp
  ModeSwitcher sw_;
  EventGuard guard_;
  WitnessSet wit_;
  const ContactChart* chart_ = nullptr;  // null: contact phases as the DAE with projection
  std::unique_ptr<PhaseSystem> free_, contact_, slip_, stick_;
  PhaseSystem* cur_ = nullptr;
  Phase phase_ = Phase::Free;
  bool omega_pending_ = false;
  bool gap_rate_deferred_ = false;  // free flight after a release: gap-rate witness not armed
  bool gap_banded_ = false;         // ... and contact onset at d_N = -graze_tol
  bool band_next_release_ = false;  // set by an arrival released at once (build_witnesses)
  double t_end_ = 0, phase_start_ = 0, t_restart_ = 0;
  // workspaces, sized for the model when the integrator is built
  Sample sample_;
  ContactOperators op_;
  PhaseDynamics dyn_;
  ContactKinematics kin_;
  Vec q_restart_, v_restart_;  // where the current phase (re)started
  Vec q_tmp_, v_tmp_;          // interpolated states (outputs, the localisers)
  Vec q_ev_, v_ev_;            // the state at an event
  Vec acc_;                    // the accelerations at a sample (the observables)
  Works work_{};
  double work_impacts_ = 0.0;
};

RunSummary Integrator::run(const MechanicalState& init, double t_end) {
  t_end_ = t_end;
  env_.emplace(opt_, sink_, init.t, t_end, m_.mechanical_energy(init.t, init.q, init.v), law_.mu,
               "event",
               fmt::format("{{\"rtol\": {:.3g}, \"atol\": {:.3g}, \"free_flight\": \"{}\", "
                           "\"contact_phases\": \"{}\", \"adams_iteration\": \"{}\", "
                           "\"output_dt\": {:.6g}}}",
                           opt_.rtol, opt_.atol, opt_.adams ? "adams" : "bdf",
                           chart_ ? (opt_.contact_adams ? "reduced+adams" : "reduced+bdf")
                                  : "bdf+projection",
                           opt_.fixed_point ? "fixed-point" : "newton", opt_.output_dt));
  RunSummary& sum = env_->summary();
  // The event solver resolves the contact to round-off: a penetration beyond a millionth of the
  // gap (the integrator's position resolution graze_tol added, for a loose atol) is no solution
  Plausibility plaus;
  plaus.max_penetration = 1e-6 * m_.gap_scale(0) + tol_.graze_tol;
  env_->set_plausibility(plaus);
  auto steps_so_far = [&sum] {
    return std::accumulate(sum.phase_steps.begin(), sum.phase_steps.end(), 0L);
  };
  long call_steps = 0;  // steps of the current advance, over the calls it was cut into
  double t = init.t;
  Vec q = init.q, v = init.v;
  bool ok = true;
  // A root that needed no restart, kept for recovery: CVODE stops when a witness is zero both
  // at the last root and just after it ("root found at and very near"), which a degenerate
  // witness can do. Restarting the phase at that root makes the witness inactive until it moves
  // away (half-open interval rule).
  bool root_without_restart = false;
  int recoveries = 0;
  double t_root = 0.0;
  Vec q_root = q, v_root = v;
  Works work_root{};
  // the roots' flags and the witnesses that fired, with room for every witness: a root that is
  // no event (a gap minimum well clear of the ring, once per whirl turn) allocates nothing
  std::vector<int> info(kNumWitnesses, 0);
  std::vector<Witness> fired_from;
  fired_from.reserve(kNumWitnesses);
  try {
    open_sessions();
    ok = start(init);
    if (ok) {
      t = t_restart_;
      q = q_restart_;
      v = v_restart_;
    }
    while (ok && t < t_end_) {
      // between steps: a failure seen by the envelope (a non-finite sample), the stop flag, and
      // every kCheckSteps steps the wall-time budget and the step-rate guard
      const long steps = steps_so_far();
      if (env_->check_due(steps)) {
        m_.compute_contact(0, t, q, v, kin_);
        env_->check_speed(t, kin_.v_N, kin_.v_t);
      }
      if (!sum.complete() || env_->watch(t, steps)) {
        // the state reached (a step end or an event) is written: the output ends where the run did
        if (!(t <= env_->last_output_time())) emit_sample(t, q, v);
        break;
      }
      // advance (per-phase cost: steps and wall time of the integration itself)
      const double tout = std::min(env_->next_output(), t_end_);
      const bool arming = gap_rate_deferred_ || gap_banded_;
      const int ph = static_cast<int>(phase_);
      const long steps0 = cur_->session().steps_since_restart();
      const auto wall_adv = std::chrono::steady_clock::now();
      const Status st = cur_->advance(tout, t, q, v, arming);
      sum.phase_wall[ph] +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_adv).count();
      const long taken = cur_->session().steps_since_restart() - steps0;
      sum.phase_steps[ph] += taken;
      // classify. A call cut at kCheckSteps steps (open_sessions) goes on at the next call
      // unless the advance has taken max_steps_per_call steps in all (then it is the
      // solver_failure that option promises).
      if (st == Status::Failure && cur_->session().last_error().rfind("CV_TOO_MUCH_WORK", 0) == 0 &&
          (call_steps += taken) < opt_.max_steps_per_call) {
        if (!all_finite(q) || !all_finite(v)) {
          fail(Termination::NonFinite, fmt::format("non-finite state at t = {:.17g}", t));
          break;
        }
        continue;
      }
      call_steps = 0;
      if (st == Status::Failure && root_without_restart && recoveries < 100) {
        ++recoveries;
        ++sum.suppressed_witnesses;
        root_without_restart = false;
        end_phase(t_root);
        work_ = work_root;
        start_phase(t_root, q_root, v_root);
        t = t_restart_;
        q = q_restart_;
        v = v_restart_;
        continue;
      }
      if (st == Status::Failure) {
        t = cur_->session().current_time();
        fail(Termination::SolverFailure,
             fmt::format("CVODE failed at t = {:.17g} in phase {}: {}", t, to_string(phase_),
                         cur_->session().last_error()));
        break;
      }
      if (!all_finite(q) || !all_finite(v)) {
        fail(Termination::NonFinite, fmt::format("non-finite state at t = {:.17g}", t));
        break;
      }
      if (arming && st != Status::Root) arm(t, q, v);
      if (st != Status::Root) root_without_restart = false;
      if (st == Status::Step) continue;
      if (st == Status::Reached) {
        emit_sample(t, q, v);
        env_->progress(t, m_.spin(t, q, v), phase_);
        // (not at the end: a run that reached t_end is complete)
        if (t < t_end_ && (env_->stop_requested(t) || env_->budget_spent(t))) break;
        if (t >= tout && tout == env_->next_output()) env_->advance_output();
        continue;
      }
      // dispatch the roots. In single-step mode (arming the gap-rate witness) the step that
      // found the root may have passed output times before it: they are written first,
      // interpolated on that step, or the restart at the event would leave them behind.
      emit_outputs_before(t);
      info.assign(wit_.list.size(), 0);
      cur_->session().root_info(info.data());
      fired_from.assign(wit_.list.begin(), wit_.list.end());  // handlers rebuild the witness set
      bool restarted = false;
      for (size_t i = 0; i < fired_from.size() && ok && !restarted; ++i)
        if (info[i] != 0) ok = on_root(fired_from[i], t, q, v, restarted);
      if (!ok) break;
      // restart
      if (restarted) {
        t = t_restart_;
        q = q_restart_;
        v = v_restart_;
        root_without_restart = false;
        continue;
      }
      root_without_restart = true;
      t_root = t;
      q_root = q;
      v_root = v;
      work_root = cur_->works();
      if (!omega_pending_ && !wit_.list.empty() && wit_.list.back() == Witness::Omega) {
        wit_.list.pop_back();  // omega_lim crossed: its witness is no longer needed
        wit_.dirs.pop_back();
        cur_->session().set_roots(wit_.size(), wit_.dirs.data());
      }
    }
  } catch (const std::exception& ex) {
    fail(Termination::SolverFailure, fmt::format("at t = {:.17g}: {}", t, ex.what()));
  }

  // Close the books.
  end_phase(t);
  if (cur_) work_ = cur_->works();
  for (const auto* s : {free_.get(), contact_.get(), slip_.get(), stick_.get()}) {
    if (!s) continue;
    const auto st = s->session().stats();
    sum.steps += st.steps;
    sum.rhs_evals += st.rhs_evals;
    sum.jac_evals += st.jac_evals;
    sum.root_evals += st.root_evals;
    sum.newton_iters += st.newton_iters;
  }
  return env_->finish(t, m_.mechanical_energy(t, q, v),
                      {work_[0], work_[1], work_[2], work_impacts_});
}

}  // namespace

std::vector<OptionProblem> event_driven_option_problems(const EventDrivenOptions& o) {
  std::vector<OptionProblem> bad;
  auto num = [](double x) { return fmt::format("{:.17g}", x); };
  if (!(std::isfinite(o.rtol) && o.rtol > 0.0))
    bad.push_back({"rtol", num(o.rtol), "must be finite and > 0"});
  if (!(std::isfinite(o.atol) && o.atol > 0.0))
    bad.push_back({"atol", num(o.atol), "must be finite and > 0"});
  if (!(std::isfinite(o.output_dt) && o.output_dt > 0.0))
    bad.push_back({"output_dt", num(o.output_dt), "must be finite and > 0"});
  if (!(std::isfinite(o.omega_lim) && o.omega_lim >= 0.0))
    bad.push_back({"omega_lim", num(o.omega_lim), "must be finite and >= 0 (0: none)"});
  if (!(o.max_events_per_second > 0.0))
    bad.push_back({"max_events_per_second", num(o.max_events_per_second), "must be > 0"});
  if (o.max_steps_per_call < 1)
    bad.push_back({"max_steps_per_call", fmt::format("{}", o.max_steps_per_call), "must be >= 1"});
  if (!(std::isfinite(o.max_wall) && o.max_wall >= 0.0))
    bad.push_back({"max_wall", num(o.max_wall), "must be finite and >= 0 (seconds; 0: none)"});
  return bad;
}

RunSummary run_event_driven(const LagrangianModel& model, const MechanicalState& initial,
                            double t_end, const EventDrivenOptions& opt, OutputSink& sink) {
  const auto bad = event_driven_option_problems(opt);
  if (!bad.empty()) {
    std::string text = "invalid event-driven options:";
    for (const auto& b : bad) text += fmt::format("\n  {} = {}: {}", b.option, b.value, b.rule);
    throw std::invalid_argument(text);
  }
  if (model.contact_count() < 1)
    throw std::invalid_argument(
        fmt::format("the event-driven solver needs a contact; model '{}' has none", model.name()));
  // several contacts: their own integrator (event_multi.hpp); one contact runs this one, as before
  if (model.contact_count() > 1)
    return detail::run_event_driven_multi(model, initial, t_end, opt, sink);
  Integrator integ(model, opt, sink);
  return integ.run(initial, t_end);
}

}  // namespace rubdyn
