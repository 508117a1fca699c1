#pragma once
// The one registry of models a case file can name ([model] kind), and how a validated case
// becomes a model. Each entry names a model, says which sections of a case file it reads, which
// coordinates a case of it has (the [initial] keys, the output columns) and how it is built.
// The case file's schema (io/case_toml.cpp) declares each model's keys and rules beside it;
// `rubdyn check`, the documentation test and the Python module read this table.
// Adding a model: its class in model/, one entry in src/io/model_registry.cpp, its keys and
// rules in src/io/case_toml.cpp, its section in cases/README.md.
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "rubdyn/io/case_spec.hpp"
#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn {

struct ModelEntry {
  std::string_view kind;     ///< [model] kind
  std::string_view summary;  ///< one line (--help, docs)
  /// The model's own sections besides [model], [contact], [loads], [initial], [run], [solver],
  /// [output] (which every model has).
  std::vector<std::string_view> sections;
  /// The coordinates of the model a case describes (its flags, e.g. stator.rigid, decide which
  /// exist; the values need not be valid). With a free spin these are the model's coordinates.
  std::vector<Coordinate> (*coordinates)(const CaseSpec& spec);
  /// Builds the model of a validated case.
  std::unique_ptr<LagrangianModel> (*build)(const CaseSpec& spec);
};

/// Every model, in the order of the documentation.
const std::vector<ModelEntry>& model_registry();
/// The entry of `kind`, or nullptr.
const ModelEntry* find_model(std::string_view kind);
/// The kinds joined by `separator`.
std::string model_names(std::string_view separator);

/// The model of a validated case (its [model] kind with its parameters and loads).
std::unique_ptr<LagrangianModel> build_model(const CaseSpec& spec);

/// The coordinates whose positions and rates the [initial] section sets (the initial state's
/// layout, InitialState::q0 and v0).
std::vector<Coordinate> initial_coordinates(const CaseSpec& spec);

/// The state a run of the case starts from, in the model's coordinates, at run.t_start.
MechanicalState initial_state(const CaseSpec& spec);

/// Kind "matrices" with a [reduction]: the reduced model (the loading's, or computed now when a
/// case built in code has none); null without a reduction. Throws ReductionRefused when the
/// reduction is refused (the case validation reports it first).
std::shared_ptr<const ReducedMatrices> matrix_reduction(const CaseSpec& spec);
/// The parameters of a matrices case's model: the reduced ones with a [reduction], else the
/// files' (spec.matrices).
MatrixParams matrix_model_params(const CaseSpec& spec);
/// What a run's model is when it is not the case's files as they stand (a reduction's
/// describe()), for the report and summary.json; empty otherwise.
std::string model_note(const CaseSpec& spec);

/// The case's driving torque tau_a (loads.torque) [N m]: the scale of the friction torque in
/// the analysis.
double nominal_torque(const CaseSpec& spec);

}  // namespace rubdyn
