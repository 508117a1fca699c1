#pragma once
// The derivative of a run of the event-driven flow with respect to its initial state, from the
// flow's sensitivities (docs/orbits.md section 7): the variational equations V' = f_x(t, x) V
// of every phase, integrated along the run in the full state x = (q, v) with the phase's
// constrained vector field f (the acceleration-level contact problem of its modes, so that a V
// tangent to the constraints stays tangent), multiplied at every event by the saltation matrix
// S = R_x P + f+ g_x^T / g', P = I - f- g_x^T / g': g the witness that fired (d_N at an onset,
// F_N at a lift-off, v_t at a stick or a reversal, the cone margin at a slip), g' its rate along
// the flow before the event, f- and f+ the vector fields on both sides, R_x the reset's Jacobian
// along the event surface: central differences of the engine's own decision at an onset
// (ContactDecider::arrive: impulses, Zeno truncation, cascade collapse), the identity at every
// other switch. f_x V by central differences of the field along each column of V. The augmented
// system (x, V) is integrated by CVODE-BDF (its Newton systems block-diagonal, one factorisation
// of I - gamma f_x). The periodic-orbit code (analysis/orbit.hpp, SensitivityMonodromy) is its
// user.
#include <string>
#include <vector>

#include "rubdyn/core/run_types.hpp"
#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn {

struct FlowSensitivity {
  bool ok = false;
  /// The run is not differentiable at one of its events (a witness crossing with zero rate:
  /// grazing; an onset whose decision changes within the difference step); `why` says where.
  bool not_smooth = false;
  std::string why;
  Mat V;           ///< d x(t_end) / d x(t_start) V0 (2n x d)
  long steps = 0;  ///< CVODE's steps of the augmented system
  int events = 0;  ///< the events whose saltation matrix was applied
};

/// DP V0 for the run of `m` under `opt` whose samples (at its start, before and after every
/// event: output_dt 0) and events are given, from its first sample's time to t_end. D (2n): the
/// state's scale (the difference steps are fractions of it; the absolute tolerance of component
/// i is opt.atol D_i / g0 scaled by rtol / opt.rtol). The variational equations are integrated
/// at the relative tolerance rtol.
FlowSensitivity flow_sensitivity(const LagrangianModel& m, const EventDrivenOptions& opt,
                                 const std::vector<Sample>& samples,
                                 const std::vector<EventRecord>& events, double t_end, MatIn V0,
                                 VecIn D, double rtol);

}  // namespace rubdyn
