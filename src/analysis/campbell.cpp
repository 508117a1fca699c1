#include "rubdyn/analysis/campbell.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "rubdyn/model/rotor_stator_model.hpp"

namespace rubdyn {

namespace {

using Mat8 = Eigen::Matrix<double, 8, 8>;
using cplx = std::complex<double>;

// Two eigenvalues of the scaled first-order form closer than this (relative) are one double
// eigenvalue. The eigen solver's absolute error is ~1e-15 |A| with |A| = O(1) after scaling, so
// 1e-10 is far above round-off; and the relative gyroscopic split of the reference case is
// 1e-4 to 3e-4 times Omega [rad/s], so only |Omega| < ~1e-6 rad/s is merged (error < 1e-10).
constexpr double kDoubleTol = 1e-10;
// A circular (isotropic) mode has purity 1 to round-off. Below this the whirl is mixed: a bug.
constexpr double kMinPurity = 0.5;

struct Mode {
  cplx lam;       // scaled eigenvalue, Im > 0
  double ef, eb;  // forward and backward kinetic energies of the mode shape
};

}  // namespace

CampbellSolver::CampbellSolver(const RotorStatorParams& p, bool damped) : damped_(damped) {
  const RotorStatorModel m(p);
  const double ms = p.stator.mass;
  M_.setZero();
  M_(0, 0) = M_(1, 1) = m.M11();
  M_(2, 2) = M_(3, 3) = m.M22() + ms;
  M_(0, 2) = M_(2, 0) = M_(1, 3) = M_(3, 1) = m.M12();
  G_ = m.G().topLeftCorner<4, 4>();
  D_.setZero();
  if (damped) {
    D_(0, 0) = D_(1, 1) = p.bearing.c;
    D_(2, 2) = D_(3, 3) = p.stator.c;
  }
  K_.setZero();
  K_(0, 0) = K_(1, 1) = p.bearing.k;
  K_(2, 2) = K_(3, 3) = p.stator.k;
  M2_ << m.M11(), m.M12(), m.M12(), m.M22() + ms;

  // First-order form in the scaled state s = (q, q'/w_ref): s' = w_ref A s with
  //   A = [0, I; -M^-1 K / w_ref^2, -M^-1 (Omega G + D) / w_ref],
  // whose entries are O(1): the eigenvalues of A are lambda / w_ref, found to ~1e-15 absolute.
  // w_ref^2 = trace(M^-1 K) / 4 is the mean of the squared natural frequencies at rest.
  const Eigen::LLT<Mat4> llt(M_);
  const Mat4 MiK = llt.solve(K_);
  w_ref_ = std::sqrt(MiK.trace() / 4.0);
  MiK_ = MiK / (w_ref_ * w_ref_);
  MiG_ = llt.solve(G_) / w_ref_;
  MiD_ = llt.solve(D_) / w_ref_;
}

CampbellPoint CampbellSolver::solve(double omega) const {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  CampbellPoint out;
  out.omega = omega;
  out.f1b = out.f1f = out.f2b = out.f2f = nan;  // a missing mode stays NaN
  out.zeta_1b = out.zeta_1f = out.zeta_2b = out.zeta_2f = nan;

  Mat8 A;
  A.topLeftCorner<4, 4>().setZero();
  A.topRightCorner<4, 4>().setIdentity();
  A.bottomLeftCorner<4, 4>() = -MiK_;
  A.bottomRightCorner<4, 4>() = -(omega * MiG_ + MiD_);
  Eigen::EigenSolver<Mat8> es;  // fixed size: no heap allocation
  es.compute(A, /*computeEigenvectors=*/true);
  if (es.info() != Eigen::Success) {
    out.min_whirl_purity = 0.0;
    return out;
  }
  const Eigen::Matrix<cplx, 8, 1> lams = es.eigenvalues();
  const Eigen::Matrix<cplx, 8, 8> V = es.eigenvectors();

  // The oscillating modes (one eigenvalue of each conjugate pair), by increasing frequency, with
  // the forward and backward kinetic energies of their shapes (see the header).
  const cplx I(0.0, 1.0);
  std::array<Mode, 8> modes;
  int n = 0;
  for (int k = 0; k < 8; ++k) {
    if (!(lams[k].imag() > 0.0)) continue;  // conjugate, or real (overdamped, no whirl)
    Eigen::Matrix<cplx, 2, 1> zf, zb;
    zf << V(0, k) + I * V(1, k), V(2, k) + I * V(3, k);
    zb << V(0, k) - I * V(1, k), V(2, k) - I * V(3, k);
    const Mode md{lams[k], std::real(zf.dot(M2_ * zf)), std::real(zb.dot(M2_ * zb))};
    int j = n++;
    for (; j > 0 && modes[j - 1].lam.imag() > md.lam.imag(); --j) modes[j] = modes[j - 1];
    modes[j] = md;
  }

  double f_fw[2] = {}, z_fw[2] = {}, f_bw[2] = {}, z_bw[2] = {};
  int nf = 0, nb = 0;
  const double to_hz = w_ref_ / (2.0 * std::numbers::pi);
  auto zeta = [this](cplx lam) { return damped_ ? -lam.real() / std::abs(lam) : 0.0; };
  auto add = [&](bool forward, cplx lam) {
    int& count = forward ? nf : nb;
    if (count < 2) {
      (forward ? f_fw : f_bw)[count] = lam.imag() * to_hz;
      (forward ? z_fw : z_bw)[count] = zeta(lam);
    }
    ++count;
  };
  for (int i = 0; i < n;) {
    if (i + 1 < n &&
        std::abs(modes[i + 1].lam - modes[i].lam) <= kDoubleTol * std::abs(modes[i].lam)) {
      // a double eigenvalue: the circular basis of its plane, one forward and one backward mode
      const cplx mean = 0.5 * (modes[i].lam + modes[i + 1].lam);
      add(false, mean);
      add(true, mean);
      i += 2;
      continue;
    }
    const Mode& md = modes[i];
    double purity = std::abs(md.ef - md.eb) / (md.ef + md.eb);
    if (!(purity >= 0.0)) purity = 0.0;  // a null or non-finite shape: no whirl to speak of
    out.min_whirl_purity = std::min(out.min_whirl_purity, purity);
    add(md.ef > md.eb, md.lam);
    ++i;
  }
  out.n_forward = nf;
  out.n_backward = nb;
  if (nb > 0) {
    out.f1b = f_bw[0];
    out.zeta_1b = z_bw[0];
  }
  if (nb > 1) {
    out.f2b = f_bw[1];
    out.zeta_2b = z_bw[1];
  }
  if (nf > 0) {
    out.f1f = f_fw[0];
    out.zeta_1f = z_fw[0];
  }
  if (nf > 1) {
    out.f2f = f_fw[1];
    out.zeta_2f = z_fw[1];
  }
  out.labels_ok = nf == 2 && nb == 2 && out.min_whirl_purity >= kMinPurity;
  return out;
}

CampbellPoint solve_campbell_point(const RotorStatorParams& p, double omega, bool damped) {
  return CampbellSolver(p, damped).solve(omega);
}

CampbellDiagram compute_campbell_diagram(const RotorStatorParams& p, double omega_max, int points,
                                         bool damped) {
  if (points < 2)
    throw std::invalid_argument(fmt::format("Campbell diagram: {} points < 2", points));
  if (!(std::isfinite(omega_max) && omega_max > 0.0)) {
    throw std::invalid_argument(
        fmt::format("Campbell diagram: omega_max = {} must be finite and > 0", omega_max));
  }
  const CampbellSolver solver(p, damped);
  CampbellDiagram d;
  d.damped = damped;
  const auto n = static_cast<std::size_t>(points);
  for (auto* v : {&d.omega, &d.f1b, &d.f1f, &d.f2b, &d.f2f}) v->reserve(n);
  if (damped) {
    for (auto* v : {&d.zeta_1b, &d.zeta_1f, &d.zeta_2b, &d.zeta_2f}) v->reserve(n);
  }
  for (int i = 0; i < points; ++i) {
    const double omega =
        i == points - 1 ? omega_max : omega_max * static_cast<double>(i) / (points - 1);
    const CampbellPoint c = solver.solve(omega);
    d.omega.push_back(omega);
    d.f1b.push_back(c.f1b);
    d.f1f.push_back(c.f1f);
    d.f2b.push_back(c.f2b);
    d.f2f.push_back(c.f2f);
    if (damped) {
      d.zeta_1b.push_back(c.zeta_1b);
      d.zeta_1f.push_back(c.zeta_1f);
      d.zeta_2b.push_back(c.zeta_2b);
      d.zeta_2f.push_back(c.zeta_2f);
    }
    if (!c.labels_ok) d.unlabelled.push_back(omega);
  }
  return d;
}

std::string campbell_csv(const CampbellDiagram& d) {
  std::string s = "omega_rad_s,omega_rpm,f1b,f1f,f2b,f2f";
  if (d.damped) s += ",zeta_1b,zeta_1f,zeta_2b,zeta_2f";
  s += '\n';
  for (std::size_t i = 0; i < d.size(); ++i) {
    s += fmt::format("{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}", d.omega[i],
                     d.omega[i] * 30.0 / std::numbers::pi, d.f1b[i], d.f1f[i], d.f2b[i], d.f2f[i]);
    if (d.damped) {
      s += fmt::format(",{:.17g},{:.17g},{:.17g},{:.17g}", d.zeta_1b[i], d.zeta_1f[i], d.zeta_2b[i],
                       d.zeta_2f[i]);
    }
    s += '\n';
  }
  return s;
}

}  // namespace rubdyn
