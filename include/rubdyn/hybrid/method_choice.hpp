#pragma once
// Which CVODE multistep family integrates the event solver's phases when the case does not say
// (solver.method / solver.contact_method = "auto", the default).
//
// Adams-Moulton with fixed-point iteration costs no Jacobian and no linear algebra per step, but
// its step is bounded by stability (and by the iteration's convergence) at h |lambda_max| of
// order 1, where lambda_max is the fastest eigenvalue of the linearised free flight, whether or
// not that mode carries any motion. BDF with Newton is stable there and takes the step accuracy
// needs, at the cost of a Newton matrix. A model is stiff, and BDF integrates it, when its
// fastest time scale is far below the slowest one it has:
//
//     ratio = lambda_max / lambda_min > kStiffRatio
//
// lambda_max: the largest of omega_max (the generalised eigenvalues of the stiffness -df/dq
// against M at the initial state, symmetric parts, as sqrt) and delta_max (the damping -df/dv
// against M, as rates), the spin coordinate's row and column left out; lambda_min: the
// smallest nonzero omega (free rings and other coordinates without stiffness are left out). The
// rotor models of the paper (the rigid rotor, the Jeffcott rotor, their rub planes) have ratios of
// 1 to 35; a finite-element shaft has hundreds to thousands (its highest bending modes against its
// first critical speed). The threshold kStiffRatio is our calibration between the two
// (docs/fe-rotors.md: the measured ratios and the costs of both families on each side).
#include <string>

#include "rubdyn/core/types.hpp"
#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn {

/// The ratio above which the free flight is integrated with BDF (our calibration, see above).
inline constexpr double kStiffRatio = 100.0;

struct StiffnessAssessment {
  double omega_max = 0.0;  ///< largest undamped frequency of the linearisation [rad/s]
  double omega_min = 0.0;  ///< smallest nonzero one [rad/s] (0: none)
  double decay_max = 0.0;  ///< fastest damping rate [1/s]
  double ratio = 0.0;      ///< max(omega_max, decay_max) / omega_min (0: no time scale)
  bool stiff = false;      ///< ratio > kStiffRatio
  /// One line: the numbers and the verdict, for the report and summary.json.
  std::string reason() const;
};

/// The stiffness of `model`'s free flight at the state (t, q, v). Costs two symmetric
/// generalised eigenvalue problems of size n (O(n^3), once per run).
StiffnessAssessment assess_stiffness(const LagrangianModel& model, double t, const Vec& q,
                                     const Vec& v);

/// The structure of the model's Newton systems M - c1 df/dv - c2 (df/dq - d(M a)/dq) at a state:
/// banded apart from the spin's row and column (core/bordered_band.hpp), and whether a banded
/// factorisation beats a dense one by the flop count (the summary's report of how a run's
/// Newton systems are solved).
struct NewtonStructure {
  int n = 0;           ///< the model's coordinates
  int kl = 0, ku = 0;  ///< half-bandwidths without the spin's row and column
  bool banded = false;
  std::string reason() const;
};

/// The Newton systems' structure of `model` at (t, q, v): O(n^2), once per run.
NewtonStructure assess_newton_structure(const LagrangianModel& model, double t, const Vec& q,
                                        const Vec& v);

}  // namespace rubdyn
