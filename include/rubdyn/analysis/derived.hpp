#pragma once
// Derived quantities of a case (what `rubdyn check` prints).
#include "rubdyn/model/rotor_stator_params.hpp"

namespace rubdyn {

struct DerivedQuantities {
  double l = 0, nu = 0, M11 = 0, M12 = 0, M22 = 0, H = 0;  ///< eq. 11 [m, -, kg, kg, kg, kg]
  // Static equilibrium at rest under gravity. The bearing is translational, so the rotor pivots
  // freely about B: with gravity > 0 it must rest on the stator, at the bottom of the clearance.
  bool rests_on_stator = false;
  double y_b = 0, y_r = 0, y_s = 0;  ///< static positions [m]
  double F_N = 0;                    ///< static contact force nu m g [N]
  // Natural frequencies at rest [Hz]
  double f1 = 0, f2 = 0;       ///< coupled system (stator tied at R), double modes
  double f_stator = 0;         ///< stator alone sqrt(k_s / m_s) / 2 pi
  double f_bearing_rotor = 0;  ///< rotor on its bearing, no stator (the other mode: 0 Hz)
  // Free acceleration from omega0 to omega_lim under tau_a, no contact, no lateral motion
  double t_free_to_omega_lim = 0;  ///< [s]: 0 if omega0 >= omega_lim, inf if never
};

DerivedQuantities derive(const RotorStatorParams& p, double omega0, double omega_lim);

}  // namespace rubdyn
