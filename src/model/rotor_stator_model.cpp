#include "rubdyn/model/rotor_stator_model.hpp"

#include <algorithm>
#include <cmath>

namespace rubdyn {

namespace {

const std::vector<Coordinate>& single_plane_coordinates() {
  using R = CoordinateRole;
  static const std::vector<Coordinate> c = {
      {"x_b", "vx_b", "vx_b", "m", "bearing B, horizontal", R::BearingX, 0},
      {"y_b", "vy_b", "vy_b", "m", "bearing B, vertical", R::BearingY, 0},
      {"x_r", "vx_r", "vx_r", "m", "rotor centre in the contact plane R, horizontal", R::RotorX, 0},
      {"y_r", "vy_r", "vy_r", "m", "rotor centre in the contact plane R, vertical", R::RotorY, 0},
      {"theta", "omega", "omega0", "rad", "spin angle (its rate: the spin speed)", R::Spin, 0},
      {"x_s", "vx_s", "vx_s", "m", "stator centre, horizontal", R::StatorX, 0},
      {"y_s", "vy_s", "vy_s", "m", "stator centre, vertical", R::StatorY, 0},
  };
  return c;
}

}  // namespace

std::vector<Coordinate> RotorStatorModel::coordinates_of(const RotorStatorParams& p) {
  if (p.planes.empty()) return single_plane_coordinates();
  using R = CoordinateRole;
  // the rotor's coordinates as in the single-plane model (R: L - delta from B, the point the
  // paper's coordinates describe; roles RotorX/Y of plane 0 name it for the ensembles' offset),
  // then each sprung ring's centre, in plane order
  std::vector<Coordinate> c(single_plane_coordinates().begin(),
                            single_plane_coordinates().begin() + 5);
  c[2].meaning = "rotor centre at R (L - delta from the bearing B), horizontal";
  c[3].meaning = "rotor centre at R (L - delta from the bearing B), vertical";
  for (std::size_t k = 0; k < p.planes.size(); ++k) {
    if (p.planes[k].rigid) continue;
    const std::string n = std::to_string(k + 1);
    const int plane = static_cast<int>(k);
    c.push_back({"x_s_" + n, "vx_s_" + n, "vx_s_" + n, "m",
                 "centre of plane " + n + "'s ring, horizontal", R::StatorX, plane});
    c.push_back({"y_s_" + n, "vy_s_" + n, "vy_s_" + n, "m",
                 "centre of plane " + n + "'s ring, vertical", R::StatorY, plane});
  }
  return c;
}

const std::vector<Coordinate>& RotorStatorModel::coordinates() const {
  return single_ ? single_plane_coordinates() : coords_;
}

RotorStatorModel::RotorStatorModel(const RotorStatorParams& p)
    : p_(p),
      chart_(p.planes.empty() ? p.stator.gap : p.planes[0].gap,
             p.planes.empty() ? p.rotor.radius : p.planes[0].radius),
      single_(p.planes.empty()) {
  const auto& r = p.rotor;
  l_ = r.L - r.delta;
  nu_ = r.d / l_;
  // the planes and their rings (without planes: the paper's one plane at R on [stator])
  if (single_) {
    rings_.push_back({XS, p.stator.mass, p.stator.k, p.stator.c, 1.0 / p.stator.mass});
    inv_ms_ = 1.0 / p.stator.mass;
    planes_.push_back({1.0, true, p.rotor.radius, p.stator.gap, p.contact, XS, {}});
    n_ = kDofs;
  } else {
    n_ = 5;
    for (const PlaneParams& pl : p.planes) {
      Plane g;
      g.s = pl.position / l_;
      g.at_R = g.s == 1.0;
      g.radius = pl.radius;
      g.gap = pl.gap;
      g.law = pl.contact;
      if (!pl.rigid) {
        g.ring = n_;
        rings_.push_back({n_, pl.mass, pl.k, pl.c, 1.0 / pl.mass});
        n_ += 2;
      }
      planes_.push_back(g);
    }
    coords_ = coordinates_of(p);
  }
  // the chart parametrises one plane at R on a sprung ring in (x_s, y_s) = dofs 5, 6: the
  // paper's model, or one [[plane]] that is exactly it
  chartable_ = planes_.size() == 1 && planes_[0].at_R && planes_[0].ring == XS;
  // each plane's point (eq. 9-10) and ring: its contact kinematics and the K-contact chart
  for (Plane& pl : planes_) {
    RingContact& c = pl.geom;
    if (pl.at_R) {
      c.ix = {XR, -1};
      c.iy = {YR, -1};
      c.w = {1.0, 0.0};
    } else {
      c.ix = {XB, XR};
      c.iy = {YB, YR};
      c.w = {1.0 - pl.s, pl.s};
    }
    c.ring = pl.ring;
    c.gap = pl.gap;
    c.radius = pl.radius;
  }
  {  // every plane, one included (a prescribed spin charts the paper's plane with it)
    std::vector<RingContact> rc;
    for (const Plane& pl : planes_) rc.push_back(pl.geom);
    ring_chart_.emplace(n_, TH, std::move(rc));
  }
  const double jl = r.Jd / (l_ * l_);
  M11_ = (1.0 - nu_) * (1.0 - nu_) * r.mass + jl;
  M12_ = nu_ * (1.0 - nu_) * r.mass - jl;
  M22_ = nu_ * nu_ * r.mass + jl;
  H_ = r.Jp / (l_ * l_);

  M0_.setZero(n_, n_);
  M0_(XB, XB) = M0_(YB, YB) = M11_;
  M0_(XR, XR) = M0_(YR, YR) = M22_;
  M0_(XB, XR) = M0_(XR, XB) = M12_;
  M0_(YB, YR) = M0_(YR, YB) = M12_;
  M0_(TH, TH) = r.Jp;
  for (const Ring& g : rings_) M0_(g.dof, g.dof) = M0_(g.dof + 1, g.dof + 1) = g.mass;

  G_.setZero(n_, n_);
  G_(XB, YB) = H_;
  G_(XB, YR) = -H_;
  G_(YB, XB) = -H_;
  G_(YB, XR) = H_;
  G_(XR, YB) = -H_;
  G_(XR, YR) = H_;
  G_(YR, XB) = H_;
  G_(YR, XR) = -H_;

  D_.setZero(n_, n_);
  D_(XB, XB) = D_(YB, YB) = p.bearing.c;
  K_.setZero(n_, n_);
  K_(XB, XB) = K_(YB, YB) = p.bearing.k;
  for (const Ring& g : rings_) {
    D_(g.dof, g.dof) = D_(g.dof + 1, g.dof + 1) = g.c;
    K_(g.dof, g.dof) = K_(g.dof + 1, g.dof + 1) = g.k;
  }

  const double mg = r.mass * p.loads.gravity;
  fext_.setZero(n_);
  fext_[YB] = -(1.0 - nu_) * mg;
  fext_[YR] = -nu_ * mg;
  fext_[TH] = p.loads.torque;
  ub_ = p.loads.unbalance;
  phi_u_ = p.loads.unbalance_phase;
  if (n_ == kDofs) {  // the fixed-size fast paths (mass_matrix, smooth_force_jacobians)
    M0f_ = M0_;
    Gf_ = G_;
    Df_ = D_;
    Kf_ = K_;
  }
  detA_ = M11_ * M22_ - M12_ * M12_;
}

void RotorStatorModel::solve_mass(VecIn q, MatOut B) const {
  // Block elimination of theta (header): A^-1 = [[M22, -M12], [-M12, M11]] / det A on each of
  // the pairs (x_b, x_r) and (y_b, y_r).
  const double a11 = M22_ / detA_, a12 = -M12_ / detA_, a22 = M11_ / detA_;
  const double Hx = 0.5 * H_ * (q[XR] - q[XB]), Hy = -0.5 * H_ * (q[YR] - q[YB]);
  if (ub_ != 0.0) {
    // with an unbalance the theta column is b = (H_y - (1-nu) u_b sin psi, H_x + (1-nu) u_b cos
    // psi, -H_y - nu u_b sin psi, -H_x + nu u_b cos psi): u = A^-1 b in general form
    const double psi = q[TH] + phi_u_, us = ub_ * std::sin(psi), uc = ub_ * std::cos(psi);
    const double bxb = Hy - (1.0 - nu_) * us, byb = Hx + (1.0 - nu_) * uc;
    const double bxr = -Hy - nu_ * us, byr = -Hx + nu_ * uc;
    const double u_xb = a11 * bxb + a12 * bxr, u_xr = a12 * bxb + a22 * bxr;
    const double u_yb = a11 * byb + a12 * byr, u_yr = a12 * byb + a22 * byr;
    const double schur = p_.rotor.Jp - (bxb * u_xb + bxr * u_xr + byb * u_yb + byr * u_yr);
    for (Eigen::Index j = 0; j < B.cols(); ++j) {
      auto r = B.col(j);
      const double zxb = a11 * r[XB] + a12 * r[XR], zxr = a12 * r[XB] + a22 * r[XR];
      const double zyb = a11 * r[YB] + a12 * r[YR], zyr = a12 * r[YB] + a22 * r[YR];
      const double th = (r[TH] - (bxb * zxb + bxr * zxr + byb * zyb + byr * zyr)) / schur;
      r[XB] = zxb - u_xb * th;
      r[XR] = zxr - u_xr * th;
      r[YB] = zyb - u_yb * th;
      r[YR] = zyr - u_yr * th;
      r[TH] = th;
      scale_rings(r);
    }
    return;
  }
  // u = A^-1 b with b = (H_y, H_x, -H_y, -H_x) on (x_b, y_b, x_r, y_r)
  const double ub = a11 - a12, ur = a12 - a22;  // A^-1 (1, -1) on a pair
  const double u_xb = Hy * ub, u_xr = Hy * ur, u_yb = Hx * ub, u_yr = Hx * ur;
  const double schur = p_.rotor.Jp - (Hy * (u_xb - u_xr) + Hx * (u_yb - u_yr));
  for (Eigen::Index j = 0; j < B.cols(); ++j) {
    auto r = B.col(j);
    const double zxb = a11 * r[XB] + a12 * r[XR], zxr = a12 * r[XB] + a22 * r[XR];
    const double zyb = a11 * r[YB] + a12 * r[YR], zyr = a12 * r[YB] + a22 * r[YR];
    const double th = (r[TH] - (Hy * (zxb - zxr) + Hx * (zyb - zyr))) / schur;
    r[XB] = zxb - u_xb * th;
    r[XR] = zxr - u_xr * th;
    r[YB] = zyb - u_yb * th;
    r[YR] = zyr - u_yr * th;
    r[TH] = th;
    scale_rings(r);
  }
}

void RotorStatorModel::Chart::chart(ChartMode mode, VecIn q, VecIn v, ChartAnchor& anchor, VecOut p,
                                    VecOut pd) const {
  const double phi = std::atan2(q[YR] - q[YS], q[XR] - q[XS]);
  anchor.fill(0.0);
  if (mode == ChartMode::Slip) {
    // phi' from the tangential component of the relative velocity (v_N = 0 on the manifold)
    const double phid = (-std::sin(phi) * (v[XR] - v[XS]) + std::cos(phi) * (v[YR] - v[YS])) / g0_;
    p << q[XB], q[YB], phi, q[TH], q[XS], q[YS];
    pd << v[XB], v[YB], phid, v[TH], v[XS], v[YS];
  } else {
    anchor[0] = phi;
    anchor[1] = q[TH];
    p << q[XB], q[YB], 0.0, q[XS], q[YS];
    pd << v[XB], v[YB], v[TH], v[XS], v[YS];
  }
}

void RotorStatorModel::Chart::embed(ChartMode mode, const ChartAnchor& anchor, VecIn p, VecIn pd,
                                    VecOut q, VecOut v) const {
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

void RotorStatorModel::Chart::reduce(ChartMode mode, const ChartAnchor& /*anchor*/, VecIn /*p*/,
                                     VecIn /*pd*/, VecIn q, VecIn a, VecOut pdd) const {
  if (mode == ChartMode::Slip) {
    // t_phi . (a_r - a_s) / g0, with t_phi from the embedded q (no second sin/cos)
    const double tx = -(q[YR] - q[YS]) / g0_, ty = (q[XR] - q[XS]) / g0_;
    pdd << a[XB], a[YB], (tx * (a[XR] - a[XS]) + ty * (a[YR] - a[YS])) / g0_, a[TH], a[XS], a[YS];
  } else {
    pdd << a[XB], a[YB], a[TH], a[XS], a[YS];
  }
}

ChartScales RotorStatorModel::Chart::scales(ChartMode mode) const {
  ChartScales sc;
  sc.length.assign(static_cast<std::size_t>(dim(mode)), 0.0);
  sc.length[2] = mode == ChartMode::Slip ? g0_ : R_r_;
  return sc;
}

void RotorStatorModel::mass_matrix(VecIn q, MatOut M) const {
  // (a fixed-size copy when M is contiguous: unrolled, where an assignment to a Ref of unknown
  // outer stride is a loop)
  if (n_ == kDofs && M.outerStride() == kDofs) {
    Eigen::Map<Eigen::Matrix<double, kDofs, kDofs>>(M.data()) = M0f_;
  } else if (n_ == kTwoPlaneDofs && M.outerStride() == kTwoPlaneDofs) {
    // two planes on sprung rings (the 9-dof fixed-size steppers): the same copy, unrolled
    using M9 = Eigen::Matrix<double, kTwoPlaneDofs, kTwoPlaneDofs>;
    Eigen::Map<M9>(M.data()) = Eigen::Map<const M9>(M0_.data());
  } else {
    M = M0_;
  }
  const double Hx = 0.5 * H_ * (q[XR] - q[XB]);
  const double Hy = -0.5 * H_ * (q[YR] - q[YB]);
  M(XB, TH) = M(TH, XB) = Hy;
  M(YB, TH) = M(TH, YB) = Hx;
  M(XR, TH) = M(TH, XR) = -Hy;
  M(YR, TH) = M(TH, YR) = -Hx;
  if (ub_ != 0.0) {
    // the unbalance in the plane of G (docs/models.md, 2.3)
    const double psi = q[TH] + phi_u_, us = ub_ * std::sin(psi), uc = ub_ * std::cos(psi);
    M(XB, TH) = M(TH, XB) = Hy - (1.0 - nu_) * us;
    M(YB, TH) = M(TH, YB) = Hx + (1.0 - nu_) * uc;
    M(XR, TH) = M(TH, XR) = -Hy - nu_ * us;
    M(YR, TH) = M(TH, YR) = -Hx + nu_ * uc;
  }
}

void RotorStatorModel::mass_product(VecIn q, VecIn x, VecOut y) const {
  // M(q) x with the structure of M (header). Each row sums its terms in column order, as a dense
  // product does (the zero terms add nothing), so that the result is that of M(q) * x.
  const double Hx = 0.5 * H_ * (q[XR] - q[XB]), Hy = -0.5 * H_ * (q[YR] - q[YB]);
  y[XB] = M11_ * x[XB] + M12_ * x[XR] + Hy * x[TH];
  y[YB] = M11_ * x[YB] + M12_ * x[YR] + Hx * x[TH];
  y[XR] = M12_ * x[XB] + M22_ * x[XR] + -Hy * x[TH];
  y[YR] = M12_ * x[YB] + M22_ * x[YR] + -Hx * x[TH];
  y[TH] = Hy * x[XB] + Hx * x[YB] + -Hy * x[XR] + -Hx * x[YR] + p_.rotor.Jp * x[TH];
  if (single_) {
    y[XS] = p_.stator.mass * x[XS];
    y[YS] = p_.stator.mass * x[YS];
  } else {
    for (const Ring& g : rings_) {
      y[g.dof] = g.mass * x[g.dof];
      y[g.dof + 1] = g.mass * x[g.dof + 1];
    }
  }
  if (ub_ != 0.0) {
    const double psi = q[TH] + phi_u_, us = ub_ * std::sin(psi), uc = ub_ * std::cos(psi);
    const double bxb = -(1.0 - nu_) * us, byb = (1.0 - nu_) * uc, bxr = -nu_ * us,
                 byr = nu_ * uc;  // the unbalance's share of the theta column
    y[XB] += bxb * x[TH];
    y[YB] += byb * x[TH];
    y[XR] += bxr * x[TH];
    y[YR] += byr * x[TH];
    y[TH] += bxb * x[XB] + byb * x[YB] + bxr * x[XR] + byr * x[YR];
  }
}

void RotorStatorModel::mass_matrix_product_jacobian(VecIn q, VecIn a, MatOut J) const {
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
  if (ub_ != 0.0) {
    // d/dtheta of the unbalance's theta column b(psi) times a_theta, and of b . a_lateral
    const double psi = q[TH] + phi_u_, us = ub_ * std::sin(psi), uc = ub_ * std::cos(psi);
    J(XB, TH) += -(1.0 - nu_) * uc * a[TH];
    J(YB, TH) += -(1.0 - nu_) * us * a[TH];
    J(XR, TH) += -nu_ * uc * a[TH];
    J(YR, TH) += -nu_ * us * a[TH];
    J(TH, TH) += -((1.0 - nu_) * (uc * a[XB] + us * a[YB]) + nu_ * (uc * a[XR] + us * a[YR]));
  }
}

void RotorStatorModel::smooth_forces(double /*t*/, VecIn q, VecIn v, VecOut f) const {
  // f = f_ext - theta' G v - D v - K q, written out (G, D, K are sparse).
  const double Hw = H_ * v[TH];
  const double cb = p_.bearing.c, kb = p_.bearing.k;
  f[XB] = -Hw * (v[YB] - v[YR]) - cb * v[XB] - kb * q[XB];
  f[YB] = fext_[YB] - Hw * (v[XR] - v[XB]) - cb * v[YB] - kb * q[YB];
  f[XR] = -Hw * (v[YR] - v[YB]);
  f[YR] = fext_[YR] - Hw * (v[XB] - v[XR]);
  f[TH] = p_.loads.drive_torque(v[TH]);  // (fext_[TH] for the constant law)
  if (single_) {                         // (fixed indices: the hot path of the one-plane model)
    const double cs = p_.stator.c, ks = p_.stator.k;
    f[XS] = -cs * v[XS] - ks * q[XS];
    f[YS] = -cs * v[YS] - ks * q[YS];
  } else {
    for (const Ring& g : rings_) {
      f[g.dof] = -g.c * v[g.dof] - g.k * q[g.dof];
      f[g.dof + 1] = -g.c * v[g.dof + 1] - g.k * q[g.dof + 1];
    }
  }
  if (ub_ != 0.0) {
    // the centrifugal force u_b Omega^2 e^{i psi}, split (1 - nu) to B and nu to R, and
    // gravity's torque (docs/models.md, 2.3)
    const double psi = q[TH] + phi_u_, c = std::cos(psi), s = std::sin(psi);
    const double cf = ub_ * v[TH] * v[TH];
    f[XB] += (1.0 - nu_) * cf * c;
    f[YB] += (1.0 - nu_) * cf * s;
    f[XR] += nu_ * cf * c;
    f[YR] += nu_ * cf * s;
    f[TH] -= ub_ * p_.loads.gravity * c;
  }
}

void RotorStatorModel::smooth_force_jacobians(double /*t*/, VecIn q, VecIn v, MatOut dfdq,
                                              MatOut dfdv) const {
  if (ub_ != 0.0 || p_.loads.torque_law != TorqueLaw::Constant) {
    dfdq = -K_;
    dfdv = -v[TH] * G_ - D_;
    // (the product into the column, then its sign: -(G v) as one expression would be evaluated
    // into a temporary, an allocation per Jacobian)
    dfdv.col(TH).noalias() = G_ * v;
    dfdv.col(TH) = -dfdv.col(TH);
    dfdv(TH, TH) += p_.loads.drive_torque_slope();
    if (ub_ != 0.0) {
      const double psi = q[TH] + phi_u_, c = std::cos(psi), s = std::sin(psi), om = v[TH];
      const double cf = ub_ * om * om, w[4] = {1.0 - nu_, 1.0 - nu_, nu_, nu_};
      const int xs[2] = {XB, XR}, ys[2] = {YB, YR};
      for (int k = 0; k < 2; ++k) {
        dfdq(xs[k], TH) += -w[2 * k] * cf * s;
        dfdq(ys[k], TH) += w[2 * k] * cf * c;
        dfdv(xs[k], TH) += 2.0 * w[2 * k] * ub_ * om * c;
        dfdv(ys[k], TH) += 2.0 * w[2 * k] * ub_ * om * s;
      }
      dfdq(TH, TH) += ub_ * p_.loads.gravity * s;
    }
    return;
  }
  if (n_ == kDofs && dfdq.outerStride() == kDofs && dfdv.outerStride() == kDofs) {
    // contiguous: the fixed-size matrices (unrolled; the steppers' fast path)
    using M7 = Eigen::Matrix<double, kDofs, kDofs>;
    Eigen::Map<M7> Q(dfdq.data()), V(dfdv.data());
    const Eigen::Map<const Eigen::Matrix<double, kDofs, 1>> v7(v.data());
    Q = -Kf_;
    V = -v[TH] * Gf_ - Df_;
    V.col(TH) = -(Gf_ * v7);  // d(theta' G v)/d(theta') = G v
    return;
  }
  if (n_ == kTwoPlaneDofs && dfdq.outerStride() == kTwoPlaneDofs &&
      dfdv.outerStride() == kTwoPlaneDofs) {
    // two planes on sprung rings: the element-wise assignments fixed-size (unrolled: as loops
    // over a Ref they were 3/4 of a Carpenter contact step's Jacobian cost), the same numbers
    using M9 = Eigen::Matrix<double, kTwoPlaneDofs, kTwoPlaneDofs>;
    Eigen::Map<M9> Q(dfdq.data()), V(dfdv.data());
    Q = -Eigen::Map<const M9>(K_.data());
    V = -v[TH] * Eigen::Map<const M9>(G_.data()) - Eigen::Map<const M9>(D_.data());
  } else {
    dfdq = -K_;
    dfdv = -v[TH] * G_ - D_;
  }
  dfdv.col(TH).noalias() = G_ * v;
  dfdv.col(TH) = -dfdv.col(TH);
}

void RotorStatorModel::plane_contact(int k, VecIn q, VecIn v, ContactKinematics& c) const {
  const Plane& pl = planes_[static_cast<std::size_t>(k)];
  // every entry of W_N and W_T written (the zeros too: no memset call in this hot path): the
  // rings (none but this plane's), ring by ring, since a loop over every coordinate after the
  // spin became two memset calls (measured: 38 % of this function's instructions); B's entries
  // for a plane at R; the rest by the one ring-contact kinematics
  double* wn = c.W_N.data();
  double* wt = c.W_T.data();
  for (const Ring& rg : rings_) wn[rg.dof] = wn[rg.dof + 1] = wt[rg.dof] = wt[rg.dof + 1] = 0.0;
  if (pl.at_R) wn[XB] = wn[YB] = wt[XB] = wt[YB] = 0.0;
  ring_contact_kinematics(pl.geom, TH, q, v, c);
}

void RotorStatorModel::compute_contact(int k, double /*t*/, VecIn q, VecIn v,
                                       ContactKinematics& c) const {
  if (!single_) {
    plane_contact(k, q, v, c);
    return;
  }
  // the paper's plane at R on the ring of [stator], with fixed indices: B's entries are 0
  double* wn = c.W_N.data();
  double* wt = c.W_T.data();
  wn[XB] = wn[YB] = wt[XB] = wt[YB] = 0.0;
  ring_contact_kinematics(planes_[0].geom, TH, q, v, c);
}

bool RotorStatorModel::plane_motion(int k, double /*t*/, VecIn q, VecIn v, PlaneMotion& out) const {
  const Plane& pl = planes_[static_cast<std::size_t>(k)];
  const double s = pl.s, sb = 1.0 - s;
  if (pl.at_R) {
    out.rotor = {q[XR], q[YR]};
    out.rotor_rate = {v[XR], v[YR]};
  } else {
    out.rotor = {sb * q[XB] + s * q[XR], sb * q[YB] + s * q[YR]};
    out.rotor_rate = {sb * v[XB] + s * v[XR], sb * v[YB] + s * v[YR]};
  }
  const int d = pl.ring;
  out.stator = d >= 0 ? Vec2(q[d], q[d + 1]) : Vec2::Zero();
  out.stator_rate = d >= 0 ? Vec2(v[d], v[d + 1]) : Vec2::Zero();
  return true;
}

double RotorStatorModel::kinetic_energy(double /*t*/, VecIn q, VecIn v) const {
  // 1/2 v^T M(q) v with the structure of M (header): the rotor's 2x2 blocks, the spin and its
  // coupling through H_x, H_y, the stator.
  const double Hx = 0.5 * H_ * (q[XR] - q[XB]), Hy = -0.5 * H_ * (q[YR] - q[YB]);
  const double rot = M11_ * (v[XB] * v[XB] + v[YB] * v[YB]) +
                     2.0 * M12_ * (v[XB] * v[XR] + v[YB] * v[YR]) +
                     M22_ * (v[XR] * v[XR] + v[YR] * v[YR]);
  const double spin =
      p_.rotor.Jp * v[TH] * v[TH] + 2.0 * v[TH] * (Hy * (v[XB] - v[XR]) + Hx * (v[YB] - v[YR]));
  double stator = 0.0;
  for (const Ring& g : rings_)
    stator += g.mass * (v[g.dof] * v[g.dof] + v[g.dof + 1] * v[g.dof + 1]);
  double unb = 0.0;
  if (ub_ != 0.0) {
    const double psi = q[TH] + phi_u_, c = std::cos(psi), s = std::sin(psi);
    unb =
        2.0 * ub_ * v[TH] * ((1.0 - nu_) * (v[YB] * c - v[XB] * s) + nu_ * (v[YR] * c - v[XR] * s));
  }
  return 0.5 * (rot + spin + stator + unb);
}

double RotorStatorModel::potential_energy(double /*t*/, VecIn q) const {
  const double mg = p_.rotor.mass * p_.loads.gravity;
  double rings = 0.0;
  for (const Ring& g : rings_)
    rings += 0.5 * g.k * (q[g.dof] * q[g.dof] + q[g.dof + 1] * q[g.dof + 1]);
  return 0.5 * p_.bearing.k * (q[XB] * q[XB] + q[YB] * q[YB]) +
         mg * (nu_ * q[YR] + (1.0 - nu_) * q[YB]) + rings +
         (ub_ != 0.0 ? p_.loads.gravity * ub_ * std::sin(q[TH] + phi_u_) : 0.0);
}

double RotorStatorModel::bearing_damping_power(VecIn v) const {
  return -p_.bearing.c * (v[XB] * v[XB] + v[YB] * v[YB]);
}

double RotorStatorModel::stator_damping_power(VecIn v) const {
  double P = 0.0;
  for (const Ring& g : rings_) P += -g.c * (v[g.dof] * v[g.dof] + v[g.dof + 1] * v[g.dof + 1]);
  return P;
}

SmoothPower RotorStatorModel::smooth_power(double /*t*/, VecIn /*q*/, VecIn v) const {
  return {torque_power(v), bearing_damping_power(v) + stator_damping_power(v)};
}

std::optional<LinearModel> RotorStatorModel::linearize(Linearization mode) const {
  // About the centred position (H_x = H_y = 0: the spin row decouples) with the spin imposed.
  LinearModel lm;
  const bool tied = mode == Linearization::Tied;
  // a fixed ring tied to the rotor is a constraint on its point, not a term of M, D or K
  if (tied)
    for (const Plane& pl : planes_)
      if (pl.ring < 0) return std::nullopt;
  // the coordinates kept: the rotor's lateral ones, and the rings' unless they are tied
  std::vector<int> idx = {XB, YB, XR, YR};
  if (!tied)
    for (const Ring& g : rings_) idx.insert(idx.end(), {g.dof, g.dof + 1});
  const int n = static_cast<int>(idx.size());
  for (int i : idx) lm.names.push_back(coordinates()[static_cast<std::size_t>(i)].name);
  lm.M.setZero(n, n);
  lm.G.setZero(n, n);
  lm.D.setZero(n, n);
  lm.K.setZero(n, n);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      lm.M(a, b) = M0_(idx[a], idx[b]);
      lm.G(a, b) = G_(idx[a], idx[b]);
      lm.D(a, b) = D_(idx[a], idx[b]);
      lm.K(a, b) = K_(idx[a], idx[b]);
    }
  if (tied) {
    // each ring tied to the rotor's point of its plane, x_s = (1 - s) x_b + s x_r (likewise y):
    // its mass, damper and spring enter through the weights w = (1 - s, s) on (x_b, x_r); at R
    // (s = 1) only on x_r
    for (const Plane& pl : planes_) {
      const Ring* g = nullptr;
      for (const Ring& r : rings_)
        if (r.dof == pl.ring) g = &r;
      const double w[2] = {1.0 - pl.s, pl.s};
      for (int axis = 0; axis < 2; ++axis)
        for (int i = 0; i < 2; ++i)
          for (int j = 0; j < 2; ++j) {
            if (pl.at_R && (i == 0 || j == 0)) continue;
            const int a = 2 * i + axis, b = 2 * j + axis;
            lm.M(a, b) += w[i] * w[j] * g->mass;
            lm.D(a, b) += w[i] * w[j] * g->c;
            lm.K(a, b) += w[i] * w[j] * g->k;
          }
    }
    lm.nodes = {{0, 1}, {2, 3}};
  } else {
    lm.nodes = {{0, 1}, {2, 3}};
    for (int k = 4; k < n; k += 2) lm.nodes.push_back({k, k + 1});
  }
  return lm;
}

}  // namespace rubdyn
