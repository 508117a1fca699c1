#pragma once
// The allocation tests' method (every tests/alloc/test_*.cpp): two runs of the same scene that
// differ only in their length, with no event in the extra time, must allocate the same number
// of times (alloc_counter.hpp counts every heap allocation of the process).
#include <catch2/catch.hpp>
#include <utility>

#include "alloc/alloc_counter.hpp"
#include "rubdyn/core/run_types.hpp"

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

}  // namespace rubdyn::testing
