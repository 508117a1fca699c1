#pragma once
// The allocation tests' method (every tests/alloc/test_*.cpp): two runs of the same scene that
// differ only in their length, with no event in the extra time, must allocate the same number
// of times (alloc_counter.hpp counts every heap allocation of the process).
#include <catch2/catch.hpp>
#include <utility>
#include <vector>

#include "alloc/alloc_counter.hpp"
#include "rubdyn/core/run_types.hpp"
#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/stepping/fixed_step.hpp"

namespace rubdyn::testing {

/// Discards the output: what is counted is the solver's own allocations.
class NullSink final : public OutputSink {
 public:
  void sample(const Sample&) override {}
  void event(const EventRecord&) override {}
  void end(const RunSummary&) override {}
};

/// Heap allocations of one whole run (set-up included), and the run's event count.
template <class Run>
std::pair<long, long> count_allocations(Run&& run) {
  const long before = allocations();
  const RunSummary s = run();
  REQUIRE(s.complete());
  long events = 0;
  for (long e : s.events) events += e;
  return {allocations() - before, events};
}

/// The same scene run to t1 and to t2 > t1 allocates the same: nothing per step, sample or root
/// that is no event.
template <class Run>
void same_allocations(Run&& run_to, double t1, double t2) {
  // a first run, not counted: what is set up once per thread (the prescribed-speed wrapper's
  // thread_local workspace) or per process is not what is compared
  count_allocations([&] { return run_to(t1); });
  const auto a = count_allocations([&] { return run_to(t1); });
  const auto b = count_allocations([&] { return run_to(t2); });
  INFO("allocations " << a.first << " and " << b.first << ", events " << a.second << " and "
                      << b.second);
  REQUIRE(a.second == b.second);  // no event in the extra time (an event may allocate its note)
  REQUIRE(a.first > 0);           // the counter counts (the set-up allocates)
  CHECK(a.first == b.first);
}

/// Every fixed-step scheme.
inline const std::vector<FixedStepScheme> kEveryScheme = {
    FixedStepScheme::CarpOneVC, FixedStepScheme::CarpQN, FixedStepScheme::MoreauJean,
    FixedStepScheme::MoreauJeanProjected};

/// same_allocations of the event-driven solver on m from s0 with the options o.
inline void event_allocations(const LagrangianModel& m, const MechanicalState& s0,
                              const EventDrivenOptions& o, double t1, double t2) {
  same_allocations(
      [&](double t) {
        NullSink sink;
        return run_event_driven(m, s0, t, o, sink);
      },
      t1, t2);
}

/// same_allocations of each fixed-step scheme of `schemes` on m from s0 with the options o (its
/// scheme set in turn).
inline void fixed_step_allocations(const LagrangianModel& m, const MechanicalState& s0,
                                   const std::vector<FixedStepScheme>& schemes, FixedStepOptions o,
                                   double t1, double t2) {
  for (const FixedStepScheme scheme : schemes) {
    INFO(to_string(scheme));
    o.scheme = scheme;
    same_allocations(
        [&](double t) {
          NullSink sink;
          return run_fixed_step(m, s0, t, o, sink);
        },
        t1, t2);
  }
}

/// Options with these fields set (the call sites' one-liners).
inline FixedStepOptions step_options(double h, double output_dt = 1e-4) {
  FixedStepOptions o;
  o.h = h;
  o.output_dt = output_dt;
  return o;
}
inline EventDrivenOptions event_options(double output_dt = 1e-4,
                                        ContactFormulation f = ContactFormulation::Reduced) {
  EventDrivenOptions o;
  o.output_dt = output_dt;
  o.contact_phases = f;
  return o;
}

}  // namespace rubdyn::testing
