#pragma once
// The models a case file can name, and how a validated case becomes a model.
#include <memory>

#include "rubdyn/io/case_spec.hpp"
#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn {

/// The model of a validated case (its [model] kind with its parameters and loads).
std::unique_ptr<LagrangianModel> build_model(const CaseSpec& spec);

/// The case's driving torque tau_a (loads.torque) [N m]: the scale of the friction torque in
/// the analysis.
double nominal_torque(const CaseSpec& spec);

}  // namespace rubdyn
