// Run time of every solver on the reference case (cmake -DRUBDYN_BUILD_BENCH=ON; run
// build/bench/rubdyn_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true).
// Fixed-step schemes report steps per wall second (counter "steps/s"); the event-driven
// integrator reports its wall time per run and its steps.
#include <benchmark/benchmark.h>

#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"
#include "rubdyn/stepping/fixed_step.hpp"

using namespace rubdyn;

namespace {

/// Discards the output: the benchmark measures the solver, not the sink.
class NullSink final : public OutputSink {
 public:
  void sample(const Sample&) override {}
  void event(const EventRecord&) override {}
  void end(const RunSummary&) override {}
};

MechanicalState reference_start() {
  MechanicalState s;
  s.v[TH] = 2000.0;
  return s;
}

void fixed_step(benchmark::State& st, FixedStepScheme scheme) {
  const RotorStatorModel model(RotorStatorParams{});
  FixedStepOptions o;
  o.scheme = scheme;
  o.h = 1e-6;
  o.output_dt = 1e-4;
  long steps = 0;
  for (auto _ : st) {
    NullSink sink;
    const RunSummary s = run_fixed_step(model, reference_start(), 0.03, o, sink);
    steps += s.steps;
    benchmark::DoNotOptimize(s.omega_final);
  }
  st.counters["steps/s"] =
      benchmark::Counter(static_cast<double>(steps), benchmark::Counter::kIsRate);
}

void event_driven(benchmark::State& st, double t_end, double rtol) {
  const RotorStatorModel model(RotorStatorParams{});
  EventDrivenOptions o;
  o.rtol = rtol;
  o.atol = 1e-2 * rtol;
  o.output_dt = 1e-4;
  o.omega_lim = 2110.0;
  long steps = 0;
  for (auto _ : st) {
    NullSink sink;
    const RunSummary s = run_event_driven(model, reference_start(), t_end, o, sink);
    steps += s.steps;
    benchmark::DoNotOptimize(s.omega_final);
  }
  st.counters["steps/s"] =
      benchmark::Counter(static_cast<double>(steps), benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK_CAPTURE(fixed_step, carp_onevc_30ms_h1e6, FixedStepScheme::CarpOneVC)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(fixed_step, carp_qn_30ms_h1e6, FixedStepScheme::CarpQN)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(fixed_step, mj_30ms_h1e6, FixedStepScheme::MoreauJean)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(fixed_step, mj_proj_30ms_h1e6, FixedStepScheme::MoreauJeanProjected)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(event_driven, event_30ms_rtol1e10, 0.03, 1e-10)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(event_driven, event_500ms_rtol1e9, 0.5, 1e-9)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(event_driven, event_500ms_rtol1e10, 0.5, 1e-10)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
