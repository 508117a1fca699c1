#include "rubdyn/io/model_registry.hpp"

#include <limits>
#include <stdexcept>
#include <string>

#include "rubdyn/model/jeffcott_model.hpp"
#include "rubdyn/model/matrix_model.hpp"
#include "rubdyn/model/prescribed_spin.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"

namespace rubdyn {

namespace {

std::vector<Coordinate> rigid_rotor_coordinates(const CaseSpec& spec) {
  return RotorStatorModel::coordinates_of(spec.params);
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

std::vector<Coordinate> matrices_coordinates(const CaseSpec& spec) {
  // with a reduction that the loading refused, the files' coordinates (the case is invalid and
  // reported; its [initial] keys are still checked against something)
  // (the names and nodes only: no copy of the matrices)
  const MatrixParams& p = spec.matrices;
  std::vector<MatrixNode> nodes = p.node_list();
  std::shared_ptr<const ReducedMatrices> red;
  if (spec.reduction.method != ReductionMethod::None) {
    try {
      red = matrix_reduction(spec);
    } catch (const ReductionRefused&) {
    }
  }
  if (!red) return matrix_model_coordinates(p.rotor.size(), p.rotor.names, nodes, p.rotor.rotation);
  for (std::size_t k = 0; k < nodes.size() && k < red->node_xy.size(); ++k) {
    nodes[k].at.x = red->node_xy[k].first;
    nodes[k].at.y = red->node_xy[k].second;
  }
  return matrix_model_coordinates(red->rotor.size(), red->rotor.names, nodes);
}
std::unique_ptr<LagrangianModel> build_matrices(const CaseSpec& spec) {
  return std::make_unique<MatrixModel>(matrix_model_params(spec));
}

}  // namespace

const std::vector<ModelEntry>& model_registry() {
  static const std::vector<ModelEntry> table = {
      {"rigid-rotor",
       "the paper's rigid rotor on one bearing inside a sprung stator ring (7 dofs), or rubbing "
       "at several planes ([[plane]]), each with its own sprung or fixed ring",
       {"rotor", "bearing", "stator", "plane"},
       &rigid_rotor_coordinates,
       &build_rigid_rotor},
      {"jeffcott",
       "the Jeffcott-Black rotor: a disc on a massless shaft, a sprung (5 dofs) or rigid (3) "
       "stator",
       {"rotor", "stator"},
       &jeffcott_coordinates,
       &build_jeffcott},
      {"matrices",
       "a user's linear rotor: M, C, K, G (and a load f0) read from files, the spin an unknown, "
       "one contact node inside a sprung or rigid stator",
       {"rotor", "contact_node", "stator", "reduction"},
       &matrices_coordinates,
       &build_matrices},
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
  if (spec.loads().spin != SpinDrive::Prescribed) return e->build(spec);
  // a prescribed spin: the free-spin model without a drive torque, its spin coordinate made a
  // given function of time from the initial theta and omega0 (model/prescribed_spin.hpp)
  CaseSpec free = spec;
  free.loads().spin = SpinDrive::Torque;
  free.loads().torque = 0.0;
  free.loads().torque_law = TorqueLaw::Constant;
  std::unique_ptr<LagrangianModel> inner = e->build(free);
  const int s = inner->spin_coordinate();
  return std::make_unique<PrescribedSpin>(std::move(inner), spec.run.t_start, spec.initial.q0[s],
                                          spec.initial.v0[s], spec.loads().spin_accel);
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
  if (spec.loads().spin == SpinDrive::Prescribed) {
    // the spin is no coordinate of the model: its initial angle and speed start the prescription
    const int sp = find_coordinate(initial_coordinates(spec), CoordinateRole::Spin);
    const auto n = s.q.size() - 1;
    Vec q(n), v(n);
    for (Eigen::Index i = 0, j = 0; j <= n; ++j) {
      if (j == sp) continue;
      q[i] = s.q[j];
      v[i++] = s.v[j];
    }
    s.q = q;
    s.v = v;
  }
  return s;
}

std::shared_ptr<const ReducedMatrices> matrix_reduction(const CaseSpec& spec) {
  if (spec.model != "matrices" || spec.reduction.method == ReductionMethod::None) return nullptr;
  if (spec.reduced) return spec.reduced;
  return std::make_shared<const ReducedMatrices>(
      reduce_matrix_model(spec.matrices, spec.reduction));
}

MatrixParams matrix_model_params(const CaseSpec& spec) {
  const std::shared_ptr<const ReducedMatrices> red = matrix_reduction(spec);
  return red ? red->apply(spec.matrices) : spec.matrices;
}

std::string model_note(const CaseSpec& spec) {
  const std::shared_ptr<const ReducedMatrices> red = matrix_reduction(spec);
  return red ? red->describe() : std::string();
}

double nominal_torque(const CaseSpec& spec) {
  // a prescribed spin has no nominal torque (its drive torque is an output)
  return spec.loads().spin == SpinDrive::Prescribed ? std::numeric_limits<double>::quiet_NaN()
                                                    : spec.loads().torque;
}

}  // namespace rubdyn
