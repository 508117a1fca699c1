#include "rubdyn/analysis/campbell.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "rubdyn/model/rotor_stator_model.hpp"

namespace rubdyn {

namespace {

using Mat4 = Eigen::Matrix<double, 4, 4>;
using Mat8 = Eigen::Matrix<double, 8, 8>;

struct Coupled {
  Mat4 M, G, D, K;
};

Coupled coupled_system(const RotorStatorParams& p) {
  const RotorStatorModel m(p);
  Coupled c;
  c.M.setZero();
  c.M(0, 0) = c.M(1, 1) = m.M11();
  c.M(2, 2) = c.M(3, 3) = m.M22() + p.stator.mass;
  c.M(0, 2) = c.M(2, 0) = c.M(1, 3) = c.M(3, 1) = m.M12();
  c.G = m.G().topLeftCorner<4, 4>();
  c.D.setZero();
  c.D(0, 0) = c.D(1, 1) = p.bearing.c;
  c.D(2, 2) = c.D(3, 3) = p.stator.c;
  c.K.setZero();
  c.K(0, 0) = c.K(1, 1) = p.bearing.k;
  c.K(2, 2) = c.K(3, 3) = p.stator.k;
  return c;
}

}  // namespace

CampbellPoint campbell_point(const RotorStatorParams& p, double omega, bool damped) {
  const Coupled c = coupled_system(p);
  const Mat4 Minv = c.M.inverse();
  Mat8 A;
  A.setZero();
  A.topRightCorner<4, 4>().setIdentity();
  A.bottomLeftCorner<4, 4>() = -Minv * c.K;
  A.bottomRightCorner<4, 4>() = -Minv * (omega * c.G + (damped ? c.D : Mat4::Zero()));
  const Eigen::EigenSolver<Mat8> es(A, true);
  const Eigen::Matrix<std::complex<double>, 8, 1> lams = es.eigenvalues();
  const Eigen::Matrix<std::complex<double>, 8, 8> V = es.eigenvectors();
  struct Mode {
    double f = 0, zeta = 0;
    bool forward = false;
  };
  Mode modes[8];
  int n = 0;
  const std::complex<double> I(0.0, 1.0);
  for (int k = 0; k < 8; ++k) {
    const std::complex<double> lam = lams[k];
    if (lam.imag() <= 0.0) continue;  // one of each conjugate pair
    double fw = 0.0, bw = 0.0;
    for (int node = 0; node < 2; ++node) {
      const std::complex<double> X = V(2 * node, k), Y = V(2 * node + 1, k);
      fw += std::norm(X + I * Y);
      bw += std::norm(X - I * Y);
    }
    Mode m{lam.imag() / (2.0 * std::numbers::pi), -lam.real() / std::abs(lam), fw > bw};
    int j = n++;  // insertion by increasing frequency
    for (; j > 0 && modes[j - 1].f > m.f; --j) modes[j] = modes[j - 1];
    modes[j] = m;
  }
  CampbellPoint out;
  out.omega = omega;
  if (omega == 0.0 && n == 4) {
    // double modes: forward and backward coincide
    out.f1b = out.f1f = modes[0].f;
    out.f2b = out.f2f = modes[2].f;
    out.z1b = out.z1f = damped ? modes[0].zeta : 0.0;
    out.z2b = out.z2f = damped ? modes[2].zeta : 0.0;
    return out;
  }
  int nb = 0, nf = 0;
  for (int k = 0; k < n; ++k) {
    const Mode& m = modes[k];
    const double z = damped ? m.zeta : 0.0;
    if (m.forward) {
      (nf == 0 ? out.f1f : out.f2f) = m.f;
      (nf == 0 ? out.z1f : out.z2f) = z;
      ++nf;
    } else {
      (nb == 0 ? out.f1b : out.f2b) = m.f;
      (nb == 0 ? out.z1b : out.z2b) = z;
      ++nb;
    }
    if (nf > 2 || nb > 2) break;
  }
  out.labels_ok = n == 4 && nf == 2 && nb == 2;
  return out;
}

std::vector<CampbellPoint> campbell_diagram(const RotorStatorParams& p, double omega_max,
                                            int points, bool damped) {
  std::vector<CampbellPoint> d;
  d.reserve(static_cast<std::size_t>(points));
  for (int i = 0; i < points; ++i) {
    const double omega = omega_max * static_cast<double>(i) / static_cast<double>(points - 1);
    d.push_back(campbell_point(p, omega, damped));
  }
  return d;
}

std::string campbell_csv(const std::vector<CampbellPoint>& d, bool damped) {
  std::string s = "omega_rad_s,omega_rpm,f1b,f1f,f2b,f2f";
  if (damped) s += ",zeta_1b,zeta_1f,zeta_2b,zeta_2f";
  s += "\n";
  for (const auto& c : d) {
    s += fmt::format("{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}", c.omega,
                     c.omega * 30.0 / std::numbers::pi, c.f1b, c.f1f, c.f2b, c.f2f);
    if (damped) s += fmt::format(",{:.17g},{:.17g},{:.17g},{:.17g}", c.z1b, c.z1f, c.z2b, c.z2f);
    s += "\n";
  }
  return s;
}

}  // namespace rubdyn
