#pragma once
// The solvers a case file can name ([solver] kind), and the one mapping from a case to each
// solver family's options.
//
// The table names each solver, its family and the [solver] keys it reads: the case file's
// validation (solver.kind, and an option the chosen solver would not read), the CLI (--solver,
// --help) and the documentation test read it. The mapping turns a case's [solver], [run] and
// [output] keys into EventDrivenOptions or FixedStepOptions: the case validation states their
// rules through it (solver_option_problems, each problem named by its case key) and the run
// (driver/simulate.hpp) uses the same options. Running a case is the driver's business.
// Adding a solver: its family's options here if it is a new family, one entry in
// src/io/solver_options.cpp, its run in src/driver/simulate.cpp.
#include <string>
#include <string_view>
#include <vector>

#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/io/case_spec.hpp"
#include "rubdyn/stepping/fixed_step.hpp"

namespace rubdyn {

struct SolverEntry {
  std::string_view name;     ///< solver.kind
  std::string_view summary;  ///< one line (--help, docs)
  /// The fixed-step family: solver.h and output.every apply, the run is a whole number of steps.
  bool fixed_step = false;
  /// The [solver] keys the solver reads (besides solver.kind); a command-line option that sets
  /// another one is refused rather than silently ignored.
  std::vector<std::string_view> keys;

  bool reads(std::string_view key) const;
};

/// Every solver, in the order of the documentation.
const std::vector<SolverEntry>& solver_registry();
/// The entry of `name`, or nullptr.
const SolverEntry* find_solver(std::string_view name);
/// The names joined by `separator` ("event, carp-onevc, ..." or "event | carp-onevc | ...").
std::string solver_names(std::string_view separator);

/// The event-driven options of a case: solver.rtol, atol, method, contact_phases,
/// contact_method, max_events_per_second; output.dt; run.omega_lim, max_wall.
EventDrivenOptions event_driven_options(const CaseSpec& spec);
/// The fixed-step options of a case (the scheme from solver.kind when it names one): solver.h,
/// itmax, qn_tol, theta, eta, projection; output.every, dt; run.omega_lim, max_wall.
FixedStepOptions fixed_step_options(const CaseSpec& spec);

/// A broken rule of a solver option, named by its case key.
struct KeyProblem {
  std::string key;    ///< "solver.rtol", "run.t_end", ...
  std::string value;  ///< the value as text (when the case does not give it: the default's)
  std::string rule;
};
/// Every rule the case's solver options break, stated by the solver families themselves
/// (event_driven_option_problems, fixed_step_option_problems and, for a fixed-step solver,
/// fixed_step_count_problems), through the mapping above. run.t_end against run.t_start is the
/// case's own rule and not repeated here.
std::vector<KeyProblem> solver_option_problems(const CaseSpec& spec);

}  // namespace rubdyn
