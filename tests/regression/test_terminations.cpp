// Every termination a run can end with is a termination everywhere its name is read: the sweep
// table's fields and sweep-merge's check of them (before, a point that ended with step_collapse or
// implausible made its shard's table unmergeable: only the names up to output_failure were
// known).

#include <catch2/catch.hpp>
#include <filesystem>
#include <string>

#include "rubdyn/core/run_types.hpp"
#include "support/cli.hpp"

using namespace rubdyn;
using namespace rubdyn::testing;
namespace fs = std::filesystem;

TEST_CASE("Every termination has a name, up to the last one", "[terminations]") {
  for (int k = 0; k <= static_cast<int>(kLastTermination); ++k) {
    const auto t = static_cast<Termination>(k);
    INFO(k);
    CHECK(to_string(t) != "?");
    CHECK(exit_code(t) == (t == Termination::Completed ? kExitOk
                           : t == Termination::Interrupted || t == Termination::TimeBudget
                               ? kExitInterrupted
                           : t == Termination::OutputFailure ? kExitOutput
                                                             : kExitEarlyEnd));
  }
}

TEST_CASE("sweep-merge takes a shard whose point ended with implausible", "[terminations][cli]") {
  // loads.torque = 1e12 spins the reference rotor past the plausible contact speed within 3 us
  // (README: implausible); the merge must read that termination as one
  const fs::path d = fresh_dir("merge-implausible");
  const std::string ref = std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml";
  const std::string sweep = "sweep " + sh(ref) +
                            " --t-end 0.01 --jobs 1 --quiet --set initial.vy_r=-1 --vary "
                            "loads.torque=20,1e12 ";
  CHECK(cli(sweep + "--shard 1/2 --out " + sh(d.string())).code == 0);
  CHECK(cli(sweep + "--shard 2/2 --out " + sh(d.string())).code == 3);
  REQUIRE(has(slurp(d / "sweep-shard-2-of-2.csv"), "implausible"));
  const CliOutcome o = cli("sweep-merge " + sh(d.string()));
  INFO(o.err);
  CHECK(o.code == 0);
  CHECK(has(slurp(d / "sweep.csv"), "implausible"));
  fs::remove_all(d);
}
