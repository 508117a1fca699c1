// The two-plane rotor through the command line: run (every solver), analyze (every plane's files
// and verdicts), check; and the same rotor as a matrices case with two contact nodes.
#include <catch2/catch.hpp>
#include <filesystem>

#include "support/cli.hpp"

using namespace rubdyn::testing;
namespace fs = std::filesystem;

TEST_CASE("CLI: a two-plane case runs, and analyze writes every plane", "[regression][planes]") {
  const fs::path out = fresh_dir("two-plane");
  const std::string c = sh(RUBDYN_SOURCE_DIR "/cases/two-plane.toml");
  CliOutcome o = cli("run " + c + " --t-end 0.012 --quiet --out " + sh(out.string()));
  REQUIRE(o.code == 0);
  const std::string ts = slurp(out / "timeseries.csv");
  CHECK(has(ts.substr(0, ts.find('\n')), "x_s_2,y_s_2"));
  CHECK(has(ts.substr(0, ts.find('\n')), "d_N_1,v_N_1"));
  CHECK(has(ts.substr(0, ts.find('\n')), "phase_2"));
  CHECK(has(slurp(out / "events.csv"), ",contact"));
  o = cli("analyze " + sh(out.string()));
  REQUIRE(o.code == 0);
  CHECK(fs::exists(out / "analysis" / "derived.csv"));
  CHECK(fs::exists(out / "analysis" / "plane_2" / "derived.csv"));
  CHECK(fs::exists(out / "analysis" / "plane_2" / "spectrogram.csv"));
  const std::string j = slurp(out / "analysis" / "analysis.json");
  CHECK(has(j, "\"planes\": ["));
  CHECK(has(j, "\"plane\": 2"));
  CHECK(has(j, "\"max_total_friction_torque_ratio\""));
  o = cli("check " + c);
  CHECK(o.code == 0);
  CHECK(has(o.out, "rub planes"));
  // the event-driven solver runs it too: both planes' events, each with its contact number
  o = cli("run " + c + " --t-end 0.012 --quiet --solver event --out " +
          sh((out / "event").string()));
  CHECK(o.code == 0);
  const std::string ev = slurp(out / "event" / "events.csv");
  CHECK(has(ev, "impact"));
  CHECK(has(ev, ",1\n"));  // the contact column (1-based), last on each row
  CHECK(has(ev, ",2\n"));
  CHECK(has(slurp(out / "event" / "summary.json"), "\"contacts\": 2"));
  // every fixed-step scheme runs it
  for (const char* kind : {"mj-proj", "carp-onevc", "carp-qn"}) {
    o = cli("run " + c + " --t-end 0.008 --quiet --solver " + kind + " --out " +
            sh((out / kind).string()));
    CHECK(o.code == 0);
  }
  fs::remove_all(out);
}

TEST_CASE("CLI: a matrices case with two contact nodes runs, and analyze writes every node",
          "[regression][planes]") {
  // cases/matrices-two-plane.toml: the two-plane rotor as a user's matrices, one
  // [[contact_node]] per plane, each with its own ring (the event solver's contact phases then
  // run in the K-contact chart, which the summary names)
  const fs::path out = fresh_dir("matrices-two-plane");
  const std::string c = sh(RUBDYN_SOURCE_DIR "/cases/matrices-two-plane.toml");
  CliOutcome o =
      cli("run " + c + " --t-end 0.012 --quiet --solver event --out " + sh(out.string()));
  REQUIRE(o.code == 0);
  CHECK(has(slurp(out / "summary.json"), "reduced+adams"));
  const std::string ts = slurp(out / "timeseries.csv");
  CHECK(has(ts.substr(0, ts.find('\n')), "x_s_2,y_s_2"));
  CHECK(has(ts.substr(0, ts.find('\n')), "phase_2"));
  o = cli("analyze " + sh(out.string()));
  REQUIRE(o.code == 0);
  CHECK(fs::exists(out / "analysis" / "derived.csv"));
  CHECK(fs::exists(out / "analysis" / "plane_2" / "derived.csv"));
  CHECK(fs::exists(out / "analysis" / "plane_2" / "spectrogram.csv"));
  CHECK(has(slurp(out / "analysis" / "analysis.json"), "\"plane\": 2"));
  o = cli("check " + c);
  CHECK(o.code == 0);
  fs::remove_all(out);
}
