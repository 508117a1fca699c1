#include "rubdyn/analysis/derived.hpp"

#include <cmath>
#include <limits>
#include <numbers>

#include "rubdyn/analysis/campbell.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"

namespace rubdyn {

std::string_view to_string(FreeAcceleration a) {
  switch (a) {
    case FreeAcceleration::reaches: return "reaches";
    case FreeAcceleration::already_reached: return "already-reached";
    case FreeAcceleration::never: return "never";
  }
  return "?";
}

DerivedQuantities compute_derived_quantities(const RotorStatorParams& p, double omega0,
                                             double omega_lim) {
  const RotorStatorModel m(p);
  DerivedQuantities d;
  d.l = m.l();
  d.nu = m.nu();
  d.M11 = m.M11();
  d.M12 = m.M12();
  d.M22 = m.M22();
  d.H = m.H();

  // statics: see the header (rows x_r, y_r, y_b, y_s of eq. 21 with n = (0, -1))
  const double mg = p.rotor.mass * p.loads.gravity;
  d.rests_on_stator = p.loads.gravity > 0.0;
  d.y_b = -(1.0 - d.nu) * mg / p.bearing.k;
  if (d.rests_on_stator) {
    d.F_N = d.nu * mg;
    d.y_s = -d.F_N / p.stator.k;
    d.y_r = d.y_s - p.stator.gap;
  }
  d.q_static.setZero();
  d.q_static[YB] = d.y_b;
  d.q_static[YR] = d.y_r;
  d.q_static[YS] = d.y_s;

  // the tied system exists only when every ring is sprung: a fixed ring ([[plane]] with
  // stator_rigid) tied to the rotor is a constraint, not a mass and spring (then NaN)
  if (const auto tied = m.linearize(Linearization::Tied)) {
    const CampbellPoint rest = CampbellSolver(*tied).solve(0.0);
    d.f1 = rest.f1b;  // = f1f: double mode
    d.f2 = rest.f2b;
  } else {
    d.f1 = d.f2 = std::numeric_limits<double>::quiet_NaN();
  }
  const double two_pi = 2.0 * std::numbers::pi;
  d.f_stator = std::sqrt(p.stator.k / p.stator.mass) / two_pi;
  d.f_bearing_rotor = std::sqrt(p.bearing.k * d.M22 / (d.M11 * d.M22 - d.M12 * d.M12)) / two_pi;

  if (omega0 >= omega_lim) {
    d.free_acceleration = FreeAcceleration::already_reached;
    d.t_free_to_omega_lim = 0.0;
  } else if (!(p.loads.torque > 0.0)) {
    d.free_acceleration = FreeAcceleration::never;
    d.t_free_to_omega_lim = std::numeric_limits<double>::infinity();
  } else {
    d.free_acceleration = FreeAcceleration::reaches;
    d.t_free_to_omega_lim = (omega_lim - omega0) * p.rotor.Jp / p.loads.torque;
  }
  return d;
}

JeffcottQuantities compute_jeffcott_quantities(const JeffcottParams& p, double omega0,
                                               double omega_lim) {
  const double two_pi = 2.0 * std::numbers::pi, nan = std::numeric_limits<double>::quiet_NaN();
  const auto& r = p.rotor;
  const auto& s = p.stator;
  const auto& L = p.loads;
  JeffcottQuantities d;
  d.f_rotor = std::sqrt(r.k / r.mass) / two_pi;
  d.zeta_rotor = r.c / (2.0 * std::sqrt(r.k * r.mass));
  d.f_stator = d.zeta_stator = d.f_tied = nan;
  if (!s.rigid) {
    d.f_stator = std::sqrt(s.k / s.mass) / two_pi;
    d.zeta_stator = s.c / (2.0 * std::sqrt(s.k * s.mass));
    d.f_tied = std::sqrt((r.k + s.k) / (r.mass + s.mass)) / two_pi;
  }
  // statics (see the header)
  const double g = L.gravity, ks_inv = s.rigid ? 0.0 : 1.0 / s.k;
  d.sag_rotor = -r.mass * g / r.k;
  d.sag_stator = s.rigid ? 0.0 : -s.mass * g * ks_inv;
  const double delta = d.sag_rotor - d.sag_stator;
  d.rests_on_stator = std::abs(delta) > s.gap;
  d.y_r = d.sag_rotor;
  d.y_s = d.sag_stator;
  if (d.rests_on_stator) {
    d.F_N = (std::abs(delta) - s.gap) / (1.0 / r.k + ks_inv);
    const double up = delta < 0.0 ? 1.0 : -1.0;  // the contact force on the rotor: up at the bottom
    d.y_r = (-r.mass * g + up * d.F_N) / r.k;
    d.y_s = s.rigid ? 0.0 : (-s.mass * g - up * d.F_N) * ks_inv;
  }
  // unbalance
  d.eps = L.unbalance / r.mass;
  d.J_G = r.Jp - L.unbalance * L.unbalance / r.mass;
  const double w = omega0, re = r.k - r.mass * w * w, im = r.c * w;
  d.unbalance_orbit = L.unbalance * w * w / std::sqrt(re * re + im * im);
  // rigid stator, rolling under a constant torque
  d.rolling_closed_form =
      s.rigid && r.c > 0.0 && L.spin == SpinDrive::Torque && L.torque_law == TorqueLaw::Constant;
  if (d.rolling_closed_form) {
    const double R = r.radius;
    d.rolling_omega = L.torque / (r.c * R * R);
    d.rolling_whirl = -(R / s.gap) * d.rolling_omega;
    d.rolling_F_N = s.gap * (r.mass * d.rolling_whirl * d.rolling_whirl - r.k);
    d.rolling_time_constant = (r.Jp + r.mass * R * R) / (r.c * R * R);
  }
  const double tau0 = L.spin == SpinDrive::Torque ? L.drive_torque(omega0) : 0.0;
  if (omega0 >= omega_lim) {
    d.free_acceleration = FreeAcceleration::already_reached;
    d.t_free_to_omega_lim = 0.0;
  } else if (L.spin == SpinDrive::Prescribed) {
    d.free_acceleration = L.spin_accel > 0.0 ? FreeAcceleration::reaches : FreeAcceleration::never;
    d.t_free_to_omega_lim = L.spin_accel > 0.0 ? (omega_lim - omega0) / L.spin_accel
                                               : std::numeric_limits<double>::infinity();
  } else if (!(tau0 > 0.0) ||
             (L.torque_law == TorqueLaw::Linear && omega_lim >= L.torque_free_speed)) {
    d.free_acceleration = FreeAcceleration::never;
    d.t_free_to_omega_lim = std::numeric_limits<double>::infinity();
  } else if (L.torque_law == TorqueLaw::Linear) {
    // J Omega' = tau_a (1 - Omega / Omega_0): Omega_0 - Omega decays with J Omega_0 / tau_a
    const double T = r.Jp * L.torque_free_speed / L.torque;
    d.t_free_to_omega_lim =
        T * std::log((L.torque_free_speed - omega0) / (L.torque_free_speed - omega_lim));
  } else {
    d.t_free_to_omega_lim = (omega_lim - omega0) * r.Jp / L.torque;
  }
  return d;
}

}  // namespace rubdyn
