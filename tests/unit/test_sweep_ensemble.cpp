// rubdyn sweep --ensemble (issue 14, item 4): every point run again as N perturbed members in
// OUT/pNNNN-eKK/, and the ensemble columns of sweep.csv. What the sweep wrote is checked against
// the members' own folders read back here (case.resolved.toml, analysis/analysis.json), never
// against the sweep's values.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <thread>

#include "rubdyn/driver/sweep.hpp"
#include "rubdyn/io/case_io.hpp"
#include "support/cli.hpp"

namespace fs = std::filesystem;
using namespace rubdyn;

namespace {

const std::string kRef = std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml";

using namespace rubdyn::testing;  // fresh_dir, slurp, sh, has, cli (support/cli.hpp)
using Outcome = CliOutcome;

using Row = std::map<std::string, std::string>;

/// sweep.csv as {column: field} rows (a plain split on commas: these tests' paths have none).
std::vector<Row> read_table(const fs::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::vector<std::string> header;
  std::vector<Row> rows;
  auto split = [](const std::string& l) {
    std::vector<std::string> f;
    std::stringstream ss(l);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    if (!l.empty() && l.back() == ',') f.push_back("");
    return f;
  };
  if (std::getline(in, line)) header = split(line);
  while (std::getline(in, line)) {
    const auto f = split(line);
    REQUIRE(f.size() == header.size());
    Row r;
    for (std::size_t i = 0; i < f.size(); ++i) r[header[i]] = f[i];
    rows.push_back(r);
  }
  return rows;
}

std::string header_of(const fs::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  return line;
}

/// The text after `"key": ` in a JSON file written by rubdyn (one key a line), up to , or }.
std::string json_field(const std::string& json, const std::string& key) {
  const std::string tag = "\"" + key + "\": ";
  const auto p = json.find(tag);
  REQUIRE(p != std::string::npos);
  const auto a = p + tag.size();
  return json.substr(a, json.find_first_of(",}\n", a) - a);
}

/// What the sweep's ensemble columns must say, computed from the runs' folders.
struct Expected {
  int runs = 0, incomplete = 0, complete = 0;
  int limited = 0, backward = 0, whip = 0, rolling = 0;
  double omega_min = INFINITY, omega_max = -INFINITY;
};

Expected from_folders(const std::vector<fs::path>& runs) {
  Expected e;
  for (const auto& dir : runs) {
    ++e.runs;
    const std::string summary = slurp(dir / "summary.json");
    if (!fs::exists(dir / "summary.json") || json_field(summary, "complete") != "true") {
      ++e.incomplete;
      continue;
    }
    const std::string a = slurp(dir / "analysis" / "analysis.json");
    ++e.complete;
    e.limited += json_field(a, "limited") == "true";
    e.backward += json_field(a, "backward_onset") != "null";
    e.whip += std::stod(json_field(a, "whip_fraction")) > 0;
    e.rolling += std::stod(json_field(a, "stick_fraction")) > 0;
    const double w = std::stod(json_field(a, "omega_max"));
    e.omega_min = std::min(e.omega_min, w);
    e.omega_max = std::max(e.omega_max, w);
  }
  return e;
}

/// The row's ensemble columns against the folders of its runs. The fractions are compared
/// exactly: the sweep and this test divide the same two small integers (one correctly rounded
/// division each) and the table prints shortest round-trip digits, so strtod gives the same
/// double back; omega_max min and max are values of analysis.json, printed the same way.
void check_row(const Row& r, const std::vector<fs::path>& runs) {
  const Expected e = from_folders(runs);
  CHECK(std::stoi(r.at("ensemble_members")) == e.runs);
  CHECK(std::stoi(r.at("ensemble_incomplete")) == e.incomplete);
  if (e.complete == 0) {
    for (const char* c : {"p_limited", "p_backward", "p_whip", "p_rolling", "omega_max_min"})
      CHECK(r.at(c).empty());
    return;
  }
  CHECK(std::stod(r.at("p_limited")) == static_cast<double>(e.limited) / e.complete);
  CHECK(std::stod(r.at("p_backward")) == static_cast<double>(e.backward) / e.complete);
  CHECK(std::stod(r.at("p_whip")) == static_cast<double>(e.whip) / e.complete);
  CHECK(std::stod(r.at("p_rolling")) == static_cast<double>(e.rolling) / e.complete);
  CHECK(std::stod(r.at("omega_max_min")) == e.omega_min);
  CHECK(std::stod(r.at("omega_max_max")) == e.omega_max);
}

std::vector<fs::path> runs_of(const fs::path& out, int point, int members) {
  char name[32];
  std::snprintf(name, sizeof name, "p%04d", point);
  std::vector<fs::path> runs{out / name};
  for (int k = 1; k <= members; ++k) {
    char m[40];
    std::snprintf(m, sizeof m, "%s-e%02d", name, k);
    runs.push_back(out / m);
  }
  return runs;
}

}  // namespace

TEST_CASE("sweep --ensemble: members' cases are the documented perturbations, P from their runs",
          "[sweep][ensemble]") {
  // 4 points x (1 + 3) runs of 30 ms (about 2 s on one core). mu = 0.6 whips and rolls within
  // 30 ms, mu = 0.1 does not; omega_lim = 2010.1 rad/s cuts the mu = 0.1 ensembles: omega_max is
  // about 2009.9 for the nominal run and +-0.5 rad/s with omega0 (domega 0.5), so the member
  // started 0.5 rad/s faster exceeds it (margins of 0.2-0.3 rad/s, six orders above the
  // solver's error at rtol 1e-10). initial.x_r is varied and y_r set: the offset adds to both.
  const fs::path dir = fresh_dir("main");
  const int n = 3;
  const double domega = 0.5, offset = 2e-6, y0 = -2e-5;
  const Outcome o = cli("sweep " + sh(kRef) +
                        " --t-end 0.03 --vary contact.mu=0.1,0.6 --vary initial.x_r=0,3e-5"
                        " --set initial.y_r=-2e-5 --set run.omega_lim=2010.1 --ensemble 3"
                        " --ensemble-domega 0.5 --ensemble-offset 2e-6 --jobs 2 --quiet --out " +
                        sh(dir.string()));
  INFO(o.err);
  REQUIRE(o.code == 0);
  CHECK(has(o.out, "this run: 16 runs"));  // the plan counts the members
  const auto rows = read_table(dir / "sweep.csv");
  REQUIRE(rows.size() == 4);
  const double x0[] = {0, 3e-5, 0, 3e-5};
  for (int p = 0; p < 4; ++p) {
    INFO("point " << p);
    const auto runs = runs_of(dir, p, n);
    const CaseSpec nominal = load_case((runs[0] / "case.resolved.toml").string());
    CHECK(nominal.initial.q0[XR] == x0[p]);
    CHECK(nominal.initial.q0[YR] == y0);
    CHECK(nominal.initial.v0[TH] == 2000.0);
    for (int k = 1; k <= n; ++k) {
      INFO("member " << k);
      REQUIRE(fs::exists(runs[k] / "analysis" / "analysis.json"));
      // read back as a case; the perturbation written out here, in the documented order of
      // operations: exact equality (the resolved case holds round-trip digits)
      const CaseSpec m = load_case((runs[k] / "case.resolved.toml").string());
      const double a = 2.0 * std::numbers::pi * (k - 1) / n;
      CHECK(m.initial.v0[TH] == 2000.0 + domega * (2.0 * (k - 1) / (n - 1) - 1.0));
      CHECK(m.initial.q0[XR] == x0[p] + offset * std::cos(a));
      CHECK(m.initial.q0[YR] == y0 + offset * std::sin(a));
      // nothing else changed: the member's case is the point's but for those three numbers
      CaseSpec back = m;
      back.initial.v0[TH] = nominal.initial.v0[TH];
      back.initial.q0[XR] = nominal.initial.q0[XR];
      back.initial.q0[YR] = nominal.initial.q0[YR];
      CHECK(to_toml(back) == to_toml(nominal));
    }
    check_row(rows[p], runs);
    // the row's own verdicts stay the nominal run's
    const std::string a = slurp(runs[0] / "analysis" / "analysis.json");
    CHECK(rows[p].at("omega_max") == json_field(a, "omega_max"));
    CHECK(rows[p].at("limited") == (json_field(a, "limited") == "true" ? "yes" : "no"));
  }
  // the physics the margins above stand for: split at mu = 0.1, whip and rolling at mu = 0.6
  CHECK(rows[0].at("p_limited") == "0.75");
  CHECK(rows[0].at("p_whip") == "0");
  CHECK(rows[2].at("p_whip") == "1");
  CHECK(rows[2].at("p_rolling") == "1");
  CHECK_FALSE(fs::exists(dir / "p0000-e04"));
  fs::remove_all(dir);
}

TEST_CASE("sweep --ensemble 0 (the default) writes no ensemble column and no member",
          "[sweep][ensemble]") {
  const fs::path a = fresh_dir("off-a"), b = fresh_dir("off-b");
  const std::string base = "sweep " + sh(kRef) + " --t-end 0.002 --vary contact.mu=0.1 --quiet";
  REQUIRE(cli(base + " --out " + sh(a.string())).code == 0);
  REQUIRE(cli(base + " --ensemble 0 --out " + sh(b.string())).code == 0);
  CHECK(header_of(a / "sweep.csv") == header_of(b / "sweep.csv"));
  CHECK_FALSE(has(header_of(b / "sweep.csv"), "ensemble"));
  CHECK_FALSE(has(header_of(b / "sweep.csv"), "p_limited"));
  CHECK_FALSE(fs::exists(b / "p0000-e01"));
  fs::remove_all(a);
  fs::remove_all(b);
}

TEST_CASE("sweep --ensemble: bad options are refused, exit 2, before any folder is written",
          "[sweep][ensemble]") {
  const fs::path dir = fresh_dir("bad");
  const std::string base =
      "sweep " + sh(kRef) + " --t-end 0.001 --vary contact.mu=0.1,0.2 --out " + sh(dir.string());
  // {options, what the message must name}
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"--ensemble -1", "--ensemble -1"},
      {"--ensemble 1001", "--ensemble 1001"},
      {"--ensemble two", "--ensemble"},
      {"--ensemble 2 --ensemble-domega -0.1", "--ensemble-domega -0.1"},
      {"--ensemble 2 --ensemble-domega nan", "--ensemble-domega nan"},
      {"--ensemble 2 --ensemble-domega inf", "--ensemble-domega inf"},
      {"--ensemble 2 --ensemble-offset -1e-09", "--ensemble-offset -1e-09"},
      // strictly below the gap (2e-4 m in the reference case)
      {"--ensemble 2 --ensemble-offset 0.0002", "must be < stator.gap = 0.0002"},
      // per point: the second gap equals the default offset of 1e-7 m
      {"--ensemble 2 --vary stator.gap=2e-4,1e-7", "first: point 1"},
      // a member released into the stator: x_r = 1.5e-4 + 0.9e-4 > g0
      {"--ensemble 2 --set initial.x_r=1.5e-4 --ensemble-offset 9e-05", "--ensemble member 1"},
      // 2 points x (1 + 2) runs against --max-points
      {"--ensemble 2 --max-points 5", "6 runs (2 points x 3 with --ensemble 2)"},
      // an ensemble setting without an ensemble (it would be ignored)
      {"--ensemble-domega 0.2", "--ensemble-domega: applies to an ensemble"},
      {"--ensemble 0 --ensemble-offset 1e-8", "--ensemble-offset: applies to an ensemble"},
  };
  for (const auto& [args, says] : bad) {
    const Outcome o = cli(base + " " + args);
    INFO(args << ": " << o.err);
    CHECK(o.code == 2);
    CHECK(has(o.err, says));
    CHECK_FALSE(fs::exists(dir));
  }
  // the same offset and count within the limits run
  const Outcome o = cli(base + " --ensemble 2 --ensemble-offset 1.999e-4 --max-points 6 --quiet");
  INFO(o.err);
  CHECK(o.code == 0);
  CHECK(has(o.out, "this run: 6 runs"));
  fs::remove_all(dir);
}

TEST_CASE("sweep --ensemble --resume skips the complete members of the same resolved case",
          "[sweep][ensemble]") {
  const fs::path dir = fresh_dir("resume");
  const std::string base = "sweep " + sh(kRef) +
                           " --t-end 0.002 --vary contact.mu=0.1 --ensemble 2 --quiet --out " +
                           sh(dir.string());
  REQUIRE(cli(base).code == 0);
  fs::remove(dir / "p0000-e02" / "summary.json");  // as if killed
  const auto nominal = fs::last_write_time(dir / "p0000" / "timeseries.csv");
  const auto first = fs::last_write_time(dir / "p0000-e01" / "timeseries.csv");
  const auto second = fs::last_write_time(dir / "p0000-e02" / "case.resolved.toml");
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // distinct write times
  REQUIRE(cli(base + " --resume").code == 0);
  CHECK(fs::last_write_time(dir / "p0000" / "timeseries.csv") == nominal);
  CHECK(fs::last_write_time(dir / "p0000-e01" / "timeseries.csv") == first);
  CHECK(fs::last_write_time(dir / "p0000-e02" / "case.resolved.toml") != second);  // run again
  auto rows = read_table(dir / "sweep.csv");
  REQUIRE(rows.size() == 1);
  CHECK(rows[0].at("ensemble_incomplete") == "0");
  check_row(rows[0], runs_of(dir, 0, 2));
  // another domega: the members are other cases and run again, the nominal point is not
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  REQUIRE(cli(base + " --resume --ensemble-domega 0.2").code == 0);
  CHECK(fs::last_write_time(dir / "p0000" / "timeseries.csv") == nominal);
  CHECK(fs::last_write_time(dir / "p0000-e01" / "timeseries.csv") != first);
  CHECK(load_case((dir / "p0000-e01" / "case.resolved.toml").string()).initial.v0[TH] ==
        2000.0 - 0.2);  // member 1 of 2: omega0 - domega, exactly as computed there
  fs::remove_all(dir);
}

TEST_CASE(
    "sweep --ensemble: shards merge with the ensemble columns - --certify re-runs the nominal",
    "[sweep][ensemble]") {
  const fs::path one = fresh_dir("serial"), two = fresh_dir("sharded");
  const std::string base = "sweep " + sh(kRef) +
                           " --t-end 0.01 --vary contact.mu=0.1,0.2,0.3 --ensemble 2 --certify "
                           "--quiet --jobs 2 --out ";
  REQUIRE(cli(base + sh(one.string())).code == 0);
  REQUIRE(cli(base + sh(two.string()) + " --shard 1/2").code == 0);
  REQUIRE(cli(base + sh(two.string()) + " --shard 2/2").code == 0);
  CHECK(has(slurp(two / "sweep-shard-1-of-2.json"),
            "\"ensemble\": {\"members\": 2, \"domega\": 0.1, \"offset\": 1e-07}"));
  REQUIRE(cli("sweep-merge " + sh(two.string())).code == 0);
  const auto a = read_table(one / "sweep.csv"), b = read_table(two / "sweep.csv");
  REQUIRE(a.size() == 3);
  REQUIRE(b.size() == 3);
  CHECK(header_of(one / "sweep.csv") == header_of(two / "sweep.csv"));
  CHECK(has(header_of(two / "sweep.csv"), ",certified,"));
  for (std::size_t i = 0; i < 3; ++i) {
    Row x = a[i], y = b[i];
    for (auto* r : {&x, &y}) {  // wall time and folder differ by design
      r->erase("wall_seconds");
      r->erase("folder");
    }
    CHECK(x == y);
    check_row(b[i], runs_of(two, static_cast<int>(i), 2));
  }
  // the tight run is the nominal point's only: "certified" is about the numerics
  CHECK(fs::exists(two / "p0001-tight"));
  CHECK_FALSE(fs::exists(two / "p0001-e01-tight"));
  // a shard of another ensemble (same columns, other perturbations) is not merged
  REQUIRE(cli(base + sh(two.string()) + " --shard 2/2 --ensemble-domega 0.2").code == 0);
  const Outcome merged = cli("sweep-merge " + sh(two.string()));
  CHECK(merged.code == 2);
  CHECK(has(merged.err, "sweep-shard-2-of-2.json: ensemble"));
  CHECK(has(merged.err, "\"domega\": 0.2"));
  fs::remove_all(one);
  fs::remove_all(two);
}

TEST_CASE("sweep --ensemble: runs that do not complete are counted apart, not in P",
          "[sweep][ensemble]") {
  SECTION("members not run after a stop: P over the complete runs") {
    // one thread, tasks in order (point 0, its members 1..3, point 1, ...): the stop raised once
    // two tasks are done leaves point 0 with its nominal run and member 1 complete
    const fs::path dir = fresh_dir("stop");
    std::atomic<bool> stop{false};
    SweepOptions o;
    o.case_path = kRef;
    o.sets = {"run.t_end=0.004"};
    o.vary = {parse_variation("contact.mu=0.1,0.2")};
    o.out = dir.string();
    o.jobs = 1;
    o.ensemble.members = 3;
    o.stop = &stop;
    o.progress = [&stop](long done, long) {
      if (done == 2) stop = true;
    };
    const auto rows = run_sweep(o);
    REQUIRE(rows.size() == 2);
    CHECK(rows[0].complete);
    REQUIRE(rows[0].members.size() == 3);
    CHECK(rows[0].members[0].complete);
    CHECK(rows[0].members[1].termination == "not_run");
    CHECK(rows[1].termination == "not_run");
    const auto table = read_table(dir / "sweep.csv");
    REQUIRE(table.size() == 2);
    CHECK(table[0].at("ensemble_incomplete") == "2");
    check_row(table[0], runs_of(dir, 0, 3));  // folders of members 2 and 3 do not exist
    CHECK(table[1].at("ensemble_incomplete") == "4");
    CHECK(table[1].at("p_limited").empty());
    fs::remove_all(dir);
  }
  SECTION("every run ends early (chattering): exit 3, the members named, no P") {
    // as in test_cli: e_n = 0.9 bounces about 230 times in 0.1 s, so 64 events come well within
    // 64 / 100 s whatever the perturbation
    const fs::path dir = fresh_dir("early");
    const Outcome o = cli("sweep " + sh(kRef) +
                          " --t-end 0.1 --set contact.e_n=0.9 --set "
                          "solver.max_events_per_second=100 --vary contact.mu=0.1 --ensemble 2 "
                          "--quiet --out " +
                          sh(dir.string()));
    CHECK(o.code == 3);
    CHECK(has(o.err, "ensemble member " + (dir / "p0000-e02").string() + " ended early"));
    const auto table = read_table(dir / "sweep.csv");
    REQUIRE(table.size() == 1);
    CHECK(table[0].at("ensemble_incomplete") == "3");
    check_row(table[0], runs_of(dir, 0, 2));
    fs::remove_all(dir);
  }
}
