#include "rubdyn/driver/simulate.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/solver_options.hpp"
#include "rubdyn/stepping/fixed_step.hpp"

namespace rubdyn {

namespace {

/// Hands everything to `inner`, the summary with its `model` line set (the solvers do not know
/// what their model was made from).
class NotedSink final : public OutputSink {
 public:
  NotedSink(OutputSink& inner, std::string note) : inner_(inner), note_(std::move(note)) {}
  void sample(const Sample& s) override { inner_.sample(s); }
  void event(const EventRecord& e) override { inner_.event(e); }
  void end(const RunSummary& s) override {
    RunSummary noted = s;
    noted.model = note_;
    inner_.end(noted);
  }

 private:
  OutputSink& inner_;
  std::string note_;
};

}  // namespace

RunSummary simulate(const CaseSpec& spec, OutputSink& out, const ProgressFn& progress,
                    const std::atomic<bool>* stop) {
  const SolverEntry* solver = find_solver(spec.solver.kind);
  if (!solver) throw std::runtime_error("unknown solver kind " + spec.solver.kind);
  const std::unique_ptr<LagrangianModel> model = build_model(spec);
  const MechanicalState s0 = initial_state(spec);
  const std::string note = model_note(spec);
  NotedSink noted(out, note);
  OutputSink& sink = note.empty() ? out : noted;
  RunSummary s;
  if (solver->fixed_step) {
    FixedStepOptions opt = fixed_step_options(spec);
    opt.progress = progress;
    opt.stop = stop;
    s = run_fixed_step(*model, s0, spec.run.t_end, opt, sink);
  } else {
    EventDrivenOptions opt = event_driven_options(spec);
    opt.progress = progress;
    opt.stop = stop;
    s = run_event_driven(*model, s0, spec.run.t_end, opt, sink);
  }
  s.model = note;
  return s;
}

std::vector<std::string> tighter_settings(const CaseSpec& s) {
  const SolverEntry* solver = find_solver(s.solver.kind);
  if (solver && solver->fixed_step) return {fmt::format("solver.h={:.6e}", s.solver.h / 10.0)};
  return {fmt::format("solver.rtol={:.3e}", s.solver.rtol / 100.0),
          fmt::format("solver.atol={:.3e}", s.solver.atol / 100.0)};
}

}  // namespace rubdyn
