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
#include "rubdyn/model/jeffcott_model.hpp"
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
  /// coupled system (stator tied at R), each a double mode; NaN when a plane's ring is fixed
  /// (a fixed ring tied to the rotor is a constraint: no tied system)
  double f1 = 0, f2 = 0;
  double f_stator = 0;         ///< stator alone sqrt(k_s / m_s) / 2 pi
  double f_bearing_rotor = 0;  ///< rotor on its bearing, no stator (its other mode: 0 Hz)
  // free acceleration from omega0 to omega_lim
  FreeAcceleration free_acceleration = FreeAcceleration::reaches;
  double t_free_to_omega_lim = 0;  ///< [s]: 0 if already reached, +inf if never
};

/// omega0: initial spin speed [rad/s]; omega_lim: the speed limit of the analysis [rad/s].
DerivedQuantities compute_derived_quantities(const RotorStatorParams& p, double omega0,
                                             double omega_lim);

/// Derived quantities of a Jeffcott-Black case (docs/models.md, section 1; docs/closed-forms.md).
///
/// Natural frequencies without contact [Hz]: the rotor f_r = sqrt(k_r / m_r) / 2 pi, the stator
/// f_s = sqrt(k_s / m_s) / 2 pi, and the pinned pair (the stator tied to the rotor)
/// f_c = sqrt((k_r + k_s) / (m_r + m_s)) / 2 pi, with damping ratios c / (2 sqrt(k m)). The
/// planar Jeffcott rotor has no gyroscopic effect: forward and backward whirl share them.
///
/// Statics under gravity: without contact y_r = -m_r g / k_r, y_s = -m_s g / k_s (0 for a rigid
/// stator). The relative sag delta = y_r - y_s closes the clearance when |delta| > g0: then the
/// rotor rests on the bottom (delta < -g0) or the top (delta > g0) of the ring with
///   F_N = (|delta| - g0) / (1/k_r + 1/k_s)      (1/k_s = 0 for a rigid stator),
/// and y_r = (-m_r g +- F_N) / k_r, y_s = (-m_s g -+ F_N) / k_s.
///
/// Unbalance: eps = u_b / m_r, the inertia about the mass centre J_G = J - u_b^2 / m_r, and the
/// steady forward whirl of the free rotor at omega0 (no contact, a stator that does not touch):
/// |z_r| = u_b omega0^2 / |k_r - m_r omega0^2 + i c_r omega0| (it touches if > g0 + the stator's
/// own motion, which is zero without contact).
///
/// Rigid stator, rolling under a constant torque (docs/closed-forms.md, 2.2): the steady spin
/// Omega_ss = tau / (c_r R^2), its whirl -(R / g0) Omega_ss, the contact force
/// g0 (m_r w^2 - k_r) and the time constant (J + m_r R^2) / (c_r R^2) of the approach.
struct JeffcottQuantities {
  double f_rotor = 0, zeta_rotor = 0;
  double f_stator = 0, zeta_stator = 0;  ///< NaN for a rigid stator
  double f_tied = 0;                     ///< NaN for a rigid stator (the rotor is pinned)
  double sag_rotor = 0, sag_stator = 0;  ///< free statics y_r, y_s [m]
  bool rests_on_stator = false;
  double F_N = 0, y_r = 0, y_s = 0;  ///< statics with the contact closed
  double eps = 0, J_G = 0;           ///< unbalance eccentricity [m], inertia about G
  double unbalance_orbit = 0;        ///< free steady whirl radius at omega0 [m]
  bool rolling_closed_form = false;  ///< rigid stator, constant torque, c_r > 0
  double rolling_omega = 0, rolling_whirl = 0, rolling_F_N = 0, rolling_time_constant = 0;
  FreeAcceleration free_acceleration = FreeAcceleration::reaches;
  double t_free_to_omega_lim = 0;  ///< (omega_lim - omega0) J / tau (free rotor, constant law)
};
JeffcottQuantities compute_jeffcott_quantities(const JeffcottParams& p, double omega0,
                                               double omega_lim);

}  // namespace rubdyn
