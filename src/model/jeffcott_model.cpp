#include "rubdyn/model/jeffcott_model.hpp"

#include <cmath>

namespace rubdyn {

std::string_view to_string(SpinDrive d) {
  return d == SpinDrive::Prescribed ? "prescribed" : "torque";
}

std::string_view to_string(TorqueLaw l) {
  return l == TorqueLaw::Linear ? "linear" : "constant";
}

namespace {
/// The contact's geometry: the disc centre inside the ring (x_s, y_s), or the fixed ring at the
/// origin.
RingContact jeffcott_geometry(const JeffcottParams& p) {
  RingContact g;
  g.ix = {JeffcottModel::XR, -1};
  g.iy = {JeffcottModel::YR, -1};
  g.w = {1.0, 0.0};
  g.ring = p.stator.rigid ? -1 : JeffcottModel::XS;
  g.gap = p.stator.gap;
  g.radius = p.rotor.radius;
  return g;
}
}  // namespace

JeffcottModel::JeffcottModel(const JeffcottParams& p)
    : p_(p),
      n_(p.stator.rigid ? 3 : 5),
      chart_(p.stator.gap, p.rotor.radius, p.stator.rigid),
      geom_(jeffcott_geometry(p)),
      ring_chart_(n_, TH, {geom_}) {
  using R = CoordinateRole;
  coords_ = {
      {"x_r", "vx_r", "vx_r", "m", "disc centre (seal circle), horizontal", R::RotorX, 0},
      {"y_r", "vy_r", "vy_r", "m", "disc centre (seal circle), vertical", R::RotorY, 0},
      {"theta", "omega", "omega0", "rad", "spin angle (its rate: the spin speed)", R::Spin, 0},
  };
  if (!p.stator.rigid) {
    coords_.push_back({"x_s", "vx_s", "vx_s", "m", "stator centre, horizontal", R::StatorX, 0});
    coords_.push_back({"y_s", "vy_s", "vy_s", "m", "stator centre, vertical", R::StatorY, 0});
    ms_ = p.stator.mass;
    ks_ = p.stator.k;
    cs_ = p.stator.c;
  }
}

void JeffcottModel::mass_matrix(VecIn q, MatOut M) const {
  const double ub = p_.loads.unbalance, psi = q[TH] + p_.loads.unbalance_phase;
  M.setZero();
  M(XR, XR) = M(YR, YR) = p_.rotor.mass;
  M(TH, TH) = p_.rotor.Jp;
  if (ub != 0.0) {
    M(XR, TH) = M(TH, XR) = -ub * std::sin(psi);
    M(YR, TH) = M(TH, YR) = ub * std::cos(psi);
  }
  if (n_ == 5) M(XS, XS) = M(YS, YS) = ms_;
}

void JeffcottModel::mass_product(VecIn q, VecIn x, VecOut y) const {
  const double m = p_.rotor.mass, J = p_.rotor.Jp, ub = p_.loads.unbalance;
  if (ub == 0.0) {
    y[XR] = m * x[XR];
    y[YR] = m * x[YR];
    y[TH] = J * x[TH];
  } else {
    const double psi = q[TH] + p_.loads.unbalance_phase;
    const double a = -ub * std::sin(psi), b = ub * std::cos(psi);
    y[XR] = m * x[XR] + a * x[TH];
    y[YR] = m * x[YR] + b * x[TH];
    y[TH] = a * x[XR] + b * x[YR] + J * x[TH];
  }
  if (n_ == 5) {
    y[XS] = ms_ * x[XS];
    y[YS] = ms_ * x[YS];
  }
}

void JeffcottModel::solve_mass(VecIn q, MatOut B) const {
  const double m = p_.rotor.mass, J = p_.rotor.Jp, ub = p_.loads.unbalance;
  double a = 0.0, b = 0.0;
  if (ub != 0.0) {
    const double psi = q[TH] + p_.loads.unbalance_phase;
    a = -ub * std::sin(psi);
    b = ub * std::cos(psi);
  }
  const double schur = J - (a * a + b * b) / m;  // = J - u_b^2 / m_r > 0
  for (Eigen::Index j = 0; j < B.cols(); ++j) {
    auto r = B.col(j);
    const double th = (r[TH] - (a * r[XR] + b * r[YR]) / m) / schur;
    r[XR] = (r[XR] - a * th) / m;
    r[YR] = (r[YR] - b * th) / m;
    r[TH] = th;
    if (n_ == 5) {
      r[XS] /= ms_;
      r[YS] /= ms_;
    }
  }
}

void JeffcottModel::mass_matrix_product_jacobian(VecIn q, VecIn a, MatOut J) const {
  // (M a) depends on q only through psi = theta + phi_u (docs/models.md, 1.3)
  J.setZero();
  const double ub = p_.loads.unbalance;
  if (ub == 0.0) return;
  const double psi = q[TH] + p_.loads.unbalance_phase, c = std::cos(psi), s = std::sin(psi);
  J(XR, TH) = -ub * c * a[TH];
  J(YR, TH) = -ub * s * a[TH];
  J(TH, TH) = -ub * c * a[XR] - ub * s * a[YR];
}

void JeffcottModel::smooth_forces(double /*t*/, VecIn q, VecIn v, VecOut f) const {
  const auto& r = p_.rotor;
  const auto& L = p_.loads;
  const double om = v[TH], g = L.gravity;
  f[XR] = -r.c * v[XR] - r.k * q[XR];
  f[YR] = -r.c * v[YR] - r.k * q[YR] - r.mass * g;
  f[TH] = L.drive_torque(om);
  if (L.unbalance != 0.0) {
    const double psi = q[TH] + L.unbalance_phase, c = std::cos(psi), s = std::sin(psi);
    const double cf = L.unbalance * om * om;  // the centrifugal force's magnitude
    f[XR] += cf * c;
    f[YR] += cf * s;
    f[TH] -= L.unbalance * g * c;
  }
  if (n_ == 5) {
    f[XS] = -cs_ * v[XS] - ks_ * q[XS];
    f[YS] = -cs_ * v[YS] - ks_ * q[YS] - ms_ * g;
  }
}

void JeffcottModel::smooth_force_jacobians(double /*t*/, VecIn q, VecIn v, MatOut dfdq,
                                           MatOut dfdv) const {
  const auto& r = p_.rotor;
  const auto& L = p_.loads;
  dfdq.setZero();
  dfdv.setZero();
  dfdq(XR, XR) = dfdq(YR, YR) = -r.k;
  dfdv(XR, XR) = dfdv(YR, YR) = -r.c;
  dfdv(TH, TH) = L.drive_torque_slope();
  if (L.unbalance != 0.0) {
    const double om = v[TH], psi = q[TH] + L.unbalance_phase, c = std::cos(psi), s = std::sin(psi),
                 ub = L.unbalance;
    dfdq(XR, TH) = -ub * om * om * s;
    dfdq(YR, TH) = ub * om * om * c;
    dfdq(TH, TH) = ub * L.gravity * s;
    dfdv(XR, TH) = 2.0 * ub * om * c;
    dfdv(YR, TH) = 2.0 * ub * om * s;
  }
  if (n_ == 5) {
    dfdq(XS, XS) = dfdq(YS, YS) = -ks_;
    dfdv(XS, XS) = dfdv(YS, YS) = -cs_;
  }
}

void JeffcottModel::compute_contact(int /*k*/, double /*t*/, VecIn q, VecIn v,
                                    ContactKinematics& c) const {
  for (int i = 0; i < n_; ++i) c.W_N[i] = c.W_T[i] = 0.0;
  ring_contact_kinematics(geom_, TH, q, v, c);
}

double JeffcottModel::kinetic_energy(double /*t*/, VecIn q, VecIn v) const {
  const auto& r = p_.rotor;
  double T = r.mass * (v[XR] * v[XR] + v[YR] * v[YR]) + r.Jp * v[TH] * v[TH];
  const double ub = p_.loads.unbalance;
  if (ub != 0.0) {
    const double psi = q[TH] + p_.loads.unbalance_phase;
    T += 2.0 * ub * v[TH] * (v[YR] * std::cos(psi) - v[XR] * std::sin(psi));
  }
  if (n_ == 5) T += ms_ * (v[XS] * v[XS] + v[YS] * v[YS]);
  return 0.5 * T;
}

double JeffcottModel::potential_energy(double /*t*/, VecIn q) const {
  const auto& r = p_.rotor;
  const auto& L = p_.loads;
  double V = 0.5 * r.k * (q[XR] * q[XR] + q[YR] * q[YR]) + L.gravity * r.mass * q[YR];
  if (L.unbalance != 0.0) V += L.gravity * L.unbalance * std::sin(q[TH] + L.unbalance_phase);
  if (n_ == 5) V += 0.5 * ks_ * (q[XS] * q[XS] + q[YS] * q[YS]) + L.gravity * ms_ * q[YS];
  return V;
}

SmoothPower JeffcottModel::smooth_power(double /*t*/, VecIn /*q*/, VecIn v) const {
  SmoothPower p;
  p.external = p_.loads.drive_torque(v[TH]) * v[TH];
  p.damping = -p_.rotor.c * (v[XR] * v[XR] + v[YR] * v[YR]);
  if (n_ == 5) p.damping -= cs_ * (v[XS] * v[XS] + v[YS] * v[YS]);
  return p;
}

std::optional<LinearModel> JeffcottModel::linearize(Linearization mode) const {
  LinearModel lm;
  const auto& r = p_.rotor;
  auto node = [&](const char* x, const char* y, double m, double c, double k) {
    const int i = lm.size();
    lm.names.push_back(x);
    lm.names.push_back(y);
    lm.nodes.push_back({i, i + 1});
    lm.M.conservativeResize(i + 2, i + 2);
    lm.D.conservativeResize(i + 2, i + 2);
    lm.K.conservativeResize(i + 2, i + 2);
    for (auto* A : {&lm.M, &lm.D, &lm.K}) {
      A->bottomRows(2).setZero();
      A->rightCols(2).setZero();
    }
    lm.M(i, i) = lm.M(i + 1, i + 1) = m;
    lm.D(i, i) = lm.D(i + 1, i + 1) = c;
    lm.K(i, i) = lm.K(i + 1, i + 1) = k;
  };
  if (mode == Linearization::Tied) {
    // the stator moves with the rotor (a rigid stator pins it: nothing is left to vibrate)
    if (n_ == 5) node("x_r", "y_r", r.mass + ms_, r.c + cs_, r.k + ks_);
  } else {
    node("x_r", "y_r", r.mass, r.c, r.k);
    if (n_ == 5) node("x_s", "y_s", ms_, cs_, ks_);
  }
  const int n = lm.size();
  lm.M.conservativeResize(n, n);
  lm.D.conservativeResize(n, n);
  lm.K.conservativeResize(n, n);
  lm.G = Mat::Zero(n, n);
  return lm;
}

// ---- minimal coordinates of the contact phases ------------------------------------------------

void JeffcottModel::Chart::chart(ChartMode mode, VecIn q, VecIn v, ChartAnchor& anchor, VecOut p,
                                 VecOut pd) const {
  const double xs = rigid_ ? 0.0 : q[XS], ys = rigid_ ? 0.0 : q[YS];
  const double vxs = rigid_ ? 0.0 : v[XS], vys = rigid_ ? 0.0 : v[YS];
  const double phi = std::atan2(q[YR] - ys, q[XR] - xs);
  anchor.fill(0.0);
  int k = 0;
  if (mode == ChartMode::Slip) {
    // phi' from the tangential component of the relative velocity (v_N = 0 on the manifold)
    p[k] = phi;
    pd[k++] = (-std::sin(phi) * (v[XR] - vxs) + std::cos(phi) * (v[YR] - vys)) / g0_;
    p[k] = q[TH];
    pd[k++] = v[TH];
  } else {
    anchor[0] = phi;
    anchor[1] = q[TH];
    p[k] = 0.0;
    pd[k++] = v[TH];
  }
  if (!rigid_) {
    p[k] = xs;
    pd[k++] = vxs;
    p[k] = ys;
    pd[k] = vys;
  }
}

void JeffcottModel::Chart::embed(ChartMode mode, const ChartAnchor& anchor, VecIn p, VecIn pd,
                                 VecOut q, VecOut v) const {
  double phi, phid;
  int k;
  if (mode == ChartMode::Slip) {
    phi = p[0];
    phid = pd[0];
    q[TH] = p[1];
    v[TH] = pd[1];
    k = 2;
  } else {
    const double ratio = R_ / g0_;
    phi = anchor[0] - ratio * p[0];
    phid = -ratio * pd[0];
    q[TH] = anchor[1] + p[0];
    v[TH] = pd[0];
    k = 1;
  }
  double xs = 0.0, ys = 0.0, vxs = 0.0, vys = 0.0;
  if (!rigid_) {
    xs = q[XS] = p[k];
    ys = q[YS] = p[k + 1];
    vxs = v[XS] = pd[k];
    vys = v[YS] = pd[k + 1];
  }
  const double c = std::cos(phi), s = std::sin(phi);
  q[XR] = xs + g0_ * c;
  q[YR] = ys + g0_ * s;
  v[XR] = vxs - g0_ * phid * s;
  v[YR] = vys + g0_ * phid * c;
}

void JeffcottModel::Chart::reduce(ChartMode mode, const ChartAnchor& /*anchor*/, VecIn /*p*/,
                                  VecIn /*pd*/, VecIn q, VecIn a, VecOut pdd) const {
  const double xs = rigid_ ? 0.0 : q[XS], ys = rigid_ ? 0.0 : q[YS];
  const double axs = rigid_ ? 0.0 : a[XS], ays = rigid_ ? 0.0 : a[YS];
  int k = 0;
  if (mode == ChartMode::Slip) {
    // phi'' = t_phi . (a_r - a_s) / g0 (the curvature term is normal to t_phi)
    const double tx = -(q[YR] - ys) / g0_, ty = (q[XR] - xs) / g0_;
    pdd[k++] = (tx * (a[XR] - axs) + ty * (a[YR] - ays)) / g0_;
  }
  pdd[k++] = a[TH];
  if (!rigid_) {
    pdd[k++] = axs;
    pdd[k] = ays;
  }
}

ChartScales JeffcottModel::Chart::scales(ChartMode mode) const {
  // phi moves the contact point by g0 per radian; theta - theta0 in stick by R
  ChartScales sc;
  sc.length.assign(static_cast<std::size_t>(dim(mode)), 0.0);
  sc.length[0] = mode == ChartMode::Slip ? g0_ : R_;
  return sc;
}

}  // namespace rubdyn
