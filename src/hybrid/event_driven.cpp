// The event-driven engine, for one contact and for K: the loop advance -> classify -> dispatch
// -> restart. The hybrid state is the tuple of the contacts' modes; the pieces the loop drives
// live next to it:
//   phase_session.*     the phases (one CVODE session per formulation: free flight, the
//                       projected DAE, minimal coordinates of each dimension) and their
//                       witnesses;
//   contact_decisions.* what happens at an event (the impulse problem, the cascades' collapse,
//                       the acceleration-level problem and its next order), decided by the
//                       contact problem of every contact at the constraint;
//   event_locator.hpp   the one localiser (every event at the last time its witness has the
//                       ending phase's sign).
#include "rubdyn/hybrid/event_driven.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <vector>

#include "contact_decisions.hpp"
#include "event_locator.hpp"
#include "phase_session.hpp"
#include "rubdyn/core/run_envelope.hpp"
#include "rubdyn/hybrid/method_choice.hpp"

namespace rubdyn {

namespace {

using namespace detail;
using Status = CvodeSession::Status;

class Engine {
 public:
  Engine(const LagrangianModel& m, const EventDrivenOptions& opt, OutputSink& sink)
      : m_(m),
        n_(m.num_dofs()),
        K_(m.contact_count()),
        opt_(opt),
        sink_(sink),
        ctx_(m, opt.rtol, opt.atol, opt.omega_lim),
        decide_(m, ctx_),
        guard_(opt.max_events_per_second),
        sample_(n_, K_, static_cast<int>(m.observables().size())),
        kin_(n_),
        forces_(static_cast<std::size_t>(K_)),
        q_restart_(Vec::Zero(n_)),
        v_restart_(Vec::Zero(n_)),
        q_tmp_(Vec::Zero(n_)),
        v_tmp_(Vec::Zero(n_)),
        q_ev_(Vec::Zero(n_)),
        v_ev_(Vec::Zero(n_)) {
    omega_witness_ = opt.omega_lim > 0.0 && m.spin_coordinate() >= 0;
  }

  RunSummary run(const MechanicalState& init, double t_end);

 private:
  /// The multistep families of the free flight and the reduced contact phases: as the options
  /// give them, or (auto) chosen by the model's stiffness at the initial state
  /// (method_choice.hpp). Returns the summary's words for them.
  std::string choose_methods(const MechanicalState& init) {
    std::optional<StiffnessAssessment> a;
    if (opt_.method == MultistepMethod::Auto || opt_.contact_method == MultistepMethod::Auto)
      a = assess_stiffness(m_, init.t, init.q, init.v);
    const auto adams = [&](MultistepMethod m) {
      return m == MultistepMethod::Adams || (m == MultistepMethod::Auto && !a->stiff);
    };
    adams_ = adams(opt_.method);
    contact_adams_ = adams(opt_.contact_method);
    const auto how = [](MultistepMethod m) {
      return m == MultistepMethod::Auto ? "auto" : "given";
    };
    // the contact phases' formulation (ContactFormulation::Auto): minimal coordinates, whose
    // Newton systems (BDF) are the projected DAE's, banded where the model is (lsys_reduced)
    formulation_ = opt_.contact_phases;
    std::string formulation;
    if (formulation_ == ContactFormulation::Auto) {
      formulation_ = ContactFormulation::Reduced;
      if (!contact_adams_) {
        const NewtonStructure ns = assess_newton_structure(m_, init.t, init.q, init.v);
        formulation = fmt::format("\"formulation\": \"auto: reduced ({})\", ", ns.reason());
      }
    }
    return fmt::format("\"methods\": \"free flight {}, contact phases {}\", ", how(opt_.method),
                       how(opt_.contact_method)) +
           (a ? fmt::format("\"stiffness\": \"{}\", ", a->reason()) : std::string()) + formulation;
  }

  const SwitchTolerances& tol(int k) const { return ctx_.tl(k); }
  const ContactLaw& law(int k) const { return ctx_.law(k); }
  Phase mode(int k) const { return ctx_.modes[k]; }

  // ---- phases ----
  void open_sessions() {
    SessionSettings s;
    s.rtol = opt_.rtol;
    s.atol_q = opt_.atol;
    s.atol_v = tol(0).atol_v;
    s.g0 = tol(0).g0;
    s.adams = adams_;
    s.fixed_point = opt_.fixed_point;
    // A CVODE call takes at most kCheckSteps steps (run_envelope.hpp): the loop then sees the
    // stop flag, the clock and the step rate between steps, not only at samples and events. A
    // call cut there (CV_TOO_MUCH_WORK) is continued by the next one with the same steps, roots
    // and output: CVODE returns at a step end whose roots it has checked (run()).
    s.max_steps = std::min(opt_.max_steps_per_call, kCheckSteps);
    free_ = std::make_unique<PhaseSession>(ctx_, s, SessionKind::Free);
    // minimal coordinates (phase_chart.hpp): one session per number r of coordinates removed
    // (1 .. 2K), built here so that no switch allocates; the projected DAE where the chart does
    // not apply
    if (formulation_ == ContactFormulation::Reduced) chart_ = make_phase_chart(m_);
    if (chart_) {
      SessionSettings sr = s;
      sr.adams = contact_adams_;
      sr.dense_reduced_newton = opt_.dense_reduced_newton;
      reduced_.resize(static_cast<std::size_t>(2 * K_ + 1));
      for (int r = 1; r <= 2 * K_ && r < n_; ++r)
        reduced_[static_cast<std::size_t>(r)] =
            std::make_unique<PhaseSession>(ctx_, sr, SessionKind::Reduced, chart_->clone(), n_ - r);
    }
    projected_ = std::make_unique<PhaseSession>(ctx_, s, SessionKind::Projected);
  }
  /// The session of the current modes: free flight, a reduced contact phase where the chart
  /// applies, the projection formulation otherwise.
  PhaseSession* session_for_modes() {
    if (!ctx_.modes.any_closed()) return free_.get();
    if (chart_ != nullptr && chart_->applies(ctx_.modes)) {
      const auto r = static_cast<std::size_t>(n_ - chart_->dim(ctx_.modes));
      if (r < reduced_.size() && reduced_[r]) return reduced_[r].get();
    }
    return projected_.get();
  }

  /// The witnesses of the current modes, per contact (event_driven.hpp): open: d_N (closing)
  /// and v_N (rising: a gap minimum); slip: F_N (falling) and v_t (towards 0; none without
  /// friction); stick: F_N, mu F_N -+ F_T (falling); and omega - omega_lim (rising).
  void build_witnesses() {
    WitnessList& w = ctx_.witnesses;
    w.clear();
    for (int k = 0; k < K_; ++k) {
      switch (mode(k)) {
        case Phase::Free:
          w.add(Witness::Gap, k, -1);
          w.add(Witness::GapRate, k, +1);
          break;
        case Phase::SlipPos:
        case Phase::SlipNeg:
          w.add(Witness::NormalForce, k, -1);
          if (law(k).has_friction())
            w.add(Witness::SlipSpeed, k, mode(k) == Phase::SlipPos ? -1 : +1);
          break;
        case Phase::Stick:
          w.add(Witness::NormalForce, k, -1);
          w.add(Witness::ConeUpper, k, -1);
          w.add(Witness::ConeLower, k, -1);
          break;
      }
    }
    if (omega_witness_ && !ctx_.arming.omega_done) w.add(Witness::Omega, -1, +1);
  }

  /// Starts the phase of the current modes at (t, q, v) (projected onto its constraints, or
  /// in its chart: q_restart_, v_restart_ become the state it starts from).
  void start_phase(double t, const Vec& q, const Vec& v) {
    phase_start_ = t;
    build_witnesses();
    cur_ = session_for_modes();
    if (&q != &q_restart_) q_restart_ = q;
    if (&v != &v_restart_) v_restart_ = v;
    // F_ref: the scale of the contact forces since the contacts closed (witness scaling and the
    // decision band at contact witnesses); a phase that starts with a vanishing force, e.g.
    // slip at the instant stick ends with F_N -> 0, keeps the scale of the contact.
    if (ctx_.modes.any_closed()) {
      cur_->evaluate(t, q_restart_, v_restart_);
      double F = 0.0;
      for (int k = 0; k < K_; ++k) F = std::max(F, std::abs(cur_->eval().F_N(k)));
      ctx_.F_ref = std::max({ctx_.F_ref, F, kForceRefFloor});
    } else {
      ctx_.F_ref = 0.0;
    }
    t_restart_ = t;
    cur_->restart(t, q_restart_, v_restart_, work_, t_end_);
    books_ = ctx_.modes.books();
  }

  /// After each step while a witness is armed (Arming): its full form once the state has left
  /// the degenerate start. Only the witness's value changes (the session's roots are not
  /// touched between restarts); both forms have the same sign where it switches.
  void arm(double t, const Vec& q, const Vec& v) {
    Arming& a = ctx_.arming;
    for (int k = 0; k < K_; ++k) {
      const bool gap = a.gap_banded.test(k), rate = a.rate_deferred.test(k);
      const bool slip = a.slip_banded.test(k);
      if (!gap && !rate && !slip) continue;
      m_.compute_contact(k, t, q, v, kin_);
      if (rate && kin_.v_N > tol(k).v_tol) a.rate_deferred.reset(k);
      if (gap && kin_.d_N > tol(k).graze_tol) a.gap_banded.reset(k);
      if (slip && (!slipping(mode(k)) || slip_sign(mode(k)) * kin_.v_t > tol(k).v_tol))
        a.slip_banded.reset(k);
    }
  }

  void close_phase(double t) {
    emit_outputs_before(t);
    work_ = cur_->works_at(t);
    end_phase(t);
  }
  void end_phase(double t) {
    env_->summary().phase_time[static_cast<int>(books_)] += t - phase_start_;
  }

  // ---- output ----
  /// A sample of the current phase at (t, q, v) (projected first in the projection
  /// formulation): observed by the monitor, the contact law checked, handed to the sink.
  void emit_sample(double t, const Vec& q, const Vec& v) {
    Sample& s = sample_;
    s.t = t;
    s.q = q;
    s.v = v;
    cur_->evaluate(t, s.q, s.v);
    const PhaseEval& e = cur_->eval();
    RunMonitor& mon = env_->monitor();
    mon.observe_spin(t, m_.spin(t, s.q, s.v));
    for (int k = 0; k < K_; ++k) {
      ContactSample& cs = s.contacts[static_cast<std::size_t>(k)];
      const ContactKinematics& c = e.c(k);
      cs.F_N = e.F_N(k);
      cs.F_T = e.F_T(k);
      cs.d_N = c.d_N;
      cs.v_N = c.v_N;
      cs.v_t = c.v_t;
      cs.phase = mode(k);
      forces_[static_cast<std::size_t>(k)] = {cs.F_N, cs.F_T};
      mon.observe_contact(c.d_N, c.v_N, cs.F_N, cs.F_T, closed(cs.phase), law(k).mu);
      env_->check_speed(t, c.v_N, c.v_t);
      check_law(t, k, cs.F_N, cs.F_T, "sample");
    }
    if (s.observables.size() > 0)
      m_.compute_observables(t, s.q, s.v, e.a(), forces_.data(), s.observables);
    env_->output(s);
  }
  /// Coulomb's law and F_N >= 0 at contact k (kLawBreachRel): a breach ends the run.
  void check_law(double t, int k, double F_N, double F_T, const char* where) {
    if (!env_->summary().complete()) return;
    const double scale = std::max(ctx_.F_ref, kForceRefFloor);
    if (law_holds(F_N, F_T, law(k).mu, scale)) return;
    fail(Termination::LawViolation,
         fmt::format("at t = {:.17g}, contact {} ({}): F_N = {:.6g} N, |F_T| = {:.6g} N, mu F_N = "
                     "{:.6g} N: the contact law is broken by more than {:.1g} of the contact "
                     "forces' scale {:.6g} N",
                     t, k + 1, where, F_N, std::abs(F_T), law(k).mu * F_N, kLawBreachRel, scale));
  }
  void emit_outputs_before(double t) {
    while (env_->next_output() < t && env_->next_output() < t_end_) {
      const double tout = env_->next_output();
      cur_->interpolate(tout, q_tmp_, v_tmp_);
      emit_sample(tout, q_tmp_, v_tmp_);
      env_->advance_output();
    }
  }
  void fail(Termination why, const std::string& msg) { env_->fail(why, msg); }
  bool guard(double t) {
    if (auto why = guard_.record(t)) {
      fail(Termination::Chattering, *why);
      return false;
    }
    return true;
  }
  /// A step of the flow on which the next order of a decision is taken (decision_tolerances.hpp).
  double next_order_dt() const { return kNextOrderRel * h_ref_; }

  // ---- events (false: the run ends) ----
  /// Logs a transition's events and restarts where it says.
  bool apply(double t, Transition& tr) {
    if (tr.pre_sample) emit_sample(t, tr.q_pre, tr.v_pre);
    for (int i = 0; i < tr.first_contact_event; ++i)
      env_->event(tr.events[static_cast<std::size_t>(i)]);
    work_impacts_ += tr.impulse_work;
    if (!tr.ok) {
      fail(tr.why, tr.message);
      return false;
    }
    ctx_.modes = tr.next;
    Arming& a = ctx_.arming;
    for (int k = 0; k < K_; ++k) {
      if (!tr.decided.test(k)) continue;
      a.gap_banded.set(k, tr.arming.gap_banded.test(k));
      a.rate_deferred.set(k, tr.arming.rate_deferred.test(k));
      a.slip_banded.set(k, tr.arming.slip_banded.test(k));
    }
    start_phase(t, tr.q, tr.v);
    // a state that was on its constraints to round-off when the run started (a restart from a
    // written sample) is written and evaluated as given: its projection, or its chart and
    // embedding, moved coordinates by an ulp, and a restart's first sample is the sample it
    // started from (the integration starts from the phase's own state)
    if (given_ && same_to_round_off(q_restart_, given_->q, true) &&
        same_to_round_off(v_restart_, given_->v, false)) {
      q_restart_ = given_->q;
      v_restart_ = given_->v;
    }
    // the forces after the event, from the phase just started
    cur_->evaluate(t, q_restart_, v_restart_);
    for (std::size_t i = static_cast<std::size_t>(tr.first_contact_event); i < tr.events.size();
         ++i) {
      EventRecord& e = tr.events[i];
      e.F_N = cur_->eval().F_N(e.contact);
      e.F_T = cur_->eval().F_T(e.contact);
      env_->event(e);
      if (closed(mode(e.contact))) check_law(t, e.contact, e.F_N, e.F_T, "event");
    }
    emit_sample(t, q_restart_, v_restart_);
    if (!env_->summary().complete()) return false;
    return guard(t);
  }

  // ---- locating ----
  double locate(const WitnessRef& w, double hi, Vec& q, Vec& v) {
    auto g = [&](double t) {
      cur_->interpolate(t, q_tmp_, v_tmp_);
      cur_->evaluate_witnesses(t, q_tmp_, v_tmp_);
      return cur_->witness_value(w, t, q_tmp_, v_tmp_);
    };
    const double lo = cur_->step_start();
    const double t = last_time_with_sign(lo, hi, g(lo), g(hi), g);
    cur_->interpolate(t, q, v);
    return t;
  }
  /// The contact onset of contact k found at hi: the last time with d_N,k > 0 in the step.
  /// After a release the witness is d_N + graze_tol (Arming): the zero of d_N itself is still
  /// taken when the step holds it, so a slow re-contact is not dated by the band; only a
  /// crossing in an earlier step (inside the band, below what the integrator resolves) is dated
  /// by the band's witness.
  double locate_onset(int k, double hi, Vec& q, Vec& v) {
    auto gap = [&](double t) {
      cur_->interpolate(t, q_tmp_, v_tmp_);
      m_.compute_contact(k, t, q_tmp_, v_tmp_, kin_);
      return kin_.d_N;
    };
    const double lo = cur_->step_start();
    const double g_lo = gap(lo);
    if (!ctx_.arming.gap_banded.test(k) || g_lo > 0.0) {
      const double t = last_time_with_sign(lo, hi, g_lo, gap(hi), gap);
      cur_->interpolate(t, q, v);
      return t;
    }
    return locate({Witness::Gap, k}, hi, q, v);
  }

  // ---- events ----
  bool arrive(double t, const Vec& q, const Vec& v, ContactSet S, const std::string& witness) {
    Transition tr = decide_.arrive(t, q, v, ctx_.modes, S, witness, next_order_dt());
    return apply(t, tr);
  }

  bool on_gap_minimum(int k, double t, const Vec& q, const Vec& v, bool& restarted) {
    if (t - phase_start_ <= kPhaseStartRel * std::max(1.0, std::abs(t))) {
      // Half-open interval rule: right after a release on the constraint (v_N = 0, and the
      // free normal acceleration ~ 0 at a lift-off) the gap rate may dip by round-off and come
      // back: that is the phase's own start, not a new gap minimum. Counted.
      ++env_->summary().suppressed_witnesses;
      return true;
    }
    q_tmp_ = q;
    v_tmp_ = v;
    cur_->evaluate(t, q_tmp_, v_tmp_);
    const ContactKinematics& c = cur_->eval().c(k);
    const SwitchTolerances& tl = tol(k);
    if (c.d_N > tl.graze_band) return true;
    EventRecord e = grazing_event(t, c);
    e.contact = k;
    if (c.d_N < -tl.graze_tol) {
      // the gap closed and reopened inside the step: back to its first crossing
      restarted = true;
      const double tc = locate_onset(k, t, q_ev_, v_ev_);
      close_phase(tc);
      return arrive(tc, q_ev_, v_ev_, ContactSet::of(k),
                    "v_N (gap minimum below 0: double crossing inside a step)");
    }
    // the normal acceleration of contact k in the running phase
    const double acc = c.W_N.dot(cur_->eval().a()) + c.wdot_N;
    if (c.d_N > tl.graze_tol || acc >= 0.0) {
      e.phase_after = Phase::Free;
      e.note = "touch and go: the normal acceleration is >= 0";
      env_->event(e);
      return guard(t);
    }
    restarted = true;
    close_phase(t);
    emit_sample(t, q, v);
    ContactDecider::PendingList ev{};
    ev[static_cast<std::size_t>(k)] = {true, e};
    Transition tr = decide_.on_constraint(t, q, v, ctx_.modes,
                                          ctx_.modes.closed_set() | ContactSet::of(k), std::nullopt,
                                          false, kDecisionBandRel, ctx_.F_ref, ev, next_order_dt());
    return apply(t, tr);
  }

  bool on_contact_witness(const WitnessRef& w, double t_root) {
    const double t = locate(w, t_root, q_ev_, v_ev_);
    close_phase(t);
    emit_sample(t, q_ev_, v_ev_);
    ContactDecider::PendingList ev{};
    // Decided with the witness band (kWitnessBandRel): the witness is zero at the event to the
    // accuracy of the root location on the interpolant, so a margin of that size is a zero, not
    // a sign. The phase whose witness fired cannot continue (tie rule 1).
    Transition tr =
        decide_.on_constraint(t, q_ev_, v_ev_, ctx_.modes, ctx_.modes.closed_set(),
                              std::make_pair(w.k, mode(w.k)), w.w == Witness::SlipSpeed,
                              kWitnessBandRel, ctx_.F_ref, ev, next_order_dt(), witness_name(w.w));
    return apply(t, tr);
  }

  /// One fired witness at t (the root finder's time, state (q, v)).
  bool on_root(const WitnessRef& w, double t, const Vec& q, const Vec& v, bool& restarted) {
    if (w.w == Witness::Omega) {
      // no event: the crossing time; the witness is constant from here (Arming)
      env_->monitor().set_omega_lim_time(t);
      ctx_.arming.omega_done = true;
      return true;
    }
    if (w.w == Witness::GapRate) return on_gap_minimum(w.k, t, q, v, restarted);
    restarted = true;
    if (w.w != Witness::Gap) return on_contact_witness(w, t);
    const double tc = locate_onset(w.k, t, q_ev_, v_ev_);
    close_phase(tc);
    return arrive(tc, q_ev_, v_ev_, ContactSet::of(w.k), "d_N");
  }

  /// The initial phase: free unless a contact is on the constraint (then an impact if it
  /// closes, else the contact problem decides).
  bool start(const MechanicalState& init) {
    const double t = init.t;
    ContactSet S;
    bool closing = false;
    for (int k = 0; k < K_; ++k) {
      m_.compute_contact(k, t, init.q, init.v, kin_);
      const ContactKinematics& c = kin_;
      if (c.d_N < -tol(k).graze_tol) {
        fail(Termination::SolverFailure,
             K_ == 1 ? fmt::format("initial state penetrates the stator: d_N = {:.6g} m", c.d_N)
                     : fmt::format("initial state penetrates contact {}: d_N = {:.6g} m", k + 1,
                                   c.d_N));
        return false;
      }
      if (c.normal_defined && c.d_N <= tol(k).graze_tol && c.v_N <= tol(k).v_tol) {
        S.set(k);
        closing = closing || c.v_N < -tol(k).v_tol;
      }
    }
    phase_start_ = t;
    cur_ = free_.get();
    if (S.none()) {
      start_phase(t, init.q, init.v);
      emit_sample(t, q_restart_, v_restart_);
      return true;
    }
    if (closing) return arrive(t, init.q, init.v, S, "initial state on the constraint, closing");
    // (no sample before this event: the run starts in the phase the contact problem picks)
    ContactDecider::PendingList ev{};
    for (int k = 0; k < K_; ++k) {
      if (!S.test(k)) continue;
      ContactDecider::Pending& p = ev[static_cast<std::size_t>(k)];
      p.active = true;
      p.e.t = t;
      p.e.contact = k;
      p.e.kind = EventKind::Contact;
      p.e.witness = "initial state on the constraint";
    }
    Transition tr = decide_.on_constraint(t, init.q, init.v, ctx_.modes, S, std::nullopt, false,
                                          kDecisionBandRel, ctx_.F_ref, ev, next_order_dt());
    given_ = &init;
    const bool ok = apply(t, tr);
    given_ = nullptr;
    return ok;
  }

  /// a and b the same state to round-off: every component within 64 eps of the largest of b's
  /// (the spin angle left out of that scale: it does not enter the constraints, whose rows a
  /// projection or a chart's embedding evaluates, and grows without bound). The projection of a
  /// state that is on its constraints moves it by that much (two-plane: 35 ulps of a 2e-4 m/s
  /// component, 1e-18 m/s, with 2000 rad/s in the same rows).
  bool same_to_round_off(const Vec& a, const Vec& b, bool positions) const {
    constexpr double kEps = 64.0 * std::numeric_limits<double>::epsilon();
    const int skip = positions ? m_.spin_coordinate() : -1;
    double scale = 0.0;
    for (Eigen::Index i = 0; i < b.size(); ++i)
      if (i != skip) scale = std::max(scale, std::abs(b[i]));
    for (Eigen::Index i = 0; i < a.size(); ++i)
      if (!(std::abs(a[i] - b[i]) <= kEps * std::max(scale, std::abs(b[i])))) return false;
    return true;
  }

  const LagrangianModel& m_;
  const int n_, K_;
  const EventDrivenOptions& opt_;
  OutputSink& sink_;
  std::optional<RunEnvelope> env_;  // the books of the run (core/run_envelope.hpp)
  PhaseContext ctx_;                // modes, laws, tolerances, witnesses: read by the sessions
  ContactDecider decide_;
  EventGuard guard_;
  const MechanicalState* given_ = nullptr;  // the initial state, while its contacts are decided
  std::unique_ptr<PhaseChart> chart_;       // null: contact phases as the DAE with projection
  std::unique_ptr<PhaseSession> free_, projected_;
  std::vector<std::unique_ptr<PhaseSession>> reduced_;  // by coordinates removed
  PhaseSession* cur_ = nullptr;
  Phase books_ = Phase::Free;
  bool omega_witness_ = false;
  bool adams_ = true, contact_adams_ = true;  // the families chosen (choose_methods)
  ContactFormulation formulation_ = ContactFormulation::Reduced;  // (choose_methods)
  double t_end_ = 0, phase_start_ = 0, t_restart_ = 0;
  /// The last step the integrator took (the next order's scale); before any step, the first
  /// step's horizon.
  double h_ref_ = kFirstStepHorizon;
  // workspaces, sized for the model when the engine is built
  Sample sample_;
  ContactKinematics kin_;  // arm(), locate_onset(), start() and the speed check
  std::vector<ContactForce> forces_;
  Vec q_restart_, v_restart_;  // where the current phase (re)started
  Vec q_tmp_, v_tmp_;          // interpolated states (outputs, the localisers)
  Vec q_ev_, v_ev_;            // the state at an event
  Works work_{};
  double work_impacts_ = 0.0;
};

RunSummary Engine::run(const MechanicalState& init, double t_end) {
  t_end_ = t_end;
  const std::string chosen = choose_methods(init);
  open_sessions();
  const std::string phases =
      !chart_ ? std::string("bdf+projection")
              : fmt::format("reduced+{}{}", contact_adams_ ? "adams" : "bdf",
                            K_ > 1 ? " (bdf+projection where the ring chart does not apply)" : "");
  const std::string contacts = K_ > 1 ? fmt::format("\"contacts\": {}, ", K_) : std::string();
  env_.emplace(opt_, sink_, init.t, t_end, m_.mechanical_energy(init.t, init.q, init.v), law(0).mu,
               "event",
               fmt::format("{{\"rtol\": {:.3g}, \"atol\": {:.3g}, \"free_flight\": \"{}\", "
                           "\"contact_phases\": \"{}\", {}{}\"adams_iteration\": \"{}\", "
                           "\"output_dt\": {:.6g}}}",
                           opt_.rtol, opt_.atol, adams_ ? "adams" : "bdf", phases, chosen, contacts,
                           opt_.fixed_point ? "fixed-point" : "newton", opt_.output_dt));
  RunSummary& sum = env_->summary();
  // The event solver resolves the contact to round-off: a penetration beyond a millionth of the
  // gap (the integrator's position resolution graze_tol added, for a loose atol) is no solution
  Plausibility plaus;
  double pen = 0.0;
  for (int k = 0; k < K_; ++k) pen = std::max(pen, 1e-6 * m_.gap_scale(k) + tol(k).graze_tol);
  plaus.max_penetration = pen;
  // The works are integrated with an absolute tolerance kWorkAtol each (three quadratures, a
  // new start at every phase): a residual of a few kWorkAtol is their resolution, whatever the
  // flows. Ten of it is the floor below which the balance is not judged (a run whose flows are
  // 4e-11 J, a block pulsed on a belt, ended "implausible" with a residual of 4e-11 J).
  plaus.energy_residual_abs = 10.0 * kWorkAtol;
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
  std::array<int, WitnessList::kCapacity> info{};
  WitnessList fired;
  try {
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
        for (int k = 0; k < K_; ++k) {
          m_.compute_contact(k, t, q, v, kin_);
          env_->check_speed(t, kin_.v_N, kin_.v_t);
        }
      }
      if (!sum.complete() || env_->watch(t, steps)) {
        // the state reached (a step end or an event) is written: the output ends where the run did
        if (!(t <= env_->last_output_time())) emit_sample(t, q, v);
        break;
      }
      // advance (per-phase cost: steps and wall time of the integration itself)
      const double tout = std::min(env_->next_output(), t_end_);
      const bool arming = ctx_.arming.any();
      const int ph = static_cast<int>(books_);
      const long steps0 = cur_->session().steps_since_restart();
      const auto wall_adv = std::chrono::steady_clock::now();
      const Status st = cur_->advance(tout, t, q, v, arming);
      sum.phase_wall[ph] +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_adv).count();
      const long taken = cur_->session().steps_since_restart() - steps0;
      sum.phase_steps[ph] += taken;
      if (taken > 0) h_ref_ = cur_->session().last_step();
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
             fmt::format("CVODE failed at t = {:.17g} in phase {}: {}", t, to_string(books_),
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
        env_->progress(t, m_.spin(t, q, v), books_);
        // (not at the end: a run that reached t_end is complete)
        if (t < t_end_ && (env_->stop_requested(t) || env_->budget_spent(t))) break;
        if (t >= tout && tout == env_->next_output()) env_->advance_output();
        continue;
      }
      // dispatch the roots. In single-step mode (while a witness is armed) the step that found
      // the root may have passed output times before it: they are written first, interpolated
      // on that step, or the restart at the event would leave them behind.
      emit_outputs_before(t);
      cur_->session().root_info(info.data());
      fired = ctx_.witnesses;  // handlers rebuild the witness list
      bool restarted = false;
      for (int i = 0; i < fired.size() && ok && !restarted; ++i)
        if (info[static_cast<std::size_t>(i)] != 0) ok = on_root(fired[i], t, q, v, restarted);
      if (!ok) break;
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
    }
  } catch (const std::exception& ex) {
    fail(Termination::SolverFailure, fmt::format("at t = {:.17g}: {}", t, ex.what()));
  }

  // Close the books.
  end_phase(t);
  if (cur_) work_ = cur_->works();
  auto add_stats = [&sum](const PhaseSession* s) {
    if (!s) return;
    const auto st = s->session().stats();
    sum.steps += st.steps;
    sum.rhs_evals += st.rhs_evals;
    sum.jac_evals += st.jac_evals;
    sum.root_evals += st.root_evals;
    sum.newton_iters += st.newton_iters;
    sum.err_test_fails += st.err_test_fails;
    sum.conv_fails += st.conv_fails;
  };
  add_stats(free_.get());
  add_stats(projected_.get());
  for (const auto& s : reduced_) add_stats(s.get());
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
  if (model.contact_count() > kMaxContacts)
    throw std::invalid_argument(
        fmt::format("the event-driven solver handles up to {} contacts; model '{}' has {}",
                    kMaxContacts, model.name(), model.contact_count()));
  Engine engine(model, opt, sink);
  return engine.run(initial, t_end);
}

}  // namespace rubdyn
