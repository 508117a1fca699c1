// Campbell diagram and derived quantities against hand computations.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "rubdyn/analysis/campbell.hpp"
#include "rubdyn/analysis/derived.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"

using namespace rubdyn;

namespace {
// Reference parameters by hand: l = 0.4, nu = 0.75, Jd/l^2 = 0.21875,
// M11 = 0.0625*5 + 0.21875 = 0.53125, M12 = 0.1875*5 - 0.21875 = 0.71875,
// M22 = 0.5625*5 + 0.21875 = 3.03125, H = 0.06 / 0.16 = 0.375.
constexpr double kM11 = 0.53125, kM12 = 0.71875, kM22 = 3.03125, kH = 0.375;

// Omega = 0, one direction: det(K - w^2 M) = 0 with M = [[M11, M12], [M12, M22 + m_s]],
// K = diag(k_b, k_s): a w^4 - b w^2 + c = 0 with a = det M, b = k_b (M22 + m_s) + k_s M11,
// c = k_b k_s.
std::pair<double, double> closed_form_rest(double kb, double ks, double ms) {
  const double a = kM11 * (kM22 + ms) - kM12 * kM12, b = kb * (kM22 + ms) + ks * kM11, c = kb * ks;
  const double disc = std::sqrt(b * b - 4 * a * c);
  const double w1 = std::sqrt((b - disc) / (2 * a)), w2 = std::sqrt((b + disc) / (2 * a));
  return {w1 / (2 * std::numbers::pi), w2 / (2 * std::numbers::pi)};
}
}  // namespace

TEST_CASE("Derived quantities of the reference case", "[check]") {
  const RotorStatorParams p;
  const DerivedQuantities d = derive(p, 2000.0, 2110.0);
  CHECK(d.l == Approx(0.4).epsilon(1e-15));
  CHECK(d.nu == Approx(0.75).epsilon(1e-15));
  CHECK(d.M11 == Approx(kM11).epsilon(1e-15));
  CHECK(d.M12 == Approx(kM12).epsilon(1e-15));
  CHECK(d.M22 == Approx(kM22).epsilon(1e-15));
  CHECK(d.H == Approx(kH).epsilon(1e-15));
  // statics: F_N = nu m g = 0.75 * 5 * 9.81 = 36.7875 N, y_b = -0.25*49.05/5e6,
  // y_s = -36.7875/2e6, y_r = y_s - 2e-4
  CHECK(d.rests_on_stator);
  CHECK(d.F_N == Approx(36.7875).epsilon(1e-14));
  CHECK(d.y_b == Approx(-0.25 * 49.05 / 5e6).epsilon(1e-14));
  CHECK(d.y_s == Approx(-36.7875 / 2e6).epsilon(1e-14));
  CHECK(d.y_r == Approx(-36.7875 / 2e6 - 2e-4).epsilon(1e-14));
  // (2110 - 2000) * 0.06 / 20 = 0.33 s
  CHECK(d.t_free_to_omega_lim == Approx(0.33).epsilon(1e-14));
  CHECK(d.f_stator == Approx(std::sqrt(1e6) / (2 * std::numbers::pi)).epsilon(1e-14));
  const auto [f1, f2] = closed_form_rest(5e6, 2e6, 2.0);
  CHECK(d.f1 == Approx(f1).epsilon(1e-10));
  CHECK(d.f2 == Approx(f2).epsilon(1e-10));
}

TEST_CASE("The static equilibrium satisfies the equations of motion", "[check]") {
  const RotorStatorParams p;
  const RotorStatorModel m(p);
  const DerivedQuantities d = derive(p, 0.0, 1.0);
  Vec7 q = Vec7::Zero(), v = Vec7::Zero();
  q[YB] = d.y_b;
  q[YR] = d.y_r;
  q[YS] = d.y_s;
  Vec7 f;
  m.smooth_forces(0.0, q, v, f);
  const auto c = m.contact(q, v);
  Vec7 res = f + c.W_N * d.F_N;
  res[TH] = 0.0;  // the torque row (tau_a drives the spin; the statics are lateral)
  // forces are ~40 N: round-off ~1e-14 N; d_N = 0 to round-off of positions ~2e-4 m
  CHECK(res.head<4>().norm() < 1e-12);
  CHECK(res.tail<2>().norm() < 1e-12);
  CHECK(std::abs(c.d_N) < 1e-18);
}

TEST_CASE("Campbell at rest matches the closed-form 2x2 problem - for several stators",
          "[campbell]") {
  for (double scale : {0.5, 1.0, 8.0}) {
    RotorStatorParams p;
    p.stator.k *= scale;
    const auto [f1, f2] = closed_form_rest(p.bearing.k, p.stator.k, p.stator.mass);
    const CampbellPoint c = campbell_point(p, 0.0);
    // the eigen solver of an 8x8 matrix: relative accuracy ~1e-13 on these frequencies
    CHECK(c.f1b == Approx(f1).epsilon(1e-10));
    CHECK(c.f1f == Approx(f1).epsilon(1e-10));
    CHECK(c.f2b == Approx(f2).epsilon(1e-10));
    CHECK(c.f2f == Approx(f2).epsilon(1e-10));
  }
}

TEST_CASE("Forward and backward split symmetrically for small Omega", "[campbell]") {
  const RotorStatorParams p;
  const CampbellPoint c0 = campbell_point(p, 0.0);
  // The gyroscopic split is first order in Omega, the asymmetry second order: at Omega and
  // Omega/2 the asymmetry (f_f + f_b - 2 f0) must drop by ~4 while the split drops by ~2.
  const double Om = 20.0;
  const CampbellPoint a = campbell_point(p, Om), b = campbell_point(p, Om / 2);
  const double split_a = a.f1f - a.f1b, split_b = b.f1f - b.f1b;
  const double asym_a = a.f1f + a.f1b - 2 * c0.f1b, asym_b = b.f1f + b.f1b - 2 * c0.f1b;
  REQUIRE(split_a > 0);
  CHECK(split_a / split_b == Approx(2.0).epsilon(1e-3));
  CHECK(std::abs(asym_a) < 1e-2 * split_a);
  CHECK(asym_a / asym_b == Approx(4.0).epsilon(1e-2));
}

TEST_CASE("Labels are consistent along the grid: continuous curves - forward rise - backward fall",
          "[campbell]") {
  const RotorStatorParams p;
  const auto d = campbell_diagram(p, 2110.0, 201);
  REQUIRE(d.size() == 201);
  for (std::size_t i = 1; i < d.size(); ++i) {
    const auto& x = d[i - 1];
    const auto& y = d[i];
    REQUIRE(y.labels_ok);
    // forward curves rise, backward curves fall with the spin (gyroscopic stiffening/softening)
    CHECK(y.f1f > x.f1f);
    CHECK(y.f2f > x.f2f);
    CHECK(y.f1b < x.f1b);
    CHECK(y.f2b < x.f2b);
    if (i < 2) continue;
    // continuity: each curve follows its own linear extrapolation from the two previous points
    // far more closely than the distance to any other curve (a swapped label would jump by at
    // least that distance)
    const auto& w = d[i - 2];
    const double fy[4] = {y.f1b, y.f1f, y.f2b, y.f2f}, fx[4] = {x.f1b, x.f1f, x.f2b, x.f2f},
                 fw[4] = {w.f1b, w.f1f, w.f2b, w.f2f};
    double closest = 1e300;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) closest = std::min(closest, std::abs(fy[a] - fy[b]));
    for (int a = 0; a < 4; ++a) CHECK(std::abs(fy[a] - (2 * fx[a] - fw[a])) < 0.1 * closest);
  }
  // the first backward mode at omega_lim: about 88 Hz (shared/spec/reference-case.toml)
  CHECK(d.back().f1b == Approx(88.0).margin(1.0));
}

TEST_CASE("Damped Campbell: positive damping ratios - frequencies close to undamped",
          "[campbell]") {
  const RotorStatorParams p;
  const CampbellPoint u = campbell_point(p, 1000.0), dmp = campbell_point(p, 1000.0, true);
  REQUIRE(dmp.labels_ok);
  for (double z : {dmp.z1b, dmp.z1f, dmp.z2b, dmp.z2f}) {
    CHECK(z > 0.0);
    CHECK(z < 0.2);  // light damping (c_b = 300, c_s = 100 N s/m)
  }
  // the damped frequency of a lightly damped mode is w sqrt(1 - zeta^2) (to first order)
  CHECK(dmp.f1b == Approx(u.f1b).epsilon(0.02));
  CHECK(dmp.f2f == Approx(u.f2f).epsilon(0.02));
}
