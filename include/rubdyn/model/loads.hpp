#pragma once
// The loads every rotor model takes (case file section [loads]; docs/models.md, section 3):
// gravity, the drive (a torque law on a free spin, or a prescribed spin speed) and a mass
// unbalance. SI units.
#include <string_view>

namespace rubdyn {

/// How the spin is driven.
enum class SpinDrive {
  Torque,     ///< the spin is free, driven by the torque law (loads.spin = "torque")
  Prescribed  ///< omega(t) = omega0 + spin_accel (t - t_start) (loads.spin = "prescribed")
};
/// The drive torque's dependence on the spin speed (free spin).
enum class TorqueLaw {
  Constant,  ///< tau = tau_a
  Linear     ///< tau = tau_a (1 - omega / torque_free_speed): a turbine line
};
std::string_view to_string(SpinDrive d);
std::string_view to_string(TorqueLaw l);

struct LoadParams {
  double gravity = 9.81;  ///< g [m/s^2], along -Y
  double torque = 20.0;   ///< tau_a [N m]: the driving torque (at rest for the linear law)
  TorqueLaw torque_law = TorqueLaw::Constant;
  double torque_free_speed = 0.0;  ///< Omega_0 [rad/s] of the linear law (> 0 when used)
  double unbalance = 0.0;          ///< u_b = m eps [kg m], >= 0
  double unbalance_phase = 0.0;    ///< phi_u [rad]: its angle from X at theta = 0
  SpinDrive spin = SpinDrive::Torque;
  double spin_accel = 0.0;  ///< alpha [rad/s^2] of a prescribed spin

  /// The torque law tau(omega) and its derivative (free spin).
  double drive_torque(double omega) const {
    return torque_law == TorqueLaw::Linear ? torque * (1.0 - omega / torque_free_speed) : torque;
  }
  double drive_torque_slope() const {
    return torque_law == TorqueLaw::Linear ? -torque / torque_free_speed : 0.0;
  }
};

}  // namespace rubdyn
