#include "rubdyn/io/solver_options.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>

namespace rubdyn {

bool SolverEntry::reads(std::string_view key) const {
  return std::find(keys.begin(), keys.end(), key) != keys.end();
}

const std::vector<SolverEntry>& solver_registry() {
  static const std::vector<SolverEntry> table = {
      {"event",
       "event-driven hybrid integrator on CVODE (the reference)",
       false,
       {"solver.rtol", "solver.atol", "solver.method", "solver.contact_phases",
        "solver.contact_method", "solver.max_events_per_second"}},
      {"carp-onevc",
       "Carpenter, one verification/correction (paper, Algorithm 1)",
       true,
       {"solver.h"}},
      {"carp-qn",
       "Carpenter inside a quasi-Newton loop",
       true,
       {"solver.h", "solver.itmax", "solver.qn_tol"}},
      {"mj",
       "Moreau-Jean theta-method, velocity-level Signorini and Coulomb",
       true,
       {"solver.h", "solver.theta", "solver.eta"}},
      {"mj-proj",
       "projected Moreau-Jean (positions projected onto d_N >= 0)",
       true,
       {"solver.h", "solver.theta", "solver.eta", "solver.projection"}},
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

namespace {
MultistepMethod multistep(const std::string& word) {
  return word == "adams" ? MultistepMethod::Adams
         : word == "bdf" ? MultistepMethod::BDF
                         : MultistepMethod::Auto;
}
}  // namespace

EventDrivenOptions event_driven_options(const CaseSpec& spec) {
  EventDrivenOptions opt;
  opt.rtol = spec.solver.rtol;
  opt.atol = spec.solver.atol;
  opt.method = multistep(spec.solver.method);
  opt.contact_phases = spec.solver.contact_phases == "projection" ? ContactFormulation::Projection
                       : spec.solver.contact_phases == "reduced"  ? ContactFormulation::Reduced
                                                                  : ContactFormulation::Auto;
  opt.contact_method = multistep(spec.solver.contact_method);
  opt.output_dt = spec.output.dt;
  opt.omega_lim = spec.run.omega_lim;
  opt.max_events_per_second = spec.solver.max_events_per_second;
  opt.max_wall = spec.run.max_wall;
  return opt;
}

FixedStepOptions fixed_step_options(const CaseSpec& spec) {
  FixedStepOptions opt;
  FixedStepScheme scheme;
  if (parse_fixed_step_scheme(spec.solver.kind, scheme)) opt.scheme = scheme;
  opt.h = spec.solver.h;
  opt.itmax = spec.solver.itmax;
  opt.qn_tol = spec.solver.qn_tol;
  opt.theta = spec.solver.theta;
  opt.eta = spec.solver.eta;
  opt.project_with_mass = spec.solver.projection == "mass";
  opt.output_every = spec.output.every;
  opt.output_dt = spec.output.dt;
  opt.omega_lim = spec.run.omega_lim;
  opt.max_wall = spec.run.max_wall;
  return opt;
}

std::vector<KeyProblem> solver_option_problems(const CaseSpec& spec) {
  std::vector<KeyProblem> out;
  // the event-driven family's rules on its own keys (output_dt and max_wall are stated by the
  // fixed-step family's too: reported once, from there)
  static const std::map<std::string, std::string> event_key = {
      {"rtol", "solver.rtol"},
      {"atol", "solver.atol"},
      {"max_events_per_second", "solver.max_events_per_second"}};
  for (const auto& p : event_driven_option_problems(event_driven_options(spec))) {
    const auto it = event_key.find(p.option);
    if (it != event_key.end()) out.push_back({it->second, p.value, p.rule});
  }
  static const std::map<std::string, std::string> fixed_key = {
      {"h", "solver.h"},           {"itmax", "solver.itmax"},
      {"qn_tol", "solver.qn_tol"}, {"theta", "solver.theta"},
      {"eta", "solver.eta"},       {"t_end", "run.t_end"},
      {"output_dt", "output.dt"},  {"output_every", "output.every"},
      {"max_wall", "run.max_wall"}};
  const FixedStepOptions fo = fixed_step_options(spec);
  auto problems = fixed_step_option_problems(fo);
  const SolverEntry* solver = find_solver(spec.solver.kind);
  if (solver && solver->fixed_step) {
    // the step count: a whole number of steps, at most kMaxFixedSteps (run.t_end <= t_start is
    // the case's own rule)
    if (spec.run.t_end > spec.run.t_start)
      for (auto& p : fixed_step_count_problems(fo.h, spec.run.t_start, spec.run.t_end))
        problems.push_back(std::move(p));
  }
  for (const auto& p : problems) out.push_back({fixed_key.at(p.option), p.value, p.rule});
  return out;
}

}  // namespace rubdyn
