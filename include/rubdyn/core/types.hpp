#pragma once
// Fixed-size linear algebra for the 7-dof rotor-stator model, and the dof layout.
//
// q = (x_b, y_b, x_r, y_r, theta, x_s, y_s)   [m, m, m, m, rad, m, m]
// v = dq/dt                                   [m/s, ..., rad/s, ...]
// Hot paths use only these fixed-size types: nothing allocates.
// Models with fewer dofs (test problems) pad the unused dofs with unit mass and no force; those
// dofs then stay at rest and never enter a contact.
#include <Eigen/Core>

namespace rubdyn {

inline constexpr int kNumDofs = 7;

using Vec2 = Eigen::Matrix<double, 2, 1>;
using Vec7 = Eigen::Matrix<double, kNumDofs, 1>;
using Mat2 = Eigen::Matrix<double, 2, 2>;
using Mat7 = Eigen::Matrix<double, kNumDofs, kNumDofs>;
using Mat7x3 = Eigen::Matrix<double, kNumDofs, 3>;
using Vec14 = Eigen::Matrix<double, 2 * kNumDofs, 1>;
using Mat14 = Eigen::Matrix<double, 2 * kNumDofs, 2 * kNumDofs>;

/// Index of each generalised coordinate in q (paper, section 3.2.2 and eq. 17).
enum Dof : int { XB = 0, YB = 1, XR = 2, YR = 3, TH = 4, XS = 5, YS = 6 };

/// Names of the dofs in q order, as used in output files and case files.
inline constexpr const char* kDofNames[kNumDofs] = {"x_b",   "y_b", "x_r", "y_r",
                                                    "theta", "x_s", "y_s"};
/// Names of the velocities in v order, as used in output files.
inline constexpr const char* kVelNames[kNumDofs] = {"vx_b",  "vy_b", "vx_r", "vy_r",
                                                    "omega", "vx_s", "vy_s"};

/// A mechanical state: positions and velocities at one time.
struct MechanicalState {
  double t = 0.0;
  Vec7 q = Vec7::Zero();
  Vec7 v = Vec7::Zero();
};

}  // namespace rubdyn
