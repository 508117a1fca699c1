// The run loop of the fixed-step schemes: steps of a Stepper (carpenter.cpp, moreau_jean.cpp),
// with what every scheme needs around them: output, the run monitor, the energy balance, and
// the events between steps (a change of contact status from one step to the next).
#include "rubdyn/stepping/fixed_step.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "rubdyn/core/demand.hpp"
#include "rubdyn/stepping/stepper.hpp"

namespace rubdyn {

std::string_view to_string(FixedStepScheme s) {
  switch (s) {
    case FixedStepScheme::CarpOneVC: return "carp-onevc";
    case FixedStepScheme::CarpQN: return "carp-qn";
    case FixedStepScheme::MoreauJean: return "mj";
    case FixedStepScheme::MoreauJeanProjected: return "mj-proj";
  }
  return "?";
}

bool parse_fixed_step_scheme(std::string_view name, FixedStepScheme& out) {
  for (auto s : {FixedStepScheme::CarpOneVC, FixedStepScheme::CarpQN, FixedStepScheme::MoreauJean,
                 FixedStepScheme::MoreauJeanProjected}) {
    if (name == to_string(s)) {
      out = s;
      return true;
    }
  }
  return false;
}

std::string_view to_string(StepOutcome o) {
  switch (o) {
    case StepOutcome::Ok: return "ok";
    case StepOutcome::NewtonFailed: return "newton_failed";
    case StepOutcome::NonFinite: return "non_finite";
    case StepOutcome::Painleve: return "painleve";
  }
  return "?";
}

std::unique_ptr<Stepper> make_stepper(const LagrangianModel& m, const FixedStepOptions& opt) {
  if (!(std::isfinite(opt.h) && opt.h > 0.0))
    throw std::invalid_argument(fmt::format("fixed-step scheme {}: h = {} must be finite and > 0",
                                            to_string(opt.scheme), opt.h));
  if (m.contact_count() < 1)
    throw std::invalid_argument(fmt::format("fixed-step scheme {}: model '{}' has no contact",
                                            to_string(opt.scheme), m.name()));
  switch (opt.scheme) {
    case FixedStepScheme::CarpOneVC:
    case FixedStepScheme::CarpQN: return make_carpenter(m, opt);
    case FixedStepScheme::MoreauJean:
    case FixedStepScheme::MoreauJeanProjected: return make_moreau_jean(m, opt);
  }
  throw std::invalid_argument("unknown fixed-step scheme");
}

namespace {

class RunLoop {
 public:
  RunLoop(const LagrangianModel& m, const FixedStepOptions& o, RunEnvelope& env)
      : m_(m),
        o_(o),
        env_(env),
        kin_(m.num_dofs()),
        K_(m.contact_count()),
        sample_(m.num_dofs(), K_, static_cast<int>(m.observables().size())),
        prev_phases_(static_cast<std::size_t>(K_), Phase::Free),
        forces_(static_cast<std::size_t>(K_)) {}

  RunSummary run(Stepper& stepper, const MechanicalState& init, double t_end);

 private:
  /// Records a completed state: monitor, the event between steps, output.
  void record(const StepReport& r, double t);
  /// record()'s monitor and events for a model with several contacts; returns the state's
  /// phase for the books (the first closed contact's, free when none is).
  Phase record_contacts(const StepReport& r, double t, double omega);
  /// The event of a contact whose status changed between steps.
  EventRecord between_steps(Phase before, Phase after, const ContactKinematics& c,
                            double v_N_before, double P_N, double P_T, double F_N,
                            double F_T) const;
  /// The contact forces of a report (one per contact), for the drive's power and observables.
  const ContactForce* forces(const StepReport& r);
  /// Writes a completed state as a sample (false: the envelope refused it, the run ends).
  bool emit(const StepReport& r, double t);

  const LagrangianModel& m_;
  const FixedStepOptions& o_;
  RunEnvelope& env_;
  ContactKinematics kin_;
  const int K_;
  Sample sample_;
  Phase prev_phase_ = Phase::Free;
  std::vector<Phase> prev_phases_;    // K > 1: each contact's status at the last step
  std::vector<ContactForce> forces_;  // K > 1: each contact's force (forces())
  long written_ = -1;                 // the index of the last state written (-1: none)
  bool recorded_ = false;             // a state has been recorded (the initial one included)
};

EventRecord RunLoop::between_steps(Phase before, Phase after, const ContactKinematics& c,
                                   double v_N_before, double P_N, double P_T, double F_N,
                                   double F_T) const {
  EventRecord e;
  e.phase_before = before;
  e.phase_after = after;
  e.d_N = c.d_N;
  e.v_N_minus = v_N_before;
  e.v_N_plus = c.v_N;
  e.v_t_plus = c.v_t;
  e.P_N = P_N;
  e.P_T = P_T;
  e.F_N = F_N;
  e.F_T = F_T;
  e.witness = "between steps";
  if (before == Phase::Free) {
    e.kind = v_N_before < 0.0 ? EventKind::Impact : EventKind::Contact;
  } else if (after == Phase::Free) {
    e.kind = EventKind::Release;
  } else if (after == Phase::Stick) {
    e.kind = EventKind::Stick;
  } else if (before == Phase::Stick) {
    e.kind = EventKind::Slip;
  } else {
    e.kind = EventKind::Reversal;
  }
  return e;
}

Phase RunLoop::record_contacts(const StepReport& r, double t, double omega) {
  env_.monitor().observe_spin(t, omega);
  Phase books = Phase::Free;
  for (int k = 0; k < K_; ++k) {
    const ContactStep& cs = r.contacts[static_cast<std::size_t>(k)];
    m_.compute_contact(k, t, r.q, r.v, kin_);
    const ContactKinematics& c = kin_;
    env_.monitor().observe_contact(c.d_N, c.v_N, cs.F_N, cs.F_T, cs.phase != Phase::Free,
                                   m_.contact_law(k).mu);
    env_.check_speed(t, c.v_N, c.v_t);
    Phase& prev = prev_phases_[static_cast<std::size_t>(k)];
    if (r.index > 0 && cs.phase != prev) {
      EventRecord e =
          between_steps(prev, cs.phase, c, cs.v_N_before, cs.P_N, cs.P_T, cs.F_N, cs.F_T);
      e.t = t;
      e.contact = k;
      env_.event(e);
    }
    prev = cs.phase;
    if (books == Phase::Free) books = cs.phase;
  }
  return books;
}

const ContactForce* RunLoop::forces(const StepReport& r) {
  for (int k = 0; k < K_; ++k) {
    const ContactStep& cs = r.contacts[static_cast<std::size_t>(k)];
    forces_[static_cast<std::size_t>(k)] = {cs.F_N, cs.F_T};
  }
  return forces_.data();
}

void RunLoop::record(const StepReport& r, double t) {
  Phase books = r.phase;
  const double omega = m_.spin(t, r.q, r.v);
  if (K_ > 1) {
    books = record_contacts(r, t, omega);
  } else {
    m_.compute_contact(0, t, r.q, r.v, kin_);
    const ContactKinematics& c = kin_;
    const bool in_contact = r.phase != Phase::Free;
    env_.monitor().observe(t, omega, c.d_N, c.v_N, r.F_N, r.F_T, in_contact);
    env_.check_speed(t, c.v_N, c.v_t);  // (the run loop stops once the summary is incomplete)
    if (r.index > 0 && r.phase != prev_phase_) {
      EventRecord e =
          between_steps(prev_phase_, r.phase, c, r.v_N_before, r.P_N, r.P_T, r.F_N, r.F_T);
      e.t = t;
      env_.event(e);
    }
  }
  env_.summary().phase_time[static_cast<int>(books)] += r.index > 0 ? o_.h : 0.0;
  prev_phase_ = books;
  recorded_ = true;
  // output: every N-th step, or the first step end at or after each point of the output grid
  bool out = false;
  if (o_.output_every > 0) {
    out = r.index % o_.output_every == 0;
  } else if (t >= env_.next_output() - 1e-9 * o_.h) {
    out = true;
    while (env_.next_output() <= t + 1e-9 * o_.h) env_.advance_output();
  }
  if (out && emit(r, t)) env_.progress(t, omega, books);
}

bool RunLoop::emit(const StepReport& r, double t) {
  Sample& s = sample_;
  s.t = t;
  s.q = r.q;
  s.v = r.v;
  for (int k = 0; k < K_; ++k) {
    m_.compute_contact(k, t, r.q, r.v, kin_);
    const ContactKinematics& c = kin_;
    ContactSample& cs = s.contacts[static_cast<std::size_t>(k)];
    cs.d_N = c.d_N;
    cs.v_N = c.v_N;
    cs.v_t = c.v_t;
    if (K_ > 1) {
      const ContactStep& st = r.contacts[static_cast<std::size_t>(k)];
      cs.F_N = st.F_N;
      cs.F_T = st.F_T;
      cs.phase = st.phase;
    } else {
      cs.F_N = r.F_N;
      cs.F_T = r.F_T;
      cs.phase = r.phase;
    }
  }
  if (s.observables.size() > 0) {
    const ContactForce F{r.F_N, r.F_T};
    m_.compute_observables(t, r.q, r.v, r.a, K_ > 1 ? forces(r) : &F, s.observables);
  }
  written_ = r.index;
  return env_.output(s);
}

RunSummary RunLoop::run(Stepper& stepper, const MechanicalState& init, double t_end) {
  const double h = o_.h;
  RunSummary& sum = env_.summary();
  const long n_steps = std::max(1L, std::lround((t_end - init.t) / h));
  RUBDYN_DEMAND(h > 0.0 && n_steps <= kMaxFixedSteps);  // run_fixed_step checked the options
  stepper.start(init.t, init.q, init.v);
  // the works: smooth loads and dampers by the trapezoidal rule between completed states,
  // contact forces and impulses as each scheme defines them (StepReport::contact_work)
  double work_ext = 0.0, work_damp = 0.0, work_contact = 0.0;
  double t_prev = init.t;
  const int n = m_.num_dofs();
  StepReport reports[2] = {StepReport(n, K_), StepReport(n, K_)};
  reports[1].q = init.q;
  reports[1].v = init.v;
  // the applied loads' power; a rheonomic drive's depends on the accelerations and contact
  // forces: the scheme's (StepReport::a), and at the start the contact-free M^-1 f
  const bool rheonomic = m_.rheonomic();
  auto rheonomic_power = [&](double t, const StepReport& r) {
    const ContactForce F{r.F_N, r.F_T};
    return m_.applied_power(t, r.q, r.v, r.a, K_ > 1 ? forces(r) : &F);
  };
  // the initial state's acceleration: the contact-free M^-1 f (a rheonomic drive's power at the
  // start, and the observables of the initial sample that Moreau-Jean's first step does not
  // report)
  if (rheonomic || !m_.observables().empty()) {
    Mat f(n, 1);
    m_.smooth_forces(init.t, init.q, init.v, f.col(0));
    m_.solve_mass(init.q, f);
    reports[1].a = f.col(0);
  }
  SmoothPower p_prev = m_.smooth_power(init.t, init.q, init.v);
  if (rheonomic) p_prev.external = rheonomic_power(init.t, reports[1]);
  long unconverged = 0, nonunique = 0;
  // two reports, used in turn: the last completed (finite) state stays in one of them while the
  // stepper writes the next into the other (no copy per step)
  const StepReport* last = &reports[1];
  std::string message;
  for (long i = 0; last->index < n_steps || i == 0; ++i) {
    StepReport& r = last == &reports[0] ? reports[1] : reports[0];
    const double t = init.t + static_cast<double>(i) * h;
    if (env_.stop_requested(t)) break;
    // the clock every 1024 steps: about 20 ns a read against about 0.3 us a step
    if (i % 1024 == 1023 && env_.budget_spent(t)) break;
    const StepOutcome outcome = stepper.step(t, r, message);
    // Moreau-Jean's step i completes t_{i+1}: the initial state is written before it (the row
    // at t_start; Carpenter's step 0 reports t_0 itself)
    if (!recorded_ && (outcome != StepOutcome::Ok || r.index > 0)) record(reports[1], init.t);
    if (outcome != StepOutcome::Ok) {
      env_.fail(outcome == StepOutcome::Painleve    ? Termination::Painleve
                : outcome == StepOutcome::NonFinite ? Termination::NonFinite
                                                    : Termination::SolverFailure,
                message);
      break;
    }
    ++sum.steps;
    sum.newton_iters += r.newton_iters;
    unconverged += r.unconverged;
    nonunique += r.nonunique;
    const double tr = init.t + static_cast<double>(r.index) * h;
    if (!all_finite(r.q) || !all_finite(r.v)) {
      env_.fail(Termination::NonFinite, fmt::format("non-finite state at t = {:.17g}", tr));
      break;
    }
    SmoothPower p = m_.smooth_power(tr, r.q, r.v);
    if (rheonomic) p.external = rheonomic_power(tr, r);
    work_ext += 0.5 * (tr - t_prev) * (p_prev.external + p.external);
    work_damp += 0.5 * (tr - t_prev) * (p_prev.damping + p.damping);
    work_contact += r.contact_work;
    p_prev = p;
    t_prev = tr;
    last = &r;
    sum.t_reached = tr;
    record(r, tr);
    if (!sum.complete()) break;  // a sample the envelope refused (not finite)
  }
  if (!recorded_) record(reports[1], init.t);  // stopped before the first step
  // the final state, when the output grid or output_every left it out (t_end off the grid, a
  // huge output.dt or output.every): the output ends where the run did
  if (written_ != last->index) emit(*last, sum.t_reached);
  if (unconverged > 0 && sum.message.empty())
    sum.message = fmt::format("carp-qn: {} steps reached itmax = {}", unconverged, o_.itmax);
  if (nonunique > 0 && sum.message.empty())
    sum.message = fmt::format(
        "{} steps had several consistent contact solutions (tie rule of the local solver)",
        nonunique);
  // contact work: friction and normal impulses together (the split is not defined for impulses
  // of a time-stepping scheme); it is written as friction work, impacts 0
  return env_.finish(sum.t_reached, m_.mechanical_energy(sum.t_reached, last->q, last->v),
                     RunWorks{work_ext, work_damp, work_contact, 0.0});
}

}  // namespace

std::vector<OptionProblem> fixed_step_option_problems(const FixedStepOptions& o) {
  std::vector<OptionProblem> bad;
  auto num = [](double x) { return fmt::format("{:.17g}", x); };
  if (!(std::isfinite(o.h) && o.h > 0.0)) bad.push_back({"h", num(o.h), "must be finite and > 0"});
  if (o.itmax < 1) bad.push_back({"itmax", fmt::format("{}", o.itmax), "must be >= 1"});
  if (!(o.qn_tol > 0.0)) bad.push_back({"qn_tol", num(o.qn_tol), "must be > 0"});
  if (!(o.theta >= 0.5 && o.theta <= 1.0))
    bad.push_back({"theta", num(o.theta), "must lie in [0.5, 1]"});
  if (!(o.eta >= 0.0 && o.eta <= 1.0)) bad.push_back({"eta", num(o.eta), "must lie in [0, 1]"});
  if (o.output_every < 0)
    bad.push_back(
        {"output_every", fmt::format("{}", o.output_every), "must be >= 0 (0: use output_dt)"});
  if (!(std::isfinite(o.output_dt) && o.output_dt > 0.0))
    bad.push_back({"output_dt", num(o.output_dt), "must be finite and > 0"});
  if (!(std::isfinite(o.max_wall) && o.max_wall >= 0.0))
    bad.push_back({"max_wall", num(o.max_wall), "must be finite and >= 0 (seconds; 0: none)"});
  return bad;
}

std::vector<OptionProblem> fixed_step_count_problems(double h, double t_start, double t_end) {
  std::vector<OptionProblem> bad;
  const double span = t_end - t_start;
  if (!(std::isfinite(span) && span > 0.0)) {
    bad.push_back({"t_end", fmt::format("{:.17g}", t_end),
                   fmt::format("must be finite and > t_start = {:.17g}", t_start)});
    return bad;
  }
  if (!(std::isfinite(h) && h > 0.0)) return bad;  // reported by fixed_step_option_problems
  const double steps = span / h;
  if (!(steps <= static_cast<double>(kMaxFixedSteps))) {
    bad.push_back({"h", fmt::format("{:.17g}", h),
                   fmt::format("(t_end - t_start) / h = {:.6g} steps, above the limit of {} steps",
                               steps, kMaxFixedSteps)});
  } else if (std::abs(steps - std::round(steps)) > 1e-6 || std::round(steps) < 1.0) {
    // 1e-6 of a step: far above the round-off of a decimal ratio (0.01 / 1e-6 is
    // 10000.000000000002), far below any fraction of a step anyone means
    bad.push_back({"h", fmt::format("{:.17g}", h),
                   fmt::format("t_end - t_start = {:.17g} s is {:.9g} steps, not a whole number "
                               "(the schemes keep one step; take h = (t_end - t_start) / n)",
                               span, steps)});
  }
  return bad;
}

RunSummary run_fixed_step(const LagrangianModel& model, const MechanicalState& initial,
                          double t_end, const FixedStepOptions& opt, OutputSink& sink) {
  auto bad = fixed_step_option_problems(opt);
  for (auto& p : fixed_step_count_problems(opt.h, initial.t, t_end)) bad.push_back(std::move(p));
  if (!bad.empty()) {
    std::string text = "invalid fixed-step options:";
    for (const auto& b : bad) text += fmt::format("\n  {} = {}: {}", b.option, b.value, b.rule);
    throw std::invalid_argument(text);
  }
  // fixed_step_count_problems makes the span a whole number of steps: with h the span over that
  // number, the last step ends at t_end (to round-off)
  FixedStepOptions o = opt;
  const long n_steps = std::max(1L, std::lround((t_end - initial.t) / opt.h));
  o.h = (t_end - initial.t) / static_cast<double>(n_steps);
  const std::unique_ptr<Stepper> stepper = make_stepper(model, o);
  // the first step end at or after each grid time, the initial time included: first_output 0
  RunEnvelope env(o, sink, initial.t, t_end,
                  model.mechanical_energy(initial.t, initial.q, initial.v), model.contact_law(0).mu,
                  std::string(stepper->name()), stepper->options_json(), 0);
  RunLoop loop(model, o, env);
  return loop.run(*stepper, initial, t_end);
}

}  // namespace rubdyn
