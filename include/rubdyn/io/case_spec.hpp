#pragma once
// CaseSpec: the one parsed, validated form of a case file (TOML). Only io/ knows TOML; the model
// gets RotorStatorParams, solvers get options structs. Every key, unit and admissible range is
// documented in cases/README.md.
#include <memory>
#include <string>
#include <vector>

#include "rubdyn/core/types.hpp"
#include "rubdyn/model/jeffcott_model.hpp"
#include "rubdyn/model/matrix_model.hpp"
#include "rubdyn/model/matrix_reduction.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"
#include "rubdyn/model/rotor_stator_params.hpp"

namespace rubdyn {

/// [initial]: every position and velocity of the model's coordinates (default 0), in the
/// model's order (io/model_registry.hpp: initial_coordinates); the keys are the coordinates'
/// names and rate keys (x_b, ..., theta, ..., omega0, ...). A prescribed spin reads theta and
/// omega0 as theta(t_start) and omega(t_start).
struct InitialState {
  Vec q0 = Vec::Zero(RotorStatorModel::kDofs);
  Vec v0 = Vec::Zero(RotorStatorModel::kDofs);
};

/// [run]
struct RunOptions {
  /// [s] time of the initial state: 0, or the sample time of a restart (rubdyn run --from)
  double t_start = 0.0;
  double t_end = 0.5;         ///< [s]
  double omega_lim = 2110.0;  ///< speed limit used by the analysis [rad/s]
  /// [s] wall-time budget of the run, 0 = none: a run that has spent it stops at its next
  /// output sample with Termination::TimeBudget, keeping what it wrote
  double max_wall = 0.0;
};

/// [solver]
struct SolverOptions {
  std::string kind = "event";  ///< a solver of the registry (io/solver_options.hpp)
  // event-driven
  double rtol = 1e-10;  ///< relative tolerance
  double atol = 1e-12;  ///< absolute tolerance, scaled per component by the solver
  /// free flight: auto | adams | bdf (CVODE multistep family; auto: bdf when the model is stiff,
  /// hybrid/method_choice.hpp)
  std::string method = "auto";
  /// auto (reduced, or projection for a banded stiff model) | reduced (minimal coordinates) |
  /// projection (DAE)
  std::string contact_phases = "auto";
  std::string contact_method = "auto";  ///< reduced contact phases: auto | adams | bdf
  double max_events_per_second = 1e6;   ///< chattering guard: events per simulated second
  // fixed-step
  double h = 1e-6;                  ///< time step [s]
  int itmax = 20;                   ///< carp-qn: max quasi-Newton iterations per step
  double qn_tol = 1e-12;            ///< carp-qn: relative tolerance on the step increment
  double theta = 0.5;               ///< Moreau-Jean theta (gamma in the paper), in [0.5, 1]
  double eta = 0.5;                 ///< Moreau-Jean mass-matrix weight, in [0, 1]
  std::string projection = "mass";  ///< mj-proj metric: mass | identity
};

/// [output]
struct OutputOptions {
  double dt = 1e-4;    ///< output interval [s] (dense output, never changes the steps taken)
  int every = 0;       ///< fixed-step schemes: write every N-th step (0: use dt)
  std::string folder;  ///< output folder (empty: out/<case name>)
  /// The coordinates timeseries.csv holds: "all", or a comma-separated list of coordinate names
  /// and the word "contacts" (the contacts' and the spin's coordinates are always written; the
  /// full state then goes to state.csv at the run's first sample, its events and its end):
  /// io/columns.hpp. Default: "all" up to 64 coordinates, "contacts" above (a wide model).
  std::string coordinates = "all";
};

/// [rotor] of kind "matrices": the files of the user's matrices, as given in the case file
/// (relative to its folder) until the case is read, then absolute (case.resolved.toml names
/// the files that were read), and the coordinates' names as written.
struct MatrixFiles {
  std::string M, C, K, G, f0;  ///< f0 empty: no constant load
  std::string coordinates;     ///< "x_b, y_b, x_r, y_r"; empty: q0, q1, ...
  std::string rotations;       ///< q's rotations (rad): "dx*, dy*"; empty: none
};

struct CaseSpec {
  std::string name;    ///< case name (file stem unless given)
  std::string source;  ///< path of the case file (for messages)
  /// [model] kind: a model of the registry (io/model_registry.hpp), "rigid-rotor" by default
  std::string model = "rigid-rotor";
  RotorStatorParams params;  ///< the parameters of kind "rigid-rotor"
  JeffcottParams jeffcott;   ///< the parameters of kind "jeffcott"
  MatrixParams matrices;     ///< the parameters of kind "matrices" (the matrices read)
  MatrixFiles matrix_files;  ///< where kind "matrices" read them
  /// [reduction] of kind "matrices": the model is the reduced one of `matrices` (which stays the
  /// files' full rotor, as the keys name it). `reduced` is that reduction as the case's loading
  /// computed it (it decides the coordinates), shared by the copies of the case; null when
  /// there is none or it failed (io/model_registry.hpp: matrix_reduction).
  ReductionParams reduction;
  std::shared_ptr<const ReducedMatrices> reduced;
  InitialState initial;
  RunOptions run;
  SolverOptions solver;
  OutputOptions output;

  /// The contact law and the loads of the case's model ([contact], [loads]).
  const ContactLaw& contact() const {
    return model == "jeffcott"   ? jeffcott.contact
           : model == "matrices" ? matrices.contact
                                 : params.contact;
  }
  ContactLaw& contact() {
    return model == "jeffcott"   ? jeffcott.contact
           : model == "matrices" ? matrices.contact
                                 : params.contact;
  }
  const LoadParams& loads() const {
    return model == "jeffcott"   ? jeffcott.loads
           : model == "matrices" ? matrices.loads
                                 : params.loads;
  }
  LoadParams& loads() {
    return model == "jeffcott"   ? jeffcott.loads
           : model == "matrices" ? matrices.loads
                                 : params.loads;
  }
};

}  // namespace rubdyn
