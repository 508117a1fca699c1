// rubdyn orbit: the output folder, the exit codes and the failures (src/app/cmd_orbit.cpp,
// analysis/orbit_case.hpp) on cases/full-rub.toml (the sprung ring's forward full annular rub).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli.hpp"

using namespace rubdyn::testing;
namespace fs = std::filesystem;

namespace {

const std::string kCase = std::string(RUBDYN_SOURCE_DIR) + "/cases/full-rub.toml";

/// The number after "key": in a JSON text (the first occurrence), NaN when absent.
double number_after(const std::string& text, const std::string& pattern);
double json_number(const std::string& text, const std::string& key) {
  return number_after(text, "\"" + key + "\": ");
}

/// The number right after the first `pattern` in a text, NaN when absent.
double number_after(const std::string& text, const std::string& pattern) {
  const auto p = text.find(pattern);
  if (p == std::string::npos) return std::nan("");
  return std::strtod(text.c_str() + p + pattern.size(), nullptr);
}

std::vector<std::vector<std::string>> csv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  for (const std::string& line : text_lines(text)) rows.push_back(csv_fields(line));
  return rows;
}

}  // namespace

TEST_CASE("rubdyn orbit: the stable full rub orbit, its folder and its periodicity",
          "[orbit][cli]") {
  const fs::path dir = fresh_dir("orbit-ok");
  const CliOutcome r = cli("orbit " + sh(kCase) + " --out " + sh(dir.string()));
  INFO(r.out << r.err);
  REQUIRE(r.code == 0);
  CHECK(has(r.out, "stable: every |multiplier| + its error < 1"));
  const std::string js = slurp(dir / "orbit.json");
  CHECK(has(js, "\"outcome\": \"converged\""));
  CHECK(has(js, "\"stability\": \"stable\""));
  CHECK(has(js, "\"phases\": [\"slip-\"]"));
  CHECK(json_number(js, "period") == Approx(2 * M_PI / 1500).epsilon(1e-15));
  CHECK(json_number(js, "residual") <= 1e-8);
  CHECK(has(js, "\"impact\": 0, \"contact\": 0, \"liftoff\": 0"));  // none per period
  CHECK(fs::is_regular_file(dir / "case.resolved.toml"));
  // orbit.csv: one period, 200 samples after the first; its last row is its first to Newton's
  // tolerance (1e-8 of g0 = 2e-4 m and of g0 Omega = 0.3 m/s: the residual of the run that wrote
  // it, which takes the same steps as Newton's last run)
  const auto rows = csv(slurp(dir / "orbit.csv"));
  REQUIRE(rows.size() == 202);  // header + 201 grid samples (no event inside the period)
  CHECK(rows[0][0] == "t");
  CHECK(rows[0][1] == "x_r");
  const auto& first = rows[1];
  const auto& last = rows.back();
  CHECK(std::stod(last[0]) == Approx(2 * M_PI / 1500).epsilon(1e-15));
  for (int c = 1; c <= 8; ++c) {  // x_r, y_r, x_s, y_s (m), then their rates (m/s)
    const double scale = c <= 4 ? 2e-4 : 2e-4 * 1500;
    INFO(rows[0][static_cast<std::size_t>(c)]);
    CHECK(std::abs(std::stod(last[static_cast<std::size_t>(c)]) -
                   std::stod(first[static_cast<std::size_t>(c)])) <= 1e-8 * scale);
  }
  CHECK(last.back() == "slip-");
  fs::remove_all(dir);
}

TEST_CASE("rubdyn orbit: the saddle, from --set, is unstable with one multiplier outside",
          "[orbit][cli]") {
  const fs::path dir = fresh_dir("orbit-saddle");
  // the smaller root of closed-forms.md 5.3 (the sprung ring), from cases/full-rub.toml's header
  const std::string sets =
      " --set initial.x_r=-0.00021227786696844736 --set initial.y_r=-0.00011101946416261583"
      " --set initial.vx_r=0.16652919624392373 --set initial.vy_r=-0.31841680045267107"
      " --set initial.x_s=-3.41268532344108e-05 --set initial.y_s=-2.012272986739972e-05"
      " --set initial.vx_s=0.03018409480109958 --set initial.vy_s=-0.051190279851616206";
  const CliOutcome r = cli("orbit " + sh(kCase) + sets + " --out " + sh(dir.string()));
  INFO(r.out << r.err);
  REQUIRE(r.code == 0);
  const std::string js = slurp(dir / "orbit.json");
  CHECK(has(js, "\"stability\": \"unstable\""));
  // the first multiplier (largest |.|) is the unstable one: exp(283.128 T) = 3.27384
  CHECK(json_number(js, "abs") == Approx(3.27384).epsilon(1e-3));
  fs::remove_all(dir);
}

TEST_CASE("rubdyn orbit: bad input is exit 2 with nothing written", "[orbit][cli]") {
  const fs::path dir = fresh_dir("orbit-bad");
  // cases/jeffcott.toml spins under a torque with an unbalance: no forced orbit, and a free
  // spin's (autonomous) orbit needs --period and no unbalance
  const CliOutcome r = cli("orbit " + sh(std::string(RUBDYN_SOURCE_DIR) + "/cases/jeffcott.toml") +
                           " --out " + sh(dir.string()) + " --periods 0");
  CHECK(r.code == 2);
  CHECK(has(r.err, "loads.spin"));
  CHECK(has(r.err, "prescribed"));
  CHECK(has(r.err, "--periods"));
  CHECK(has(r.err, "its period is an unknown"));
  CHECK(has(r.err, "loads.unbalance"));
  CHECK_FALSE(fs::exists(dir));
  const CliOutcome a =
      cli("orbit " + sh(kCase) + " --out " + sh(dir.string()) + " --set loads.spin_accel=10");
  CHECK(a.code == 2);
  CHECK(has(a.err, "loads.spin_accel"));
  CHECK_FALSE(fs::exists(dir));
  // a prescribed spin's period is known: --period is refused
  const CliOutcome p = cli("orbit " + sh(kCase) + " --out " + sh(dir.string()) + " --period 0.004");
  CHECK(p.code == 2);
  CHECK(has(p.err, "--period"));
  CHECK_FALSE(fs::exists(dir));
}

TEST_CASE("rubdyn orbit: no convergence is exit 3 with the history and the last iterate",
          "[orbit][cli]") {
  const fs::path dir = fresh_dir("orbit-noconv");
  // below the computed map's noise floor (measured 1e-13 .. 1e-11 on this case at rtol 1e-10):
  // Newton cannot reach it in two iterations
  const CliOutcome r =
      cli("orbit " + sh(kCase) + " --out " + sh(dir.string()) + " --tol 1e-15 --max-iter 2");
  INFO(r.out << r.err);
  CHECK(r.code == 3);
  CHECK(has(r.err, "no_convergence"));
  const std::string js = slurp(dir / "orbit.json");
  CHECK(has(js, "\"outcome\": \"no_convergence\""));
  CHECK(has(js, "\"stability\": \"undecided\""));
  CHECK(has(js, "\"iteration\": 2"));  // the guess and two iterates
  CHECK(has(js, "\"state\": {\"x_r\": "));
  CHECK(fs::file_size(dir / "orbit.csv") > 1000);  // the last iterate's period
  fs::remove_all(dir);
}

TEST_CASE("rubdyn orbit --from: the section at the end of a transient run", "[orbit][cli]") {
  const fs::path run = fresh_dir("orbit-from-run"), dir = fresh_dir("orbit-from");
  // from the closed form's state moved 1 % of g0 inwards in x_r (off the constraint: a free start,
  // an impact, then sliding), 20 ms of transient
  const CliOutcome a = cli("run " + sh(kCase) + " --set initial.x_r=0.000412 --t-end 0.02 --out " +
                           sh(run.string()));
  REQUIRE(a.code == 0);
  const CliOutcome r =
      cli("orbit " + sh(kCase) + " --from " + sh(run.string()) + " --out " + sh(dir.string()));
  INFO(r.out << r.err);
  REQUIRE(r.code == 0);
  const std::string js = slurp(dir / "orbit.json");
  CHECK(json_number(js, "t0") == Approx(0.02).epsilon(1e-14));
  CHECK(has(js, "\"stability\": \"stable\""));
  fs::remove_all(run);
  fs::remove_all(dir);
}

TEST_CASE("rubdyn branch: a few points of the full rub's branch, and bad input", "[orbit][cli]") {
  const fs::path dir = fresh_dir("branch");
  const CliOutcome r =
      cli("branch " + sh(kCase) + " --vary initial.omega0 --points 4 --out " + sh(dir.string()));
  INFO(r.out << r.err);
  REQUIRE(r.code == 0);
  const std::string js = slurp(dir / "branch.json");
  CHECK(has(js, "\"outcome\": \"max_points\""));
  CHECK(has(js, "\"points\": 4"));
  const auto rows = csv(slurp(dir / "branch.csv"));
  REQUIRE(rows.size() == 5);
  CHECK(rows[0][1] == "initial.omega0");
  CHECK(std::stod(rows[1][1]) == 1500.0);
  const auto col = std::find(rows[0].begin(), rows[0].end(), "stability") - rows[0].begin();
  REQUIRE(col < static_cast<long>(rows[0].size()));
  for (std::size_t i = 2; i < rows.size(); ++i) {  // increasing speed, all stable
    CHECK(std::stod(rows[i][1]) > std::stod(rows[i - 1][1]));
    CHECK(rows[i][static_cast<std::size_t>(col)] == "stable");
  }
  fs::remove_all(dir);
  const CliOutcome b =
      cli("branch " + sh(kCase) + " --vary rotor.nonsense --points 1 --out " + sh(dir.string()));
  CHECK(b.code == 2);
  CHECK(has(b.err, "--vary"));
  CHECK(has(b.err, "--points"));
  CHECK_FALSE(fs::exists(dir));
}

// --resume continues a branch from its folder's last point, the way it went: its rows kept as
// they were, the fold reached after the resume located as by a branch in one piece; a resume of
// a branch that ended changes nothing; another case or method is refused with nothing written.
TEST_CASE("rubdyn branch --resume: the full rub's branch in two pieces", "[orbit][cli]") {
  const fs::path dir = fresh_dir("branch-resume");
  const std::string base =
      "branch " + sh(kCase) + " --vary initial.omega0 --ds-max 3 --out " + sh(dir.string());
  const CliOutcome a = cli(base + " --points 10");
  INFO(a.out << a.err);
  REQUIRE(a.code == 0);
  const std::string first = slurp(dir / "branch.csv");
  const auto rows10 = text_lines(first);
  REQUIRE(rows10.size() == 11);
  // (a resume with other tolerances or another monodromy: exit 2, the folder as it was)
  for (const std::string bad : {" --rtol 1e-9", " --monodromy sensitivities", " --periods 2"}) {
    const CliOutcome b = cli(base + " --points 70 --resume" + bad);
    INFO(bad << ": " << b.err);
    CHECK(b.code == 2);
    CHECK(slurp(dir / "branch.csv") == first);
  }
  const CliOutcome r = cli(base + " --points 200 --resume");
  INFO(r.out << r.err);
  REQUIRE(r.code == 0);
  CHECK(has(r.out, "resumed from its point 9"));
  const std::string all = slurp(dir / "branch.csv");
  const auto rows = text_lines(all);
  // the first ten points' rows (and the header) as the first piece wrote them, byte for byte
  REQUIRE(rows.size() > 70);
  for (std::size_t i = 0; i < rows10.size(); ++i) CHECK(rows[i] == rows10[i]);
  // on the way the first piece went: the speed rises to the fold, and the branch ends as the
  // one-piece branch does (validation/orbits/branch.md), where the saddle lifts off
  CHECK(std::stod(csv_fields(rows[11])[1]) > std::stod(csv_fields(rows[10])[1]));
  const std::string js = slurp(dir / "branch.json");
  CHECK(has(js, "\"outcome\": \"events_change\""));
  CHECK(has(js, "\"from\": 1500"));
  const double fold = number_after(js, "\"kind\": \"fold\", \"value\": ");
  // The closed form's fold, 1804.5921501041 rad/s (the discriminant of docs/closed-forms.md
  // (5.2) vanishes: validation/orbits/branch.py, by brentq in Python); the one-piece branch
  // locates it 3.6e-9 relative away, by the orbits' integration error at rtol 1e-10 (see
  // test_orbit.cpp's fold test, whose bound 1e-6 relative this takes)
  CHECK(std::abs(fold / 1804.5921501041 - 1.0) <= 1e-6);
  // resumed again: it has ended, nothing to do, nothing written
  const CliOutcome again = cli(base + " --points 200 --resume");
  CHECK(again.code == 0);
  CHECK(has(again.out, "nothing to do"));
  CHECK(slurp(dir / "branch.csv") == all);
  CHECK(slurp(dir / "branch.json") == js);
  // a branch.csv whose row 3 (line 4) has a damaged number: refused, naming the file, line and
  // column, the folder as it was
  {
    std::string damaged = all;
    const auto line4 = damaged.find('\n', damaged.find('\n', damaged.find('\n') + 1) + 1) + 1;
    const auto comma = damaged.find(',', damaged.find(',', line4) + 1);  // after the key's value
    damaged.insert(comma, "x");
    std::ofstream(dir / "branch.csv", std::ios::binary) << damaged;
    const CliOutcome d = cli(base + " --points 300 --resume");
    INFO(d.err);
    CHECK(d.code == 2);
    CHECK(has(d.err, "branch.csv:4: initial.omega0 = "));
    CHECK(has(d.err, "must be a number"));
    CHECK(slurp(dir / "branch.csv") == damaged);
  }
  // a folder without a branch
  const fs::path none = fresh_dir("branch-resume-none");
  const CliOutcome n =
      cli("branch " + sh(kCase) + " --vary initial.omega0 --resume --out " + sh(none.string()));
  CHECK(n.code == 2);
  CHECK(has(n.err, "branch.json"));
  CHECK_FALSE(fs::exists(none));
  fs::remove_all(dir);
  fs::remove_all(none);
}

// --switch: the frictionless impact oscillator (a Jeffcott rotor on a soft shaft against a rigid
// ring, e_N = 0.8, at a prescribed speed; tests/unit/test_orbit_determinant.cpp's scene) has a
// period doubling below 250 rad/s; the branch of twice the period leaves it, on the side where
// the period-1 orbit is unstable.
TEST_CASE("rubdyn branch --switch: the period-2 orbits at the impact oscillator's doubling",
          "[orbit][cli]") {
  const fs::path dir = fresh_dir("branch-switch");
  fs::create_directories(dir);
  const std::string case_path = (dir / "io.toml").string();
  {
    std::ofstream f(case_path);
    f << "name = \"impact-oscillator\"\n[model]\nkind = \"jeffcott\"\n"
         "[rotor]\nmass = 5.0\nk = 5e5\nc = 300.0\nradius = 0.05\nJp = 0.06\n"
         "[contact]\nmu = 0.0\ne_n = 0.8\ne_t = 0.0\n"
         "[loads]\ngravity = 9.81\nspin = \"prescribed\"\nspin_accel = 0.0\nunbalance = 4e-4\n"
         "unbalance_phase = 0.3\n[initial]\nomega0 = 250.0\n[run]\nt_end = 1.0\n"
         "omega_lim = 2000.0\n[output]\ndt = 1e-4\n[stator]\nrigid = true\ngap = 2e-4\n"
         "[solver]\nkind = \"event\"\nrtol = 1e-10\natol = 1e-13\n";
  }
  const std::string run = (dir / "run").string(), one = (dir / "one").string(),
                    two = (dir / "two").string();
  // 40 periods of transient (1 s: it decays at c / 2m = 30 1/s) leave Newton a start
  REQUIRE(cli("run " + sh(case_path) + " --out " + sh(run)).code == 0);
  const std::string common = "branch " + sh(case_path) + " --from " + sh(run) +
                             " --vary initial.omega0 --scale 2.5 --ds 0.5 --ds-max 2";
  const CliOutcome a = cli(common + " --down --points 8 --out " + sh(one));
  INFO(a.out << a.err);
  REQUIRE(a.code == 0);
  const std::string js1 = slurp(fs::path(one) / "branch.json");
  const double pd = number_after(js1, "\"kind\": \"period_doubling\", \"value\": ");
  REQUIRE(std::isfinite(pd));
  CHECK(has(js1, "\"direction\": {"));
  // without the run's state (another case: the forcing's phase at the section differs): refused
  const CliOutcome bad = cli("branch " + sh(case_path) + " --vary initial.omega0 --switch " +
                             sh(one) + " --out " + sh(two));
  CHECK(bad.code == 2);
  CHECK(has(bad.err, "case.resolved.toml"));
  CHECK_FALSE(fs::exists(two));
  const CliOutcome b = cli(common + " --switch " + sh(one) + " --points 3 --out " + sh(two));
  INFO(b.out << b.err);
  REQUIRE(b.code == 0);
  CHECK(has(b.out, "switched at the period doubling"));
  const std::string js2 = slurp(fs::path(two) / "branch.json");
  CHECK(has(js2, "\"periods\": 2"));
  const auto rows = text_lines(slurp(fs::path(two) / "branch.csv"));
  REQUIRE(rows.size() >= 2);
  const auto head = csv_fields(rows[0]);
  const auto col = [&](const std::string& name) {
    const auto it = std::find(head.begin(), head.end(), name);
    REQUIRE(it != head.end());
    return static_cast<std::size_t>(it - head.begin());
  };
  const auto p0 = csv_fields(rows[1]);
  const double w = std::stod(p0[1]);
  // below the doubling (the period-1 orbit's multiplier is below -1 there: a supercritical
  // doubling's side), with twice the forcing's period, two impacts in it and stable
  CHECK(w < pd);
  CHECK(std::stod(p0[col("period")]) == Approx(4 * M_PI / w).epsilon(1e-14));
  CHECK(p0.back() == "\"free | impact impact | free\"");  // (the csv quotes it)
  CHECK(p0[col("stability")] == "stable");
  fs::remove_all(dir);
}

// A key with a bound (mu >= 0): the branch follows the full rub down to the frictionless orbit
// and ends at the bound as asked (exit 0), its last point's derivative in mu taken one-sided
// where mu - h is refused (before: G_lambda failed next to 0, exit 3).
TEST_CASE("rubdyn branch: down to a key's bound (contact.mu to 0)", "[orbit][cli]") {
  const fs::path dir = fresh_dir("branch-bound");
  const CliOutcome r =
      cli("branch " + sh(kCase) + " --vary contact.mu --down --to 0 --points 100 --out " +
          sh(dir.string()));
  INFO(r.out << r.err);
  REQUIRE(r.code == 0);
  const std::string js = slurp(dir / "branch.json");
  CHECK(has(js, "\"outcome\": \"lambda_bound\""));
  const auto rows = text_lines(slurp(dir / "branch.csv"));
  REQUIRE(rows.size() > 3);
  const auto last = csv_fields(rows.back());
  // within the smallest step (ds_min 1e-3 of the scale, 1e-3 here: 1e-6) of 0, up to its
  // predictor's factor 2, and every point a smooth sliding orbit (no events)
  CHECK(std::stod(last[1]) >= 0.0);
  CHECK(std::stod(last[1]) <= 1e-5);
  for (std::size_t i = 1; i < rows.size(); ++i)
    CHECK(csv_fields(rows[i]).back() == "\"slip- | | slip-\"");
  fs::remove_all(dir);
}
