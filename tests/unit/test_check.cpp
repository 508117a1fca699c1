// Derived quantities (analysis/derived.hpp) against hand computations, and `rubdyn check`.
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>

#include "rubdyn/analysis/derived.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"

using namespace rubdyn;

namespace {
// the rigid rotor's size, as fixed-size types (the model's arguments bind to them, no copies)
using Vec7 = Eigen::Matrix<double, 7, 1>;
using Mat7 = Eigen::Matrix<double, 7, 7>;
}  // namespace
namespace fs = std::filesystem;

namespace {
constexpr double kTwoPi = 2.0 * std::numbers::pi;
}  // namespace

TEST_CASE("Derived quantities of the reference case, by hand", "[check]") {
  const RotorStatorParams p;  // the reference case
  const DerivedQuantities d = compute_derived_quantities(p, 2000.0, 2110.0);
  // Hand values from the reference case's parameters. Each is a few floating-point operations
  // on the inputs: a few ulps, so 1e-14 relative.
  //   l = 0.5 - 0.1 = 0.4, nu = 0.3 / 0.4 = 0.75, Jd / l^2 = 0.035 / 0.16 = 0.21875
  CHECK(d.l == Approx(0.4).epsilon(1e-14));
  CHECK(d.nu == Approx(0.75).epsilon(1e-14));
  //   M11 = 0.25^2 * 5 + 0.21875 = 0.3125 + 0.21875, M12 = 0.75 * 0.25 * 5 - 0.21875,
  //   M22 = 0.75^2 * 5 + 0.21875 = 2.8125 + 0.21875, H = 0.06 / 0.16
  CHECK(d.M11 == Approx(0.53125).epsilon(1e-14));
  CHECK(d.M12 == Approx(0.71875).epsilon(1e-14));
  CHECK(d.M22 == Approx(3.03125).epsilon(1e-14));
  CHECK(d.H == Approx(0.375).epsilon(1e-14));
  // statics: m g = 49.05 N; F_N = 0.75 * 49.05 = 36.7875 N;
  //   y_b = -0.25 * 49.05 / 5e6 = -2.4525e-6 m; y_s = -36.7875 / 2e6 = -1.839375e-5 m;
  //   y_r = y_s - 2e-4 = -2.1839375e-4 m
  CHECK(d.rests_on_stator);
  CHECK(d.F_N == Approx(36.7875).epsilon(1e-14));
  CHECK(d.y_b == Approx(-2.4525e-6).epsilon(1e-14));
  CHECK(d.y_s == Approx(-1.839375e-5).epsilon(1e-14));
  CHECK(d.y_r == Approx(-2.1839375e-4).epsilon(1e-14));
  CHECK(d.q_static[XB] == 0.0);
  CHECK(d.q_static[XR] == 0.0);
  CHECK(d.q_static[XS] == 0.0);
  CHECK(d.q_static[TH] == 0.0);
  CHECK(d.q_static[YR] == d.y_r);
  // stator alone: sqrt(2e6 / 2) = 1000 rad/s
  CHECK(d.f_stator == Approx(1000.0 / kTwoPi).epsilon(1e-14));
  // rotor on its bearing: det [M11, M12; M12, M22] = m Jd / l^2 (expand: the nu terms sum to
  // ((1-nu) + nu)^2 = 1) = 5 * 0.21875 = 1.09375; w^2 = k_b M22 / det = 5e6 * 3.03125 / 1.09375
  CHECK(d.f_bearing_rotor == Approx(std::sqrt(5e6 * 3.03125 / 1.09375) / kTwoPi).epsilon(1e-14));
  // coupled, at rest, per direction: a w^4 - b w^2 + c = 0 with Ms = M22 + m_s = 5.03125,
  //   a = M11 Ms - M12^2 = 2.6728515625 - 0.5166015625 = 2.15625,
  //   b = k_b Ms + k_s M11 = 25156250 + 1062500 = 26218750,  c = k_b k_s = 1e13
  const double a = 2.15625, b = 26218750.0, c = 1e13, disc = std::sqrt(b * b - 4 * a * c);
  // the eigen solver: ~1e-13 relative (see test_campbell.cpp); 1e-11 leaves a margin
  CHECK(d.f1 == Approx(std::sqrt((b - disc) / (2 * a)) / kTwoPi).epsilon(1e-11));
  CHECK(d.f2 == Approx(std::sqrt((b + disc) / (2 * a)) / kTwoPi).epsilon(1e-11));
  // free acceleration: (2110 - 2000) * 0.06 / 20 = 0.33 s
  CHECK(d.free_acceleration == FreeAcceleration::reaches);
  CHECK(d.t_free_to_omega_lim == Approx(0.33).epsilon(1e-14));
}

TEST_CASE("The static equilibrium satisfies the model's equations of motion", "[check]") {
  RotorStatorParams ref;
  RotorStatorParams other;  // a different, asymmetric set: nothing cancels by accident
  other.rotor.mass = 7.0;
  other.rotor.d = 0.2;
  other.stator.k = 3.3e6;
  other.bearing.k = 1.7e6;
  other.stator.gap = 3.1e-4;
  other.loads.gravity = 3.7;
  for (const RotorStatorParams& p0 : {ref, other}) {
    RotorStatorParams p = p0;
    p.loads.torque = 0.0;  // at rest: no driving torque, so the theta row is at rest too
    const RotorStatorModel m(p);
    const DerivedQuantities d = compute_derived_quantities(p, 0.0, 1.0);
    REQUIRE(d.rests_on_stator);
    const Vec v = Vec::Zero(7);
    Vec f(7);
    m.smooth_forces(0.0, d.q_static, v, f);
    // without contact the rotor is not in equilibrium: row y_r is -nu m g (it must fall)
    CHECK(f[YR] == Approx(-d.nu * p.rotor.mass * p.loads.gravity).epsilon(1e-14));
    const ContactKinematics c = m.contact(0, 0.0, d.q_static, v);
    REQUIRE(c.normal_defined);
    // closed contact, at the bottom of the clearance: d_N = 0 up to the rounding of
    // y_r = y_s - g0 (ulp of 2e-4 m ~ 3e-20 m)
    CHECK(std::abs(c.d_N) < 1e-18);
    CHECK(c.W_N[YR] == Approx(1.0).epsilon(1e-14));  // C_N of eq. 18: (y_s - y_r)/|sr| = 1
    CHECK(d.F_N >= 0.0);                             // Signorini: compressive
    const Vec res = f + c.W_N * d.F_N;               // + W_T F_T with F_T = 0 (inside the cone)
    // every row is a sum of terms of at most ~50 N (weights, spring forces, F_N): round-off
    // ~1e-14 N; 1e-11 N is a relative 2e-13 of the weight, far below any wrong sign or factor
    CHECK(res.cwiseAbs().maxCoeff() < 1e-11);
  }
}

TEST_CASE("Statics without gravity and the outcomes of the free acceleration", "[check]") {
  RotorStatorParams p;
  p.loads.gravity = 0.0;
  const DerivedQuantities d0 = compute_derived_quantities(p, 2000.0, 2110.0);
  CHECK_FALSE(d0.rests_on_stator);
  CHECK(d0.F_N == 0.0);
  CHECK(d0.q_static.isZero(0.0));
  const RotorStatorModel m(p);
  Vec7 f;
  const Vec7 rest = Vec7::Zero();
  m.smooth_forces(0.0, d0.q_static, rest, f);
  CHECK(f.head<4>().isZero(0.0));  // centred, no weight: exactly at rest

  const RotorStatorParams ref;
  const DerivedQuantities above = compute_derived_quantities(ref, 2200.0, 2110.0);
  CHECK(above.free_acceleration == FreeAcceleration::already_reached);
  CHECK(above.t_free_to_omega_lim == 0.0);
  RotorStatorParams braking = ref;
  braking.loads.torque = -1.0;
  const DerivedQuantities never = compute_derived_quantities(braking, 2000.0, 2110.0);
  CHECK(never.free_acceleration == FreeAcceleration::never);
  CHECK(std::isinf(never.t_free_to_omega_lim));
  RotorStatorParams idle = ref;
  idle.loads.torque = 0.0;
  CHECK(compute_derived_quantities(idle, 2000.0, 2110.0).free_acceleration ==
        FreeAcceleration::never);
}

TEST_CASE("rubdyn check prints the derived quantities, bad input exits 2", "[check][cli]") {
  const fs::path log =
      fs::temp_directory_path() / ("rubdyn-check-cli-" + std::to_string(::getpid()) + ".log");
  auto run = [&](const std::string& args, std::string& out) {
    const std::string cmd = std::string(RUBDYN_CLI) + " " + args + " > " + log.string() + " 2>&1";
    const int st = std::system(cmd.c_str());
    std::ifstream in(log);
    std::stringstream s;
    s << in.rdbuf();
    out = s.str();
    fs::remove(log);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  };
  const std::string ref = std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml";
  std::string out;
  REQUIRE(run("check " + ref, out) == 0);
  // hand values of the reference case (see the first test case), as printed with 6 digits
  CHECK(out.find("36.7875 N") != std::string::npos);
  CHECK(out.find("-2.4525e-06 m") != std::string::npos);
  CHECK(out.find("0.33 s") != std::string::npos);
  // an override changes the statics: m = 6 kg -> F_N = 0.75 * 6 * 9.81 = 44.145 N
  REQUIRE(run("check " + ref + " --set rotor.mass=6", out) == 0);
  CHECK(out.find("44.145 N") != std::string::npos);
  // invalid override: exit 2, the key named
  CHECK(run("check " + ref + " --set rotor.delta=0.6", out) == 2);
  CHECK(out.find("rotor.delta") != std::string::npos);
  CHECK(run("check /nonexistent/case.toml", out) == 2);
  CHECK(run("check --help", out) == 0);
}
