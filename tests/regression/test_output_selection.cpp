// output.coordinates (issue 32, item 6): a wide model writes the coordinates asked for (by
// default its contacts' and spin's), the full state stays recoverable from state.csv for
// restarts, and the selection changes no bit of what is written.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/output_folder.hpp"
#include "rubdyn/io/output_reader.hpp"
#include "support/cli.hpp"

namespace fs = std::filesystem;
using namespace rubdyn;
using namespace rubdyn::testing;

namespace {

const std::string kFe = std::string(RUBDYN_SOURCE_DIR) + "/cases/fe-runup.toml";

std::vector<std::string> lines_of(const fs::path& p) {
  return text_lines(slurp(p));
}

/// A CSV file's rows as maps from the header's names to the fields as written.
std::vector<std::map<std::string, std::string>> rows_of(const fs::path& p) {
  const auto l = lines_of(p);
  REQUIRE(!l.empty());
  const auto h = csv_fields(l.front());
  std::vector<std::map<std::string, std::string>> out;
  for (std::size_t i = 1; i < l.size(); ++i) {
    const auto f = csv_fields(l[i]);
    REQUIRE(f.size() == h.size());
    std::map<std::string, std::string> r;
    for (std::size_t c = 0; c < h.size(); ++c) r[h[c]] = f[c];
    out.push_back(std::move(r));
  }
  return out;
}

/// The times of events.csv, as written (its first column; later ones hold quoted text).
std::vector<std::string> event_times(const fs::path& dir) {
  const auto l = lines_of(dir / "events.csv");
  REQUIRE(!l.empty());
  REQUIRE(csv_fields(l.front()).front() == "t");
  std::vector<std::string> t;
  for (std::size_t i = 1; i < l.size(); ++i) t.push_back(csv_fields(l[i]).front());
  return t;
}

std::string run_fe(const fs::path& out, const std::string& extra) {
  // 0.16 s of the run-up: its first impact (about 0.107 s), two lift-offs and impacts after it
  return "run " + sh(kFe) + " --t-end 0.16 --quiet " + extra + " --out " + sh(out.string());
}

}  // namespace

TEST_CASE("Output selection: the columns asked for, the same bits, the full state in state.csv",
          "[output][cli]") {
  const fs::path a = fresh_dir("sel-all"), b = fresh_dir("sel-part");
  REQUIRE(cli(run_fe(a, "")).code == 0);  // 52 coordinates: every one by default
  REQUIRE(cli(run_fe(b, "--set " + sh("output.coordinates=x3, contacts"))).code == 0);
  CHECK(!fs::exists(a / "state.csv"));

  // the rule (io/columns.hpp): the coordinates with a role (the seal node x6, y6, the ring's
  // x_s, y_s; the prescribed spin's theta, omega are observables, always written) and the one
  // named, in the model's order, then the observables and the contact's columns
  CHECK(lines_of(b / "timeseries.csv").front() ==
        "t,x3,x6,y6,x_s,y_s,vx3,vx6,vy6,vx_s,vy_s,theta,omega,drive_torque,d_N,v_N,v_t,F_N,F_T,"
        "phase");

  // the selection changes no bit: every column written equals the full run's, row by row
  const auto ra = rows_of(a / "timeseries.csv"), rb = rows_of(b / "timeseries.csv");
  REQUIRE(ra.size() == rb.size());
  REQUIRE(ra.size() > 1000);
  long differ = 0;
  for (std::size_t i = 0; i < ra.size(); ++i)
    for (const auto& [name, value] : rb[i]) differ += ra[i].at(name) != value;
  CHECK(differ == 0);
  CHECK(slurp(a / "events.csv") == slurp(b / "events.csv"));

  // state.csv: the full run's columns, at the first sample, after each event (the last row at
  // the event's time) and at the last sample
  CHECK(lines_of(b / "state.csv").front() == lines_of(a / "timeseries.csv").front());
  const auto st = rows_of(b / "state.csv");
  const auto ev = event_times(b);
  REQUIRE(ev.size() >= 3);
  REQUIRE(st.size() == ev.size() + 2);
  CHECK(st.front() == ra.front());
  CHECK(st.back() == ra.back());
  for (std::size_t k = 0; k < ev.size(); ++k) {
    const std::map<std::string, std::string>* after = nullptr;
    for (const auto& r : ra)
      // (as numbers: events.csv writes 17 digits, timeseries.csv the shortest that reads back)
      if (std::stod(r.at("t")) == std::stod(ev[k])) after = &r;
    REQUIRE(after != nullptr);
    CHECK(st[k + 1] == *after);
  }

  // restarts: from the selection's state.csv exactly as from the full run's last sample
  const fs::path c = fresh_dir("sel-from-all"), d = fresh_dir("sel-from-part");
  const std::string on = "--t-end 0.17 --set " + sh("output.coordinates=x3, contacts");
  REQUIRE(cli("run " + sh(kFe) + " --quiet " + on + " --from " + sh(a.string()) + " --out " +
              sh(c.string()))
              .code == 0);
  REQUIRE(cli("run " + sh(kFe) + " --quiet " + on + " --from " + sh(b.string()) + " --out " +
              sh(d.string()))
              .code == 0);
  CHECK(slurp(c / "timeseries.csv") == slurp(d / "timeseries.csv"));
  CHECK(slurp(c / "state.csv") == slurp(d / "state.csv"));
  CHECK(rows_of(d / "state.csv").front() == st.back());
  // --at: an event's time (a row of state.csv) starts there; a sample of the timeseries that
  // state.csv does not hold is refused with exit 2, naming state.csv
  const fs::path e = fresh_dir("sel-at");
  REQUIRE(cli("run " + sh(kFe) + " --quiet --t-end 0.17 --from " + sh(b.string()) + " --at " +
              ev[1] + " --out " + sh(e.string()))
              .code == 0);
  CHECK(rows_of(e / "timeseries.csv").front() == st[2]);  // (every coordinate: the case's)
  const CliOutcome refused = cli("run " + sh(kFe) + " --t-end 0.17 --from " + sh(b.string()) +
                                 " --at 0.12 --out " + sh(e.string()));
  CHECK(refused.code == 2);
  CHECK(has(refused.err, "state.csv"));

  // the analysis reads the contacts' and the spin's coordinates only: the same result
  REQUIRE(cli("analyze " + sh(a.string())).code == 0);
  REQUIRE(cli("analyze " + sh(b.string())).code == 0);
  CHECK(slurp(a / "analysis/analysis.json") == slurp(b / "analysis/analysis.json"));
  CHECK(slurp(a / "analysis/derived.csv") == slurp(b / "analysis/derived.csv"));
  // read back: the coordinates not written are NaN, never zero
  const RunRecord rec = read_run(b.string());
  CHECK_FALSE(rec.every_coordinate);
  CHECK(std::isnan(rec.samples.front().q[0]));
  CHECK(rec.states.size() == st.size());

  // a run into the folder that writes every coordinate removes the old state.csv
  REQUIRE(cli(run_fe(b, "")).code == 0);
  CHECK(!fs::exists(b / "state.csv"));
  for (const auto& p : {a, b, c, d, e}) fs::remove_all(p);
}

TEST_CASE("Output selection: a wide model writes its contacts by default", "[output][cli]") {
  // A matrices model of 70 coordinates (above the 64 of kWideModelCoordinates): unit masses on
  // springs, the seal at the first two coordinates, a sprung ring, a torque-driven spin
  const fs::path dir = fresh_dir("sel-wide"), out = dir / "out";
  fs::create_directories(dir);
  const int n = 70;
  auto write = [&](const char* name, double diag) {
    std::ofstream f(dir / name);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) f << (i == j ? diag : 0.0) << (j + 1 < n ? "," : "\n");
  };
  write("M.csv", 1.0);
  write("C.csv", 10.0);
  write("K.csv", 1e6);
  write("G.csv", 0.0);
  {
    std::ofstream c(dir / "case.toml");
    c << "[model]\nkind = \"matrices\"\n[rotor]\nM = \"M.csv\"\nC = \"C.csv\"\nK = \"K.csv\"\n"
         "G = \"G.csv\"\nJp = 0.1\n[contact_node]\nx = 0\ny = 1\nradius = 0.05\ngap = 1e-4\n"
         "[stator]\nmass = 1.0\nk = 1e6\nc = 10.0\n[contact]\nmu = 0.1\n[loads]\ngravity = "
         "0.0\ntorque = 1.0\n[initial]\nomega0 = 100.0\n"
         "[run]\nt_end = 0.005\nomega_lim = 1000.0\n[output]\ndt = 1e-3\n";
  }
  const CliOutcome r =
      cli("run " + sh((dir / "case.toml").string()) + " --quiet --out " + sh(out.string()));
  REQUIRE(r.code == 0);
  const auto header = csv_fields(lines_of(out / "timeseries.csv").front());
  const auto contains = [&](const std::string& name) {
    return std::find(header.begin(), header.end(), name) != header.end();
  };
  // the seal's coordinates and the spin: written; the others: in state.csv only
  CHECK(contains("q0"));
  CHECK(contains("q1"));
  CHECK(contains("theta"));
  CHECK(contains("omega"));
  CHECK_FALSE(contains("q2"));
  CHECK_FALSE(contains("q69"));
  CHECK(has(slurp(out / "case.resolved.toml"), "coordinates = \"contacts\""));
  const auto full = csv_fields(lines_of(out / "state.csv").front());
  CHECK(std::find(full.begin(), full.end(), "q69") != full.end());
  // asked for: every coordinate, and no state.csv
  REQUIRE(cli("run " + sh((dir / "case.toml").string()) + " --quiet --set " +
              sh("output.coordinates=all") + " --out " + sh(out.string()))
              .code == 0);
  CHECK(has(lines_of(out / "timeseries.csv").front(), ",q69,"));
  CHECK(!fs::exists(out / "state.csv"));
  fs::remove_all(dir);
}

TEST_CASE("Output selection: a bad output.coordinates is exit 2 naming the key, nothing written",
          "[output][cli]") {
  const fs::path out = fresh_dir("sel-bad");
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"x6, y99", "'y99' is no coordinate"},
      {"all, x3", "stands alone"},
      {"x3,,y3", "empty word"},
      {"", "empty word"}};
  for (const auto& [value, why] : bad) {
    const CliOutcome r = cli(run_fe(out, "--set " + sh("output.coordinates=" + value)));
    INFO(value << ": " << r.err);
    CHECK(r.code == 2);
    CHECK(has(r.err, "output.coordinates"));
    CHECK(has(r.err, why));
    CHECK(!fs::exists(out));
  }
}

TEST_CASE("Output selection: state.csv rows are on disk at once, the last sample at the end",
          "[output]") {
  // What a killed run keeps (the state after its last event) and what its end adds (the last
  // sample, once): read while the sink is alive, as after a SIGKILL
  const fs::path dir = fresh_dir("sel-sink");
  const CaseSpec spec = load_case(kFe, {"output.coordinates=\"contacts\""});
  const auto model = build_model(spec);
  Sample s(model->num_dofs(), model->contact_count(),
           static_cast<int>(model->observables().size()));
  auto rows = [&] { return lines_of(dir / "state.csv").size() - 1; };
  {
    OutputFolder out(dir.string(), spec);
    s.t = 0.0;
    s.q[0] = 1.0;  // x0: written to state.csv only
    out.sample(s);
    CHECK(rows() == 1);  // the first sample
    s.t = 1e-4;
    s.q[0] = 2.0;
    out.sample(s);
    CHECK(rows() == 1);  // an ordinary sample: not a state row
    EventRecord e;
    e.t = 1.5e-4;
    out.event(e);
    s.t = 1.5e-4;
    s.q[0] = 3.0;
    out.sample(s);  // the sample after the event
    CHECK(rows() == 2);
    CHECK(csv_fields(lines_of(dir / "state.csv").back()).at(1) == "3");
    s.t = 2e-4;
    s.q[0] = 4.0;
    out.sample(s);
    CHECK(rows() == 2);
    out.end(RunSummary{});
  }
  const auto st = lines_of(dir / "state.csv");
  REQUIRE(st.size() == 4);  // header, first, after the event, last
  CHECK(csv_fields(st.front()).at(1) == "x0");
  CHECK(csv_fields(st[3]).at(0) == "0.0002");
  CHECK(csv_fields(st[3]).at(1) == "4");
  // the timeseries holds the selection only
  CHECK(!has(lines_of(dir / "timeseries.csv").front(), "x0,"));
  fs::remove_all(dir);
}
