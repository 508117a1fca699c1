// rubdyn compare: differences and event matching on constructed solutions with known answers.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "rubdyn/analysis/compare.hpp"
#include "rubdyn/io/output_reader.hpp"

using namespace rubdyn;
namespace fs = std::filesystem;

namespace {
fs::path tmp(const std::string& name) {
  return fs::temp_directory_path() / ("rubdyn-cmp-" + std::to_string(::getpid()) + "-" + name);
}
void write(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
}
}  // namespace

TEST_CASE("compare: linear series differ by a known amount", "[compare]") {
  // a: omega = t on t = 0, 1, 2; b: omega = t + 0.5 on t = 0, 0.5, 2 (a plain CSV with only the
  // columns it has). The difference is 0.5 everywhere: sup = rms = 0.5.
  const auto pa = tmp("a.csv"), pb = tmp("b.csv");
  write(pa, "t,omega,x_r,phase\n0,0,0,free\n1,1,0,free\n2,2,0,free\n");
  write(pb, "t,omega\n0,0.5\n0.5,1.0\n2,2.5\n");
  const Series a = read_series(pa.string()), b = read_series(pb.string());
  const Comparison c = compare_solutions(a, b, {}, {});
  REQUIRE(c.points == 4);  // union of {0, 1, 2} and {0, 0.5, 2}
  REQUIRE(c.columns.size() == 1);
  CHECK(c.columns[0].name == "omega");
  CHECK(c.columns[0].sup == Approx(0.5).epsilon(1e-15));
  CHECK(c.columns[0].rms == Approx(0.5).epsilon(1e-15));
  // x_r is only in a; the other standard columns in neither
  CHECK(std::find(c.missing.begin(), c.missing.end(), "x_r") != c.missing.end());
  // a window restricts the comparison
  const Comparison w = compare_solutions(a, b, {}, {}, std::make_pair(0.25, 0.75));
  CHECK(w.t0 == 0.25);
  CHECK(w.t1 == 0.75);
  CHECK(w.points == 1);  // only t = 0.5 lies inside
  fs::remove(pa);
  fs::remove(pb);
}

TEST_CASE("compare: a repeated time takes the sample after the event", "[compare]") {
  // a jumps from 0 to 1 at t = 1 (two samples at t = 1); b is 1 from t = 1 on.
  const auto pa = tmp("ja.csv"), pb = tmp("jb.csv");
  write(pa, "t,omega\n0,0\n1,0\n1,1\n2,1\n");
  write(pb, "t,omega\n0,0\n1,1\n2,1\n");
  const Comparison c =
      compare_solutions(read_series(pa.string()), read_series(pb.string()), {}, {});
  // at t = 1 both give 1 (after the jump); between 0 and 1 b rises linearly while a stays 0:
  // the sup over the sample times {0, 1, 2} is 0
  CHECK(c.columns[0].sup == 0.0);
  fs::remove(pa);
  fs::remove(pb);
}

TEST_CASE("compare: events are matched by kind and nearest time", "[compare]") {
  const std::vector<TimedEvent> ea = {{0.1, "impact"}, {0.2, "liftoff"}, {0.3, "impact"}};
  const std::vector<TimedEvent> eb = {
      {0.1001, "impact"}, {0.2, "stick"}, {0.3002, "impact"}, {0.5, "impact"}};
  const auto pa = tmp("ea.csv");
  write(pa, "t,omega\n0,0\n1,0\n");
  const Series s = read_series(pa.string());
  const Comparison c = compare_solutions(s, s, ea, eb, std::nullopt, 1e-3);
  REQUIRE(c.matched.size() == 2);
  CHECK(c.max_event_shift() == Approx(2e-4).epsilon(1e-9));
  REQUIRE(c.unmatched_a.size() == 1);
  CHECK(c.unmatched_a[0].kind == "liftoff");
  REQUIRE(c.unmatched_b.size() == 2);  // the stick and the impact at 0.5
  fs::remove(pa);
}

TEST_CASE("compare: bad files name the file, line and problem", "[compare]") {
  const auto p = tmp("bad.csv");
  write(p, "time,omega\n0,1\n");
  CHECK_THROWS_WITH(read_series(p.string()), Catch::Contains(":1: no column named t"));
  write(p, "t,omega\n0,1\n1\n");
  CHECK_THROWS_WITH(read_series(p.string()), Catch::Contains(":3:"));
  write(p, "t,omega\n0,1\n-1,2\n");
  CHECK_THROWS_WITH(read_series(p.string()), Catch::Contains("decreases"));
  CHECK_THROWS_WITH(read_series(tmp("none.csv").string()), Catch::Contains("cannot read"));
  fs::remove(p);
}

TEST_CASE("compare: inputs that are not two solutions are refused naming the solution",
          "[compare]") {
  // Every case below crashed (empty t: front() of an empty vector) or was silently accepted
  // (NaN times and windows drop out of every comparison) before compare_solutions checked them.
  Series ok;
  ok.source = "good";
  ok.t = {0.0, 1.0, 2.0};
  ok.names = {"omega"};
  ok.values = {{0.0, 1.0, 2.0}};
  const double nan = std::nan(""), inf = std::numeric_limits<double>::infinity();
  auto broken = [&](auto edit) {
    Series s = ok;
    s.source = "bad";
    edit(s);
    return s;
  };
  const std::vector<std::pair<Series, std::string>> bad = {
      {broken([](Series& s) {
         s.t.clear();
         s.values[0].clear();
       }),
       "bad: 0 samples"},
      {broken([](Series& s) {
         s.t = {0.0};
         s.values[0] = {0.0};
       }),
       "bad: 1 samples"},
      {broken([](Series& s) { s.values[0].pop_back(); }),
       "bad: column omega has 2 values, t has 3"},
      {broken([](Series& s) { s.names.push_back("x_r"); }), "bad: 2 column names for 1 columns"},
      {broken([&](Series& s) { s.t[1] = nan; }), "bad: t[1] = nan: times must be finite"},
      {broken([&](Series& s) { s.t[2] = inf; }), "bad: t[2] = inf: times must be finite"},
      {broken([](Series& s) { s.t[2] = 0.5; }), "bad: t[2] = 0.5 < t[1] = 1: times must not"}};
  for (const auto& [s, what] : bad) {
    INFO(what);
    CHECK_THROWS_AS(compare_solutions(s, ok, {}, {}), std::invalid_argument);
    CHECK_THROWS_WITH(compare_solutions(s, ok, {}, {}), Catch::Contains("compare: " + what));
    CHECK_THROWS_WITH(compare_solutions(ok, s, {}, {}), Catch::Contains("compare: " + what));
  }
  CHECK_THROWS_WITH(compare_solutions(ok, ok, {{nan, "impact"}}, {}),
                    Catch::Contains("good: event 0 (impact) at t = nan: times must be finite"));
  using W = std::pair<double, double>;
  for (const W& w : {W{nan, 1.0}, W{0.0, nan}, W{1.0, 0.5}, W{1.0, 1.0}, W{-inf, 1.0}}) {
    INFO(w.first << " " << w.second);
    CHECK_THROWS_WITH(compare_solutions(ok, ok, {}, {}, w),
                      Catch::Contains("must be two finite times t0 < t1"));
  }
  // a valid window outside both solutions: nothing in common, said with both ranges
  CHECK_THROWS_WITH(compare_solutions(ok, ok, {}, {}, W{5.0, 6.0}),
                    Catch::Contains("good [0, 2] and good [0, 2] share no time inside the window "
                                    "[5, 6]"));
  for (const double tol : {nan, 0.0, -1.0, inf}) {
    INFO(tol);
    CHECK_THROWS_WITH(compare_solutions(ok, ok, {}, {}, std::nullopt, tol),
                      Catch::Contains("event_tol"));
  }
  // the unperturbed input is accepted: the refusals above are the edits'
  CHECK(compare_solutions(ok, ok, {{1.0, "impact"}}, {{1.0, "impact"}}).matched.size() == 1);
}

TEST_CASE("compare: a folder or file that is not a solution is a ReadError with file and line",
          "[compare]") {
  const auto dir = tmp("folder");
  fs::create_directories(dir);
  write(dir / "timeseries.csv", "t,omega\n");  // a run killed before its first sample
  CHECK_THROWS_AS(read_series(dir.string()), ReadError);
  CHECK_THROWS_WITH(read_series(dir.string()),
                    Catch::Contains("timeseries.csv: 0 samples: compare needs at least two"));
  write(dir / "timeseries.csv", "t,omega\n0,1\nnan,2\n");
  CHECK_THROWS_WITH(read_series(dir.string()),
                    Catch::Contains("timeseries.csv:3: t = 'nan' is not a finite number"));
  write(dir / "timeseries.csv", std::string("t,omega\n0,1\n1,\xff\x01\n"));
  CHECK_THROWS_WITH(read_series(dir.string()),
                    Catch::Contains("timeseries.csv:3: byte 0xff at column 3: not text"));
  write(dir / "timeseries.csv", "t,omega\r\n0,1\r\n1,2\r\n");  // CRLF: read as LF
  CHECK(read_series(dir.string()).column("omega")->back() == 2.0);
  write(dir / "events.csv", "t,kind\ninf,impact\n");
  CHECK_THROWS_WITH(read_events(dir.string()),
                    Catch::Contains("events.csv:2: t = 'inf' is not a finite time"));
  fs::remove_all(dir);
}
