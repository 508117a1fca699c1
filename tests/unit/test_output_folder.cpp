// Output folders: headers, rows, summary.json (complete flag, null for NaN), resolved case; the
// output-path rule (text_files.hpp) and a folder lost while a run writes into it.
#include <atomic>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/output_folder.hpp"
#include "rubdyn/io/text_files.hpp"

using namespace rubdyn;
namespace fs = std::filesystem;

namespace {
std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}
bool has_text(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
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

// --- the output-path rule (text_files.hpp) and the folder held by a run -----------------------

TEST_CASE("write_file_atomic: a regular file is replaced, a link never, refusals throw", "[io]") {
  const fs::path d = fresh_dir("paths");
  fs::create_directories(d);
  write_file_atomic((d / "new.txt").string(), "one\n");
  CHECK(slurp(d / "new.txt") == "one\n");
  write_file_atomic((d / "new.txt").string(), "two\n");  // replaced whole
  CHECK(slurp(d / "new.txt") == "two\n");
  CHECK_FALSE(fs::exists(d / "new.txt.tmp"));
  fs::create_symlink("new.txt", d / "link.txt");
  write_file_atomic((d / "link.txt").string(), "three\n");
  CHECK(fs::is_symlink(d / "link.txt"));
  CHECK(slurp(d / "new.txt") == "three\n");
  // a temporary file's name taken by a link is not written through: it is removed first
  fs::create_symlink("victim.txt", d / "plain.txt.tmp");
  std::ofstream(d / "victim.txt") << "keep\n";
  write_file_atomic((d / "plain.txt").string(), "p\n");
  CHECK(slurp(d / "victim.txt") == "keep\n");
  CHECK(slurp(d / "plain.txt") == "p\n");
  CHECK_THROWS_AS(write_file_atomic(d.string(), "x"), PathRefused);
  fs::create_symlink("nowhere/at/all", d / "dangling");
  CHECK_THROWS_AS(write_file_atomic((d / "dangling").string(), "x"), PathRefused);
  CHECK_THROWS_AS(write_file_atomic("", "x"), PathRefused);
  // a device: written through, left as it is. A link to /dev/null and /dev/full: were the rule
  // broken, the link would be replaced, not the system's device
  fs::create_symlink("/dev/null", d / "null");
  fs::create_symlink("/dev/full", d / "full");
  write_file_atomic((d / "null").string(), "x");
  CHECK(fs::is_symlink(d / "null"));
  CHECK_THROWS_WITH(write_file_atomic((d / "full").string(), "x"),
                    Catch::Contains((d / "full").string()));
  CHECK(fs::is_symlink(d / "full"));
  fs::remove_all(d);
}

TEST_CASE("OutputFolder: a folder moved away during the run is a failed write", "[io]") {
  const fs::path dir = fresh_dir("lost"), moved = fresh_dir("lost-moved");
  const CaseSpec spec = load_case(std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml");
  std::atomic<bool> stop{false};
  {
    OutputFolder out(dir.string(), spec, &stop);
    out.sample(Sample(7, 1));
    CHECK(out.error().empty());
    fs::rename(dir, moved);
    fs::create_directories(dir);  // another folder takes the path
    out.event(EventRecord{});     // every event checks the folder
    CHECK(has_text(out.error(), "removed or replaced"));
    CHECK(stop.load());
    RunSummary r;
    r.solver = "event";
    out.end(r);  // into the folder held: the moved one
  }
  CHECK(fs::is_empty(dir));
  const std::string js = slurp(moved / "summary.json");
  CHECK(js.find("\"termination\": \"output_failure\"") != std::string::npos);
  CHECK(js.find("\"complete\": false") != std::string::npos);
  fs::remove_all(dir);
  fs::remove_all(moved);
}

TEST_CASE("OutputFolder: samples alone notice a lost folder within kCheckEverySamples", "[io]") {
  const fs::path dir = fresh_dir("lost-samples");
  const CaseSpec spec = load_case(std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml");
  OutputFolder out(dir.string(), spec);
  fs::remove_all(dir);
  const Sample s(7, 1);
  for (int i = 0; i < OutputFolder::kCheckEverySamples; ++i) out.sample(s);
  CHECK(has_text(out.error(), "removed or replaced"));
  CHECK_THROWS_AS(out.end(RunSummary{}), OutputError);  // no folder left for the summary
  CHECK_FALSE(fs::exists(dir));
}
