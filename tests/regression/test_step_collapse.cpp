// The step-rate guard of the event solver (core/run_envelope.hpp) judges a collapse by its
// persistence, not by one window of kCheckSteps steps (issue 34): the reference case at
// mu = 0.25 with t_end = 100 s ended step_collapse at 0.116 s, its first 1000 steps of rolling
// (8.1e-8 s each) extrapolated to 1.25e9 steps, although the run takes 2e7 steps for 28 s of
// rolling (its step grows with the falling spin). A real collapse is still caught: a step that
// keeps falling, a step below the round-off of the run's time, and any run that has taken
// kMaxRunSteps steps.
#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>

#include "rubdyn/core/run_envelope.hpp"
#include "rubdyn/driver/simulate.hpp"
#include "rubdyn/io/case_io.hpp"

using namespace rubdyn;

namespace {

/// Feeds windows of kCheckSteps steps of mean step h(window) to an envelope of a run over
/// [0, t_end] until `windows` are fed or the guard stops the run; returns the windows fed.
template <class H>
long feed(RunEnvelope& env, double t_end, long windows, H&& h, double& t) {
  t = 0.0;
  long steps = 0;
  for (long w = 0; w < windows; ++w) {
    t += static_cast<double>(kCheckSteps) * h(w);
    steps += kCheckSteps;
    if (t >= t_end) return w + 1;
    if (env.watch(t, steps)) return w + 1;
  }
  return windows;
}

}  // namespace

TEST_CASE("Step-rate guard: a burst or a long steady phase of small steps goes on",
          "[bounded][collapse]") {
  RunControls c;
  MemorySink sink;
  double t = 0.0;
  SECTION("the onset of rolling of a 100 s run: 100 windows at 8.1e-8 s, then growing") {
    // the pattern (measured: 1e5 steps at 8.1e-8 s from the onset at 0.117 s to
    // 0.125 s, then 1.5e-7 s, 3.7e-7 s, ... 5e-6 s as the spin falls): each of the first 100
    // windows, alone, extrapolates to 1.25e9 steps
    RunEnvelope env(c, sink, 0.0, 100.0, 1.0, 0.25, "test", "{}");
    const long fed = feed(
        env, 100.0, 400,
        [](long w) {
          return w < 100 ? 8.1e-8 : 8.1e-8 * std::pow(1.02, static_cast<double>(w - 100));
        },
        t);
    INFO(env.summary().message);
    CHECK(fed == 400);
    CHECK(env.summary().complete());
  }
  SECTION("one window of tiny steps (an impact's restart), then the step recovers") {
    RunEnvelope env(c, sink, 0.0, 1.0, 1.0, 0.1, "test", "{}");
    const long fed = feed(
        env, 1.0, 20, [](long w) { return w == 3 ? 1e-12 : 1e-6; }, t);
    CHECK(fed == 20);
    CHECK(env.summary().complete());
  }
}

TEST_CASE("Step-rate guard: a real collapse is caught", "[bounded][collapse]") {
  RunControls c;
  MemorySink sink;
  double t = 0.0;
  SECTION("a step that keeps falling: caught within kCollapseWindows windows of its fall") {
    // halved every window from 1e-10 s (over the bound of a 1 s run from the first window):
    // 10 windows later it has fallen by 1024 > kCollapseFall
    RunEnvelope env(c, sink, 0.0, 1.0, 1.0, 0.1, "test", "{}");
    const long fed = feed(
        env, 1.0, 1000, [](long w) { return 1e-10 * std::pow(0.5, w); }, t);
    INFO(env.summary().message);
    CHECK(fed == kCollapseWindows + 1);
    CHECK(env.summary().termination == Termination::StepCollapse);
    CHECK(env.summary().message.find("fell") != std::string::npos);
  }
  SECTION("a step below the round-off of the run's time: caught at once") {
    // 1000 steps that advance 1e-15 s of a 1 s run (100 ulps of 1 s is 2.2e-14 s)
    RunEnvelope env(c, sink, 0.0, 1.0, 1.0, 0.1, "test", "{}");
    CHECK_FALSE(env.watch(1e-16, kCheckSteps - 1));  // not yet a check
    CHECK(env.watch(1e-15, kCheckSteps));
    CHECK(env.summary().termination == Termination::StepCollapse);
    CHECK(env.summary().message.find("round-off") == std::string::npos);  // (says "ulps")
    CHECK(env.summary().message.find("ulps") != std::string::npos);
  }
  SECTION("a steady step that would need 1e12 steps ends when the run has taken 1e9") {
    // 1e-12 s a step over 1 s: neither falling nor below round-off; bounded by the step count
    RunEnvelope env(c, sink, 0.0, 1.0, 1.0, 0.1, "test", "{}");
    CHECK_FALSE(env.watch(1e-9, kCheckSteps));
    CHECK_FALSE(env.watch(1e-3, static_cast<long>(kMaxRunSteps) - kCheckSteps));
    CHECK(env.watch(1e-3 + 1e-9, static_cast<long>(kMaxRunSteps)));
    CHECK(env.summary().termination == Termination::StepCollapse);
  }
  SECTION("1000 steps of 1e-6 s in a 1 s run (1e6 steps) go on") {
    RunEnvelope env(c, sink, 0.0, 1.0, 1.0, 0.1, "test", "{}");
    CHECK_FALSE(env.watch(1e-3, kCheckSteps));
    CHECK(env.summary().complete());
  }
}

TEST_CASE("Step-rate guard: the onset of rolling of a 100 s run at mu = 0.25 is no collapse",
          "[bounded][collapse][events]") {
  // The scene, stopped at 0.15 s (past the 1e5 steps of 8.1e-8 s that follow the onset
  // of rolling at 0.117 s; about a second of wall time): it ended step_collapse at 0.116 s.
  const CaseSpec spec =
      load_case(RUBDYN_SOURCE_DIR "/cases/reference.toml", {"contact.mu=0.25", "run.t_end=100"});
  std::atomic<bool> stop{false};
  MemorySink sink;
  const RunSummary s = simulate(
      spec, sink, [&](double t, long, double, Phase) { stop = stop || t >= 0.15; }, &stop);
  INFO(to_string(s.termination) << ": " << s.message);
  CHECK(s.termination == Termination::Interrupted);
  CHECK(s.t_reached >= 0.15);
  CHECK(s.phase_time[static_cast<int>(Phase::Stick)] > 0.03);  // it rolls
}

TEST_CASE("Step-rate guard: the 100 s run at mu = 0.25 completes", "[.long][bounded][collapse]") {
  // The whole run of the issue (about 2e7 steps: a few minutes of wall time).
  const CaseSpec spec = load_case(RUBDYN_SOURCE_DIR "/cases/reference.toml",
                                  {"contact.mu=0.25", "run.t_end=100", "output.dt=0.01"});
  MemorySink sink;
  const RunSummary s = simulate(spec, sink);
  INFO(to_string(s.termination) << ": " << s.message);
  CHECK(s.complete());
  CHECK(static_cast<double>(s.steps) < kMaxRunSteps);
}
