#include "rubdyn/io/simulate.hpp"

#include <stdexcept>

#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/solver_registry.hpp"

namespace rubdyn {

RunSummary simulate(const CaseSpec& spec, OutputSink& sink, const ProgressFn& progress,
                    const std::atomic<bool>* stop) {
  const std::unique_ptr<LagrangianModel> model = build_model(spec);
  const MechanicalState s0 = initial_state(spec);
  const SolverEntry* solver = find_solver(spec.solver.kind);
  if (!solver) throw std::runtime_error("unknown solver kind " + spec.solver.kind);
  return solver->run(spec, *model, s0, sink, progress, stop);
}

}  // namespace rubdyn
