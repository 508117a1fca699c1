#include "rubdyn/io/model_registry.hpp"

#include "rubdyn/model/rotor_stator_model.hpp"

namespace rubdyn {

std::unique_ptr<LagrangianModel> build_model(const CaseSpec& spec) {
  return std::make_unique<RotorStatorModel>(spec.params);
}

double nominal_torque(const CaseSpec& spec) {
  return spec.params.loads.torque;
}

}  // namespace rubdyn
