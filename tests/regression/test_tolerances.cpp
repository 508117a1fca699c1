// Tolerances down to round-off (validation/tolerances): the setting that once stopped with
// CV_TOO_MUCH_ACC in the rolling regime completes, and runs at two tight tolerances agree to the
// floor that the problem's conditioning sets.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "rubdyn/driver/simulate.hpp"
#include "rubdyn/io/case_io.hpp"

using namespace rubdyn;

namespace {

const std::string kRef = std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml";

}  // namespace

TEST_CASE("Rolling at rtol 1e-12 / atol 1e-16 completes and agrees with rtol 1e-13 / 1e-17",
          "[regression][tolerances]") {
  // The reported case stopped with CV_TOO_MUCH_ACC at t = 0.176 s, in stick (rolling from
  // 0.116 s); 0.2 s covers the impacts, the whip, the stick onset and 84 ms of rolling.
  auto run = [](const char* rtol, const char* atol) {
    const CaseSpec spec =
        load_case(kRef, {"contact.mu=0.25", "run.t_end=0.2", std::string("solver.rtol=") + rtol,
                         std::string("solver.atol=") + atol});
    MemorySink sink;
    const RunSummary s = simulate(spec, sink);
    INFO(s.message);
    REQUIRE(s.complete());
    REQUIRE(s.t_reached == 0.2);
    return sink.samples;
  };
  const auto a = run("1e-12", "1e-16");
  const auto b = run("1e-13", "1e-17");
  // Same output grid (dt = 1e-4) and the same event rows: compare sample by sample where the
  // times coincide. The floor measured by validation/tolerances is ~1e-10 m (one ulp of omega0
  // moves the rolling orbit by 5.6e-11 m, 2 ulps by 9.6e-11 m; these two runs: 6.9e-11 m); 3e-10
  // m keeps a margin of 3 over the floor and is 1e-6 of the gap (2e-4 m), far below what a lost
  // step or a wrong stick time gives (the rtol 1e-10 run is 2.8e-9 m away).
  std::size_t i = 0, j = 0, compared = 0;
  double worst = 0.0;
  while (i < a.size() && j < b.size()) {
    if (a[i].t < b[j].t) {
      ++i;
    } else if (b[j].t < a[i].t) {
      ++j;
    } else {
      worst = std::max(worst, std::hypot(a[i].q[2] - b[j].q[2], a[i].q[3] - b[j].q[3]));
      ++compared;
      ++i;
      ++j;
    }
  }
  CHECK(compared >= 2000);  // 0.2 s at dt = 1e-4
  CHECK(worst <= 3e-10);
}
