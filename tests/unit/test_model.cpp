// The rotor-stator model (paper eq. 11-21) against independent computations: the Lagrangian
// written from eq. (8)-(10) and differentiated by finite differences, the gap differentiated by
// finite differences, and the material-point velocities at the contact.
#include <Eigen/Eigenvalues>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "rubdyn/model/rotor_stator_model.hpp"

using namespace rubdyn;

namespace {
// the rigid rotor's size, as fixed-size types (the model's arguments bind to them, no copies)
using Vec7 = Eigen::Matrix<double, 7, 1>;
using Mat7 = Eigen::Matrix<double, 7, 7>;
}  // namespace

namespace {

RotorStatorParams reference_params() {
  return RotorStatorParams{};
}

struct RandomStates {
  std::mt19937_64 rng{12345};
  // positions within and around the clearance (|sr| up to 2 g0), spin angle anywhere
  Vec7 q(double g0) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Vec7 x;
    x << 0.5 * g0 * u(rng), 0.5 * g0 * u(rng), 1.4 * g0 * u(rng), 1.4 * g0 * u(rng), 50.0 * u(rng),
        0.5 * g0 * u(rng), 0.5 * g0 * u(rng);
    return x;
  }
  Vec7 v() {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Vec7 x;
    x << 0.1 * u(rng), 0.1 * u(rng), 0.2 * u(rng), 0.2 * u(rng), 2000.0 + 500.0 * u(rng),
        0.1 * u(rng), 0.1 * u(rng);
    return x;
  }
  Vec7 a() {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Vec7 x;
    for (int i = 0; i < 7; ++i) x[i] = 1e3 * u(rng);
    x[TH] = 300.0 * u(rng);
    return x;
  }
};

// Kinetic energy written independently from eq. (8) with the kinematics (9)-(10), plus the stator.
double kinetic_eq8(const RotorStatorParams& p, const Vec7& q, const Vec7& v) {
  const double l = p.rotor.L - p.rotor.delta, nu = p.rotor.d / l;
  const double xGd = nu * v[XR] + (1 - nu) * v[XB], yGd = nu * v[YR] + (1 - nu) * v[YB];
  const double thx = -(q[YR] - q[YB]) / l, thy = (q[XR] - q[XB]) / l;
  const double thxd = -(v[YR] - v[YB]) / l, thyd = (v[XR] - v[XB]) / l;
  const double twoT = p.rotor.mass * (xGd * xGd + yGd * yGd) +
                      p.rotor.Jd * (thxd * thxd + thyd * thyd) + p.rotor.Jp * v[TH] * v[TH] +
                      p.rotor.Jp * v[TH] * (thxd * thy - thyd * thx) +
                      p.stator.mass * (v[XS] * v[XS] + v[YS] * v[YS]);
  return 0.5 * twoT;
}

double potential_eq12(const RotorStatorParams& p, const Vec7& q) {
  const double l = p.rotor.L - p.rotor.delta, nu = p.rotor.d / l;
  return 0.5 * p.bearing.k * (q[XB] * q[XB] + q[YB] * q[YB]) +
         p.rotor.mass * p.loads.gravity * (nu * q[YR] + (1 - nu) * q[YB]) +
         0.5 * p.stator.k * (q[XS] * q[XS] + q[YS] * q[YS]);
}

}  // namespace

TEST_CASE("M(q) is symmetric positive definite - G is skew - gyroscopic forces do no work",
          "[model]") {
  const auto p = reference_params();
  const RotorStatorModel model(p);
  RandomStates rs;
  for (int k = 0; k < 2000; ++k) {
    const Vec7 q = rs.q(p.stator.gap), v = rs.v();
    Mat7 M;
    model.mass_matrix(q, M);
    REQUIRE((M - M.transpose()).norm() == 0.0);
    Eigen::SelfAdjointEigenSolver<Mat7> es(M);
    REQUIRE(es.eigenvalues().minCoeff() > 0.0);
    // T = 1/2 v^T M v equals eq. (8): both are sums of ~1e5 J terms; 1e-12 relative is round-off.
    REQUIRE(model.kinetic_energy(0.0, q, v) == Approx(kinetic_eq8(p, q, v)).epsilon(1e-12));
    const double gyro_power = v.dot(v[TH] * (model.G() * v));
    // exactly zero in exact arithmetic; round-off of terms of size H * |v|^3 ~ 1e2
    REQUIRE(std::abs(gyro_power) < 1e-12 * model.H() * v.squaredNorm() * std::abs(v[TH]));
  }
  REQUIRE((model.G() + model.G().transpose()).norm() == 0.0);
}

TEST_CASE("Equations of motion equal Euler-Lagrange of the Lagrangian (11)-(12)", "[model]") {
  auto p = reference_params();
  const RotorStatorModel model(p);
  RandomStates rs;
  // Central differences are exact for polynomials of degree <= 2, and every difference below is
  // of such a polynomial: T is quadratic in v; along (q + s v, v + s a) the momentum dT/dv is
  // quadratic in s; T - V is quadratic in each q_i. So the steps are chosen large, to keep
  // round-off small (T ~ 1.2e5 J is dominated by the spin), and the only error is round-off.
  auto momentum = [&](const Vec7& q, const Vec7& v) {
    Vec7 pm;
    for (int i = 0; i < 7; ++i) {
      const double s = 1.0;
      Vec7 vp = v, vm = v;
      vp[i] += s;
      vm[i] -= s;
      pm[i] = (kinetic_eq8(p, q, vp) - kinetic_eq8(p, q, vm)) / (2 * s);
    }
    return pm;
  };
  for (int k = 0; k < 200; ++k) {
    const Vec7 q = rs.q(p.stator.gap), v = rs.v(), a = rs.a();
    const double s = 1e-1;
    const Vec7 dpdt = (momentum(q + s * v, v + s * a) - momentum(q - s * v, v - s * a)) / (2 * s);
    Vec7 dLdq;
    for (int i = 0; i < 7; ++i) {
      const double sq = 1e-1;
      Vec7 qp = q, qm = q;
      qp[i] += sq;
      qm[i] -= sq;
      dLdq[i] = ((kinetic_eq8(p, qp, v) - potential_eq12(p, qp)) -
                 (kinetic_eq8(p, qm, v) - potential_eq12(p, qm))) /
                (2 * sq);
    }
    const Vec7 el = dpdt - dLdq;  // = generalised non-conservative forces
    Mat7 M;
    model.mass_matrix(q, M);
    Vec7 f;
    model.smooth_forces(0.0, q, v, f);
    Vec7 q_nc = -model.D() * v;  // non-conservative: torque and dampers
    q_nc[TH] += p.loads.torque;
    const Vec7 model_el = M * a - f + q_nc;
    // Round-off only: momenta ~ Jp omega ~ 150 computed from T ~ 1e5 with step 1 (~1e-11), then
    // differenced with step 0.1 (~1e-10); dL/dq from T - V with step 0.1 (~1e-10). Forces are
    // ~1e3 N, so 1e-11 relative to them is ~100 times the expected round-off.
    const double scale = 1.0 + (M * a).norm() + f.norm();
    INFO("k = " << k << "\nEL(fd) = " << el.transpose() << "\nmodel  = " << model_el.transpose());
    REQUIRE((el - model_el).norm() < 1e-11 * scale);
  }
}

TEST_CASE("W_N is the gradient of d_N - v_t is the relative velocity of the material points",
          "[model][contact]") {
  const auto p = reference_params();
  const RotorStatorModel model(p);
  RandomStates rs;
  for (int k = 0; k < 500; ++k) {
    const Vec7 q = rs.q(p.stator.gap), v = rs.v();
    const auto c = model.contact(0, 0.0, q, v);
    REQUIRE(c.normal_defined);
    Vec7 grad;
    for (int i = 0; i < 7; ++i) {
      const double s =
          1e-9;  // gap ~ 1e-4 m: truncation ~ s^2/g0 ~ 1e-14, round-off ~ 1e-16*1e-4/1e-9
      Vec7 qp = q, qm = q;
      qp[i] += s;
      qm[i] -= s;
      grad[i] = (model.contact(0, 0.0, qp, v).d_N - model.contact(0, 0.0, qm, v).d_N) / (2 * s);
    }
    REQUIRE((grad - c.W_N).norm() < 1e-6);  // |W_N| = sqrt(2): 1e-6 covers the FD errors above
    REQUIRE(std::abs(c.W_N.dot(c.W_T)) < 1e-15);
    REQUIRE(c.v_N == Approx(c.W_N.dot(v)).margin(1e-15));
    REQUIRE(c.v_t == Approx(c.W_T.dot(v)).margin(1e-12));

    // Material points: the rotor point at the contact rotates with the spin, the stator point
    // translates with the stator. Follow both for a short time s and differentiate.
    const double sx = q[XR] - q[XS], sy = q[YR] - q[YS], rho = std::hypot(sx, sy);
    const double nx = sx / rho, ny = sy / rho;
    const double Rr = p.rotor.radius;
    auto rotor_point = [&](double s) {
      const double dth = s * v[TH];
      const double px = std::cos(dth) * nx - std::sin(dth) * ny;
      const double py = std::sin(dth) * nx + std::cos(dth) * ny;
      return Vec2(q[XR] + s * v[XR] + Rr * px, q[YR] + s * v[YR] + Rr * py);
    };
    auto stator_point = [&](double s) {
      return Vec2(q[XS] + s * v[XS] + (Rr + p.stator.gap) * nx,
                  q[YS] + s * v[YS] + (Rr + p.stator.gap) * ny);
    };
    const double s = 1e-8;
    const Vec2 vrel =
        ((rotor_point(s) - rotor_point(-s)) - (stator_point(s) - stator_point(-s))) / (2 * s);
    const Vec2 t(ny, -nx);  // the paper's tangent (eq. 19 on the rotor dofs)
    // |v_t| ~ R_r omega ~ 100 m/s; FD truncation ~ (s omega)^2 ~ 4e-10 relative
    REQUIRE(c.v_t == Approx(t.dot(vrel)).epsilon(1e-8));
    REQUIRE(c.v_N == Approx(-Vec2(nx, ny).dot(vrel)).margin(1e-9));
  }
}

TEST_CASE("Acceleration-level terms (dW/dt) v match finite differences along a motion",
          "[model][contact]") {
  const auto p = reference_params();
  const RotorStatorModel model(p);
  RandomStates rs;
  for (int k = 0; k < 300; ++k) {
    // near-contact states (|sr| in [0.5 g0, 1.5 g0]), where these terms are used
    Vec7 q = rs.q(p.stator.gap);
    const double ang = q[TH], rho = p.stator.gap * (1.0 + 0.5 * std::sin(3.0 * ang));
    q[XR] = q[XS] + rho * std::cos(ang);
    q[YR] = q[YS] + rho * std::sin(ang);
    const Vec7 v = rs.v(), a = rs.a();
    const auto c = model.contact(0, 0.0, q, v);
    const double s = 1e-7;
    const auto cp = model.contact(0, 0.0, q + s * v + 0.5 * s * s * a, v + s * a);
    const auto cm = model.contact(0, 0.0, q - s * v + 0.5 * s * s * a, v - s * a);
    const double dvN = (cp.v_N - cm.v_N) / (2 * s), dvt = (cp.v_t - cm.v_t) / (2 * s);
    // |v_rel| <= 0.3 m/s at rho >= 1e-4 m: angular rate of n up to 3e3 rad/s, so the third
    // derivative of v_N is ~ 0.3 * (3e3)^3 ~ 1e10 and the truncation s^2/6 * 1e10 ~ 2e-5;
    // round-off 1e-16 * 0.3 / 1e-7 ~ 3e-10. Terms are ~1e3: 1e-4 absolute is 5x the truncation.
    REQUIRE(dvN == Approx(c.W_N.dot(a) + c.wdot_N).margin(1e-4));
    REQUIRE(dvt == Approx(c.W_T.dot(a) + c.wdot_T).margin(1e-4));
  }
}

TEST_CASE("Centred rotor: no normal is defined and no contact is possible", "[model][contact]") {
  const RotorStatorModel model(reference_params());
  Vec7 q = Vec7::Zero(), v = Vec7::Zero();
  q[XR] = q[XS] = 3e-5;
  q[YR] = q[YS] = -2e-5;
  v[TH] = 2000.0;
  const auto c = model.contact(0, 0.0, q, v);
  REQUIRE_FALSE(c.normal_defined);
  REQUIRE(c.d_N == model.params().stator.gap);
  REQUIRE(c.W_N.isZero());
  REQUIRE(c.W_T.isZero());
}

TEST_CASE("Analytic Jacobians match finite differences", "[model]") {
  const auto p = reference_params();
  const RotorStatorModel model(p);
  RandomStates rs;
  for (int k = 0; k < 100; ++k) {
    const Vec7 q = rs.q(p.stator.gap), v = rs.v(), a = rs.a();
    Mat7 J, dfdq, dfdv;
    model.mass_matrix_product_jacobian(q, a, J);
    model.smooth_force_jacobians(0.0, q, v, dfdq, dfdv);
    for (int i = 0; i < 7; ++i) {
      const double s = 1e-6;
      Vec7 qp = q, qm = q, vp = v, vm = v;
      qp[i] += s;
      qm[i] -= s;
      vp[i] += s;
      vm[i] -= s;
      Mat7 Mp, Mm;
      model.mass_matrix(qp, Mp);
      model.mass_matrix(qm, Mm);
      Vec7 fqp, fqm, fvp, fvm;
      model.smooth_forces(0, qp, v, fqp);
      model.smooth_forces(0, qm, v, fqm);
      model.smooth_forces(0, q, vp, fvp);
      model.smooth_forces(0, q, vm, fvm);
      // all three are affine in the perturbed variable: central differences are exact up to
      // round-off (forces ~ 1e3 N, step 1e-6: ~1e-7 absolute)
      REQUIRE(((Mp - Mm) * a / (2 * s) - J.col(i)).norm() < 1e-7);
      REQUIRE(((fqp - fqm) / (2 * s) - dfdq.col(i)).norm() < 1e-4);
      REQUIRE(((fvp - fvm) / (2 * s) - dfdv.col(i)).norm() < 1e-4);
    }
  }
}

namespace {
// Classical RK4 on (q, v, W) with W the work of the non-conservative forces: an independent,
// accurate integrator for contact-free runs.
struct Rk4State {
  Vec7 q, v;
  double W;
};
Rk4State rk4_step(const RotorStatorModel& m, const Rk4State& s, double h) {
  auto deriv = [&m](const Rk4State& x) {
    Mat7 M;
    Vec7 f;
    m.mass_matrix(x.q, M);
    m.smooth_forces(0.0, x.q, x.v, f);
    const auto p = m.smooth_power(0.0, x.q, x.v);
    return Rk4State{x.v, M.ldlt().solve(f), p.external + p.damping};
  };
  auto axpy = [](const Rk4State& x, double a, const Rk4State& d) {
    return Rk4State{x.q + a * d.q, x.v + a * d.v, x.W + a * d.W};
  };
  const Rk4State k1 = deriv(s), k2 = deriv(axpy(s, h / 2, k1)), k3 = deriv(axpy(s, h / 2, k2)),
                 k4 = deriv(axpy(s, h, k3));
  return Rk4State{s.q + h / 6 * (k1.q + 2 * k2.q + 2 * k3.q + k4.q),
                  s.v + h / 6 * (k1.v + 2 * k2.v + 2 * k3.v + k4.v),
                  s.W + h / 6 * (k1.W + 2 * k2.W + 2 * k3.W + k4.W)};
}
}  // namespace

TEST_CASE("Contact-free motion conserves energy - with torque and damping the balance closes",
          "[model]") {
  // A whirling, spinning rotor inside the clearance (no contact over 5 ms), RK4 with h = 2e-7 s:
  // (h w)^4 ~ (2e-7 * 4e3)^4 ~ 4e-13 per unit time on the fastest mode, far below 1e-10.
  Rk4State s0;
  s0.q = Vec7::Zero();
  s0.v = Vec7::Zero();
  s0.q[XR] = 5e-5;
  s0.v[YR] = 0.05;
  s0.v[XB] = -0.01;
  s0.v[TH] = 2000.0;
  s0.W = 0.0;
  const int steps = 25000;
  const double h = 2e-7;
  {
    RotorStatorParams p;
    p.bearing.c = p.stator.c = 0.0;
    p.loads.torque = 0.0;
    p.loads.gravity = 0.0;
    const RotorStatorModel m(p);
    auto energy = [&m](const Rk4State& x) {
      return m.kinetic_energy(0.0, x.q, x.v) + m.potential_energy(0.0, x.q);
    };
    Rk4State s = s0;
    double spin_min = 1e300, spin_max = 0;
    for (int i = 0; i < steps; ++i) {
      s = rk4_step(m, s, h);
      REQUIRE(m.contact(0, 0.0, s.q, s.v).d_N > 0.0);
      const double spin = 0.5 * p.rotor.Jp * s.v[TH] * s.v[TH];
      spin_min = std::min(spin_min, spin);
      spin_max = std::max(spin_max, spin);
    }
    const double E0 = energy(s0), E1 = energy(s);
    REQUIRE(std::abs(E1 - E0) < 1e-10 * E0);
    // the check is not vacuous: the spin exchanges energy with the whirl through M(q) far above
    // the residual (the theta row couples the spin to lateral accelerations)
    REQUIRE(spin_max - spin_min > 1e3 * std::abs(E1 - E0));
  }
  {
    const RotorStatorParams p;  // torque, dampers and gravity
    const RotorStatorModel m(p);
    auto energy = [&m](const Rk4State& x) {
      return m.kinetic_energy(0.0, x.q, x.v) + m.potential_energy(0.0, x.q);
    };
    Rk4State s = s0;
    for (int i = 0; i < steps; ++i) s = rk4_step(m, s, h);
    const double torque_work = p.loads.torque * (s.q[TH] - s0.q[TH]);
    REQUIRE(std::abs((energy(s) - energy(s0)) - s.W) < 1e-10 * torque_work);
  }
}
