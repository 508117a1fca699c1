// The command-line program: exit codes, nothing written on bad input, the main job's outputs.
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace {
int run(const std::string& args) {
  const std::string cmd = std::string(RUBDYN_CLI) + " " + args + " > /dev/null 2>&1";
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}
fs::path fresh_dir(const std::string& tag) {
  const fs::path d =
      fs::temp_directory_path() / ("rubdyn-cli-" + tag + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}
const std::string kRef = std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml";
}  // namespace

TEST_CASE("CLI: usage errors and bad input exit with 2 and write nothing", "[cli]") {
  const fs::path dir = fresh_dir("bad");
  CHECK(run("") == 2);
  CHECK(run("frobnicate") == 2);
  CHECK(run("run /nonexistent.toml --out " + dir.string()) == 2);
  CHECK(run("run " + kRef + " --set contact.mu=-1 --out " + dir.string()) == 2);
  CHECK(run("run " + kRef + " --rtol abc --out " + dir.string()) == 2);
  CHECK_FALSE(fs::exists(dir));
  CHECK(run("--help") == 0);
  CHECK(run("run --help") == 0);
}

TEST_CASE("CLI: a short event-driven run writes its output folder and exits 0", "[cli]") {
  const fs::path dir = fresh_dir("run");
  REQUIRE(run("run " + kRef + " --t-end 0.01 --quiet --out " + dir.string()) == 0);
  for (const char* f : {"timeseries.csv", "events.csv", "summary.json", "case.resolved.toml"})
    CHECK(fs::exists(dir / f));
  std::ifstream in(dir / "summary.json");
  std::stringstream s;
  s << in.rdbuf();
  CHECK(s.str().find("\"complete\": true") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("CLI: a run ended early by numerical trouble exits 3 and keeps its output", "[cli]") {
  // 64 events in less than 64 / max_events_per_second seconds of simulated time: chattering.
  // With e_n = 0.9 the rotor bounces (about 230 impacts in 0.1 s): a bound of 100 events per
  // second trips as soon as 64 events fall within 0.64 s, i.e. at the 64th event.
  const fs::path dir = fresh_dir("early");
  CHECK(run("run " + kRef + " --set contact.e_n=0.9 --t-end 0.1" +
            " --set solver.max_events_per_second=100 --quiet --out " + dir.string()) == 3);
  std::ifstream in(dir / "summary.json");
  std::stringstream s;
  s << in.rdbuf();
  CHECK(s.str().find("\"complete\": false") != std::string::npos);
  CHECK(s.str().find("\"termination\": \"chattering\"") != std::string::npos);
  CHECK(fs::file_size(dir / "timeseries.csv") > 1000);
  fs::remove_all(dir);
}

TEST_CASE("CLI: campbell writes campbell.csv - check prints - bad options exit 2", "[cli]") {
  const fs::path dir = fresh_dir("campbell");
  REQUIRE(run("campbell " + kRef + " --points 11 --out " + dir.string()) == 0);
  std::ifstream in(dir / "campbell.csv");
  std::string header;
  std::getline(in, header);
  CHECK(header == "omega_rad_s,omega_rpm,f1b,f1f,f2b,f2f");
  int rows = 0;
  for (std::string l; std::getline(in, l);) ++rows;
  CHECK(rows == 11);
  fs::remove_all(dir);
  CHECK(run("campbell " + kRef + " --points 1 --out " + dir.string()) == 2);
  CHECK(run("campbell /nonexistent.toml --out " + dir.string()) == 2);
  CHECK_FALSE(fs::exists(dir));
  CHECK(run("check " + kRef) == 0);
  CHECK(run("check " + kRef + " --set rotor.delta=0.6") == 2);
}

TEST_CASE("CLI: compare two runs of different tolerance - events matched - exit codes", "[cli]") {
  const fs::path a = fresh_dir("cmpa"), b = fresh_dir("cmpb");
  REQUIRE(run("run " + kRef + " --t-end 0.03 --quiet --out " + a.string()) == 0);
  REQUIRE(run("run " + kRef + " --t-end 0.03 --rtol 1e-8 --atol 1e-10 --quiet --out " +
              b.string()) == 0);
  const fs::path json =
      fs::temp_directory_path() / ("rubdyn-cmp-" + std::to_string(::getpid()) + ".json");
  REQUIRE(run("compare " + a.string() + " " + b.string() + " --json " + json.string()) == 0);
  std::ifstream in(json);
  std::stringstream s;
  s << in.rdbuf();
  CHECK(s.str().find("\"unmatched_a\": []") != std::string::npos);
  CHECK(s.str().find("\"omega\"") != std::string::npos);
  CHECK(run("compare " + a.string() + " /nonexistent") == 2);
  CHECK(run("compare " + a.string() + " " + b.string() + " --window 0.02 0.01") == 2);
  fs::remove_all(a);
  fs::remove_all(b);
  fs::remove(json);
}

TEST_CASE("CLI: analyze and sweep - bad input exits 2 and writes nothing - a run is analysed",
          "[cli]") {
  const fs::path dir = fresh_dir("sweep");
  CHECK(run("analyze /nonexistent-folder") == 2);
  CHECK(run("sweep " + kRef + " --vary contact.mu=0.1,abc --out " + dir.string()) == 2);
  CHECK(run("sweep " + kRef + " --vary mu=0.1 --out " + dir.string()) == 2);
  CHECK(run("sweep " + kRef + " --vary contact.mu=0.1 --shard 3/2 --out " + dir.string()) == 2);
  CHECK(run("sweep-merge " + dir.string()) == 2);
  CHECK_FALSE(fs::exists(dir));
  const fs::path r = fresh_dir("analyze");
  REQUIRE(run("run " + kRef + " --t-end 0.05 --out " + r.string()) == 0);
  CHECK(run("analyze " + r.string() + " --overlap 1.5") == 2);
  CHECK_FALSE(fs::exists(r / "analysis" / "analysis.json"));
  CHECK(run("analyze " + r.string()) == 0);
  for (const char* f :
       {"derived.csv", "spectrum.csv", "spectrogram.csv", "campbell.csv", "analysis.json"})
    CHECK(fs::exists(r / "analysis" / f));
  fs::remove_all(r);
}
