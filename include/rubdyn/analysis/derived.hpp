#pragma once
// Derived quantities of a case: what `rubdyn check` prints. SI units, paper section 3.
//
// Geometry and inertia (eq. 9-11): l = L - delta, nu = d / l,
//   M11 = (1-nu)^2 m + Jd/l^2,  M12 = nu (1-nu) m - Jd/l^2,  M22 = nu^2 m + Jd/l^2,  H = Jp/l^2.
//
// Static equilibrium under gravity, rotor at rest (theta' = 0, every velocity 0). The bearing is
// translational only: x_r, y_r carry no stiffness (K of eq. 14 acts on x_b, y_b, x_s, y_s), so
// without contact row y_r of eq. (21) reads 0 = -nu m g, impossible for g > 0: the rotor pivots
// about B until it rests on the stator. In contact (d_N = 0, F_N >= 0), with the normal of the
// model (n = (r - s) / |r - s|, W_N = (0, 0, -n_x, -n_y, 0, n_x, n_y)):
//   x_r:  0 = -n_x F_N                    -> n_x = 0
//   y_r:  0 = -nu m g - n_y F_N           -> n_y = -1 (F_N > 0): the bottom of the clearance,
//                                            F_N = nu m g
//   y_b:  0 = -(1-nu) m g - k_b y_b       -> y_b = -(1-nu) m g / k_b
//   y_s:  0 = -k_s y_s + n_y F_N          -> y_s = -nu m g / k_s
//   d_N = g0 - |y_r - y_s| = 0, n_y = -1  -> y_r = y_s - g0
// and x_b = x_s = 0 (friction F_T = 0 is inside the Coulomb cone). This is the only equilibrium
// for g > 0. With g = 0 the rotor stays centred (no contact, F_N = 0, every position 0). The case
// validation imposes g >= 0 (gravity along -Y).
//
// Natural frequencies at rest [Hz]: the coupled 4-dof system of the Campbell diagram at
// Omega = 0 (two double modes f1 < f2, analysis/campbell.hpp); for information, the stator alone
// sqrt(k_s/m_s)/2pi and the rotor on its bearing without the stator, per direction
// det(diag(k_b, 0) - w^2 [M11, M12; M12, M22]) = 0: w^2 = k_b M22 / (M11 M22 - M12^2) and a 0 Hz
// mode (free pivot about the bearing).
//
// Free acceleration: no contact and no lateral motion, Jp theta'' = tau_a (row theta of eq. 16),
// so omega_lim is reached after (omega_lim - omega0) Jp / tau_a.
#include <string_view>

#include "rubdyn/core/types.hpp"
#include "rubdyn/model/rotor_stator_params.hpp"

namespace rubdyn {

/// Outcome of the free acceleration from omega0 to omega_lim.
enum class FreeAcceleration {
  reaches,          ///< omega0 < omega_lim and tau_a > 0: after t_free_to_omega_lim > 0
  already_reached,  ///< omega0 >= omega_lim: t_free_to_omega_lim = 0
  never             ///< omega0 < omega_lim and tau_a <= 0: t_free_to_omega_lim = +inf
};
std::string_view to_string(FreeAcceleration a);

struct DerivedQuantities {
  double l = 0, nu = 0;                     ///< L - delta [m], d / l [-]
  double M11 = 0, M12 = 0, M22 = 0, H = 0;  ///< eq. 11 [kg]
  // static equilibrium at rest under gravity
  bool rests_on_stator = false;      ///< true iff gravity > 0 (then at the bottom of the clearance)
  double F_N = 0;                    ///< static contact force nu m g [N] (0 without gravity)
  double y_b = 0, y_r = 0, y_s = 0;  ///< static positions [m]
  Vec q_static = Vec::Zero(7);       ///< the same as a generalised position (x_* = theta = 0)
  // natural frequencies at rest [Hz]
  double f1 = 0, f2 = 0;       ///< coupled system (stator tied at R), each a double mode
  double f_stator = 0;         ///< stator alone sqrt(k_s / m_s) / 2 pi
  double f_bearing_rotor = 0;  ///< rotor on its bearing, no stator (its other mode: 0 Hz)
  // free acceleration from omega0 to omega_lim
  FreeAcceleration free_acceleration = FreeAcceleration::reaches;
  double t_free_to_omega_lim = 0;  ///< [s]: 0 if already reached, +inf if never
};

/// omega0: initial spin speed [rad/s]; omega_lim: the speed limit of the analysis [rad/s].
DerivedQuantities compute_derived_quantities(const RotorStatorParams& p, double omega0,
                                             double omega_lim);

}  // namespace rubdyn
