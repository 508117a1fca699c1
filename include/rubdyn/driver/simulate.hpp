#pragma once
// One run of a validated case with the solver it names: what `rubdyn run`, `rubdyn sweep` and
// the Python module do for each run. The driver layer sits above io (case files, output folders)
// and analysis: it builds the case's model (io/model_registry.hpp), maps the case to its
// solver's options (io/solver_options.hpp: the one mapping, which the case validation also
// uses) and runs it. No global state: runs on different threads are independent.
#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "rubdyn/core/run_types.hpp"
#include "rubdyn/io/case_spec.hpp"

namespace rubdyn {

/// Called at output samples with (t, events so far, omega, phase).
using ProgressFn = std::function<void(double, long, double, Phase)>;

/// Runs `spec` from its initial state to run.t_end, handing samples, events and the summary to
/// `sink`. Throws std::runtime_error only for a solver kind it does not know (a validated case
/// has none); numerical trouble is a typed termination in the summary. When `stop` is given and
/// becomes true, the run ends at its next output sample (fixed-step: next step) with
/// Termination::Interrupted.
RunSummary simulate(const CaseSpec& spec, OutputSink& sink, const ProgressFn& progress = {},
                    const std::atomic<bool>* stop = nullptr);

/// Tighter settings of the case's solver, as case overrides (sweep --certify): rtol and atol a
/// hundred times smaller (event-driven), h ten times smaller (fixed-step).
std::vector<std::string> tighter_settings(const CaseSpec& spec);

}  // namespace rubdyn
