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
#include <string_view>

#include "rubdyn/core/run_types.hpp"
#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn {

enum class FixedStepScheme { CarpOneVC, CarpQN, MoreauJean, MoreauJeanProjected };
std::string_view to_string(FixedStepScheme s);
/// Parses "carp-onevc" | "carp-qn" | "mj" | "mj-proj"; returns false on an unknown name.
bool parse_fixed_step_scheme(std::string_view name, FixedStepScheme& out);

struct FixedStepOptions {
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
  double output_dt = 1e-4;
  double omega_lim = 0.0;  ///< for the summary: first time omega (the model's spin) >= it
};

/// Runs a scheme from `initial` to t_end, handing samples, events and the summary to `sink`.
/// Numerical trouble (Newton failure, non-finite state, Painleve) ends the run with a typed
/// termination; nothing is thrown from inside the time loop. Throws std::invalid_argument for a
/// bad h or a model with other than one contact (make_stepper), before any output.
RunSummary run_fixed_step(const LagrangianModel& model, const MechanicalState& initial,
                          double t_end, const FixedStepOptions& opt, OutputSink& sink);

}  // namespace rubdyn
