#include "rubdyn/driver/simulate.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/solver_options.hpp"
#include "rubdyn/stepping/fixed_step.hpp"

namespace rubdyn {

RunSummary simulate(const CaseSpec& spec, OutputSink& sink, const ProgressFn& progress,
                    const std::atomic<bool>* stop) {
  const SolverEntry* solver = find_solver(spec.solver.kind);
  if (!solver) throw std::runtime_error("unknown solver kind " + spec.solver.kind);
  const std::unique_ptr<LagrangianModel> model = build_model(spec);
  const MechanicalState s0 = initial_state(spec);
  if (solver->fixed_step) {
    FixedStepOptions opt = fixed_step_options(spec);
    opt.progress = progress;
    opt.stop = stop;
    return run_fixed_step(*model, s0, spec.run.t_end, opt, sink);
  }
  EventDrivenOptions opt = event_driven_options(spec);
  opt.progress = progress;
  opt.stop = stop;
  return run_event_driven(*model, s0, spec.run.t_end, opt, sink);
}

std::vector<std::string> tighter_settings(const CaseSpec& s) {
  const SolverEntry* solver = find_solver(s.solver.kind);
  if (solver && solver->fixed_step) return {fmt::format("solver.h={:.6e}", s.solver.h / 10.0)};
  return {fmt::format("solver.rtol={:.3e}", s.solver.rtol / 100.0),
          fmt::format("solver.atol={:.3e}", s.solver.atol / 100.0)};
}

}  // namespace rubdyn
