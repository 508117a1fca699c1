// Post-processing and sweeps on constructed runs with known answers.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

#include "rubdyn/analysis/postprocess.hpp"
#include "rubdyn/driver/sweep.hpp"

using namespace rubdyn;
namespace fs = std::filesystem;

namespace {

const std::string kRef = std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml";

fs::path tmp(const std::string& name) {
  const fs::path p =
      fs::temp_directory_path() / ("rubdyn-post-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

// The reference case as case.resolved.toml in `dir` and timeseries.csv opened there with its
// header written (rows follow with 17 digits): an output folder built by hand.
std::ofstream timeseries(const fs::path& dir) {
  fs::copy_file(kRef, dir / "case.resolved.toml");
  std::ofstream f(dir / "timeseries.csv");
  f << "t,x_b,y_b,x_r,y_r,theta,x_s,y_s,vx_b,vy_b,vx_r,vy_r,omega,vx_s,vy_s,d_N,v_N,v_t,F_N,F_T,"
       "phase\n";
  f.precision(17);
  return f;
}

// An output folder whose rotor runs on the circle of radius a about the (fixed) stator centre at
// angular speed w (w < 0: clockwise, backward for a positive spin), sampled every dt, in the
// given phase, with F_T constant.
fs::path circular_run(const std::string& name, double a, double w, double dt, int n,
                      const char* phase, double F_T, double t_contact = 0.0) {
  const fs::path dir = tmp(name);
  std::ofstream f = timeseries(dir);
  for (int k = 0; k < n; ++k) {
    const double t = k * dt;
    const double x = a * std::cos(w * t), y = a * std::sin(w * t);
    const double vx = -a * w * std::sin(w * t), vy = a * w * std::cos(w * t);
    f << t << ",0,0," << x << "," << y << ",0,0,0,0,0," << vx << "," << vy << ",2000,0,0,"
      << 2e-4 - a << ",0,0,1," << F_T << "," << (t < t_contact ? "free" : phase) << "\n";
  }
  return dir;
}

}  // namespace

TEST_CASE("postprocess: a circular backward orbit - precession - whirl - spectrum peak", "[post]") {
  // 2^12 samples at dt = 1e-4 s; f0 = -80 / (4096 dt) = -195.3 Hz lies on an FFT bin, where a
  // Hann-windowed transform normalised by sum(w) returns the amplitude a exactly (up to
  // round-off), and the spectrum peaks there.
  const double dt = 1e-4, a = 1e-4;
  const int n = 4096;
  const double f0 = -80.0 / (n * dt), w = 2.0 * M_PI * f0;
  const auto dir = circular_run("circle", a, w, dt, n, "slip-", 5.0);
  const RunRecord r = read_run(dir.string());
  REQUIRE(r.samples.size() == static_cast<size_t>(n));
  auto d = derive(r);
  // precession = w exactly (velocities written with 17 digits): relative 1e-12
  for (const auto& x : d) {
    REQUIRE(x.precession == Approx(w).epsilon(1e-12));
    REQUIRE(x.whirl == Whirl::Backward);
    REQUIRE(x.regime == Regime::Sliding);
  }
  // friction torque ratio = R_r F_T / tau_a = 0.05 * 5 / 20
  CHECK(d[7].friction_torque_ratio == Approx(0.0125).epsilon(1e-15));
  CHECK(d[7].dN_over_g0 == Approx(0.5).epsilon(1e-12));
  const RunVerdicts v = verdicts(r, d);
  // the orbit turns 80 times in the run: one sustained backward run covering the whole run
  REQUIRE(v.backward_onset.has_value());
  CHECK(*v.backward_onset == 0.0);
  CHECK(v.whip_onset == v.backward_onset);
  CHECK_FALSE(v.whirl_onset.has_value());
  CHECK(v.backward_fraction == Approx(1.0).epsilon(1e-12));
  CHECK(v.whip_fraction == Approx(1.0).epsilon(1e-12));
  CHECK(v.forward_fraction == 0.0);
  CHECK(v.contact_fraction == Approx(1.0).epsilon(1e-12));
  CHECK(v.limited);  // omega = 2000 < omega_lim = 2110 throughout
  AnalysisOptions o;
  o.f_max = 1000.0;
  const Spectrum s = full_spectrum(r, o);
  const auto peak = std::max_element(s.amplitude.begin(), s.amplitude.end());
  CHECK(s.f[peak - s.amplitude.begin()] == Approx(f0).epsilon(1e-12));
  CHECK(*peak == Approx(a).epsilon(1e-9));
  // spectrogram: every frame peaks at f0 (frames of 0.04 s, zero-padded: the bin nearest f0 is
  // within half a bin, df = 1 / (pad * 0.04 s) / ... <= 6.25 Hz)
  o.window = 0.04;
  const Spectrogram g = spectrogram(r, o);
  REQUIRE(g.t.size() >= 10);
  for (const auto& amp : g.amplitude) {
    const auto pk = std::max_element(amp.begin(), amp.end());
    CHECK(std::abs(g.f[pk - amp.begin()] - f0) <= 0.5 * (g.f[1] - g.f[0]) + 1e-9);
  }
  // the Campbell overlay at omega = 2000: backward modes at negative frequency
  REQUIRE(g.campbell_labels == std::vector<std::string>{"f1f", "f2f", "f1b", "f2b"});
  CHECK(g.campbell[2][0] < 0.0);  // f1b
  CHECK(g.campbell[0][0] > 0.0);  // f1f
  fs::remove_all(dir);
}

TEST_CASE("postprocess: a backward orbit in flight is a precession-sign whirl, not a sustained one",
          "[post]") {
  // The orbit turns backward at 50 Hz from t = 0 (5 turns per 0.1 s); the rotor is in flight until
  // t_c = 0.1 s and in contact after. The precession-sign whirl (any regime) starts at t = 0, the
  // sustained whirl (in contact) and the permanent contact at the first contact sample, t_c.
  // Sample times are k * 1e-4 written with 17 digits, and t_c = 1000 samples: the onsets are
  // sample times, compared to 1e-12 relative (the decimal round trip of k * 1e-4).
  const double dt = 1e-4, a = 1e-4, tc = 0.1;
  const double w = -2.0 * M_PI * 50.0;
  const auto dir = circular_run("flight-then-contact", a, w, dt, 2000, "slip-", 5.0, tc);
  const RunRecord r = read_run(dir.string());
  auto d = derive(r);
  const RunVerdicts v = verdicts(r, d);
  REQUIRE(v.sign_backward_onset.has_value());
  CHECK(*v.sign_backward_onset == 0.0);
  REQUIRE(v.backward_onset.has_value());
  CHECK(*v.backward_onset == Approx(tc).epsilon(1e-12));
  CHECK(v.whip_onset == v.backward_onset);
  REQUIRE(v.permanent_contact_onset.has_value());
  CHECK(*v.permanent_contact_onset == Approx(tc).epsilon(1e-12));
  // time fractions: sample i holds over [t_i, t_i+1), so the run spans 1999 intervals; the sign
  // whirl covers all of them, the sustained one the 999 from t_c (sums of dt: 1e-9 relative is
  // far above their round-off and far below the 1 / 1999 that one interval more or less makes)
  CHECK(v.sign_backward_fraction == Approx(1.0).epsilon(1e-12));
  CHECK(v.backward_fraction == Approx(999.0 / 1999.0).epsilon(1e-9));
  CHECK(d.front().sign_run);
  CHECK_FALSE(d.front().sustained);
  // min_turns = 6: the whole run (about 10 turns) is still a sign whirl, the contact stretch
  // (999 dt at 50 Hz: 4.995 turns) is no longer a sustained one
  AnalysisOptions o;
  o.min_turns = 6.0;
  auto d6 = derive(r);
  const RunVerdicts v6 = verdicts(r, d6, o);
  REQUIRE(v6.sign_backward_onset.has_value());
  CHECK(*v6.sign_backward_onset == 0.0);
  CHECK_FALSE(v6.backward_onset.has_value());
  CHECK(v6.backward_fraction == 0.0);
  fs::remove_all(dir);
}

TEST_CASE("postprocess: a run ending in flight has no permanent contact", "[post]") {
  // contact first, flight from t_c on: the rotor lifted off and did not come back
  const fs::path dir = tmp("contact-then-flight");
  std::ofstream f = timeseries(dir);
  for (int k = 0; k < 1000; ++k)
    f << k * 1e-4 << ",0,0,0,-1e-4,0,0,0,0,0,0,0,2000,0,0,1e-4,0,0,0,0,"
      << (k < 500 ? "slip-" : "free") << "\n";
  f.close();
  const RunRecord r = read_run(dir.string());
  auto d = derive(r);
  const RunVerdicts v = verdicts(r, d);
  CHECK_FALSE(v.permanent_contact_onset.has_value());
  CHECK(v.contact_fraction == Approx(500.0 / 999.0).epsilon(1e-9));
  fs::remove_all(dir);
}

TEST_CASE("postprocess: rocking to and fro in contact is not a sustained whirl", "[post]") {
  // the orbit angle oscillates by +-0.3 rad: the precession changes sign every half period and
  // no run covers a full turn, so there is no whirl verdict (the reference case's persistent
  // sliding at the bottom of the stator looks like this)
  const fs::path dir = tmp("rocking");
  std::ofstream f = timeseries(dir);
  const double a = 2e-4, W = 2 * M_PI * 50;
  for (int k = 0; k < 2000; ++k) {
    const double t = k * 1e-4, phi = -M_PI / 2 + 0.3 * std::sin(W * t);
    const double dphi = 0.3 * W * std::cos(W * t);
    f << t << ",0,0," << a * std::cos(phi) << "," << a * std::sin(phi) << ",0,0,0,0,0,"
      << -a * dphi * std::sin(phi) << "," << a * dphi * std::cos(phi) << ",2000,0,0,0,0,0,1,0,"
      << "slip-\n";
  }
  f.close();
  const RunRecord r = read_run(dir.string());
  auto d = derive(r);
  const RunVerdicts v = verdicts(r, d);
  CHECK_FALSE(v.backward_onset.has_value());
  CHECK(v.backward_fraction == 0.0);
  CHECK(v.forward_fraction == 0.0);
  CHECK(v.contact_fraction == Approx(1.0).epsilon(1e-12));
  fs::remove_all(dir);
}

TEST_CASE("postprocess: bad folders are reported with the file and line", "[post]") {
  CHECK_THROWS_WITH(read_run("/nonexistent/run"), Catch::Contains("not an output folder"));
  const fs::path dir = tmp("bad");
  fs::copy_file(kRef, dir / "case.resolved.toml");
  std::ofstream(dir / "timeseries.csv")
      << "t,x_b,y_b,x_r,y_r,theta,x_s,y_s,vx_b,vy_b,vx_r,vy_r,omega,vx_s,vy_s,d_N,v_N,v_t,F_N,F_T,"
         "phase\n0,0,0,0,0,0,0,0,0,0,0,0,2000,0,0,0,0,0,0,0,free\n"
         "1e-4,0,0,0,oops,0,0,0,0,0,0,0,2000,0,0,0,0,0,0,0,free\n";
  CHECK_THROWS_WITH(read_run(dir.string()), Catch::Contains("timeseries.csv:3: column y_r"));
  fs::remove_all(dir);
}

TEST_CASE("sweep: variations - points - shards parse and order deterministically", "[sweep]") {
  const Variation a = parse_variation("contact.mu=0, 0.1,0.2");
  CHECK(a.key == "contact.mu");
  CHECK(a.values == std::vector<std::string>{"0", "0.1", "0.2"});
  const Variation b = parse_variation("stator.k=1e6:4e6:4");
  CHECK(b.values == std::vector<std::string>{"1000000", "2000000", "3000000", "4000000"});
  CHECK_THROWS_WITH(parse_variation("mu=0.1"), Catch::Contains("has no section"));
  CHECK_THROWS_WITH(parse_variation("contact.mu=0.1,,0.2"), Catch::Contains("empty value"));
  CHECK_THROWS_WITH(parse_variation("stator.k=1:2:1.5"), Catch::Contains("integer in [2"));
  CHECK_THROWS(parse_variation("contact.mu"));
  const auto pts = sweep_points({a, b});
  REQUIRE(pts.size() == 12);
  CHECK(pts[5].index == 5);  // mu index 1, k index 1 (the last variation varies fastest)
  CHECK(pts[5].overrides() == std::vector<std::string>{"contact.mu=0.1", "stator.k=2000000"});
  const Shard s = parse_shard("2/3");
  CHECK(s.index == 2);
  CHECK(s.count == 3);
  CHECK_THROWS(parse_shard("0/3"));
  CHECK_THROWS(parse_shard("4/3"));
  CHECK_THROWS(parse_shard("1-3"));
}

namespace {
// sweep.csv without the wall-time and folder columns (which differ between runs by design)
std::vector<std::string> stable_rows(const fs::path& csv) {
  std::ifstream f(csv);
  std::string line;
  std::vector<std::string> out;
  std::vector<char> drop;  // wall_seconds and folder differ between runs: found by header name
  while (std::getline(f, line)) {
    std::stringstream ss(line);
    std::string cell, keep;
    size_t c = 0;
    while (std::getline(ss, cell, ',')) {
      if (out.empty()) drop.push_back(cell == "wall_seconds" || cell == "folder");
      if (c >= drop.size() || !drop[c]) keep += cell + "|";
      ++c;
    }
    out.push_back(keep);
  }
  return out;
}
}  // namespace

TEST_CASE("sweep: parallel - sharded and merged tables equal the serial table", "[sweep]") {
  const fs::path out1 = tmp("sweep-serial"), out2 = tmp("sweep-sharded");
  SweepOptions o;
  o.case_path = kRef;
  o.sets = {"run.t_end=0.012", "solver.rtol=1e-8", "solver.atol=1e-10"};
  o.vary = {parse_variation("contact.mu=0.05,0.1,0.3")};
  o.out = out1.string();
  o.jobs = 1;
  const auto rows = run_sweep(o);
  REQUIRE(rows.size() == 3);
  for (const auto& r : rows) {
    CHECK(r.complete);
    CHECK(r.v.events >= 1);  // first impact at about 6 ms
    CHECK(fs::exists(fs::path(r.folder) / "analysis" / "analysis.json"));
  }
  o.out = out2.string();
  o.jobs = 2;
  o.shard = parse_shard("1/2");
  CHECK(run_sweep(o).size() == 2);  // points 0 and 2
  CHECK_THROWS_WITH(merge_sweep_shards(out2.string()), Catch::Contains("shard 2 of 2 missing"));
  o.shard = parse_shard("2/2");
  CHECK(run_sweep(o).size() == 1);
  CHECK(merge_sweep_shards(out2.string()) == 3);
  const auto a = stable_rows(out1 / "sweep.csv"), b = stable_rows(out2 / "sweep.csv");
  REQUIRE(a.size() == 4);
  CHECK(a == b);
  // a bad value stops the sweep before anything is written
  const fs::path out3 = tmp("sweep-bad");
  fs::remove_all(out3);
  o.out = out3.string();
  o.shard = {};
  o.vary = {parse_variation("contact.mu=0.1,-1")};
  CHECK_THROWS_WITH(run_sweep(o), Catch::Contains("contact.mu"));
  CHECK_FALSE(fs::exists(out3));
  fs::remove_all(out1);
  fs::remove_all(out2);
}

TEST_CASE("sweep --certify: a verdict that changes with the step is not certified", "[sweep]") {
  // carp-onevc at h = 1e-4 on the full reference case: at mu = 0.2 the coarse run crosses
  // omega_lim = 2110 rad/s (omega_max about 2126 rad/s: not limited) while the run at h = 1e-5
  // stays below it (about 2104 rad/s: limited); at mu = 0.1 both pass omega_lim with no
  // backward whirl. The margins (16 and 6 rad/s on omega_lim) are physical
  // discretisation errors, far above round-off, so the verdicts do not depend on the build.
  const fs::path out = tmp("sweep-certify");
  SweepOptions o;
  o.case_path = kRef;
  o.sets = {"solver.kind=\"carp-onevc\"", "solver.h=1e-4"};
  o.vary = {parse_variation("contact.mu=0.1,0.2")};
  o.out = out.string();
  o.jobs = 2;
  o.certify = true;
  const auto rows = run_sweep(o);
  REQUIRE(rows.size() == 2);
  for (const auto& r : rows) {
    REQUIRE(r.complete);
    REQUIRE(r.certified_run);
    CHECK(r.tight_termination == "completed");
    // the certified flag is exactly the agreement of the two runs' verdicts
    const bool same = r.v.limited == r.tight.limited &&
                      r.v.backward_onset.has_value() == r.tight.backward_onset.has_value() &&
                      r.v.whip_onset.has_value() == r.tight.whip_onset.has_value();
    CHECK(r.certified == same);
    // the tight run used a ten times smaller step
    std::ifstream f(fs::path(r.folder + "-tight") / "case.resolved.toml");
    std::stringstream ss;
    ss << f.rdbuf();
    CHECK(ss.str().find("\nh = 1e-05\n") != std::string::npos);
  }
  CHECK(rows[0].certified);
  CHECK_FALSE(rows[0].v.limited);
  CHECK_FALSE(rows[1].certified);
  CHECK_FALSE(rows[1].v.limited);
  CHECK(rows[1].tight.limited);
  // the table says so
  std::ifstream t(out / "sweep.csv");
  std::string header, l0, l1;
  std::getline(t, header);
  std::getline(t, l0);
  std::getline(t, l1);
  CHECK(header.find(",certified,tight_termination,tight_limited,") != std::string::npos);
  CHECK(l0.find(",yes,completed,no,") != std::string::npos);
  CHECK(l1.find(",no,completed,yes,") != std::string::npos);
  fs::remove_all(out);
}

TEST_CASE("postprocess: NaN sample times and NaN or reversed windows are refused", "[post]") {
  // The samples reach verdicts from memory too (Python's analyze): a NaN time or window bound
  // dropped out of std::max / std::min and of every comparison, and was analysed as the whole run.
  const auto dir = circular_run("nan", 1e-4, -300.0, 1e-4, 200, "slip-", 5.0);
  const RunRecord good = read_run(dir.string());
  auto d = derive(good);
  CHECK_NOTHROW(verdicts(good, d));  // the unperturbed run is analysed
  const double nan = std::nan("");
  for (const std::size_t i : {std::size_t{0}, std::size_t{57}, std::size_t{199}}) {
    RunRecord r = good;
    r.samples[i].t = nan;
    auto dr = derive(r);
    INFO(i);
    CHECK_THROWS_AS(verdicts(r, dr), std::invalid_argument);
    CHECK_THROWS_WITH(verdicts(r, dr),
                      Catch::Contains("sample " + std::to_string(i) + ": t = nan"));
    CHECK_THROWS_WITH(full_spectrum(r), Catch::Contains("is not finite"));
  }
  RunRecord back = good;
  back.samples[100].t = back.samples[98].t;  // goes back by one sample
  auto db = derive(back);
  CHECK_THROWS_WITH(verdicts(back, db), Catch::Contains("sample 100: t = "));
  CHECK_THROWS_WITH(verdicts(back, db), Catch::Contains("times must not decrease"));
  const double inf = std::numeric_limits<double>::infinity();
  using W = std::pair<std::optional<double>, std::optional<double>>;
  for (const W& w : {W{nan, std::nullopt}, W{std::nullopt, nan}, W{0.001, nan}, W{-inf, 0.01}}) {
    AnalysisOptions o;
    o.t0 = w.first;
    o.t1 = w.second;
    INFO(o.t0.value_or(-1) << " " << o.t1.value_or(-1));
    CHECK_FALSE(analysis_option_problems(o).empty());
    CHECK_THROWS_WITH(verdicts(good, d, o), Catch::Contains("times must be finite"));
  }
  AnalysisOptions reversed;
  reversed.t0 = 0.015;
  reversed.t1 = 0.005;
  const auto problems = analysis_option_problems(reversed);
  REQUIRE(problems.size() == 1);
  CHECK(problems[0] == "--t-window t1 = 0.005: must be > t0");
  CHECK_THROWS_WITH(verdicts(good, d, reversed), Catch::Contains("does not overlap"));
  AnalysisOptions inside;  // a valid window is accepted: the refusals above are the bounds'
  inside.t0 = 0.005;
  inside.t1 = 0.015;
  CHECK(analysis_option_problems(inside).empty());
  CHECK(verdicts(good, d, inside).t0 == 0.005);
  fs::remove_all(dir);
}
