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

  const CampbellPoint rest = CampbellSolver(p).solve(0.0);
  d.f1 = rest.f1b;  // = f1f: double mode
  d.f2 = rest.f2b;
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

}  // namespace rubdyn
