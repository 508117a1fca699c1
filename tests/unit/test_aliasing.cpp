// Spectrogram frames that alias the orbit's whirl are marked (issue 22: in rolling the orbit
// whirls at R_r / g0 times the spin, far above the Nyquist frequency of the output grid).
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "rubdyn/analysis/postprocess.hpp"

using namespace rubdyn;
namespace fs = std::filesystem;

namespace {

// An output folder of the reference case whose rotor whirls at f0 [Hz] on a circle of radius a
// about the point (cx, cy), sampled every dt for n samples (velocities exact, as a solver
// writes them).
fs::path whirl_run(const std::string& name, double f0, double a, double cx, double cy, double dt,
                   int n) {
  const fs::path dir =
      fs::temp_directory_path() / ("rubdyn-alias-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy_file(std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml",
                dir / "case.resolved.toml");
  std::ofstream f(dir / "timeseries.csv");
  f << "t,x_b,y_b,x_r,y_r,theta,x_s,y_s,vx_b,vy_b,vx_r,vy_r,omega,vx_s,vy_s,d_N,v_N,v_t,F_N,F_T,"
       "phase\n";
  f.precision(17);
  const double w = 2.0 * M_PI * f0;
  for (int k = 0; k < n; ++k) {
    const double t = k * dt, c = std::cos(w * t), s = std::sin(w * t);
    f << t << ",0,0," << cx + a * c << "," << cy + a * s << ",0,0,0,0,0," << -a * w * s << ","
      << a * w * c << ",2000,0,0,0,0,0,1,0,stick\n";
  }
  return dir;
}

}  // namespace

TEST_CASE("spectrogram: frames that alias a whirl faster than the samples are marked",
          "[post][aliasing]") {
  AnalysisOptions o;
  o.window = 0.04;
  o.overlap = 0.5;
  const double dt = 1e-4;  // Nyquist 5 kHz
  SECTION("a 195 Hz whirl is sampled well: no frame marked, the scale is the whirl") {
    const RunRecord r = read_run(whirl_run("slow", 195.3125, 2e-4, 1e-5, -3e-5, dt, 4096).string());
    const Spectrogram g = spectrogram(r, o);
    REQUIRE(g.t.size() > 5);
    CHECK(g.f_nyquist == Approx(5000.0).epsilon(1e-9));
    for (std::size_t i = 0; i < g.t.size(); ++i) {
      CHECK_FALSE(g.undersampled[i]);
      // a circle: max |z'| / (2 pi max |z - mean z|) = f0 exactly, up to the frame's mean of a
      // sampled circle over 7.8 turns (off the centre by < 1/7.8 of a turn's chord: < 3 %)
      CHECK(g.f_whirl[i] == Approx(195.3125).epsilon(0.03));
    }
  }
  SECTION("a 40 kHz whirl (rolling at 250 x 1000 rad/s) aliases: every frame marked") {
    const RunRecord r =
        read_run(whirl_run("fast", 40000.0 + 3.7, 2e-4, 0.0, 0.0, dt, 4096).string());
    const Spectrogram g = spectrogram(r, o);
    REQUIRE(g.t.size() > 5);
    for (std::size_t i = 0; i < g.t.size(); ++i) {
      CHECK(g.undersampled[i]);
      // the samples alias it to 3.7 Hz (they cover 0.15 of a turn per frame), but the
      // velocities see 40 kHz: every sample lies within 2 a of the samples' mean (a point of
      // the disc), so the scale is at least f0 / 2, above the Nyquist frequency's half
      CHECK(g.f_whirl[i] >= 0.5 * 40003.7);
    }
  }
  SECTION("analysis.json names the undersampled spans; campbell.csv carries the flag") {
    const fs::path dir = whirl_run("json", 40003.7, 2e-4, 0.0, 0.0, dt, 4096);
    write_analysis(read_run(dir.string()), o);
    std::ifstream j(dir / "analysis" / "analysis.json");
    const std::string text((std::istreambuf_iterator<char>(j)), std::istreambuf_iterator<char>());
    CHECK(text.find("\"spectrogram_nyquist_hz\": 5000") != std::string::npos);
    CHECK(text.find("\"spectrogram_undersampled_spans\": [[") != std::string::npos);
    std::ifstream c(dir / "analysis" / "campbell.csv");
    std::string header;
    std::getline(c, header);
    CHECK(header.rfind("t,omega,f_whirl,undersampled", 0) == 0);
  }
}
