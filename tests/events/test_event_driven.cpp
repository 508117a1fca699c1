// The event-driven integrator on problems with exact solutions, and its invariants on the rotor.

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <map>

#include "rubdyn/driver/simulate.hpp"
#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"
#include "support/jeffcott_cases.hpp"
#include "support/problems.hpp"

using namespace rubdyn;
using rubdyn::testing::BlockOnBelt;
using rubdyn::testing::BouncingBall;
using rubdyn::testing::SpringMass;

namespace {
std::vector<const EventRecord*> events_of(const MemorySink& s, EventKind k) {
  std::vector<const EventRecord*> out;
  for (const auto& e : s.events)
    if (e.kind == k) out.push_back(&e);
  return out;
}
}  // namespace

namespace {
/// Contact phases in minimal coordinates (the default) and as the DAE with projection: the
/// exact-solution tests hold for both.
ContactFormulation formulation() {
  const auto f = GENERATE(ContactFormulation::Reduced, ContactFormulation::Projection);
  UNSCOPED_INFO(
      "contact phases: " << (f == ContactFormulation::Reduced ? "reduced" : "projection"));
  return f;
}
}  // namespace

TEST_CASE("Spring-mass without contact: no event - error proportional to rtol", "[events]") {
  const SpringMass model;
  double errs[2];
  const double rtols[2] = {1e-8, 1e-12};
  for (int i = 0; i < 2; ++i) {
    MemorySink sink;
    EventDrivenOptions opt;
    opt.output_dt = 0.01;
    opt.rtol = rtols[i];
    opt.atol = 1e-3 * rtols[i];
    const RunSummary s = run_event_driven(model, model.initial(), 2.0, opt, sink);
    REQUIRE(s.complete());
    REQUIRE(sink.events.empty());
    double err = 0.0;
    for (const auto& x : sink.samples) err = std::max(err, std::abs(x.q[0] - model.exact_x(x.t)));
    errs[i] = err;
    // Local error control does not bound the global error; over two periods (~1e3 steps) BDF
    // accumulates up to a few hundred times rtol on a unit amplitude. 1e3 rtol bounds that.
    REQUIRE(err < 1e3 * rtols[i]);
    // energy E = 1/2 (w x)^2 + 1/2 v^2 is quadratic in the state: its relative error is about
    // twice the relative state error, bounded above by 1e3 rtol
    REQUIRE(std::abs(s.energy_residual) < 2e3 * rtols[i] * s.energy_initial);
  }
  // Tolerance proportionality: 1e4 x tighter rtol gives at least 100 x smaller error (BDF's
  // global error is not proportional to rtol step for step: measured 3.6e-7 and 5.2e-10, and
  // non-monotone in between, because CVODE changes order; 100 is the robust part of 700).
  REQUIRE(errs[1] < errs[0] / 100.0);
}

TEST_CASE("Bouncing ball: impact times and the accumulation time match the closed form",
          "[events]") {
  const BouncingBall model(0.5);
  MemorySink sink;
  EventDrivenOptions opt;
  opt.contact_phases = formulation();
  opt.output_dt = 0.05;
  const double t_inf = model.accumulation_time();
  const RunSummary s = run_event_driven(model, model.initial(), t_inf + 0.5, opt, sink);
  INFO(s.message);
  REQUIRE(s.complete());
  const auto impacts = events_of(sink, EventKind::Impact);
  REQUIRE(impacts.size() >= 10);
  for (size_t k = 0; k < 10; ++k) {
    // Flights are parabolas that BDF of order >= 2 integrates exactly up to round-off; the event
    // time is the root of the interpolant polished by Newton: 1e-9 s is the bound.
    INFO("impact " << k + 1);
    REQUIRE(impacts[k]->t == Approx(model.impact_time(static_cast<int>(k) + 1)).margin(1e-9));
    REQUIRE(impacts[k]->v_N_plus == Approx(-0.5 * impacts[k]->v_N_minus).epsilon(1e-9));
  }
  const auto zeno = events_of(sink, EventKind::Zeno);
  REQUIRE(zeno.size() == 1);
  // The extrapolated accumulation time is exact for a constant normal acceleration, up to the
  // error of the impact time and speed it starts from (~1e-9 s, as above).
  REQUIRE(zeno[0]->t_accumulation == Approx(t_inf).margin(1e-9));
  // The truncation happens when the next bounce would rise less than the grazing tolerance
  // h_tol = 10 (atol + rtol g0) ~ 1e-9 m (g0 = h0 = 1 m here): the remaining sequence lasts at
  // most 2 sqrt(2 h_tol / g) / (1 - e) ~ 5.7e-5 s.
  REQUIRE(zeno[0]->t < t_inf);
  REQUIRE(t_inf - zeno[0]->t < 2.0 * std::sqrt(2.0 * 10.0 * (1e-12 + 1e-10) / model.g()) / 0.5);
  // After the accumulation the ball rests: F_N = m g (unit mass).
  const Sample& last = sink.samples.back();
  REQUIRE(last.contacts[0].phase != Phase::Free);
  REQUIRE(last.contacts[0].F_N == Approx(model.g()).epsilon(1e-9));
  REQUIRE(last.q[1] == Approx(0.0).margin(1e-12));
}

TEST_CASE("Block on a belt: stick and slip switch times match the analytic solution", "[events]") {
  const BlockOnBelt model(0.5, 100.0, 1.0, 0.2);  // x_e w = 0.49 > v_b = 0.2: sticks
  REQUIRE(model.x_e() * model.w() > model.belt_speed());
  MemorySink sink;
  EventDrivenOptions opt;
  opt.contact_phases = formulation();
  opt.output_dt = 1e-3;
  const double t2 = model.slip_time();
  const double t_end = t2 + 0.5 * 2.0 * M_PI / model.w();  // stop before the degenerate touch
  // The block starts on the belt (d_N = 0) with F_N = m g and v_t = -v_b: slip-.
  const RunSummary s = run_event_driven(model, model.initial(), t_end, opt, sink);
  INFO(s.message);
  REQUIRE(s.complete());
  const auto sticks = events_of(sink, EventKind::Stick);
  const auto slips = events_of(sink, EventKind::Slip);
  REQUIRE(sticks.size() == 1);
  REQUIRE(slips.size() == 1);
  REQUIRE(sticks[0]->t == Approx(model.stick_time()).margin(1e-9));
  REQUIRE(slips[0]->t == Approx(model.slip_time()).margin(1e-9));
  REQUIRE(sticks[0]->phase_after == Phase::Stick);
  REQUIRE(slips[0]->phase_after == Phase::SlipNeg);
  double err = 0.0;
  for (const auto& x : sink.samples)
    err = std::max(err, std::abs(x.q[0] + model.belt_speed() * x.t - model.exact_lab_x(x.t)));
  // positions ~ 0.05 m, rtol 1e-10 / atol 1e-12 over a few hundred steps
  REQUIRE(err < 1e-8);
  // friction inside the cone and normal force m g throughout
  for (const auto& x : sink.samples) {
    REQUIRE(x.contacts[0].F_N == Approx(model.normal_force()).epsilon(1e-9));
    REQUIRE(std::abs(x.contacts[0].F_T) <= 0.5 * x.contacts[0].F_N * (1 + 1e-9));
  }
}

TEST_CASE("Rotor resting on the stator - mu = 0 - no spin: static contact force", "[events]") {
  RotorStatorParams p;
  p.contact.mu = 0.0;
  p.loads.torque = 0.0;
  const RotorStatorModel model(p);
  // Closed-form static state (rotor at the bottom of the clearance): y_b = -(1-nu) m g / k_b,
  // F_N = nu m g, y_s = -nu m g / k_s, y_r = y_s - g0.
  const double mg = p.rotor.mass * p.loads.gravity, nu = model.nu();
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.q[YB] = -(1 - nu) * mg / p.bearing.k;
  s0.q[YS] = -nu * mg / p.stator.k;
  s0.q[YR] = s0.q[YS] - p.stator.gap;
  MemorySink sink;
  EventDrivenOptions opt;
  opt.contact_phases = formulation();
  opt.output_dt = 1e-3;
  const RunSummary s = run_event_driven(model, s0, 0.02, opt, sink);
  INFO(s.message);
  REQUIRE(s.complete());
  for (const auto& x : sink.samples) {
    REQUIRE(x.contacts[0].phase != Phase::Free);
    // equilibrium: F_N = nu m g to round-off of forces ~ 1e4 N (stiffness x deflection)
    REQUIRE(x.contacts[0].F_N == Approx(nu * mg).epsilon(1e-9));
  }
}

TEST_CASE("Reference case over its whole 0.5 s: invariants hold", "[events][rotor]") {
  const RotorStatorModel model(RotorStatorParams{});
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.v[TH] = 2000.0;
  MemorySink sink;
  EventDrivenOptions opt;
  opt.output_dt = 1e-4;
  opt.omega_lim = 2110.0;
  const RunSummary s = run_event_driven(model, s0, 0.5, opt, sink);
  INFO(s.message);
  REQUIRE(s.complete());
  REQUIRE(s.events[static_cast<int>(EventKind::Impact)] >= 1);
  // spec: omega passes omega_lim at about 0.33 s (free acceleration alone: exactly 0.33 s)
  REQUIRE(s.t_omega_lim == Approx(0.33).margin(0.01));
  const double g0 = model.params().stator.gap;
  REQUIRE(s.max_penetration <= 1e-9 * g0);
  // F_N >= 0 in contact: a lift-off is logged at the last time F_N still has its sign.
  REQUIRE(s.min_F_N_in_contact >= 0.0);
  REQUIRE(s.max_cone_violation <= 1e-9);
  REQUIRE(s.max_drift_position <= 1e-12 * g0);
  // energy balance to 1e-8 of the torque's work
  INFO("residual " << s.energy_residual << " torque work " << s.work_torque);
  REQUIRE(std::abs(s.energy_residual) <= 1e-8 * std::abs(s.work_torque));
  // first contact about 6 ms after release (spec): the rotor pivots under gravity
  const auto first = sink.events.front();
  REQUIRE(first.t > 0.004);
  REQUIRE(first.t < 0.008);
  // No double event right after a reset: consecutive events are separated by more than the
  // root-finding resolution (a witness zero at the start of a phase does not fire again).
  for (size_t k = 1; k < sink.events.size(); ++k) {
    INFO("events " << k - 1 << " and " << k);
    REQUIRE(sink.events[k].t - sink.events[k - 1].t > 1e-9);
  }
  REQUIRE(s.suppressed_witnesses == 0);
}

namespace {
// y'' = -w^2 (y - 1): from y = 1 with y' = -w the orbit y = 1 - sin(w t) touches the plane y = 0
// tangentially at t = pi / (2 w) (a grazing contact) and leaves again.
class GrazingOscillator final : public rubdyn::testing::PlaneModel {
 public:
  GrazingOscillator() : PlaneModel({}, 1.0) {}
  std::string_view name() const override { return "grazing-oscillator"; }
  void smooth_forces(double, VecIn q, VecIn, VecOut f) const override {
    f.setZero();
    f[1] = -w * w * (q[1] - 1.0);
  }
  void smooth_force_jacobians(double, VecIn, VecIn, MatOut dfdq, MatOut dfdv) const override {
    dfdq.setZero();
    dfdv.setZero();
    dfdq(1, 1) = -w * w;
  }
  double potential_energy(double, VecIn q) const override {
    return 0.5 * w * w * (q[1] - 1.0) * (q[1] - 1.0);
  }
  SmoothPower smooth_power(double, VecIn, VecIn) const override { return {}; }
  double w = 10.0;
};
}  // namespace

TEST_CASE("Grazing: a tangential touch is detected - logged - and does not change the motion",
          "[events]") {
  const GrazingOscillator model;
  MechanicalState s0(2);
  s0.q[1] = 1.0;
  s0.v[1] = -model.w;
  MemorySink sink;
  EventDrivenOptions opt;
  opt.output_dt = 1e-3;
  const RunSummary s = run_event_driven(model, s0, 0.5, opt, sink);
  INFO(s.message);
  REQUIRE(s.complete());
  REQUIRE(sink.events.size() == 1);
  REQUIRE(sink.events[0].kind == EventKind::Grazing);
  REQUIRE(sink.events[0].phase_after == Phase::Free);
  // the gap minimum is located by the v_N witness on the interpolant: its time to ~1e-9 s
  REQUIRE(sink.events[0].t == Approx(M_PI / (2 * model.w)).margin(1e-8));
  double err = 0;
  for (const auto& x : sink.samples)
    err = std::max(err, std::abs(x.q[1] - (1 - std::sin(model.w * x.t))));
  REQUIRE(err < 1e-7);  // rtol 1e-10 over ~1 period on a unit amplitude (cf. the spring-mass test)
}

TEST_CASE("Event times converge as rtol decreases (block on a belt)", "[events]") {
  const BlockOnBelt model(0.5, 100.0, 1.0, 0.2);
  const double t_end = model.slip_time() + 0.1;
  double prev = 1.0;
  // Measured (stick, slip time errors): rtol 1e-5 ... 1e-9: ~1e-9 s, flat, because on this
  // smooth problem the steps (~90) are set by the solution, not by the tolerance; 1e-10: 7.7e-10,
  // 1e-11: 6.7e-11, 1e-12: 4.8e-12. The test takes 1e-8, 1e-10, 1e-12.
  for (double rtol : {1e-8, 1e-10, 1e-12}) {
    MemorySink sink;
    EventDrivenOptions opt;
    opt.contact_phases = formulation();
    opt.rtol = rtol;
    opt.atol = 1e-2 * rtol;
    opt.output_dt = 1e-2;
    const RunSummary s = run_event_driven(model, model.initial(), t_end, opt, sink);
    REQUIRE(s.complete());
    const auto st = events_of(sink, EventKind::Stick), sl = events_of(sink, EventKind::Slip);
    REQUIRE(st.size() == 1);
    REQUIRE(sl.size() == 1);
    const double err =
        std::max(std::abs(st[0]->t - model.stick_time()), std::abs(sl[0]->t - model.slip_time()));
    INFO("rtol " << rtol << ": event time error " << err);
    // each 100x tighter tolerance must reduce the error
    REQUIRE(err < prev);
    REQUIRE(err < 1e3 * rtol);  // the event time error is of the order of the state error
    prev = err;
  }
}

TEST_CASE("mu = 2: the slip-to-stick switch with a huge normal force ends in stick, not a loop",
          "[events][rotor]") {
  // Near the Painleve limit the normal force in slip reaches ~5e7 N and v_t falls so fast that
  // the located zero of v_t leaves |v_t| ~ 3e-8 m/s, above the velocity tolerance: the switch
  // must still be decided at v_t = 0 (it was a loop of 'stick' events staying in slip).
  RotorStatorParams p;
  p.contact.mu = 2.0;
  const RotorStatorModel model(p);
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.v[TH] = 2000.0;
  MemorySink sink;
  EventDrivenOptions opt;
  const RunSummary s = run_event_driven(model, s0, 0.0067, opt, sink);
  INFO(s.message);
  REQUIRE(s.complete());
  REQUIRE(sink.events.size() == 2);
  CHECK(sink.events[0].kind == EventKind::Impact);
  CHECK(sink.events[1].kind == EventKind::Stick);
  CHECK(sink.events[1].phase_after == Phase::Stick);
  // v_t = t.(v_r - v_s) - R_r omega is a difference of terms of R_r omega = 100 m/s: after the
  // projection onto v_t = 0 it is zero to the round-off of that size (a few ulps of 100, 1.4e-14
  // each), not necessarily exactly 0
  const double roundoff = 4.0 * std::numeric_limits<double>::epsilon() * p.rotor.radius * 2000.0;
  INFO(sink.events[1].v_t_plus);
  CHECK(std::abs(sink.events[1].v_t_plus) <= roundoff);
}

TEST_CASE("Loose tolerances: output times passed by a single step around a root are written",
          "[events][rotor]") {
  // Found by validation/work-precision: after a release, the free phase steps one at a time to
  // arm the gap-rate witness. (1) Adams, rtol 1e-6: a root return left the integrator past the
  // next output time and one more step put that time outside CVODE's interpolation interval
  // (CV_BAD_T at t = 0.2289). (2) BDF, rtol 1e-5: the step that found a root passed an output
  // time before the root; the restart at the event left it behind, and CVODE, asked for an
  // output time behind t0, turned the integration direction (CV_ILL_INPUT at t = 0.1967).
  const bool adams = GENERATE(true, false);
  const RotorStatorModel model(RotorStatorParams{});
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.v[TH] = 2000.0;
  MemorySink sink;
  EventDrivenOptions opt;
  opt.rtol = adams ? 1e-6 : 1e-5;
  opt.atol = opt.rtol * 1e-2;
  opt.method = adams ? MultistepMethod::Adams : MultistepMethod::BDF;
  INFO("adams " << adams);
  const RunSummary s = run_event_driven(model, s0, 0.5, opt, sink);
  INFO(s.message);
  REQUIRE(s.complete());
  // every output time of the 0.1 ms grid is written once, in order
  long on_grid = 0;
  double last = -1.0;
  for (const auto& x : sink.samples) {
    REQUIRE(x.t >= last);
    last = x.t;
    const double k = std::round(x.t / opt.output_dt);
    if (std::abs(x.t - k * opt.output_dt) < 1e-12) ++on_grid;
  }
  REQUIRE(on_grid >= 5001);
}

namespace {
/// Largest differences of two runs on the common output grid (event rows skipped): orbit of the
/// rotor centre relative to the stator [m] and spin speed [rad/s].
struct GridDiff {
  double orbit = 0.0, omega = 0.0;
  int n = 0;
};
GridDiff grid_difference(const MemorySink& a, const MemorySink& b, double dt) {
  auto on_grid = [dt](const MemorySink& s) {
    std::map<long, const Sample*> g;
    for (const auto& x : s.samples) {
      const long k = std::lround(x.t / dt);
      if (std::abs(x.t - k * dt) < 1e-12 && !g.count(k)) g[k] = &x;
    }
    return g;
  };
  const auto ga = on_grid(a), gb = on_grid(b);
  GridDiff d;
  for (const auto& [k, sa] : ga) {
    const auto it = gb.find(k);
    if (it == gb.end()) continue;
    const Sample& sb = *it->second;
    const double dx = (sa->q[XR] - sa->q[XS]) - (sb.q[XR] - sb.q[XS]);
    const double dy = (sa->q[YR] - sa->q[YS]) - (sb.q[YR] - sb.q[YS]);
    d.orbit = std::max(d.orbit, std::hypot(dx, dy));
    d.omega = std::max(d.omega, std::abs(sa->v[TH] - sb.v[TH]));
    ++d.n;
  }
  return d;
}

/// The same run with contact phases in minimal coordinates and as the DAE with projection.
struct BothFormulations {
  MemorySink red, proj;
  RunSummary sr, sp;
  BothFormulations(const LagrangianModel& model, const MechanicalState& s0, double t_end,
                   EventDrivenOptions opt) {
    opt.contact_phases = ContactFormulation::Reduced;
    sr = run_event_driven(model, s0, t_end, opt, red);
    opt.contact_phases = ContactFormulation::Projection;
    sp = run_event_driven(model, s0, t_end, opt, proj);
  }
};
}  // namespace

TEST_CASE("Reduced and projection contact phases agree: impacts, sliding and lift-offs",
          "[events][rotor]") {
  const RotorStatorModel model(RotorStatorParams{});
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.v[TH] = 2000.0;
  const EventDrivenOptions opt;
  const BothFormulations b(model, s0, 0.03, opt);
  REQUIRE(b.sr.complete());
  REQUIRE(b.sp.complete());
  REQUIRE(b.sr.events == b.sp.events);
  const GridDiff d = grid_difference(b.red, b.proj, opt.output_dt);
  REQUIRE(d.n == 301);
  INFO("orbit " << d.orbit << " m, omega " << d.omega << " rad/s");
  CHECK(d.orbit <= 1e-10);
  CHECK(d.omega <= 1e-6);
}

TEST_CASE("Reduced and projection contact phases agree while rolling (stick)", "[events][rotor]") {
  // mu = 2: sticks at the first contact (6.7 ms) after a short slide with F_N ~ 5e7 N, then rolls
  // (dry whirl at 250 x the spin, ~75 kHz). At rtol 1e-12 the reduced run differs from itself at
  // rtol 1e-13 by 7e-11 m (orbit) and 2e-9 rad/s (omega) at 10 ms; the projection formulation by
  // 2e-11 m and 1.7e-6 rad/s: its velocity projections onto v_t = 0 let omega drift (the reason
  // for minimal coordinates). The bounds are 10x the larger of each.
  RotorStatorParams p;
  p.contact.mu = 2.0;
  const RotorStatorModel model(p);
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.v[TH] = 2000.0;
  EventDrivenOptions opt;
  opt.rtol = 1e-12;
  opt.atol = 1e-14;
  const BothFormulations b(model, s0, 0.01, opt);
  const RunSummary &sr = b.sr, &sp = b.sp;
  REQUIRE(sr.complete());
  REQUIRE(sp.complete());
  REQUIRE(sr.events == sp.events);
  REQUIRE(sr.phase_time[static_cast<int>(Phase::Stick)] > 0.003);
  const GridDiff d = grid_difference(b.red, b.proj, opt.output_dt);
  INFO("orbit " << d.orbit << " m, omega " << d.omega << " rad/s");
  CHECK(d.orbit <= 1e-9);
  CHECK(d.omega <= 2e-5);
  // Energy: in minimal coordinates nothing is projected away; the residual is the integration
  // error of the works, below 1e-9 of the largest energy flow (friction, in the slide).
  const double flow = std::max({std::abs(sr.work_torque), std::abs(sr.work_damping),
                                std::abs(sr.work_friction), std::abs(sr.work_impacts)});
  INFO("energy residual: reduced " << sr.energy_residual << " J, projection " << sp.energy_residual
                                   << " J, largest flow " << flow << " J");
  CHECK(std::abs(sr.energy_residual) <= 1e-9 * flow);
}

TEST_CASE("The steps taken depend neither on the output grid nor on the end time",
          "[events][rotor]") {
  // Output is interpolated (CV_NORMAL), events are localised to a unique double independent of
  // where the root finder stopped, and the first step after a restart is estimated from a
  // fixed horizon: so the output interval cannot change the solution, and a shorter run is a
  // bitwise prefix of a longer one (up to the phase running at its end). Checked on 60 ms of
  // the reference case (3 impacts, 3 lift-offs).
  const RotorStatorModel model(RotorStatorParams{});
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.v[TH] = 2000.0;
  auto run = [&](double dt, double t_end) {
    MemorySink sink;
    EventDrivenOptions opt;
    opt.contact_phases = formulation();
    opt.output_dt = dt;
    const RunSummary s = run_event_driven(model, s0, t_end, opt, sink);
    REQUIRE(s.complete());
    return std::make_pair(s, sink.events);
  };
  const auto [a, ev_a] = run(1e-4, 0.06);
  const auto [b, ev_b] = run(3.7e-4, 0.06);
  const auto [c, ev_c] = run(1e-4, 0.045);
  REQUIRE(ev_a.size() >= 6);
  CHECK(a.steps == b.steps);
  REQUIRE(ev_a.size() == ev_b.size());
  for (size_t i = 0; i < ev_a.size(); ++i) {
    CHECK(ev_a[i].t == ev_b[i].t);  // bitwise
    CHECK(ev_a[i].v_N_minus == ev_b[i].v_N_minus);
  }
  // the shorter run: every event of the longer run before its last phase, bitwise
  REQUIRE(ev_c.size() >= 2);
  for (size_t i = 0; i + 1 < ev_c.size(); ++i) {
    CHECK(ev_c[i].t == ev_a[i].t);
    CHECK(ev_c[i].v_N_minus == ev_a[i].v_N_minus);
  }
}

TEST_CASE("The solver asks the model for its spin coordinate and its number of contacts",
          "[events]") {
  MechanicalState s0(2);
  s0.q[1] = 1.0;
  s0.v[0] = 5000.0;  // a fast rate, but on no spin coordinate: no omega
  EventDrivenOptions opt;
  opt.omega_lim = 1.0;  // would be crossed at once if a coordinate's rate were taken as the spin
  MemorySink sink;
  const RunSummary s = run_event_driven(rubdyn::testing::FreeFall(1), s0, 0.1, opt, sink);
  REQUIRE(s.complete());
  CHECK(s.omega_max == 0.0);
  CHECK(std::isnan(s.t_omega_lim));
  // a model without a contact, or with more than the K-contact integrator takes (8), is
  // refused, not silently reduced
  CHECK_THROWS_AS(run_event_driven(rubdyn::testing::FreeFall(0), s0, 0.1, opt, sink),
                  std::invalid_argument);
  CHECK_THROWS_AS(run_event_driven(rubdyn::testing::FreeFall(9), s0, 0.1, opt, sink),
                  std::invalid_argument);
}

TEST_CASE("Coulomb-damped oscillator: slip reversals and the final stick, with their kinds",
          "[events]") {
  // BlockOnBelt with the belt at rest: a mass on a spring sliding on a fixed floor. From
  // X0 = 4.5 x_e at rest, each half period pi / w the amplitude about +-x_e drops by 2 x_e: the
  // block stops at -2.5 x_e (spring force 2.5 mu m g > mu m g: the slip reverses), at +0.5 x_e
  // (0.5 mu m g: it sticks). Exact: v = 0 at t = pi / w and 2 pi / w.
  const BlockOnBelt model(0.5, 100.0, 1.0, 0.0);
  MechanicalState s0 = model.initial();
  s0.q[0] = 4.5 * model.x_e();
  MemorySink sink;
  EventDrivenOptions opt;
  opt.contact_phases = formulation();
  opt.output_dt = 1e-3;
  const double T = M_PI / model.w();
  const RunSummary s = run_event_driven(model, s0, 2.5 * T, opt, sink);
  INFO(s.message);
  REQUIRE(s.complete());
  const auto reversals = events_of(sink, EventKind::Reversal);
  const auto sticks = events_of(sink, EventKind::Stick);
  REQUIRE(reversals.size() == 1);
  REQUIRE(sticks.size() == 1);
  // the zero of v_t located on the interpolant: 1e-9 s as for the belt's switch times
  CHECK(reversals[0]->t == Approx(T).margin(1e-9));
  CHECK(reversals[0]->phase_before == Phase::SlipNeg);
  CHECK(reversals[0]->phase_after == Phase::SlipPos);
  CHECK(sticks[0]->t == Approx(2.0 * T).margin(1e-9));
  CHECK(sticks[0]->phase_before == Phase::SlipPos);
  CHECK(sticks[0]->phase_after == Phase::Stick);
  // where it sticks: rtol 1e-10 over about 1000 steps, measured 9e-11 m (4e-9 relative) in
  // minimal coordinates; the projected DAE (the cross-check formulation) loses 30x more in slip,
  // measured 2.9e-9 m (1.2e-7 relative)
  const bool reduced = opt.contact_phases == ContactFormulation::Reduced;
  CHECK(sink.samples.back().q[0] == Approx(0.5 * model.x_e()).epsilon(reduced ? 1e-8 : 3e-7));
}

TEST_CASE("Event-driven options are checked at the library boundary, every broken rule listed",
          "[events]") {
  const SpringMass m;
  EventDrivenOptions opt;
  opt.rtol = 0.0;
  opt.atol = -1.0;
  opt.output_dt = std::numeric_limits<double>::infinity();
  CHECK(event_driven_option_problems(opt).size() == 3);
  MemorySink sink;
  try {
    run_event_driven(m, m.initial(), 1.0, opt, sink);
    FAIL("no exception");
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    CHECK(what.find("rtol = 0: must be finite and > 0") != std::string::npos);
    CHECK(what.find("atol = -1:") != std::string::npos);
    CHECK(what.find("output_dt = inf:") != std::string::npos);
  }
  CHECK(sink.samples.empty());  // nothing reached the sink
  CHECK(event_driven_option_problems(EventDrivenOptions{}).empty());
}

TEST_CASE("A long roll: the chart angle grows without bound and the run still completes",
          "[events][jeffcott]") {
  // Jeffcott rotor on a rigid ring, rolling at the steady spin Omega = tau / (c_r R^2) (the
  // power balance of rolling, docs/closed-forms.md): started on that orbit, it stays there. The
  // stick chart integrates theta - theta_a with an absolute weight (rtol g0 + atol) / R = 4e-15
  // rad here; before the round-off floor of the error weights (decision_tolerances.hpp) CVODE
  // stopped with CV_TOO_MUCH_ACC once eps |theta - theta_a| outgrew it: at 0.093 s (248 rad).
  // One second is 2667 rad.
  using rubdyn::testing::SteadyRoll;
  const double Om = SteadyRoll::omega;
  const std::string text = SteadyRoll::text("[solver]\nrtol = 1e-12\natol = 1e-15\n");
  const CaseSpec spec = parse_case(text, "long-roll");
  MemorySink sink;
  const RunSummary s = simulate(spec, sink);
  INFO(s.message);
  REQUIRE(s.complete());
  CHECK(s.t_reached == 1.0);
  for (const auto& smp : sink.samples) CHECK(smp.contacts[0].phase == Phase::Stick);
  const Sample& last = sink.samples.back();
  CHECK(last.q[2] - sink.samples.front().q[2] > 2600.0);  // theta turned: 2667 rad
  // on the orbit the spin stays at the closed form: the steady integration error at rtol 1e-12
  // is a few 1e-12 (validation/analytic, (b): 6e-14 measured); 1e-10 is far above that and far
  // below any departure from the orbit (a slip, a wrong power balance: 1e-3 and more)
  CHECK(std::abs(last.v[2] / Om - 1.0) <= 1e-10);
}
