#pragma once
// The rigid rotor on one bearing inside a sprung rigid stator ring (paper, section 3, eq. 9-21).
//
// Coordinates q = (x_b, y_b, x_r, y_r, theta, x_s, y_s): bearing B and contact plane R of the
// rotor (translations), spin angle theta, stator centre. Y is vertical (gravity along -Y).
// Let l = L - delta (B to R), nu = d / l (B to G over B to R), u = x_r - x_b, w = y_r - y_b.
//
// Derivation (short). The small-angle kinematics (eq. 5, 9, 10) give
//   x_G = nu x_r + (1 - nu) x_b,  theta_x = -w / l,  theta_y = u / l,
// and the kinetic energy (eq. 8) becomes (eq. 11)
//   2 T = M11 (xb'^2 + yb'^2) + M22 (xr'^2 + yr'^2) + 2 M12 (xb' xr' + yb' yr') + Jp theta'^2
//         + H theta' (u' w - w' u) + m_s (xs'^2 + ys'^2),
//   M11 = (1-nu)^2 m + Jd/l^2,  M12 = nu (1-nu) m - Jd/l^2,  M22 = nu^2 m + Jd/l^2,  H = Jp/l^2.
// T = 1/2 v^T M(q) v with the only q-dependent entries from the term H theta' (u' w - w' u) / 2:
//   M(theta, x_r) = dT/dtheta' dxr' = H w / 2 = -H_y,   M(theta, x_b) = H_y = -H w / 2,
//   M(theta, y_r) = -H u / 2 = -H_x,                     M(theta, y_b) = H_x = H u / 2    (eq. 14)
// Lagrange's equations, row by row:
//   theta:  d/dt(Jp theta' + H (u' w - w' u)/2) - 0 = Jp theta'' + H (w u'' - u w'')/2
//           (the u'w' terms cancel): the theta row is M(q) row 5 times q'', with NO velocity term.
//   x_r:    d/dt(M22 xr' + M12 xb' + H theta' w / 2) - dT/dx_r
//           = M22 xr'' + M12 xb'' + H w theta''/2 + H theta' w'/2 - (-H theta' w'/2)
//           = [M q'']_xr + H theta' (yr' - yb')                      -> row x_r of theta' G v
//   and likewise for x_b, y_b, y_r. Hence (eq. 13, 16) with G skew-symmetric (eq. 14):
//   M(q) q'' + (theta' G + D) q' + K q = f_ext,   f_ext = (0, -(1-nu) m g, 0, -nu m g, tau_a, 0,
//   0).
// The potential is V = k_b/2 (x_b^2 + y_b^2) + m g (nu y_r + (1-nu) y_b) + k_s/2 (x_s^2 + y_s^2)
// (eq. 12, 15: the stator has no gravity term in the paper; its weight is carried by its
// support at q_s = 0). D holds c_b on (x_b, y_b) and c_s on (x_s, y_s). Since G is skew, the
// gyroscopic forces do no work: d(T+V)/dt = tau_a theta' - v^T D v + F_N v_N + F_T v_t.
// Contact kinematics: see contact/contact_kinematics.hpp (eq. 17-19).
#include <string_view>

#include "rubdyn/model/lagrangian_model.hpp"
#include "rubdyn/model/rotor_stator_params.hpp"

namespace rubdyn {

class RotorStatorModel final : public LagrangianModel {
 public:
  explicit RotorStatorModel(const RotorStatorParams& p);

  std::string_view name() const override { return "rotor-stator"; }
  void mass_matrix(const Vec7& q, Mat7& M) const override;
  void mass_matrix_product_jacobian(const Vec7& q, const Vec7& a, Mat7& J) const override;
  void smooth_forces(double t, const Vec7& q, const Vec7& v, Vec7& f) const override;
  void smooth_force_jacobians(double t, const Vec7& q, const Vec7& v, Mat7& dfdq,
                              Mat7& dfdv) const override;
  ContactKinematics contact(const Vec7& q, const Vec7& v) const override;
  double potential_energy(const Vec7& q) const override;
  SmoothPower smooth_power(double t, const Vec7& q, const Vec7& v) const override;
  double gap_scale() const override { return p_.stator.gap; }
  const ContactLaw& contact_law() const override { return p_.contact; }

  /// Power of the bearing dampers -c_b |v_b|^2 and of the stator dampers -c_s |v_s|^2 [W].
  double bearing_damping_power(const Vec7& v) const;
  double stator_damping_power(const Vec7& v) const;
  /// Power of the driving torque tau_a theta' [W].
  double torque_power(const Vec7& v) const { return p_.loads.torque * v[TH]; }

  const RotorStatorParams& params() const { return p_; }
  double l() const { return l_; }      ///< L - delta [m]
  double nu() const { return nu_; }    ///< d / (L - delta) [-]
  double M11() const { return M11_; }  ///< [kg]
  double M12() const { return M12_; }  ///< [kg]
  double M22() const { return M22_; }  ///< [kg]
  double H() const { return H_; }      ///< Jp / (L - delta)^2 [kg]
  /// Gyroscopic matrix G (eq. 14), constant and skew-symmetric; the force is theta' G v.
  const Mat7& G() const { return G_; }
  /// Damping and stiffness matrices D, K.
  const Mat7& D() const { return D_; }
  const Mat7& K() const { return K_; }
  /// External load vector f_ext (gravity split and driving torque).
  const Vec7& f_ext() const { return fext_; }

 private:
  RotorStatorParams p_;
  double l_, nu_, M11_, M12_, M22_, H_;
  Mat7 G_, D_, K_, M0_;  // M0_: the constant part of M(q)
  Vec7 fext_;
};

}  // namespace rubdyn
