#include "rubdyn/analysis/derived.hpp"

#include <cmath>
#include <limits>
#include <numbers>

#include "rubdyn/analysis/campbell.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"

namespace rubdyn {

DerivedQuantities derive(const RotorStatorParams& p, double omega0, double omega_lim) {
  const RotorStatorModel m(p);
  DerivedQuantities d;
  d.l = m.l();
  d.nu = m.nu();
  d.M11 = m.M11();
  d.M12 = m.M12();
  d.M22 = m.M22();
  d.H = m.H();
  const double mg = p.rotor.mass * p.loads.gravity;
  d.rests_on_stator = p.loads.gravity > 0.0;
  // rows y_b, y_s and y_r of eq. (21) at rest with the contact at the bottom (n = (0, -1)):
  //   k_b y_b = -(1 - nu) m g,   k_s y_s = -F_N,   0 = -nu m g + F_N
  d.F_N = d.rests_on_stator ? d.nu * mg : 0.0;
  d.y_b = -(1.0 - d.nu) * mg / p.bearing.k;
  d.y_s = -d.F_N / p.stator.k;
  d.y_r = d.rests_on_stator ? d.y_s - p.stator.gap : 0.0;
  const CampbellPoint c0 = campbell_point(p, 0.0);
  d.f1 = c0.f1b;
  d.f2 = c0.f2b;
  const double two_pi = 2.0 * std::numbers::pi;
  d.f_stator = std::sqrt(p.stator.k / p.stator.mass) / two_pi;
  // bearing-only rotor: det(K - w^2 M) = 0 with K = diag(k_b, 0): w^2 = k_b M22 / det(M)
  d.f_bearing_rotor = std::sqrt(p.bearing.k * d.M22 / (d.M11 * d.M22 - d.M12 * d.M12)) / two_pi;
  if (omega0 >= omega_lim) {
    d.t_free_to_omega_lim = 0.0;
  } else if (p.loads.torque <= 0.0) {
    d.t_free_to_omega_lim = std::numeric_limits<double>::infinity();
  } else {
    d.t_free_to_omega_lim = (omega_lim - omega0) * p.rotor.Jp / p.loads.torque;
  }
  return d;
}

}  // namespace rubdyn
