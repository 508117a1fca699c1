// The rotor-stator model's structured mass solve and its minimal coordinates of the contact
// phases (contact/contact_chart.hpp), checked against independent computations: a dense
// factorisation of M(q), the contact kinematics of the full model, and finite differences of
// the embedding along a motion.
#include <Eigen/Cholesky>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "rubdyn/model/rotor_stator_model.hpp"

using namespace rubdyn;

namespace {

struct ManifoldStates {
  std::mt19937_64 rng{2024};
  double u() { return std::uniform_real_distribution<double>(-1.0, 1.0)(rng); }
  /// A state on the contact manifold of `mode`: the rotor centre on the clearance circle,
  /// v_N = 0, and v_t = 0 for stick.
  void make(const RotorStatorModel& m, ChartMode mode, Vec& q, Vec& v) {
    q.resize(7);
    v.resize(7);
    const double g0 = m.params().stator.gap, Rr = m.params().rotor.radius;
    const double phi = 3.0 * u(), th = 40.0 * u();
    q << 0.3 * g0 * u(), 0.3 * g0 * u(), 0, 0, th, 0.3 * g0 * u(), 0.3 * g0 * u();
    q[XR] = q[XS] + g0 * std::cos(phi);
    q[YR] = q[YS] + g0 * std::sin(phi);
    const double omega = 2000.0 + 300.0 * u();
    // v_t = -g0 phi' - R_r omega: rolling needs phi' = -(R_r / g0) omega
    const double phid = mode == ChartMode::Stick ? -Rr / g0 * omega : 500.0 * u();
    v << 0.1 * u(), 0.1 * u(), 0, 0, omega, 0.1 * u(), 0.1 * u();
    v[XR] = v[XS] - g0 * phid * std::sin(phi);
    v[YR] = v[YS] + g0 * phid * std::cos(phi);
  }
};

}  // namespace

TEST_CASE("Structured mass solve equals a dense factorisation of M(q)", "[model]") {
  const RotorStatorModel model(RotorStatorParams{});
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    Vec q(7);
    for (int i = 0; i < 7; ++i) q[i] = 4e-4 * u(rng);
    q[TH] = 100.0 * u(rng);
    Mat B(7, 3);
    for (int i = 0; i < 7; ++i)
      for (int j = 0; j < 3; ++j) B(i, j) = 1e3 * u(rng);
    Mat M(7, 7);
    model.mass_matrix(q, M);
    const Mat X_ref = M.ldlt().solve(B);
    Mat X = B;
    model.solve_mass(q, X);
    // Both solves are backward stable; M is well conditioned (its entries span 1e-2 .. 5 kg), so
    // they agree to a few hundred ulps of the solution's size.
    CHECK((X - X_ref).norm() <= 1e-13 * X_ref.norm());
    // fewer columns: the others are left alone
    Mat Y = B;
    model.solve_mass(q, Y.leftCols(1));
    CHECK((Y.col(0) - X_ref.col(0)).norm() <= 1e-13 * X_ref.col(0).norm());
    CHECK(Y.col(1) == B.col(1));
  }
}

TEST_CASE("Contact chart: the embedding stays on the constraints and inverts the chart",
          "[model][contact]") {
  const RotorStatorModel model(RotorStatorParams{});
  const ContactChart& chart = *model.contact_chart();
  const double g0 = model.params().stator.gap;
  ManifoldStates gen;
  for (ChartMode mode : {ChartMode::Slip, ChartMode::Stick}) {
    INFO((mode == ChartMode::Slip ? "slip" : "stick"));
    CHECK(chart.dim(mode) == (mode == ChartMode::Slip ? 6 : 5));
    for (int trial = 0; trial < 100; ++trial) {
      const int d = chart.dim(mode);
      Vec q, v, p(d), pd(d), q2(7), v2(7);
      ChartAnchor anchor;
      gen.make(model, mode, q, v);
      chart.chart(mode, q, v, anchor, p, pd);
      chart.embed(mode, anchor, p, pd, q2, v2);
      // round trip to round-off: positions O(g0), spin angle O(40 rad), speeds O(100 m/s)
      CHECK((q2 - q).cwiseAbs().maxCoeff() <= 1e-15 * (40.0 + g0));
      CHECK((v2 - v).cwiseAbs().maxCoeff() <= 1e-12);
      // any reduced state embeds onto the manifold: d_N = 0, v_N = 0 (and v_t = 0 in stick)
      for (int i = 0; i < chart.dim(mode); ++i) {
        p[i] += (i == 2 ? 0.5 : 1e-5) * gen.u();
        pd[i] += (i == 2 && mode == ChartMode::Slip ? 100.0 : 0.05) * gen.u();
      }
      chart.embed(mode, anchor, p, pd, q2, v2);
      const ContactKinematics c = model.contact(0, 0.0, q2, v2);
      // d_N = g0 - sqrt(sx^2 + sy^2) with sx, sy = g0 (cos, sin): a few ulps of g0
      CHECK(std::abs(c.d_N) <= 8 * 2.2e-16 * g0);
      CHECK(std::abs(c.v_N) <= 1e-15 * (1.0 + v2.head<4>().norm()));
      // |v_t| is a difference of terms of R_r omega ~ 100 m/s: zero to its round-off
      if (mode == ChartMode::Stick) CHECK(std::abs(c.v_t) <= 1e-13);
    }
  }
}

TEST_CASE("Contact chart: v = J p' and a = J p'' + c by finite differences along a motion",
          "[model][contact]") {
  // A motion p(t) = p + p' t + p'' t^2 / 2 in reduced coordinates. Its embedding's velocity
  // (central differences of q(t)) must equal the embedded v, and the embedding's acceleration
  // (central differences of v(t)) must reduce back to p''.
  const RotorStatorModel model(RotorStatorParams{});
  const ContactChart& chart = *model.contact_chart();
  ManifoldStates gen;
  for (ChartMode mode : {ChartMode::Slip, ChartMode::Stick}) {
    INFO((mode == ChartMode::Slip ? "slip" : "stick"));
    for (int trial = 0; trial < 50; ++trial) {
      const int d = chart.dim(mode);
      Vec q, v, p(d), pd(d), pdd = Vec::Zero(d);
      ChartAnchor anchor;
      gen.make(model, mode, q, v);
      chart.chart(mode, q, v, anchor, p, pd);
      for (int i = 0; i < d; ++i) pdd[i] = 1e3 * gen.u();
      auto at = [&](double t, Vec& qt, Vec& vt) {
        const Vec pt = p + pd * t + 0.5 * pdd * t * t, pdt = pd + pdd * t;
        chart.embed(mode, anchor, pt, pdt, qt, vt);
      };
      // the fastest motion is the whirl, phi' up to 1e5 rad/s: h = 1e-9 s resolves it; central
      // differences then have truncation error O((phi' h)^2) ~ 1e-8 relative and round-off
      // error eps |q| / h ~ 1e-11 m/s on positions of O(g0)
      const double h = 1e-9;
      Vec qm(7), vm(7), qp(7), vp(7), q0(7), v0(7);
      at(-h, qm, vm);
      at(h, qp, vp);
      at(0.0, q0, v0);
      const Vec v_fd = (qp - qm) / (2 * h);
      const Vec a_fd = (vp - vm) / (2 * h);
      CHECK((v_fd - v0).norm() <= 1e-7 * v0.norm());
      Vec pdd_back(d);
      chart.reduce(mode, anchor, p, pd, q0, a_fd, pdd_back);
      CHECK((pdd_back - pdd).norm() <= 1e-5 * pdd.norm());
    }
  }
}
