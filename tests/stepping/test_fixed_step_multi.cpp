// Moreau-Jean (mj, mj-proj) with K contacts (moreau_jean.cpp, step_multi): the joint impulse
// problem of the active contacts at every Newton iterate, per-contact output and events.
// Checked on problems whose answer is known without the scheme: two uncoupled models side by
// side (each part must follow its own single-contact run), two identical copies (simultaneous
// impacts, identical columns), a rod dropped flat on both ends (exact impact time, the weight
// shared equally), a rod sliding flat (exact deceleration and stop), and the two-plane rotor
// (energy balance, invariants, events of both planes).
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <memory>

#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"
#include "rubdyn/stepping/fixed_step.hpp"
#include "support/multi_problems.hpp"
#include "support/problems.hpp"
#include "support/split_ring.hpp"

using namespace rubdyn;
using namespace rubdyn::testing;

namespace {

RunSummary run(const LagrangianModel& m, const MechanicalState& s0, double t_end,
               FixedStepScheme scheme, double h, MemorySink& sink, int every = 1) {
  FixedStepOptions o;
  o.scheme = scheme;
  o.h = h;
  o.output_every = every;
  o.omega_lim = 1e9;
  return run_fixed_step(m, s0, t_end, o, sink);
}

const FixedStepScheme kMj[] = {FixedStepScheme::MoreauJean, FixedStepScheme::MoreauJeanProjected};
const FixedStepScheme kAll[] = {FixedStepScheme::MoreauJean, FixedStepScheme::MoreauJeanProjected,
                                FixedStepScheme::CarpOneVC, FixedStepScheme::CarpQN};

}  // namespace

TEST_CASE("Fixed-step schemes with K contacts: two uncoupled models follow their own runs",
          "[stepping][multi]") {
  auto ball = std::make_shared<BouncingBall>(0.5, 0.2);
  auto belt = std::make_shared<BlockOnBelt>();
  const ProductModel p(ball, belt);
  for (const auto scheme : kAll) {
    INFO(to_string(scheme));
    MemorySink joint, a, b;
    const double t_end = 0.5, h = 1e-4;
    REQUIRE(run(p, p.join(ball->initial(), belt->initial()), t_end, scheme, h, joint).complete());
    REQUIRE(run(*ball, ball->initial(), t_end, scheme, h, a).complete());
    REQUIRE(run(*belt, belt->initial(), t_end, scheme, h, b).complete());
    REQUIRE(joint.samples.size() == a.samples.size());
    REQUIRE(joint.samples.size() == b.samples.size());
    double dq = 0.0;
    for (std::size_t i = 0; i < joint.samples.size(); ++i) {
      const Sample& s = joint.samples[i];
      dq = std::max(dq, (s.q.head(2) - a.samples[i].q).cwiseAbs().maxCoeff());
      dq = std::max(dq, (s.q.tail(2) - b.samples[i].q).cwiseAbs().maxCoeff());
      CHECK(s.contacts[0].phase == a.samples[i].contacts[0].phase);
      CHECK(s.contacts[1].phase == b.samples[i].contacts[0].phase);
    }
    // Not bit for bit: the joint Newton iteration stops on the joint change (1e-14 relative
    // plus 1e-15 m/s), and the two-contact impulse problem is solved by elimination where one
    // contact uses the closed form; each step's difference is round-off on O(1) m/s velocities
    // (1e-15 m/s), and 5000 steps of h = 1e-4 s accumulate at most 5e-16 m per step: 1e-11 m
    // bounds it with a margin of 4.
    INFO("largest difference " << dq << " m");
    CHECK(dq < 1e-11);
    // each contact's events are its part's, with the contact's number
    std::size_t ev_a = 0, ev_b = 0;
    for (const auto& e : joint.events) (e.contact == 0 ? ev_a : ev_b) += 1;
    CHECK(ev_a == a.events.size());
    CHECK(ev_b == b.events.size());
  }
}

TEST_CASE("mj with K contacts: two identical copies impact at the same step, identically",
          "[stepping][multi]") {
  auto ball = std::make_shared<BouncingBall>(0.0, 0.2);
  const ProductModel p(ball, ball);
  MemorySink s;
  REQUIRE(
      run(p, p.join(ball->initial(), ball->initial()), 0.4, FixedStepScheme::MoreauJean, 1e-4, s)
          .complete());
  REQUIRE(s.events.size() >= 2);
  CHECK(s.events[0].t == s.events[1].t);
  CHECK(s.events[0].contact != s.events[1].contact);
  for (const Sample& x : s.samples) {
    // the same numbers in both halves: the joint problem is symmetric and solved symmetrically
    CHECK(x.q[1] == x.q[3]);
    CHECK(x.contacts[0].F_N == x.contacts[1].F_N);
  }
}

TEST_CASE("mj with K contacts: a rod dropped flat lands on both ends and shares its weight",
          "[stepping][multi]") {
  const FallingRod rod({0.3, 0.0, 0.0});
  const double h0 = 0.05, h = 1e-5;
  const double t1 = std::sqrt(2.0 * h0 / rod.g());
  for (const auto scheme : kMj) {
    INFO(to_string(scheme));
    MemorySink s;
    REQUIRE(run(rod, rod.initial(h0), 0.2, scheme, h, s, 100).complete());
    REQUIRE(s.events.size() >= 2);
    // both ends impact in the same step, the first whose predicted gap closes: within 2 h of
    // the exact time (the index set is decided half a step ahead)
    CHECK(s.events[0].t == s.events[1].t);
    CHECK(std::abs(s.events[0].t - t1) < 2 * h);
    const Sample& end = s.samples.back();
    // at rest on the ground: each end carries m g / 2. Moreau-Jean's F_N is the step's impulse
    // over h, exact for a constant force; 1e-9 relative covers the Newton tolerance (1e-14)
    // times the condition of the 4x4 Delassus matrix (about 4) with a wide margin
    const double half = 0.5 * rod.mass() * rod.g();
    CHECK(end.contacts[0].F_N == Approx(half).epsilon(1e-9));
    CHECK(end.contacts[1].F_N == Approx(half).epsilon(1e-9));
    CHECK(std::abs(end.v[1]) < 1e-9);
    CHECK(std::abs(end.q[2]) < 1e-12);  // no tilt appears: the problem is symmetric
  }
}

TEST_CASE("mj with K contacts: a rod sliding flat decelerates at mu g and stops",
          "[stepping][multi]") {
  const double mu = 0.3, vx0 = 1.0;
  const FallingRod rod({mu, 0.0, 0.0});
  const double h = 1e-5, t_stop = vx0 / (mu * rod.g());
  MemorySink s;
  REQUIRE(
      run(rod, rod.initial(0.0, 0.0, vx0), 0.5, FixedStepScheme::MoreauJean, h, s, 100).complete());
  for (const Sample& x : s.samples) {
    if (x.t > t_stop - 2 * h) break;
    // constant deceleration: theta = 1/2 integrates it exactly; the Newton tolerance leaves
    // 1e-14 relative per step on v (3e4 steps: 3e-10 m/s), 1e-9 is 3x that
    CHECK(x.v[0] == Approx(vx0 - mu * rod.g() * x.t).margin(1e-9));
    if (x.t == 0.0) continue;  // the initial row: written before the first step decides
    CHECK(x.contacts[0].phase == Phase::SlipPos);  // v_t = x' > 0
    CHECK(x.contacts[1].phase == Phase::SlipPos);
  }
  const Sample& end = s.samples.back();
  CHECK(end.v[0] == 0.0);
  // stopped where x'' = -mu g puts it, within one step's travel (vx h at most)
  CHECK(end.q[0] == Approx(vx0 * vx0 / (2 * mu * rod.g())).margin(vx0 * h));
  CHECK(end.contacts[0].phase == Phase::Stick);
}

TEST_CASE("Fixed-step schemes with K contacts: the two-plane rotor closes its energy balance",
          "[stepping][multi]") {
  const CaseSpec c = load_case(RUBDYN_SOURCE_DIR "/cases/two-plane.toml");
  const auto m = build_model(c);
  for (const auto scheme : kAll) {
    INFO(to_string(scheme));
    MemorySink s;
    const RunSummary r = run(*m, initial_state(c), 0.03, scheme, 1e-6, s, 100);
    REQUIRE(r.complete());
    int first[2] = {0, 0};
    for (const auto& e : s.events)
      if (e.kind == EventKind::Impact) ++first[e.contact];
    CHECK(first[0] > 0);  // both planes are hit
    CHECK(first[1] > 0);
    // the scheme's own balance: dE = works, to its quadrature (trapezoidal loads over 3e4
    // steps). Moreau-Jean's impulses work at the mid-step velocity: measured 2e-7 J of 1.2e3 J,
    // bounded by 1e-8 relative (a margin of 50). Carpenter's correction force works at the
    // central velocity of its step, first order: measured 2e-4 J over 50 ms (1.4e-7 of the
    // drive's work), bounded by 1e-6 relative
    const bool carpenter =
        scheme == FixedStepScheme::CarpOneVC || scheme == FixedStepScheme::CarpQN;
    CHECK(std::abs(r.energy_residual) < (carpenter ? 1e-6 : 1e-8) * std::abs(r.work_torque) + 1e-9);
    // mj-proj removes the penetration; mj keeps O(h v_N) of it; Carpenter corrects positions
    // (what is left is the correction's linearisation error, 2e-12 m measured: 1e-10 bounds it)
    if (scheme == FixedStepScheme::MoreauJeanProjected) CHECK(r.max_penetration < 1e-12);
    if (carpenter) CHECK(r.max_penetration < 1e-10);
  }
}

TEST_CASE("mj with K contacts: two identical rings at one plane are the one ring (redundant)",
          "[stepping][multi]") {
  // tests/support/split_ring.hpp: the run must be the one-ring run; the set solver's tie rule
  // picks one split of the force
  const CaseSpec two = parse_case(split_ring_case_text(), "split.toml", {"solver.kind=mj"});
  const CaseSpec one = load_case(RUBDYN_SOURCE_DIR "/cases/reference.toml");
  const auto m2 = build_model(two), m1 = build_model(one);
  for (const auto scheme : kMj) {
    INFO(to_string(scheme));
    MemorySink a, b;
    REQUIRE(run(*m2, initial_state(two), 0.03, scheme, 1e-6, a, 100).complete());
    REQUIRE(run(*m1, initial_state(one), 0.03, scheme, 1e-6, b, 100).complete());
    REQUIRE(a.samples.size() == b.samples.size());
    double dq = 0.0, dF = 0.0, Fmax = 0.0;
    for (std::size_t i = 0; i < a.samples.size(); ++i) {
      const Sample& x = a.samples[i];
      const Sample& y = b.samples[i];
      for (int k : {XB, YB, XR, YR}) dq = std::max(dq, std::abs(x.q[k] - y.q[k]));
      // the rings move as one
      CHECK(std::abs(x.q[5] - x.q[7]) < 1e-17);
      dF = std::max(dF, std::abs(x.contacts[0].F_N + x.contacts[1].F_N - y.contacts[0].F_N));
      Fmax = std::max(Fmax, y.contacts[0].F_N);
    }
    // measured 3e-18 m on O(2e-4) m orbits: the joint problem's velocities are those of the
    // one-contact problem to round-off (its redundant rows give a determinate motion); 1e-15 m
    // is 1e-11 of the orbit
    CHECK(dq < 1e-15);
    // the two forces add up to the one ring's: measured 1.3e-11 N of 1e4 N (the elimination of
    // a singular 4x4 system keeps about 1e-15 relative); 1e-9 relative bounds it
    CHECK(dF < 1e-9 * Fmax);
  }
}
