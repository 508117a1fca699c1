#pragma once
// One run of a validated case with the solver it names: what `rubdyn run` and `rubdyn sweep` do
// for each point. No global state: runs on different threads are independent.
#include <atomic>
#include <functional>

#include "rubdyn/core/run_types.hpp"
#include "rubdyn/io/case_spec.hpp"

namespace rubdyn {

/// Called at output samples with (t, events so far, omega, phase); event-driven solver only.
using ProgressFn = std::function<void(double, long, double, Phase)>;

/// Runs `spec` from its initial state to run.t_end, handing samples, events and the summary to
/// `sink`. Throws std::runtime_error only for a solver kind it does not know (a validated case
/// has none); numerical trouble is a typed termination in the summary. When `stop` is given and
/// becomes true, the run ends at its next output sample (fixed-step: next step) with
/// Termination::Interrupted.
RunSummary simulate(const CaseSpec& spec, OutputSink& sink, const ProgressFn& progress = {},
                    const std::atomic<bool>* stop = nullptr);

}  // namespace rubdyn
