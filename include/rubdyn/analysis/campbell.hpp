#pragma once
// Campbell diagram of the coupled rotor-stator system (paper, section 5.1.2, Fig. 8).
//
// The stator is tied to the rotor at R (x_s = x_r, y_s = y_r): its mass is added to M22 on x_r
// and y_r, k_s and c_s act on x_r and y_r. The spin theta' = Omega is imposed and the mass matrix
// is taken at the centred position (H_x = H_y = 0: the theta row decouples). The 4-dof system
//     M4 q'' + (Omega G4 + D4) q' + K4 q = 0,   q = (x_b, y_b, x_r, y_r),
// has four modes of positive frequency. Forward and backward are told apart by the whirl of the
// mode shape, not by sorting: for a mode q = Re(Q e^{i w t}) (w > 0) and a node with complex
// amplitudes X, Y, the whirl z = x + i y splits into a forward part (X + iY) e^{i w t}/2 turning
// with the spin (counterclockwise for Omega > 0) and a backward part (X - iY)^* e^{-i w t}/2;
// a mode is forward when sum over both nodes of |X + iY|^2 exceeds that of |X - iY|^2. Within
// each direction, index 1 is the lower frequency. At Omega = 0 the modes are double (any
// combination of x and y is a mode): f1b = f1f and f2b = f2f there.
#include <array>
#include <string>
#include <vector>

#include "rubdyn/model/rotor_stator_params.hpp"

namespace rubdyn {

struct CampbellPoint {
  double omega = 0.0;                         ///< spin speed [rad/s]
  double f1b = 0, f1f = 0, f2b = 0, f2f = 0;  ///< frequencies [Hz]
  double z1b = 0, z1f = 0, z2b = 0, z2f = 0;  ///< damping ratios (0 when undamped)
  bool labels_ok = true;                      ///< exactly two forward and two backward modes found
};

/// The four frequencies (and damping ratios) at one spin speed. No allocation.
CampbellPoint campbell_point(const RotorStatorParams& p, double omega, bool damped = false);

/// The diagram on a uniform grid of `points` speeds from 0 to omega_max.
std::vector<CampbellPoint> campbell_diagram(const RotorStatorParams& p, double omega_max,
                                            int points, bool damped = false);

/// campbell.csv text: omega_rad_s, omega_rpm, f1b, f1f, f2b, f2f [, zeta_1b, ...].
std::string campbell_csv(const std::vector<CampbellPoint>& d, bool damped);

}  // namespace rubdyn
