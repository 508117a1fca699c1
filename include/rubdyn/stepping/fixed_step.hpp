#pragma once
// Fixed-step validation schemes on the same model and contact law as the event-driven integrator
// (paper, section 4.2-4.3, Table 1):
//   carp-onevc  Carpenter, Algorithm 1 (central differences, one verification/correction)
//   carp-qn     Carpenter inside a quasi-Newton loop (Roques et al., JSV 329, 2010)
//   mj          Moreau-Jean theta-method, velocity-level Signorini + Coulomb cone, Newton impact
//               law
//   mj-proj     projected Moreau-Jean (Acary, CMAME 256, 2013): positions projected onto
//               d_N >= 0
// Each scheme is a Stepper (stepper.hpp; carpenter.cpp, moreau_jean.cpp state the decisions the
// paper leaves open where they are taken); run_fixed_step is their one run loop.
#include <atomic>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "rubdyn/core/run_envelope.hpp"
#include "rubdyn/core/run_types.hpp"
#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn {

enum class FixedStepScheme { CarpOneVC, CarpQN, MoreauJean, MoreauJeanProjected };
std::string_view to_string(FixedStepScheme s);
/// Parses "carp-onevc" | "carp-qn" | "mj" | "mj-proj"; returns false on an unknown name.
bool parse_fixed_step_scheme(std::string_view name, FixedStepScheme& out);

/// The schemes' own options, beside the run controls every solver shares (output_dt,
/// omega_lim, progress, stop, max_wall: core/run_envelope.hpp). A fixed-step run checks the
/// stop flag before every step and reads the clock for the wall-time budget every 1024 steps.
struct FixedStepOptions : RunControls {
  FixedStepScheme scheme = FixedStepScheme::MoreauJean;
  double h = 1e-6;        ///< time step [s]
  int itmax = 20;         ///< carp-qn: max quasi-Newton iterations per step
  double qn_tol = 1e-12;  ///< carp-qn: relative tolerance on the step increment
  double theta = 0.5;     ///< Moreau-Jean theta (gamma in the paper)
  double eta = 0.5;       ///< Moreau-Jean weight of q in M(q_{i+eta})
  /// mj-proj: metric of the position projection. true: the kinetic metric, positions move
  /// along M(q)^-1 W_N (default); false: the Euclidean metric in q, along W_N (Siconos'
  /// MLCPProjectOnConstraints without mass normalisation).
  bool project_with_mass = true;
  int output_every = 0;  ///< write every N-th step (0: use output_dt)
};

/// Largest number of steps of one fixed-step run (README, "Exit codes and the output contract").
/// At about 1 us per step that is a quarter of an hour of integration alone; a larger count is
/// almost surely a typo in h (h = 1e-20 s asks for 1e17 steps) and is refused before the run.
inline constexpr long kMaxFixedSteps = 1'000'000'000;

/// Every rule that `opt` breaks on its own (empty: valid): h finite and > 0; itmax >= 1;
/// qn_tol > 0; theta in [0.5, 1]; eta in [0, 1]; output_every >= 0; output_dt finite and > 0.
/// The one statement of these rules: run_fixed_step and the case-file validation
/// (io/case_toml.cpp) both call it.
std::vector<OptionProblem> fixed_step_option_problems(const FixedStepOptions& opt);

/// The rules on the step count of a run from t_start to t_end with step h (empty: valid):
/// t_end finite and > t_start; (t_end - t_start) / h a whole number of steps (within 1e-6 of a
/// step: the schemes keep one h, Carpenter's central differences and Moreau-Jean's reused
/// iteration matrix need it), at most kMaxFixedSteps. The run then ends at t_end exactly (to
/// round-off), never one step short or past it.
std::vector<OptionProblem> fixed_step_count_problems(double h, double t_start, double t_end);

/// Runs a scheme from `initial` to t_end, handing samples, events and the summary to `sink`.
/// Throws std::invalid_argument listing every broken rule of both functions above (and for a
/// model with other than one contact, make_stepper) before anything is handed to the sink.
/// Numerical trouble (Newton failure, non-finite state, Painleve) ends the run with a typed
/// termination; nothing is thrown from inside the time loop.
RunSummary run_fixed_step(const LagrangianModel& model, const MechanicalState& initial,
                          double t_end, const FixedStepOptions& opt, OutputSink& sink);

}  // namespace rubdyn
