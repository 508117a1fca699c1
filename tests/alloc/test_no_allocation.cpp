// Hot paths allocate nothing: a solver sizes its workspaces when it is built, and a step, a
// right-hand side, a witness or an output sample reuses them. Checked by counting every heap
// allocation of the process (malloc, calloc, realloc; operator new and Eigen go through them)
// while a run goes on: two runs of the same scene that differ only in their length, with no
// event in the extra time, must allocate the same number of times. A separate program (not
// under the sanitizers, which replace malloc themselves).

#include <catch2/catch.hpp>
#include <cstddef>

#include "alloc/run_allocations.hpp"
#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"
#include "rubdyn/stepping/fixed_step.hpp"
#include "support/jeffcott_cases.hpp"
#include "support/problems.hpp"

using namespace rubdyn;
using namespace rubdyn::testing;

TEST_CASE("No allocation per step: the rigid rotor in free flight, every solver", "[alloc]") {
  RotorStatorParams p;
  p.loads.gravity = 0.0;  // centred and spinning: the gap never closes
  const RotorStatorModel model(p);
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.v[TH] = 2000.0;
  event_allocations(model, s0, event_options(), 0.01, 0.02);
  fixed_step_allocations(model, s0, kEveryScheme, step_options(1e-5), 0.01, 0.02);
}

TEST_CASE("No allocation per step: the rigid rotor in permanent contact, every solver", "[alloc]") {
  // resting at the bottom of the clearance without friction and without spin: a contact phase
  // (slip, frictionless) for the whole run, with its static force
  RotorStatorParams p;
  p.contact.mu = 0.0;
  p.loads.torque = 0.0;
  const RotorStatorModel model(p);
  const double mg = p.rotor.mass * p.loads.gravity, nu = model.nu();
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.q[YB] = -(1 - nu) * mg / p.bearing.k;
  s0.q[YS] = -nu * mg / p.stator.k;
  s0.q[YR] = s0.q[YS] - p.stator.gap;
  for (auto formulation : {ContactFormulation::Reduced, ContactFormulation::Projection})
    event_allocations(model, s0, event_options(1e-4, formulation), 0.01, 0.02);
  fixed_step_allocations(model, s0, kEveryScheme, step_options(1e-5), 0.01, 0.02);
}

TEST_CASE("No allocation per step: a 2-dof model (dynamic sizes) sliding, then sticking",
          "[alloc]") {
  // the block on the belt slides until t1, then sticks until t2
  const rubdyn::testing::BlockOnBelt model(0.5, 100.0, 1.0, 0.2);
  const double t1 = model.stick_time(), t2 = model.slip_time();
  REQUIRE(t2 > t1 + 0.02);
  event_allocations(model, model.initial(), event_options(1e-3), t1 / 3.0, 2.0 * t1 / 3.0);
  // sticking (after the one stick event)
  event_allocations(model, model.initial(), event_options(1e-3), t1 + 0.01, t1 + 0.02);
  fixed_step_allocations(model, model.initial(), kEveryScheme, step_options(1e-5, 1e-3), 0.01,
                         0.02);
}

TEST_CASE("No allocation per step: the Jeffcott rotor rolling, and spun at a prescribed speed",
          "[alloc]") {
  // (1) rolling on a rigid ring at the steady spin tau / (c_r R^2) = 2666.67 rad/s: a stick
  // phase (the 3-dof chart) for the whole run
  const CaseSpec rolling = parse_case(rubdyn::testing::SteadyRoll::text(), "alloc");
  const auto roll = build_model(rolling);
  const MechanicalState r0 = initial_state(rolling);
  event_allocations(*roll, r0, event_options(), 0.01, 0.02);
  // (Carpenter's correction has sliding friction only: no roll)
  fixed_step_allocations(*roll, r0,
                         {FixedStepScheme::MoreauJean, FixedStepScheme::MoreauJeanProjected},
                         step_options(1e-6), 0.002, 0.004);
  // (2) an unbalance whirling freely at a prescribed 800 rad/s (the wrapper without its spin
  // coordinate, the drive torque an observable), sprung stator: free flight
  const CaseSpec spinning =
      parse_case(rubdyn::testing::jeffcott_case("mass = 2.0\nk = 2.0e7\nc = 2500.0\n",
                                                "spin = \"prescribed\"\nunbalance = 1e-4\n",
                                                "omega0 = 800.0\n"),
                 "alloc");
  const auto spun = build_model(spinning);
  const MechanicalState s0 = initial_state(spinning);
  event_allocations(*spun, s0, event_options(), 0.01, 0.02);
  fixed_step_allocations(*spun, s0, kEveryScheme, step_options(1e-5), 0.01, 0.02);
}
