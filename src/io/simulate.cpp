#include "rubdyn/io/simulate.hpp"

#include <stdexcept>

#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"
#include "rubdyn/stepping/fixed_step.hpp"

namespace rubdyn {

RunSummary simulate(const CaseSpec& spec, OutputSink& sink, const ProgressFn& progress,
                    const std::atomic<bool>* stop) {
  const RotorStatorModel model(spec.params);
  MechanicalState s0;
  s0.q = spec.initial.q0;
  s0.v = spec.initial.v0;
  s0.t = spec.run.t_start;
  if (spec.solver.kind == "event") {
    EventDrivenOptions opt;
    opt.rtol = spec.solver.rtol;
    opt.atol = spec.solver.atol;
    opt.adams = spec.solver.method == "adams";
    opt.contact_phases = spec.solver.contact_phases == "projection" ? ContactFormulation::Projection
                                                                    : ContactFormulation::Reduced;
    opt.contact_adams = spec.solver.contact_method == "adams";
    opt.output_dt = spec.output.dt;
    opt.omega_lim = spec.run.omega_lim;
    opt.max_events_per_second = spec.solver.max_events_per_second;
    opt.progress = progress;
    opt.stop = stop;
    return run_event_driven(model, s0, spec.run.t_end, opt, sink);
  }
  FixedStepOptions opt;
  if (!parse_fixed_step_scheme(spec.solver.kind, opt.scheme)) {
    throw std::runtime_error("unknown solver kind " + spec.solver.kind);
  }
  opt.h = spec.solver.h;
  opt.itmax = spec.solver.itmax;
  opt.qn_tol = spec.solver.qn_tol;
  opt.theta = spec.solver.theta;
  opt.eta = spec.solver.eta;
  opt.project_with_mass = spec.solver.projection == "mass";
  opt.output_every = spec.output.every;
  opt.output_dt = spec.output.dt;
  opt.omega_lim = spec.run.omega_lim;
  opt.stop = stop;
  return run_fixed_step(model, s0, spec.run.t_end, opt, sink);
}

}  // namespace rubdyn
