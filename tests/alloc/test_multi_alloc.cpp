// Hot paths allocate nothing with K contacts (Moreau-Jean's joint impulse problem and joint
// projection, Carpenter's joint correction, the run loop's per-contact output): the rod of
// tests/support/multi_problems.hpp resting flat on both ends (two closed contacts every step, no
// event after the landing) and the two-plane rotor case in free flight before its first impact,
// each run to two lengths.
#include <catch2/catch.hpp>

#include "alloc/run_allocations.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/stepping/fixed_step.hpp"
#include "support/multi_problems.hpp"

using namespace rubdyn;
using namespace rubdyn::testing;

TEST_CASE("No allocation per step: the fixed-step schemes with two contacts", "[alloc]") {
  const FallingRod rod({0.3, 0.0, 0.0});
  const CaseSpec c = load_case(RUBDYN_SOURCE_DIR "/cases/two-plane.toml");
  const auto rotor = build_model(c);
  // landed flat at t = 0 (height 0): both ends closed for the whole run (Moreau-Jean only:
  // Carpenter's start-up from a state on the constraint ends this resting scene as
  // implausible, its energy error being of the size of the scene's tiny flows)
  fixed_step_allocations(rod, rod.initial(0.0),
                         {FixedStepScheme::MoreauJean, FixedStepScheme::MoreauJeanProjected},
                         step_options(1e-4, 1e-3), 0.05, 0.1);
  // the rotor falls freely for about 6 ms before either plane is touched
  fixed_step_allocations(*rotor, initial_state(c), kEveryScheme, step_options(1e-6), 0.002, 0.004);
}

TEST_CASE("No allocation per step: the event-driven solver with two contacts", "[alloc]") {
  // the rod resting flat (both ends closed in stick, redundant tangential rows: the
  // minimum-norm solves of contact/min_norm.hpp every step), the rod sliding flat (both in slip
  // until it stops at 0.34 s), the two-plane rotor in free flight before its first impact, and
  // sliding at both planes between 6.5 ms and 11 ms (no event there; its contact phases in the
  // K-contact chart, ring_chart.hpp)
  const FallingRod rod({0.3, 0.0, 0.0});
  const CaseSpec c = load_case(RUBDYN_SOURCE_DIR "/cases/two-plane.toml");
  const auto rotor = build_model(c);
  event_allocations(rod, rod.initial(0.0), event_options(1e-3), 0.05, 0.1);
  event_allocations(rod, rod.initial(0.0, 0.0, 1.0), event_options(1e-3), 0.1, 0.2);
  event_allocations(*rotor, initial_state(c), event_options(), 0.002, 0.004);
  event_allocations(*rotor, initial_state(c), event_options(), 0.008, 0.010);
}
