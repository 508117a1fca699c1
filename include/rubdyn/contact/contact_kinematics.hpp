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
#include <array>
#include <cmath>

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

/// One ring contact's geometry: a rotor point P inside a ring of centre S. Every model's contacts
/// are of this kind (the rigid rotor's planes, the Jeffcott disc, a matrices model's nodes), and
/// the K-contact chart (ring_chart.hpp) parametrises them.
struct RingContact {
  /// The rotor's point: x = sum_j w[j] q[ix[j]], y = sum_j w[j] q[iy[j]] (unused terms: -1).
  std::array<int, 2> ix{-1, -1}, iy{-1, -1};
  std::array<double, 2> w{0.0, 0.0};
  int ring = -1;        ///< the ring's x coordinate (y: ring + 1); -1: a fixed ring
  double gap = 0.0;     ///< g_k [m]
  double radius = 0.0;  ///< R_k, the seal radius (the spin's entry of W_T is -R_k) [m]
};

/// The one ring-contact kinematics (the header's formulas, paper eq. 17-19) of geometry g with the
/// spin at coordinate `spin`: d_N, v_N, v_t, wdot_N, wdot_T, normal_defined, and the entries of
/// W_N and W_T at the point's coordinates, the spin and the ring (0 when no normal is defined).
/// The other entries of W_N and W_T are the caller's to set to 0 (a model knows which of them
/// can be non-zero: the rigid rotor clears only its rings'). The point's coordinates of the two
/// terms must differ from the ring's and the spin. b_N = b_T = 0 (nothing prescribed).
inline void ring_contact_kinematics(const RingContact& g, int spin, VecIn q, VecIn v,
                                    ContactKinematics& c) {
  double* wn = c.W_N.data();
  double* wt = c.W_T.data();
  c.b_N = c.b_T = 0.0;
  const bool two = g.ix[1] >= 0;
  const double px = two ? g.w[0] * q[g.ix[0]] + g.w[1] * q[g.ix[1]] : g.w[0] * q[g.ix[0]];
  const double py = two ? g.w[0] * q[g.iy[0]] + g.w[1] * q[g.iy[1]] : g.w[0] * q[g.iy[0]];
  const int d = g.ring;
  const double sx = px - (d >= 0 ? q[d] : 0.0), sy = py - (d >= 0 ? q[d + 1] : 0.0);
  // sqrt instead of hypot: positions are O(1e-3) m at most, no overflow or underflow is
  // possible, and hypot's extra precision costs ~2x in the hot path of every solver
  const double rho = std::sqrt(sx * sx + sy * sy);
  c.d_N = g.gap - rho;
  auto set = [&](double* w, int i, double x) {
    if (i >= 0) w[i] = x;
  };
  if (rho == 0.0) {  // centred: no normal; d_N = g0 > 0, so no contact can exist here
    c.normal_defined = false;
    for (int j = 0; j < 2; ++j) {
      set(wn, g.ix[j], 0.0);
      set(wn, g.iy[j], 0.0);
      set(wt, g.ix[j], 0.0);
      set(wt, g.iy[j], 0.0);
    }
    set(wn, spin, 0.0);
    set(wt, spin, 0.0);
    if (d >= 0) wn[d] = wn[d + 1] = wt[d] = wt[d + 1] = 0.0;
    c.v_N = c.v_t = c.wdot_N = c.wdot_T = 0.0;
    return;
  }
  c.normal_defined = true;
  const double nx = sx / rho, ny = sy / rho;
  const double tx = ny, ty = -nx;
  set(wn, spin, 0.0);
  for (int j = 0; j < (two ? 2 : 1); ++j) {
    const double w = g.w[static_cast<std::size_t>(j)];
    wn[g.ix[j]] = -w * nx;
    wn[g.iy[j]] = -w * ny;
    wt[g.ix[j]] = w * tx;
    wt[g.iy[j]] = w * ty;
  }
  set(wt, spin, -g.radius);
  if (d >= 0) {
    wn[d] = nx;
    wn[d + 1] = ny;
    wt[d] = -tx;
    wt[d + 1] = -ty;
  }
  const double vpx = two ? g.w[0] * v[g.ix[0]] + g.w[1] * v[g.ix[1]] : g.w[0] * v[g.ix[0]];
  const double vpy = two ? g.w[0] * v[g.iy[0]] + g.w[1] * v[g.iy[1]] : g.w[0] * v[g.iy[0]];
  const double dvx = vpx - (d >= 0 ? v[d] : 0.0), dvy = vpy - (d >= 0 ? v[d + 1] : 0.0);
  const double vn = nx * dvx + ny * dvy;  // n . dsr/dt
  const double vt = tx * dvx + ty * dvy;  // t . dsr/dt
  c.v_N = -vn;
  c.v_t = vt - (spin >= 0 ? g.radius * v[spin] : 0.0);
  c.wdot_N = -vt * vt / rho;
  c.wdot_T = vt * c.v_N / rho;
}

}  // namespace rubdyn
