// Campbell diagram (analysis/campbell.hpp) against hand-derived characteristic equations.
//
// Independent reference: complex whirl coordinates. With z_b = x_b + i y_b, z_r = x_r + i y_r and
// the gyroscopic matrix of the paper (eq. 14), rows x_b: H (y_b' - y_r'), y_b: -H (x_b' - x_r'),
// x_r: -H (y_b' - y_r'), y_r: H (x_b' - x_r'), the gyroscopic force on z_b is
//   H (y_b' - y_r') - i H (x_b' - x_r') = -i H (z_b' - z_r'),   and on z_r: +i H (z_b' - z_r').
// So the 4 real dofs become 2 complex ones:
//   M2 z'' + (D2 - i Omega H S) z' + K2 z = 0,   S = [1, -1; -1, 1],
//   M2 = [M11, M12; M12, M22 + m_s],  K2 = diag(k_b, k_s),  D2 = diag(c_b, c_s).
// A solution z = Z e^{lambda t} with Im(lambda) = w > 0 turns counterclockwise in (X, Y) = with the
// spin (theta' > 0 is a right-handed rotation about +Z): a FORWARD mode; w < 0: a BACKWARD mode of
// frequency |w|. Undamped (lambda = i w): det(K2 - w^2 M2 + w Omega H S) = 0, a real quartic in w
//   g(w) = (k_b - w^2 M11 + w Omega H)(k_s - w^2 Ms + w Omega H) - (w^2 M12 + w Omega H)^2,
// whose positive roots are f1f, f2f and negative roots -f1b, -f2b (times 2 pi).
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "rubdyn/analysis/campbell.hpp"

using namespace rubdyn;
namespace fs = std::filesystem;

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Reference case by hand: l = 0.4, nu = 0.75, Jd/l^2 = 0.035/0.16 = 0.21875,
// M11 = 0.0625*5 + 0.21875 = 0.53125, M12 = 0.1875*5 - 0.21875 = 0.71875,
// M22 = 0.5625*5 + 0.21875 = 3.03125, H = 0.06/0.16 = 0.375.
struct Hand {
  double M11 = 0.53125, M12 = 0.71875, M22 = 3.03125, H = 0.375;
  double ms = 2.0, kb = 5e6, ks = 2e6, cb = 300.0, cs = 100.0;
  double Ms() const { return M22 + ms; }
};

// Undamped characteristic function g(w) of the header comment.
double g(const Hand& h, double w, double Om) {
  const double gy = w * Om * h.H;
  return (h.kb - w * w * h.M11 + gy) * (h.ks - w * w * h.Ms() + gy) -
         (w * w * h.M12 + gy) * (w * w * h.M12 + gy);
}

// The four real roots of g, found by a sign scan (step 0.25 Hz; the roots are tens of Hz apart)
// and bisection to the last bit. Returns {f1b, f1f, f2b, f2f} [Hz].
std::array<double, 4> roots(const Hand& h, double Om, double f_max = 4000.0) {
  std::vector<double> pos, neg;
  const double dw = kTwoPi * 0.25;
  for (double a = -kTwoPi * f_max; a < kTwoPi * f_max; a += dw) {
    double lo = a, hi = a + dw;
    if ((g(h, lo, Om) > 0) == (g(h, hi, Om) > 0)) continue;
    for (int it = 0; it < 200 && hi - lo > 0; ++it) {
      const double mid = 0.5 * (lo + hi);
      if (mid == lo || mid == hi) break;
      ((g(h, mid, Om) > 0) == (g(h, lo, Om) > 0) ? lo : hi) = mid;
    }
    const double w = 0.5 * (lo + hi);
    (w > 0 ? pos : neg).push_back(std::abs(w) / kTwoPi);
  }
  REQUIRE(pos.size() == 2);
  REQUIRE(neg.size() == 2);
  std::sort(pos.begin(), pos.end());
  std::sort(neg.begin(), neg.end());
  return {neg[0], pos[0], neg[1], pos[1]};
}

// At rest, one direction: det(K - w^2 M) = 0 with M = [[M11, M12], [M12, Ms]], K = diag(kb, ks):
// a w^4 - b w^2 + c = 0, a = det M, b = kb Ms + ks M11, c = kb ks. Returns w1^2 < w2^2.
std::pair<double, double> rest_w2(const Hand& h) {
  const double a = h.M11 * h.Ms() - h.M12 * h.M12, b = h.kb * h.Ms() + h.ks * h.M11,
               c = h.kb * h.ks;
  const double disc = std::sqrt(b * b - 4 * a * c);
  return {(b - disc) / (2 * a), (b + disc) / (2 * a)};
}

// First-order gyroscopic split at rest: with the mode Z of (K - w0^2 M) Z = 0 (row 1:
// Z = (w0^2 M12, kb - w0^2 M11)), differentiating Z^T (K - w^2 M + w Omega H S) Z = 0 at Omega = 0
// gives dw/dOmega = H (Z_b - Z_r)^2 / (2 Z^T M Z): df_f/dOmega = -df_b/dOmega = that / 2 pi.
double split_slope_hz(const Hand& h, double w0sq) {
  const double zb = w0sq * h.M12, zr = h.kb - w0sq * h.M11;
  const double ztmz = h.M11 * zb * zb + 2 * h.M12 * zb * zr + h.Ms() * zr * zr;
  return h.H * (zb - zr) * (zb - zr) / (2 * ztmz) / kTwoPi;
}

RotorStatorParams params_of(const Hand& h) {
  RotorStatorParams p;  // rotor: the reference (M11..H above)
  p.stator.mass = h.ms;
  p.bearing.k = h.kb;
  p.stator.k = h.ks;
  p.bearing.c = h.cb;
  p.stator.c = h.cs;
  return p;
}

}  // namespace

TEST_CASE("Campbell at rest: two double modes of the closed-form 2x2 problem", "[campbell]") {
  for (double ks_scale : {0.5, 1.0, 8.0}) {
    for (double ms_scale : {1.0, 3.15}) {
      Hand h;
      h.ks *= ks_scale;
      h.ms *= ms_scale;
      const auto [w1sq, w2sq] = rest_w2(h);
      const double f1 = std::sqrt(w1sq) / kTwoPi, f2 = std::sqrt(w2sq) / kTwoPi;
      const CampbellPoint c = CampbellSolver(params_of(h)).solve(0.0);
      REQUIRE(c.labels_ok);
      // The scaled 8x8 eigenproblem has O(1) entries: eigenvalue error a few 1e-15 relative
      // (2e-15 observed); 1e-11 leaves a wide margin and is far below any physical difference.
      CHECK(c.f1b == Approx(f1).epsilon(1e-11));
      CHECK(c.f1f == Approx(f1).epsilon(1e-11));
      CHECK(c.f2b == Approx(f2).epsilon(1e-11));
      CHECK(c.f2f == Approx(f2).epsilon(1e-11));
      CHECK(c.zeta_1b == 0.0);  // undamped: exactly zero by definition, not round-off
    }
  }
}

TEST_CASE("Campbell frequencies and whirl labels match the complex-coordinate quartic",
          "[campbell]") {
  const Hand h;
  const CampbellSolver s(params_of(h));
  for (double Om : {1.0, 10.0, 300.0, 1000.0, 2110.0, 5000.0, 20000.0}) {
    INFO("Omega = " << Om);
    const auto r = roots(h, Om, 6000.0);
    const CampbellPoint c = s.solve(Om);
    REQUIRE(c.labels_ok);
    CHECK(c.n_forward == 2);
    CHECK(c.n_backward == 2);
    // circular modes: purity 1 up to eigenvector round-off (~1e-12 here)
    CHECK(c.min_whirl_purity > 1.0 - 1e-9);
    // 1e-11 relative: as at rest (the bisected roots are exact to the last bits). A swapped
    // label would be wrong by the split, >= 1e-4 relative even at Omega = 1 rad/s.
    CHECK(c.f1b == Approx(r[0]).epsilon(1e-11));
    CHECK(c.f1f == Approx(r[1]).epsilon(1e-11));
    CHECK(c.f2b == Approx(r[2]).epsilon(1e-11));
    CHECK(c.f2f == Approx(r[3]).epsilon(1e-11));
    // Omega -> -Omega reverses the spin: forward and backward swap (same tolerance)
    const CampbellPoint m = s.solve(-Om);
    CHECK(m.f1f == Approx(c.f1b).epsilon(1e-11));
    CHECK(m.f2b == Approx(c.f2f).epsilon(1e-11));
  }
  // the story of the reference case (cases/reference.toml): first backward mode
  // "about 88 Hz" at omega_lim; the spec rounds to the hertz
  CHECK(s.solve(2110.0).f1b == Approx(88.0).margin(1.0));
}

TEST_CASE("Campbell: first-order symmetric split for small Omega, asymmetry O(Omega^2)",
          "[campbell]") {
  const Hand h;
  const auto [w1sq, w2sq] = rest_w2(h);
  const double f0[2] = {std::sqrt(w1sq) / kTwoPi, std::sqrt(w2sq) / kTwoPi};
  const double a[2] = {split_slope_hz(h, w1sq), split_slope_hz(h, w2sq)};
  const CampbellSolver s(params_of(h));
  auto ff = [](const CampbellPoint& c, int k) { return k == 0 ? c.f1f : c.f2f; };
  auto fb = [](const CampbellPoint& c, int k) { return k == 0 ? c.f1b : c.f2b; };

  // split = f_f - f_b = 2 a Omega + O(Omega^3) (odd in Omega: f_f(-Omega) = f_b(Omega)), from
  // 1e-8 rad/s (inside the double-eigenvalue band, where the modes are merged: split 0) to 10.
  for (int e = -8; e <= 1; ++e) {
    const double Om = std::pow(10.0, e);
    const CampbellPoint c = s.solve(Om);
    INFO("Omega = " << Om);
    REQUIRE(c.labels_ok);
    for (int k = 0; k < 2; ++k) {
      const double split = ff(c, k) - fb(c, k);
      // allowance: 1e-4 relative for the O(Omega^3) term, relative size (Omega / Omega_c)^2
      // with Omega_c ~ 2e3 rad/s (the scale on which the curves bend, Fig. 8): ~3e-7 at
      // Omega = 10; plus 1e-9 f0 for the eigenvalue round-off (~1e-15 f0) and for the merge of
      // a double eigenvalue (within 1e-10 relative: |Omega| < ~1e-6 rad/s here, split 0)
      CHECK(std::abs(split - 2 * a[k] * Om) <= 1e-4 * 2 * a[k] * Om + 1e-9 * f0[k]);
      CHECK(split >= 0.0);  // forward above backward for Omega > 0
    }
  }
  // asymmetry f_f + f_b - 2 f0 = 2 b Omega^2 + O(Omega^4): much smaller than the split, and
  // divided by ~4 when Omega is halved. At Omega = 20 it is -1.6e-4 Hz (mode 1) and 7.6e-3 Hz (mode
  // 2), far above the round-off
  // (~1e-12 Hz); the O(Omega^4) term changes the ratio by ~(20 / Omega_c)^2 ~ 1e-4 with
  // Omega_c ~ 2e3 rad/s as above: tolerance 1e-3.
  const CampbellPoint c1 = s.solve(20.0), c2 = s.solve(10.0);
  for (int k = 0; k < 2; ++k) {
    const double asym1 = ff(c1, k) + fb(c1, k) - 2 * f0[k];
    const double asym2 = ff(c2, k) + fb(c2, k) - 2 * f0[k];
    CHECK(std::abs(asym1) < 1e-2 * (ff(c1, k) - fb(c1, k)));
    CHECK(asym1 / asym2 == Approx(4.0).epsilon(1e-3));
  }
}

TEST_CASE("Campbell diagram: continuous curves, forward rise, backward fall", "[campbell]") {
  const RotorStatorParams p;
  for (const double omega_max : {2110.0, 50000.0}) {
    INFO("omega_max = " << omega_max);
    const CampbellDiagram d = compute_campbell_diagram(p, omega_max, 201);
    REQUIRE(d.size() == 201);
    REQUIRE(d.labels_ok());
    CHECK(d.omega.front() == 0.0);
    CHECK(d.omega.back() == omega_max);
    CHECK(d.zeta.empty());
    REQUIRE(d.labels == std::vector<std::string>{"f1b", "f1f", "f2b", "f2f"});
    const auto &f1b = d.column("f1b"), &f1f = d.column("f1f"), &f2b = d.column("f2b"),
               &f2f = d.column("f2f");
    for (std::size_t i = 1; i < d.size(); ++i) {
      // gyroscopic stiffening of forward whirl, softening of backward whirl: strictly monotone
      CHECK(f1f[i] > f1f[i - 1]);
      CHECK(f2f[i] > f2f[i - 1]);
      CHECK(f1b[i] < f1b[i - 1]);
      CHECK(f2b[i] < f2b[i - 1]);
      if (i < 2) continue;
      // continuity: each curve's value is by far the nearest to the linear extrapolation of
      // its two previous points. A label swap between curves a and b at point i would put
      // curve b's value next to a's prediction and a's residual at the full gap (ratio >= 1);
      // a smooth curve on a 201-point grid leaves a curvature residual far below the gaps
      // (worst ratio measured: 5e-4 to omega_lim, 1.3e-2 to 50000 rad/s): 0.25.
      const double y[4] = {f1b[i], f1f[i], f2b[i], f2f[i]};
      const double x[4] = {f1b[i - 1], f1f[i - 1], f2b[i - 1], f2f[i - 1]};
      const double w[4] = {f1b[i - 2], f1f[i - 2], f2b[i - 2], f2f[i - 2]};
      for (int a = 0; a < 4; ++a) {
        const double pred = 2 * x[a] - w[a];
        double others = 1e300;
        for (int b = 0; b < 4; ++b)
          if (b != a) others = std::min(others, std::abs(y[b] - pred));
        CHECK(std::abs(y[a] - pred) < 0.25 * others);
      }
    }
  }
  CHECK_THROWS_AS(compute_campbell_diagram(p, 2110.0, 1), std::invalid_argument);
  CHECK_THROWS_AS(compute_campbell_diagram(p, 0.0, 11), std::invalid_argument);
  CHECK_THROWS_AS(compute_campbell_diagram(p, -1.0, 11), std::invalid_argument);
  CHECK_THROWS_AS(compute_campbell_diagram(p, std::nan(""), 11), std::invalid_argument);
}

namespace {
// Damped reference: lambda roots of P(lambda) = det(lambda^2 M2 + lambda (D2 - i Omega H S) + K2)
// (complex coordinates, header comment), by Newton from the undamped root i w (w signed).
std::complex<double> damped_root(const Hand& h, double Om, double w_undamped) {
  using C = std::complex<double>;
  const C iOH(0.0, Om * h.H);
  auto P = [&](C l, C& dP) {
    const C a = h.M11 * l * l + (h.cb - iOH) * l + h.kb;   // entry (b, b)
    const C d = h.Ms() * l * l + (h.cs - iOH) * l + h.ks;  // entry (r, r)
    const C o = h.M12 * l * l + iOH * l;                   // entries (b, r) = (r, b)
    const C da = 2.0 * h.M11 * l + (h.cb - iOH), dd = 2.0 * h.Ms() * l + (h.cs - iOH),
            dob = 2.0 * h.M12 * l + iOH;
    dP = da * d + a * dd - 2.0 * o * dob;
    return a * d - o * o;
  };
  C l(0.0, w_undamped);
  for (int it = 0; it < 100; ++it) {
    C dP;
    const C step = P(l, dP) / dP;
    l -= step;
    if (std::abs(step) < 1e-15 * std::abs(l)) break;
  }
  return l;
}
}  // namespace

TEST_CASE("Damped Campbell: the damped complex quartic - positive ratios - close to undamped",
          "[campbell]") {
  const Hand h;
  const CampbellSolver und(params_of(h)), dmp(params_of(h), true);
  for (double Om : {0.0, 1e-3, 700.0, 2110.0}) {
    INFO("Omega = " << Om);
    const CampbellPoint u = und.solve(Om), c = dmp.solve(Om);
    REQUIRE(c.labels_ok);
    const auto r = roots(h, Om);  // undamped, by whirl: {f1b, f1f, f2b, f2f}
    const double sign[4] = {-1, 1, -1, 1};
    const double fd[4] = {c.f1b, c.f1f, c.f2b, c.f2f},
                 zd[4] = {c.zeta_1b, c.zeta_1f, c.zeta_2b, c.zeta_2f};
    const double fu[4] = {u.f1b, u.f1f, u.f2b, u.f2f};
    for (int k = 0; k < 4; ++k) {
      const std::complex<double> l = damped_root(h, Om, sign[k] * kTwoPi * r[k]);
      // Newton converges to the last bits; the 8x8 solver's error is a few 1e-15 relative on
      // f and ~1e-13 on zeta (a difference of nearby numbers): 1e-9 is a safe margin, and far
      // below the effect of damping itself (zeta^2 ~ 2e-4 to 1e-2)
      CHECK(fd[k] == Approx(std::abs(l.imag()) / kTwoPi).epsilon(1e-9));
      CHECK(zd[k] == Approx(-l.real() / std::abs(l)).epsilon(1e-9));
      // physics: dampers dissipate, and light damping barely moves the frequency. For
      // proportional damping f_d = f sqrt(1 - zeta^2), a change of zeta^2/2; the bound zeta^2
      // leaves a factor 2 for the non-proportional coupling of the two modes.
      CHECK(zd[k] > 0.0);
      CHECK(zd[k] < 0.2);
      CHECK(std::abs(fd[k] / fu[k] - 1.0) < zd[k] * zd[k]);
    }
  }
}

// ----- command line: rubdyn campbell -----

namespace {
int run_cli(const std::string& args, std::string* out = nullptr) {
  const fs::path log =
      fs::temp_directory_path() / ("rubdyn-campbell-cli-" + std::to_string(::getpid()) + ".log");
  const std::string cmd = std::string(RUBDYN_CLI) + " " + args + " > " + log.string() + " 2>&1";
  const int st = std::system(cmd.c_str());
  if (out) {
    std::ifstream in(log);
    std::stringstream s;
    s << in.rdbuf();
    *out = s.str();
  }
  fs::remove(log);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}
const std::string kRefCase = std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml";
}  // namespace

TEST_CASE("rubdyn campbell writes campbell.csv, bad input exits 2 and writes nothing",
          "[campbell][cli]") {
  const fs::path dir =
      fs::temp_directory_path() / ("rubdyn-campbell-" + std::to_string(::getpid()));
  fs::remove_all(dir);

  REQUIRE(run_cli("campbell " + kRefCase + " --out " + dir.string()) == 0);
  {
    std::ifstream in(dir / "campbell.csv");
    std::string line;
    std::getline(in, line);
    CHECK(line == "omega_rad_s,omega_rpm,f1b,f1f,f2b,f2f");
    std::vector<std::vector<double>> rows;
    while (std::getline(in, line)) {
      std::vector<double> v;
      std::stringstream ss(line);
      for (std::string cell; std::getline(ss, cell, ',');) v.push_back(std::stod(cell));
      rows.push_back(v);
    }
    REQUIRE(rows.size() == 201);  // default --points
    CHECK(rows.front()[0] == 0.0);
    CHECK(rows.back()[0] == 2110.0);  // default --omega-max = run.omega_lim of the case
    // rpm = rad/s * 30 / pi, written with 17 digits
    CHECK(rows.back()[1] == Approx(2110.0 * 30.0 / std::numbers::pi).epsilon(1e-15));
    // last row against the independent quartic at omega_lim (as in the library test)
    const auto r = roots(Hand{}, 2110.0);
    for (int k = 0; k < 4; ++k) CHECK(rows.back()[2 + k] == Approx(r[k]).epsilon(1e-11));
  }
  fs::remove_all(dir);

  REQUIRE(run_cli("campbell " + kRefCase + " --damped --points 3 --omega-max 1000 --out " +
                  dir.string()) == 0);
  {
    std::ifstream in(dir / "campbell.csv");
    std::string line;
    std::getline(in, line);
    CHECK(line == "omega_rad_s,omega_rpm,f1b,f1f,f2b,f2f,zeta_1b,zeta_1f,zeta_2b,zeta_2f");
    int n = 0;
    while (std::getline(in, line)) ++n;
    CHECK(n == 3);
  }
  fs::remove_all(dir);

  // bad input: exit 2, a message naming the problem, nothing written
  std::string msg;
  CHECK(run_cli("campbell /nonexistent/case.toml --out " + dir.string(), &msg) == 2);
  CHECK(run_cli("campbell " + kRefCase + " --points 1 --out " + dir.string(), &msg) == 2);
  CHECK(msg.find("--points") != std::string::npos);
  CHECK(run_cli("campbell " + kRefCase + " --omega-max 0 --out " + dir.string(), &msg) == 2);
  CHECK(msg.find("--omega-max") != std::string::npos);
  CHECK(run_cli("campbell " + kRefCase + " --omega-max -5 --points 0 --set stator.k=-1 --out " +
                    dir.string(),
                &msg) == 2);
  // every problem at once: the two options and the case key
  CHECK(msg.find("--omega-max") != std::string::npos);
  CHECK(msg.find("--points") != std::string::npos);
  CHECK(msg.find("stator.k") != std::string::npos);
  CHECK(run_cli("campbell " + kRefCase + " --points abc --out " + dir.string()) == 2);
  CHECK_FALSE(fs::exists(dir));
  CHECK(run_cli("campbell --help", &msg) == 0);
  CHECK(msg.find("--omega-max") != std::string::npos);
}
