#pragma once
// Kinematics of one unilateral contact with friction, as every model provides it per contact
// (LagrangianModel::compute_contact). For the rotor-stator contact of the paper (section 4.1,
// eq. 17-19) and of the Jeffcott rotor, in the contact plane:
//
// Gap      d_N = g0 - |sr|,   sr = (rotor centre - stator centre), n = sr / |sr| (stator centre
//          -> rotor)
// Normal   W_N = C_N = grad_q d_N                                         (eq. 18)
// Tangent  W_T = C_T, orthogonal to C_N, with -R_r on the spin angle      (eq. 19)
//          t = (n_y, -n_x) is the direction of a positive F_T on the rotor centre.
// Speeds   v_N = W_N^T v + b_N = d(d_N)/dt (negative when closing)
//          v_t = W_T^T v + b_T = t . (v_rotor_point - v_stator_point): relative tangential
//                velocity of the rotor's material point at the contact (spin included) with
//                respect to the stator's material point. A positive spin with a still orbit gives
//                v_t = -R_r theta_dot < 0.
//          b_N, b_T: the part of the speeds that no coordinate's rate carries, i.e. a prescribed
//          motion (a spin speed imposed as a function of time: b_T = -R_r omega(t)); 0 otherwise.
//          Impulses and projections change W^T v only.
// Forces   f_c = W_N F_N + W_T F_T   (eq. 20); F_N >= 0 pushes the rotor towards the stator centre.
//          The friction power is F_T v_t (<= 0 under Coulomb's law).
// Acceleration level: d(v_N)/dt = W_N^T a + wdot_N,  d(v_t)/dt = W_T^T a + wdot_T, with
//          wdot_N = (dW_N/dt)^T v + db_N/dt = -(t . dsr/dt)^2 / |sr|
//          wdot_T = (dW_T/dt)^T v + db_T/dt = (t . dsr/dt) v_N / |sr|  (+ db_T/dt)
// |sr| = 0 (centred rotor): no normal is defined. Then d_N = g0 > 0, normal_defined = false and
// W_N, W_T, v_N, v_t, wdot_* are zero: no contact can exist there, and no solver may use them.
#include "rubdyn/core/types.hpp"

namespace rubdyn {

struct ContactKinematics {
  ContactKinematics() = default;
  /// Sized for a model with n dofs (W_N, W_T zero).
  explicit ContactKinematics(int n) : W_N(Vec::Zero(n)), W_T(Vec::Zero(n)) {}

  double d_N = 0.0;     ///< gap [m]
  Vec W_N, W_T;         ///< size num_dofs()
  double v_N = 0.0;     ///< normal gap rate [m/s]
  double v_t = 0.0;     ///< relative tangential velocity [m/s]
  double b_N = 0.0;     ///< v_N - W_N^T v (a prescribed motion's share) [m/s]
  double b_T = 0.0;     ///< v_t - W_T^T v [m/s]
  double wdot_N = 0.0;  ///< (dW_N/dt)^T v + db_N/dt [m/s^2]
  double wdot_T = 0.0;  ///< (dW_T/dt)^T v + db_T/dt [m/s^2]
  bool normal_defined = true;
};

}  // namespace rubdyn
