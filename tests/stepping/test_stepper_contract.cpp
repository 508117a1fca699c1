// The contract every fixed-step stepper must pass (stepping/stepper.hpp), run for each scheme:
// order 2 without contact, Signorini after a landing, convergence through stick-slip, bad h
// rejected, and a typed outcome (never Ok) when the model turns non-finite.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "rubdyn/stepping/stepper.hpp"
#include "support/problems.hpp"

using namespace rubdyn;
using rubdyn::testing::BlockOnBelt;
using rubdyn::testing::BouncingBall;
using rubdyn::testing::SpringMass;

namespace {

FixedStepScheme any_scheme() {
  return GENERATE(FixedStepScheme::CarpOneVC, FixedStepScheme::CarpQN, FixedStepScheme::MoreauJean,
                  FixedStepScheme::MoreauJeanProjected);
}

RunSummary run(const LagrangianModel& m, const MechanicalState& s0, double t_end,
               FixedStepScheme scheme, double h, MemorySink& sink) {
  FixedStepOptions o;
  o.scheme = scheme;
  o.h = h;
  o.output_every = 1;
  return run_fixed_step(m, s0, t_end, o, sink);
}

const Sample& at(const MemorySink& s, double t) {
  const Sample* best = &s.samples.front();
  for (const auto& x : s.samples)
    if (std::abs(x.t - t) < std::abs(best->t - t)) best = &x;
  return *best;
}

}  // namespace

TEST_CASE("Stepper contract: order 2 without contact", "[stepping][contract]") {
  const FixedStepScheme scheme = any_scheme();
  const SpringMass m;  // w = 2 pi, exact x = cos(w t); T = 0.3 avoids a half-period cancellation
  const double T = 0.3;
  double err[4];
  double h = 1e-2;
  for (int k = 0; k < 4; ++k, h /= 2) {
    MemorySink s;
    REQUIRE(run(m, m.initial(), T, scheme, h, s).complete());
    const Sample& x = at(s, T);
    REQUIRE(x.t == Approx(T).margin(1e-12));
    err[k] = std::abs(x.q[0] - m.exact_x(T)) + std::abs(x.v[0] - m.exact_v(T)) / m.omega();
  }
  for (int k = 0; k < 3; ++k) {
    INFO(to_string(scheme) << " errors " << err[k] << " -> " << err[k + 1]);
    // second order: each halving divides the error by 4 (rate 2 +- 0.2)
    CHECK(std::abs(std::log2(err[k] / err[k + 1]) - 2.0) < 0.2);
  }
}

TEST_CASE("Stepper contract: Signorini after a landing, F_N >= 0", "[stepping][contract]") {
  const FixedStepScheme scheme = any_scheme();
  const BouncingBall ball(0.0);  // plastic: rests on the ground after the first impact
  const double h = 1e-3;
  MemorySink s;
  REQUIRE(run(ball, ball.initial(), 0.6, scheme, h, s).complete());
  const double v_land = ball.g() * ball.first_impact_time();
  for (const auto& x : s.samples) {
    INFO(to_string(scheme) << " t " << x.t << " y " << x.q[1] << " F_N " << x.contacts[0].F_N);
    CHECK(x.contacts[0].F_N >= 0.0);
    // velocity-level Signorini (plain mj) may end a step below the ground by O(h |v|): at most
    // 1.5 h v_land (the free step plus theta = 1/2 of the impulse step); the position-level
    // schemes stay on it to round-off
    CHECK(x.q[1] >= -1.5 * h * v_land);
  }
  CHECK(s.summary.events[static_cast<int>(EventKind::Impact)] >= 1);
}

TEST_CASE("Stepper contract: convergence through stick-slip", "[stepping][contract]") {
  const FixedStepScheme scheme = any_scheme();
  const BlockOnBelt m(0.5, 100.0, 1.0, 0.2);
  // before the degenerate touch at t2 + 2 pi / w; a whole number of the steps below (1 ms and
  // its halvings), as run_fixed_step requires
  const double T = std::ceil((m.slip_time() + 0.2) / 1e-3) * 1e-3;
  double err[3];
  double h = 1e-3;
  for (int k = 0; k < 3; ++k, h /= 2) {
    MemorySink s;
    REQUIRE(run(m, m.initial(), T, scheme, h, s).complete());
    double e = 0;
    for (const auto& x : s.samples)
      e = std::max(e, std::abs(x.q[0] + m.belt_speed() * x.t - m.exact_lab_x(x.t)));
    err[k] = e;
  }
  INFO(to_string(scheme) << ": " << err[0] << " " << err[1] << " " << err[2]);
  // order >= 1: two halvings divide the error by at least 3 (rate >= 0.8 each)
  CHECK(err[2] < err[0] / 3.0);
}

TEST_CASE("Stepper contract: bad h is rejected before any step", "[stepping][contract]") {
  const FixedStepScheme scheme = any_scheme();
  const SpringMass m;
  for (double h : {0.0, -1e-6, std::numeric_limits<double>::quiet_NaN(),
                   std::numeric_limits<double>::infinity()}) {
    FixedStepOptions o;
    o.scheme = scheme;
    o.h = h;
    INFO(to_string(scheme) << " h = " << h);
    CHECK_THROWS_AS(make_stepper(m, o), std::invalid_argument);
    MemorySink s;
    CHECK_THROWS_AS(run_fixed_step(m, m.initial(), 0.1, o, s), std::invalid_argument);
    CHECK(s.samples.empty());
  }
}

TEST_CASE("Stepper contract: a non-finite model ends the step with a typed outcome",
          "[stepping][contract]") {
  const FixedStepScheme scheme = any_scheme();
  const rubdyn::testing::FreeFall m(1, 0.01);  // its force turns NaN after t = 0.01
  MechanicalState s0 = m.state();
  s0.q[1] = 1.0;
  FixedStepOptions o;
  o.scheme = scheme;
  o.h = 1e-3;
  const auto stepper = make_stepper(m, o);
  stepper->start(0.0, s0.q, s0.v);
  StepReport r(m.num_dofs());
  std::string message;
  StepOutcome last = StepOutcome::Ok;
  int i = 0;
  for (; i < 100 && last == StepOutcome::Ok; ++i) last = stepper->step(i * o.h, r, message);
  INFO(to_string(scheme) << ": " << message);
  CHECK(last == StepOutcome::NonFinite);
  // the failing step [t_f, t_f + h] is the first that reaches past t = 0.01 (Moreau-Jean
  // evaluates f at its end, Carpenter at its start): not earlier, and at most 2 steps later
  const double t_f = (i - 1) * o.h;
  CHECK(t_f + o.h > 0.01);
  CHECK(t_f < 0.0125);
  CHECK_FALSE(message.empty());
  MemorySink s;
  const RunSummary sum = run_fixed_step(m, s0, 0.05, o, s);
  CHECK(sum.termination == Termination::NonFinite);
  CHECK_FALSE(sum.complete());
  for (const auto& x : s.samples) CHECK(std::isfinite(x.q[1]));
}
