// Output folders: headers, rows, summary.json (complete flag, null for NaN), resolved case.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/output_folder.hpp"

using namespace rubdyn;
namespace fs = std::filesystem;

namespace {
std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}
fs::path fresh_dir(const std::string& tag) {
  const fs::path d =
      fs::temp_directory_path() / ("rubdyn-test-" + tag + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}
}  // namespace

TEST_CASE("OutputFolder writes the documented files", "[io]") {
  const fs::path dir = fresh_dir("out");
  const CaseSpec spec = load_case(std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml");
  {
    OutputFolder out(dir.string(), spec);
    Sample s(7, 1);
    s.t = 0.25;
    s.q[4] = 1.5;
    s.v[4] = 2000.0;
    s.contacts[0].d_N = 1e-4;
    s.contacts[0].phase = Phase::SlipNeg;
    out.sample(s);
    EventRecord e;
    e.t = 0.125;
    e.kind = EventKind::Impact;
    e.phase_after = Phase::SlipNeg;
    e.witness = "d_N";
    e.note = "a \"quoted\" note";
    out.event(e);
    RunSummary r;
    r.solver = "event";
    r.termination = Termination::Painleve;
    r.message = "line1\nline \"2\"";
    r.t_omega_lim = std::numeric_limits<double>::quiet_NaN();
    out.end(r);
  }
  const std::string ts = slurp(dir / "timeseries.csv");
  CHECK(ts.rfind("t,x_b,y_b,x_r,y_r,theta,x_s,y_s,vx_b,vy_b,vx_r,vy_r,omega,vx_s,vy_s,d_N,v_N,v_t,"
                 "F_N,F_T,phase\n",
                 0) == 0);
  CHECK(ts.find("\n0.25,0,0,0,0,1.5,0,0,0,0,0,0,2000,0,0,0.0001,0,0,0,0,slip-\n") !=
        std::string::npos);
  const std::string ev = slurp(dir / "events.csv");
  CHECK(ev.rfind("t,kind,phase_before,phase_after,d_N,v_N_minus,v_N_plus,v_t_minus,v_t_plus,P_N,"
                 "P_T,F_N,F_T,t_accumulation,witness,note\n",
                 0) == 0);
  CHECK(ev.find("0.125,impact,free,slip-,") != std::string::npos);
  CHECK(ev.find("\"a \"\"quoted\"\" note\"") != std::string::npos);  // CSV quoting
  const std::string js = slurp(dir / "summary.json");
  CHECK(js.find("\"complete\": false") != std::string::npos);
  CHECK(js.find("\"termination\": \"painleve\"") != std::string::npos);
  CHECK(js.find("\"t_omega_lim\": null") != std::string::npos);
  CHECK(js.find("\"message\": \"line1\\nline \\\"2\\\"\"") != std::string::npos);
  // the resolved case reads back to the same case
  const CaseSpec back = load_case((dir / "case.resolved.toml").string());
  CHECK(to_toml(back) == to_toml(spec));
  fs::remove_all(dir);
}

TEST_CASE("A run that never ends cleanly leaves no summary.json", "[io]") {
  const fs::path dir = fresh_dir("noend");
  const CaseSpec spec = load_case(std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml");
  {
    OutputFolder out(dir.string(), spec);
    out.sample(Sample(7, 1));
  }
  CHECK(fs::exists(dir / "timeseries.csv"));
  CHECK_FALSE(fs::exists(dir / "summary.json"));
  fs::remove_all(dir);
}
