#pragma once
// The one registry of solvers. Each entry names a solver and says which family it belongs to,
// which [solver] case keys it reads, how it runs a validated case, and which tighter settings
// `sweep --certify` uses for it. The case file's validation (solver.kind and the options of the
// family), the CLI (--solver, --help, refusing an option the chosen solver would ignore),
// simulate(), sweeps and the documentation test all read this table.
// Adding a solver: its source file and one entry in src/io/solver_registry.cpp.
#include <atomic>
#include <string>
#include <string_view>
#include <vector>

#include "rubdyn/io/case_spec.hpp"
#include "rubdyn/io/simulate.hpp"
#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn {

struct SolverEntry {
  std::string_view name;     ///< solver.kind
  std::string_view summary;  ///< one line (--help, docs)
  /// The fixed-step family: solver.h and output.every apply, the run is a whole number of steps.
  bool fixed_step = false;
  /// The [solver] keys the solver reads (besides solver.kind); a command-line option that sets
  /// another one is refused rather than silently ignored.
  std::vector<std::string_view> keys;
  /// Runs a validated case on `model` from `s0` to run.t_end.
  RunSummary (*run)(const CaseSpec& spec, const LagrangianModel& model, const MechanicalState& s0,
                    OutputSink& sink, const ProgressFn& progress, const std::atomic<bool>* stop);
  /// Tighter settings of the same solver, as case overrides (sweep --certify).
  std::vector<std::string> (*tighter)(const CaseSpec& spec);

  bool reads(std::string_view key) const;
};

/// Every solver, in the order of the documentation.
const std::vector<SolverEntry>& solver_registry();
/// The entry of `name`, or nullptr.
const SolverEntry* find_solver(std::string_view name);
/// The names joined by `separator` ("event, carp-onevc, ..." or "event | carp-onevc | ...").
std::string solver_names(std::string_view separator);

}  // namespace rubdyn
