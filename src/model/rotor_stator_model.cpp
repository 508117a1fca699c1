#include "rubdyn/model/rotor_stator_model.hpp"

#include <cmath>

namespace rubdyn {

RotorStatorModel::RotorStatorModel(const RotorStatorParams& p) : p_(p) {
  const auto& r = p.rotor;
  l_ = r.L - r.delta;
  nu_ = r.d / l_;
  const double jl = r.Jd / (l_ * l_);
  M11_ = (1.0 - nu_) * (1.0 - nu_) * r.mass + jl;
  M12_ = nu_ * (1.0 - nu_) * r.mass - jl;
  M22_ = nu_ * nu_ * r.mass + jl;
  H_ = r.Jp / (l_ * l_);

  M0_.setZero();
  M0_(XB, XB) = M0_(YB, YB) = M11_;
  M0_(XR, XR) = M0_(YR, YR) = M22_;
  M0_(XB, XR) = M0_(XR, XB) = M12_;
  M0_(YB, YR) = M0_(YR, YB) = M12_;
  M0_(TH, TH) = r.Jp;
  M0_(XS, XS) = M0_(YS, YS) = p.stator.mass;

  G_.setZero();
  G_(XB, YB) = H_;
  G_(XB, YR) = -H_;
  G_(YB, XB) = -H_;
  G_(YB, XR) = H_;
  G_(XR, YB) = -H_;
  G_(XR, YR) = H_;
  G_(YR, XB) = H_;
  G_(YR, XR) = -H_;

  D_.setZero();
  D_(XB, XB) = D_(YB, YB) = p.bearing.c;
  D_(XS, XS) = D_(YS, YS) = p.stator.c;
  K_.setZero();
  K_(XB, XB) = K_(YB, YB) = p.bearing.k;
  K_(XS, XS) = K_(YS, YS) = p.stator.k;

  const double mg = r.mass * p.loads.gravity;
  fext_.setZero();
  fext_[YB] = -(1.0 - nu_) * mg;
  fext_[YR] = -nu_ * mg;
  fext_[TH] = p.loads.torque;
}

void RotorStatorModel::mass_matrix(const Vec7& q, Mat7& M) const {
  M = M0_;
  const double Hx = 0.5 * H_ * (q[XR] - q[XB]);
  const double Hy = -0.5 * H_ * (q[YR] - q[YB]);
  M(XB, TH) = M(TH, XB) = Hy;
  M(YB, TH) = M(TH, YB) = Hx;
  M(XR, TH) = M(TH, XR) = -Hy;
  M(YR, TH) = M(TH, YR) = -Hx;
}

void RotorStatorModel::mass_matrix_product_jacobian(const Vec7& /*q*/, const Vec7& a,
                                                    Mat7& J) const {
  // (M a) depends on q only through H_x = H (x_r - x_b)/2 and H_y = -H (y_r - y_b)/2.
  const double h = 0.5 * H_;
  J.setZero();
  J(XB, YB) = h * a[TH];
  J(XB, YR) = -h * a[TH];
  J(YB, XR) = h * a[TH];
  J(YB, XB) = -h * a[TH];
  J(XR, YB) = -h * a[TH];
  J(XR, YR) = h * a[TH];
  J(YR, XR) = -h * a[TH];
  J(YR, XB) = h * a[TH];
  // row theta: H_y (a_xb - a_xr) + H_x (a_yb - a_yr)
  J(TH, YB) = h * (a[XB] - a[XR]);
  J(TH, YR) = -h * (a[XB] - a[XR]);
  J(TH, XR) = h * (a[YB] - a[YR]);
  J(TH, XB) = -h * (a[YB] - a[YR]);
}

void RotorStatorModel::smooth_forces(double /*t*/, const Vec7& q, const Vec7& v, Vec7& f) const {
  // f = f_ext - theta' G v - D v - K q, written out (G, D, K are sparse).
  const double Hw = H_ * v[TH];
  const double cb = p_.bearing.c, cs = p_.stator.c, kb = p_.bearing.k, ks = p_.stator.k;
  f[XB] = -Hw * (v[YB] - v[YR]) - cb * v[XB] - kb * q[XB];
  f[YB] = fext_[YB] - Hw * (v[XR] - v[XB]) - cb * v[YB] - kb * q[YB];
  f[XR] = -Hw * (v[YR] - v[YB]);
  f[YR] = fext_[YR] - Hw * (v[XB] - v[XR]);
  f[TH] = fext_[TH];
  f[XS] = -cs * v[XS] - ks * q[XS];
  f[YS] = -cs * v[YS] - ks * q[YS];
}

void RotorStatorModel::smooth_force_jacobians(double /*t*/, const Vec7& /*q*/, const Vec7& v,
                                              Mat7& dfdq, Mat7& dfdv) const {
  dfdq = -K_;
  dfdv = -v[TH] * G_ - D_;
  dfdv.col(TH) = -(G_ * v);  // d(theta' G v)/d(theta') = G v
}

ContactKinematics RotorStatorModel::contact(const Vec7& q, const Vec7& v) const {
  ContactKinematics c;
  const double sx = q[XR] - q[XS], sy = q[YR] - q[YS];
  // sqrt instead of hypot: positions are O(1e-3) m at most, no overflow or underflow is
  // possible, and hypot's extra precision costs ~2x in the hot path of every solver
  const double rho = std::sqrt(sx * sx + sy * sy);
  c.d_N = p_.stator.gap - rho;
  if (rho == 0.0) {  // centred rotor: no normal; d_N = g0 > 0, so no contact can exist here
    c.normal_defined = false;
    return c;
  }
  const double nx = sx / rho, ny = sy / rho;
  const double tx = ny, ty = -nx;
  c.W_N[XR] = -nx;
  c.W_N[YR] = -ny;
  c.W_N[XS] = nx;
  c.W_N[YS] = ny;
  c.W_T[XR] = tx;
  c.W_T[YR] = ty;
  c.W_T[TH] = -p_.rotor.radius;
  c.W_T[XS] = -tx;
  c.W_T[YS] = -ty;
  const double dvx = v[XR] - v[XS], dvy = v[YR] - v[YS];
  const double wn = nx * dvx + ny * dvy;  // n . dsr/dt
  const double wt = tx * dvx + ty * dvy;  // t . dsr/dt
  c.v_N = -wn;
  c.v_t = wt - p_.rotor.radius * v[TH];
  c.wdot_N = -wt * wt / rho;
  c.wdot_T = wt * c.v_N / rho;
  return c;
}

double RotorStatorModel::potential_energy(const Vec7& q) const {
  const double mg = p_.rotor.mass * p_.loads.gravity;
  return 0.5 * p_.bearing.k * (q[XB] * q[XB] + q[YB] * q[YB]) +
         mg * (nu_ * q[YR] + (1.0 - nu_) * q[YB]) +
         0.5 * p_.stator.k * (q[XS] * q[XS] + q[YS] * q[YS]);
}

double RotorStatorModel::bearing_damping_power(const Vec7& v) const {
  return -p_.bearing.c * (v[XB] * v[XB] + v[YB] * v[YB]);
}

double RotorStatorModel::stator_damping_power(const Vec7& v) const {
  return -p_.stator.c * (v[XS] * v[XS] + v[YS] * v[YS]);
}

SmoothPower RotorStatorModel::smooth_power(double /*t*/, const Vec7& /*q*/, const Vec7& v) const {
  return {torque_power(v), bearing_damping_power(v) + stator_damping_power(v)};
}

}  // namespace rubdyn
