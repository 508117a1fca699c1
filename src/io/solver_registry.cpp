#include "rubdyn/io/solver_registry.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/stepping/fixed_step.hpp"

namespace rubdyn {

namespace {

RunSummary run_event(const CaseSpec& spec, const LagrangianModel& model, const MechanicalState& s0,
                     OutputSink& sink, const ProgressFn& progress, const std::atomic<bool>* stop) {
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
  opt.max_wall = spec.run.max_wall;
  return run_event_driven(model, s0, spec.run.t_end, opt, sink);
}

std::vector<std::string> tighter_event(const CaseSpec& s) {
  return {fmt::format("solver.rtol={:.3e}", s.solver.rtol / 100.0),
          fmt::format("solver.atol={:.3e}", s.solver.atol / 100.0)};
}

template <FixedStepScheme scheme>
RunSummary run_fixed(const CaseSpec& spec, const LagrangianModel& model, const MechanicalState& s0,
                     OutputSink& sink, const ProgressFn& progress, const std::atomic<bool>* stop) {
  FixedStepOptions opt;
  opt.scheme = scheme;
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
  opt.progress = progress;
  opt.max_wall = spec.run.max_wall;
  return run_fixed_step(model, s0, spec.run.t_end, opt, sink);
}

std::vector<std::string> tighter_fixed(const CaseSpec& s) {
  return {fmt::format("solver.h={:.6e}", s.solver.h / 10.0)};
}

}  // namespace

bool SolverEntry::reads(std::string_view key) const {
  return std::find(keys.begin(), keys.end(), key) != keys.end();
}

const std::vector<SolverEntry>& solver_registry() {
  static const std::vector<SolverEntry> table = {
      {"event",
       "event-driven hybrid integrator on CVODE (the reference)",
       false,
       {"solver.rtol", "solver.atol", "solver.method", "solver.contact_phases",
        "solver.contact_method", "solver.max_events_per_second"},
       &run_event,
       &tighter_event},
      {"carp-onevc",
       "Carpenter, one verification/correction (paper, Algorithm 1)",
       true,
       {"solver.h"},
       &run_fixed<FixedStepScheme::CarpOneVC>,
       &tighter_fixed},
      {"carp-qn",
       "Carpenter inside a quasi-Newton loop",
       true,
       {"solver.h", "solver.itmax", "solver.qn_tol"},
       &run_fixed<FixedStepScheme::CarpQN>,
       &tighter_fixed},
      {"mj",
       "Moreau-Jean theta-method, velocity-level Signorini and Coulomb",
       true,
       {"solver.h", "solver.theta", "solver.eta"},
       &run_fixed<FixedStepScheme::MoreauJean>,
       &tighter_fixed},
      {"mj-proj",
       "projected Moreau-Jean (positions projected onto d_N >= 0)",
       true,
       {"solver.h", "solver.theta", "solver.eta", "solver.projection"},
       &run_fixed<FixedStepScheme::MoreauJeanProjected>,
       &tighter_fixed},
  };
  return table;
}

const SolverEntry* find_solver(std::string_view name) {
  for (const auto& e : solver_registry())
    if (e.name == name) return &e;
  return nullptr;
}

std::string solver_names(std::string_view separator) {
  std::string s;
  for (const auto& e : solver_registry()) {
    if (!s.empty()) s += separator;
    s += e.name;
  }
  return s;
}

}  // namespace rubdyn
