#include "rubdyn/model/rotor_stator_model.hpp"

#include <cmath>

namespace rubdyn {

RotorStatorModel::RotorStatorModel(const RotorStatorParams& p)
    : p_(p), chart_(p.stator.gap, p.rotor.radius) {
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
  detA_ = M11_ * M22_ - M12_ * M12_;
  Minv_s_ = 1.0 / p.stator.mass;
}

void RotorStatorModel::solve_mass(const Vec7& q, Mat7x3& B, int ncols) const {
  // Block elimination of theta (header): A^-1 = [[M22, -M12], [-M12, M11]] / det A on each of
  // the pairs (x_b, x_r) and (y_b, y_r).
  const double a11 = M22_ / detA_, a12 = -M12_ / detA_, a22 = M11_ / detA_;
  const double Hx = 0.5 * H_ * (q[XR] - q[XB]), Hy = -0.5 * H_ * (q[YR] - q[YB]);
  // u = A^-1 b with b = (H_y, H_x, -H_y, -H_x) on (x_b, y_b, x_r, y_r)
  const double ub = a11 - a12, ur = a12 - a22;  // A^-1 (1, -1) on a pair
  const double u_xb = Hy * ub, u_xr = Hy * ur, u_yb = Hx * ub, u_yr = Hx * ur;
  const double schur = p_.rotor.Jp - (Hy * (u_xb - u_xr) + Hx * (u_yb - u_yr));
  for (int j = 0; j < ncols; ++j) {
    auto r = B.col(j);
    const double zxb = a11 * r[XB] + a12 * r[XR], zxr = a12 * r[XB] + a22 * r[XR];
    const double zyb = a11 * r[YB] + a12 * r[YR], zyr = a12 * r[YB] + a22 * r[YR];
    const double th = (r[TH] - (Hy * (zxb - zxr) + Hx * (zyb - zyr))) / schur;
    r[XB] = zxb - u_xb * th;
    r[XR] = zxr - u_xr * th;
    r[YB] = zyb - u_yb * th;
    r[YR] = zyr - u_yr * th;
    r[TH] = th;
    r[XS] *= Minv_s_;
    r[YS] *= Minv_s_;
  }
}

void RotorStatorModel::Chart::chart(ChartMode mode, const Vec7& q, const Vec7& v, Vec7& anchor,
                                    Vec7& p, Vec7& pd) const {
  const double phi = std::atan2(q[YR] - q[YS], q[XR] - q[XS]);
  anchor.setZero();
  p.setZero();
  pd.setZero();
  if (mode == ChartMode::Slip) {
    // phi' from the tangential component of the relative velocity (v_N = 0 on the manifold)
    const double phid = (-std::sin(phi) * (v[XR] - v[XS]) + std::cos(phi) * (v[YR] - v[YS])) / g0_;
    p << q[XB], q[YB], phi, q[TH], q[XS], q[YS], 0.0;
    pd << v[XB], v[YB], phid, v[TH], v[XS], v[YS], 0.0;
  } else {
    anchor[0] = phi;
    anchor[1] = q[TH];
    p << q[XB], q[YB], 0.0, q[XS], q[YS], 0.0, 0.0;
    pd << v[XB], v[YB], v[TH], v[XS], v[YS], 0.0, 0.0;
  }
}

void RotorStatorModel::Chart::embed(ChartMode mode, const Vec7& anchor, const Vec7& p,
                                    const Vec7& pd, Vec7& q, Vec7& v) const {
  double phi, phid, xs, ys, vxs, vys;
  if (mode == ChartMode::Slip) {
    phi = p[2];
    phid = pd[2];
    q[TH] = p[3];
    v[TH] = pd[3];
    xs = p[4], ys = p[5], vxs = pd[4], vys = pd[5];
  } else {
    const double k = R_r_ / g0_;
    phi = anchor[0] - k * p[2];
    phid = -k * pd[2];
    q[TH] = anchor[1] + p[2];
    v[TH] = pd[2];
    xs = p[3], ys = p[4], vxs = pd[3], vys = pd[4];
  }
  const double c = std::cos(phi), s = std::sin(phi);
  q[XB] = p[0];
  q[YB] = p[1];
  q[XS] = xs;
  q[YS] = ys;
  q[XR] = xs + g0_ * c;
  q[YR] = ys + g0_ * s;
  v[XB] = pd[0];
  v[YB] = pd[1];
  v[XS] = vxs;
  v[YS] = vys;
  v[XR] = vxs - g0_ * phid * s;
  v[YR] = vys + g0_ * phid * c;
}

void RotorStatorModel::Chart::reduce(ChartMode mode, const Vec7& /*anchor*/, const Vec7& p,
                                     const Vec7& /*pd*/, const Vec7& q, const Vec7& a,
                                     Vec7& pdd) const {
  pdd.setZero();
  if (mode == ChartMode::Slip) {
    // t_phi . (a_r - a_s) / g0, with t_phi from the embedded q (no second sin/cos)
    const double tx = -(q[YR] - q[YS]) / g0_, ty = (q[XR] - q[XS]) / g0_;
    pdd << a[XB], a[YB], (tx * (a[XR] - a[XS]) + ty * (a[YR] - a[YS])) / g0_, a[TH], a[XS], a[YS],
        0.0;
    (void)p;
  } else {
    pdd << a[XB], a[YB], a[TH], a[XS], a[YS], 0.0, 0.0;
  }
}

ChartScales RotorStatorModel::Chart::scales(ChartMode mode) const {
  ChartScales sc;
  sc.length[2] = mode == ChartMode::Slip ? g0_ : R_r_;
  return sc;
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
