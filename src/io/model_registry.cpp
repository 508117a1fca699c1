#include "rubdyn/io/model_registry.hpp"

#include <stdexcept>
#include <string>

#include "rubdyn/model/jeffcott_model.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"

namespace rubdyn {

namespace {

std::vector<Coordinate> rigid_rotor_coordinates(const CaseSpec&) {
  return RotorStatorModel(RotorStatorParams{}).coordinates();
}
std::unique_ptr<LagrangianModel> build_rigid_rotor(const CaseSpec& spec) {
  return std::make_unique<RotorStatorModel>(spec.params);
}

std::vector<Coordinate> jeffcott_coordinates(const CaseSpec& spec) {
  JeffcottParams p;
  p.stator.rigid = spec.jeffcott.stator.rigid;
  return JeffcottModel(p).coordinates();
}
std::unique_ptr<LagrangianModel> build_jeffcott(const CaseSpec& spec) {
  return std::make_unique<JeffcottModel>(spec.jeffcott);
}

}  // namespace

const std::vector<ModelEntry>& model_registry() {
  static const std::vector<ModelEntry> table = {
      {"rigid-rotor",
       "the paper's rigid rotor on one bearing inside a sprung stator ring (7 dofs)",
       {"rotor", "bearing", "stator"},
       &rigid_rotor_coordinates,
       &build_rigid_rotor},
      {"jeffcott",
       "the Jeffcott-Black rotor: a disc on a massless shaft, a sprung (5 dofs) or rigid (3) "
       "stator",
       {"rotor", "stator"},
       &jeffcott_coordinates,
       &build_jeffcott},
  };
  return table;
}

const ModelEntry* find_model(std::string_view kind) {
  for (const auto& e : model_registry())
    if (e.kind == kind) return &e;
  return nullptr;
}

std::string model_names(std::string_view separator) {
  std::string s;
  for (const auto& e : model_registry()) {
    if (!s.empty()) s += separator;
    s += e.kind;
  }
  return s;
}

std::unique_ptr<LagrangianModel> build_model(const CaseSpec& spec) {
  const ModelEntry* e = find_model(spec.model);
  if (!e) throw std::invalid_argument("unknown model kind " + spec.model);
  return e->build(spec);
}

std::vector<Coordinate> initial_coordinates(const CaseSpec& spec) {
  const ModelEntry* e = find_model(spec.model);
  if (!e) throw std::invalid_argument("unknown model kind " + spec.model);
  return e->coordinates(spec);
}

MechanicalState initial_state(const CaseSpec& spec) {
  MechanicalState s;
  s.t = spec.run.t_start;
  s.q = spec.initial.q0;
  s.v = spec.initial.v0;
  return s;
}

double nominal_torque(const CaseSpec& spec) {
  return spec.loads().torque;
}

}  // namespace rubdyn
