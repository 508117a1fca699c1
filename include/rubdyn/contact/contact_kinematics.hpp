#pragma once
// Kinematics of the single rotor-stator contact (paper, section 4.1, eq. 17-19).
//
// Gap      d_N = g0 - |sr|,   sr = (x_r - x_s, y_r - y_s),  n = sr / |sr| (stator centre -> rotor)
// Normal   W_N = C_N = grad_q d_N                                         (eq. 18)
// Tangent  W_T = C_T, orthogonal to C_N, with -R_r on theta               (eq. 19)
//          t = (n_y, -n_x) is the direction of a positive F_T on the rotor centre.
// Speeds   v_N = W_N^T v = d(d_N)/dt (negative when closing)
//          v_t = W_T^T v = t . (v_rotor_point - v_stator_point): relative tangential velocity of
//          the
//                rotor's material point at the contact (spin included) with respect to the stator's
//                material point. A positive spin with a still orbit gives v_t = -R_r theta_dot < 0.
// Forces   f_c = W_N F_N + W_T F_T   (eq. 20); F_N >= 0 pushes the rotor towards the stator centre.
//          The friction power is F_T v_t (<= 0 under Coulomb's law).
// Acceleration level: d(v_N)/dt = W_N^T a + wdot_N,  d(v_t)/dt = W_T^T a + wdot_T, with
//          wdot_N = (dW_N/dt)^T v = -(t . dsr/dt)^2 / |sr|
//          wdot_T = (dW_T/dt)^T v = (t . dsr/dt) v_N / |sr|
// |sr| = 0 (centred rotor): no normal is defined. Then d_N = g0 > 0, normal_defined = false and
// W_N, W_T, v_N, v_t, wdot_* are zero: no contact can exist there, and no solver may use them.
#include "rubdyn/core/types.hpp"

namespace rubdyn {

struct ContactKinematics {
  double d_N = 0.0;  ///< gap [m]
  Vec7 W_N = Vec7::Zero();
  Vec7 W_T = Vec7::Zero();
  double v_N = 0.0;     ///< normal gap rate [m/s]
  double v_t = 0.0;     ///< relative tangential velocity [m/s]
  double wdot_N = 0.0;  ///< (dW_N/dt)^T v [m/s^2]
  double wdot_T = 0.0;  ///< (dW_T/dt)^T v [m/s^2]
  bool normal_defined = true;
};

}  // namespace rubdyn
