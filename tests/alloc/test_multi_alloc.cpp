// Hot paths allocate nothing with K contacts (Moreau-Jean's joint impulse problem and joint
// projection, the run loop's per-contact output): the rod of tests/support/multi_problems.hpp
// resting flat on both ends (two closed contacts every step, no event after the landing) and
// the two-plane rotor case in free flight before its first impact, each run to two lengths.
#include <catch2/catch.hpp>

#include "alloc/run_allocations.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/stepping/fixed_step.hpp"
#include "support/multi_problems.hpp"

using namespace rubdyn;
using rubdyn::testing::NullSink;
using rubdyn::testing::same_allocations;

TEST_CASE("No allocation per step: Moreau-Jean with two contacts", "[alloc]") {
  const rubdyn::testing::FallingRod rod({0.3, 0.0, 0.0});
  const CaseSpec c = load_case(RUBDYN_SOURCE_DIR "/cases/two-plane.toml");
  const auto rotor = build_model(c);
  for (const auto scheme : {FixedStepScheme::MoreauJean, FixedStepScheme::MoreauJeanProjected}) {
    FixedStepOptions o;
    o.scheme = scheme;
    o.h = 1e-4;
    o.output_dt = 1e-3;
    // landed flat at t = 0 (height 0): both ends closed for the whole run
    same_allocations(
        [&](double t) {
          NullSink sink;
          return run_fixed_step(rod, rod.initial(0.0), t, o, sink);
        },
        0.05, 0.1);
    // the rotor falls freely for about 6 ms before either plane is touched
    o.h = 1e-6;
    o.output_dt = 1e-4;
    same_allocations(
        [&](double t) {
          NullSink sink;
          return run_fixed_step(*rotor, initial_state(c), t, o, sink);
        },
        0.002, 0.004);
  }
}
