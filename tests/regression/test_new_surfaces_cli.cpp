// Issue 34 (first half), through the CLI: no crash, the right exit code and a message naming the
// file, key, value and rule, on the models, rub planes and matrix files. Each test case failed
// before its fix (named in each). The library side: test_new_surfaces.cpp.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "rubdyn/io/output_reader.hpp"
#include "support/cli.hpp"

using namespace rubdyn::testing;
namespace fs = std::filesystem;

namespace {

const std::string kCases = std::string(RUBDYN_SOURCE_DIR) + "/cases/";
const std::string kRef = kCases + "reference.toml";

}  // namespace

// Fix: src/io/case_toml.cpp (an unknown kind's keys unchecked); before: SIGSEGV, exit 139.
TEST_CASE("Issue 34 CLI: check of an unknown [model] kind exits 2 naming it", "[issue34][cli]") {
  for (const char* kind : {"jefcott", "Matrices", "nope"}) {
    INFO(kind);
    const CliOutcome o = cli("check " + sh(kRef) + " --set model.kind=" + kind);
    CHECK(o.code == 2);
    CHECK(has(o.err, "--set: model.kind = \"" + std::string(kind) + "\": must be one of"));
  }
}

// Fix: src/analysis/derived.cpp (no tied frequency without a tied system); before: check died
// with "std::bad_alloc" while run and campbell accepted the case.
TEST_CASE("Issue 34 CLI: check and campbell of a [[plane]] case with a fixed ring",
          "[issue34][cli][planes]") {
  const fs::path d = fresh_dir("fixed-ring-check");
  fs::create_directories(d);
  std::string t = slurp(kCases + "two-plane.toml");
  const std::string ring = "stator_mass  = 1.0\nstator_k     = 4.0e6\nstator_c     = 50.0\n";
  REQUIRE(has(t, ring));
  t.replace(t.find(ring), ring.size(), "stator_rigid = true\n");
  std::ofstream(d / "case.toml") << t;
  CliOutcome o = cli("check " + sh((d / "case.toml").string()));
  CHECK(o.code == 0);
  CHECK(has(o.out, "fixed"));
  CHECK(o.err.empty());
  o = cli("campbell " + sh((d / "case.toml").string()) + " --points 5 --out " +
          sh((d / "c").string()));
  CHECK(has(o.out, "no contact"));
  CHECK(fs::exists(d / "c" / "campbell.csv"));
  fs::remove_all(d);
}

// Fix: src/io/matrix_files.cpp (the declared size checked without overflow); before:
// "rubdyn: error: std::bad_alloc", no key, no file.
TEST_CASE("Issue 34 CLI: a .npy of an absurd shape exits 2 naming the key and the file",
          "[issue34][cli][matrices]") {
  const fs::path d = fresh_dir("npy-absurd");
  fs::create_directories(d);
  std::string h = "{'descr': '<f8', 'fortran_order': False, 'shape': (4294967296, 4294967296), }";
  while ((10 + h.size() + 1) % 64 != 0) h += ' ';
  h += '\n';
  std::string f = "\x93NUMPY";
  f += '\x01';
  f += '\x00';
  f += static_cast<char>(h.size());
  f += '\x00';
  std::ofstream(d / "huge.npy", std::ios::binary) << f + h;
  const CliOutcome o = cli("check " + sh(kCases + "matrices-paper.toml") + " --set " +
                           sh("rotor.M=\"" + (d / "huge.npy").string() + "\""));
  CHECK(o.code == 2);
  CHECK(has(o.err, "rotor.M"));
  CHECK(has(o.err, (d / "huge.npy").string()));
  CHECK(has(o.err, "declares"));
  CHECK_FALSE(has(o.err, "bad_alloc"));
  fs::remove_all(d);
}

// Fix: src/app/main.cpp (the first word must name a subcommand); before: `rubdyn orbit --help`
// printed the general help and exited 0.
TEST_CASE("Issue 34 CLI: an unknown subcommand is an error naming it, --help or not",
          "[issue34][cli]") {
  // (`orbit` was the example, before rubdyn orbit existed: now `orbits`)
  for (const char* args : {"orbits --help", "orbits", "orbits -h", "chek " /* a typo */}) {
    INFO(args);
    const CliOutcome o = cli(args);
    CHECK(o.code == 2);
    CHECK(has(o.err, "is not a subcommand"));
    CHECK(has(o.err, "check, campbell, run, compare, analyze, sweep"));
    CHECK(o.out.empty());
  }
  CHECK(has(cli("orbits --help").err, "'orbits'"));
  // the known ones keep their help
  CHECK(cli("--help").code == 0);
  CHECK(cli("check --help").code == 0);
  CHECK(cli("sweep-merge --help").code == 0);
  CHECK(cli("orbit --help").code == 0);
}

// Fix: src/app/cmd_sweep.cpp and src/driver/sweep.cpp (a point's failed write is exit 5); before,
// a file size limit hit inside a sweep gave exit 3, "a numerical reason".
TEST_CASE("Issue 34 CLI: a file size limit hit inside a sweep is exit 5", "[issue34][cli]") {
  const fs::path d = fresh_dir("sweep-fsize");
  // 0.2 s of the reference case writes about 0.8 MB of rows per point: above 100 blocks
  const CliOutcome o = cli("sweep " + sh(kRef) + " --vary contact.mu=0.1,0.2 --t-end 0.2 " +
                               "--jobs 1 --quiet --out " + sh(d.string()),
                           "ulimit -f 100; ");
  CHECK(o.code == 5);
  CHECK(has(o.err, "output_failure"));
  CHECK(has(o.err, "File too large"));
  fs::remove_all(d);
}

// Fix: src/io/text_files.cpp (a FIFO read with a bounded wait); before: "is a FIFO (named pipe),
// not a regular file: not read", exit 2, for a process substitution too.
TEST_CASE("Issue 34 CLI: check, run and sweep <(cat case.toml) read the pipe", "[issue34][cli]") {
  // (bash: /bin/sh may have no process substitution)
  const fs::path out = fresh_dir("psub-out"), dir = fresh_dir("psub-dir");
  auto bash = [&](const std::string& args) {
    const std::string cmd =
        "bash -c " + sh(std::string(RUBDYN_CLI) + " " + args + " > " + sh(out.string()) + " 2>&1");
    const int st = std::system(cmd.c_str());
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  };
  CHECK(bash("check <(cat " + sh(kRef) + ")") == 0);
  CHECK(has(slurp(out), "valid"));
  CHECK(has(slurp(out), "/dev/fd/"));
  // run and sweep read the case once (a second read of the pipe would find nothing)
  CHECK(bash("run <(cat " + sh(kRef) + ") --t-end 0.002 --quiet --out " + sh(dir / "run")) == 0);
  CHECK(fs::exists(dir / "run" / "summary.json"));
  CHECK(bash("sweep <(cat " + sh(kRef) + ") --vary contact.mu=0.1,0.2 --t-end 0.002 --jobs 1 " +
             "--quiet --out " + sh(dir / "sweep")) == 0);
  CHECK(fs::exists(dir / "sweep" / "sweep.csv"));
  fs::remove(out);
  fs::remove_all(dir);
}

// Fix: src/app/cmd_run.cpp (the folder's model and coordinates must be the case's); before, a
// restart from a Jeffcott run into a rigid-rotor case ran (exit 0) with x_b, y_b, vx_b, vy_b of
// the case.
TEST_CASE("Issue 34 CLI: run --from a folder of another model or layout exits 2, nothing written",
          "[issue34][cli]") {
  const fs::path j = fresh_dir("from-jeffcott");
  const fs::path out = fresh_dir("from-jeffcott-out");
  REQUIRE(
      cli("run " + sh(kCases + "jeffcott.toml") + " --t-end 0.002 --quiet --out " + sh(j.string()))
          .code == 0);
  CliOutcome o =
      cli("run " + sh(kRef) + " --from " + sh(j.string()) + " --quiet --out " + sh(out.string()));
  CHECK(o.code == 2);
  CHECK(has(o.err, "--from = " + j.string()));
  CHECK(has(o.err, "model 'jeffcott' with coordinates (x_r, y_r, theta, x_s, y_s)"));
  CHECK(has(o.err, "model 'rigid-rotor' with coordinates (x_b, y_b, x_r, y_r, theta, x_s, y_s)"));
  CHECK_FALSE(fs::exists(out));
  // the same model with another layout: a rigid ring has no x_s, y_s
  std::string rigid = slurp(kCases + "jeffcott.toml");
  const std::string ring =
      "mass = 2.0        # m_s [kg]\nk    = 2.0e7      # k_s [N/m]\n"
      "c    = 2500.0     # c_s [N s/m]\n";
  REQUIRE(has(rigid, ring));
  rigid.replace(rigid.find(ring), ring.size(), "rigid = true\n");
  fs::create_directories(out.string() + "-case");
  const std::string rigid_case = out.string() + "-case/rigid.toml";
  std::ofstream(rigid_case) << rigid;
  o = cli("run " + sh(rigid_case) + " --from " + sh(j.string()) + " --quiet --out " +
          sh(out.string()));
  CHECK(o.code == 2);
  CHECK(has(o.err, "model 'jeffcott' with coordinates (x_r, y_r, theta)"));
  CHECK_FALSE(fs::exists(out));
  fs::remove_all(out.string() + "-case");
  // and the same case still restarts
  o = cli("run " + sh(kCases + "jeffcott.toml") + " --t-end 0.003 --from " + sh(j.string()) +
          " --quiet --out " + sh(out.string()));
  CHECK(o.code == 0);
  fs::remove_all(j);
  fs::remove_all(out);
}

// Fix: src/hybrid/event_driven.cpp (a start on the constraints to round-off is written as
// given); before: the restart's first row was off its sample by one to 35 ulps in vx_b, vy_b,
// vy_s_2 (two-plane, both planes sliding at 0.01 s), its chart's embedding or projection of
// a state already on its constraints.
TEST_CASE("Issue 34 CLI: run --from a folder that ends in contact starts on its sample exactly",
          "[issue34][cli][planes][matrices]") {
  for (const char* name : {"two-plane", "matrices-two-plane", "four-plane", "reference"}) {
    INFO(name);
    const std::string c = sh(kCases + name + ".toml");
    const fs::path a = fresh_dir("from-contact-a"), b = fresh_dir("from-contact-b");
    REQUIRE(cli("run " + c + " --set solver.kind='\"event\"' --t-end 0.01 --quiet --out " +
                sh(a.string()))
                .code == 0);
    REQUIRE(cli("run " + c + " --set solver.kind='\"event\"' --t-end 0.011 --from " +
                sh(a.string()) + " --quiet --out " + sh(b.string()))
                .code == 0);
    const rubdyn::RunRecord ra = rubdyn::read_run(a.string()), rb = rubdyn::read_run(b.string());
    const rubdyn::Sample &last = ra.samples.back(), &first = rb.samples.front();
    CHECK(first.t == last.t);
    CHECK(first.q == last.q);
    CHECK(first.v == last.v);
    fs::remove_all(a);
    fs::remove_all(b);
  }
}

// Fix: src/analysis/postprocess.cpp (a spacing below the resampling grid's 1e-12 s unit is no
// grid); before: `rubdyn analyze` of a run that ended 7.8e-17 s after its start (rotor.L = 1e30:
// step_collapse) died with "vector::_M_default_append" (a grid step of 0), exit 2, and a sweep
// point of it was "error: analysis".
TEST_CASE("Issue 34 CLI: analyze of a run that ended within 1e-12 s of its start",
          "[issue34][cli]") {
  const fs::path d = fresh_dir("analyze-collapsed");
  CliOutcome o = cli("run " + sh(kRef) + " --set rotor.L=1e30 --quiet --out " + sh(d.string()));
  REQUIRE(o.code == 3);  // step_collapse, two samples 7.8e-17 s apart
  o = cli("analyze " + sh(d.string()));
  CHECK(o.code == 0);
  CHECK(has(slurp((d / "analysis" / "analysis.json").string()),
            "no two sample times 1e-12 s apart or more"));
  fs::remove_all(d);
}

// Fix: src/io/case_toml.cpp (an override must be UTF-8); before: `--out $'dir\xe9'` (a Latin-1
// path) was taken as a bare string with its quotes and the run wrote into a folder named
// "dir\xe9" with the quote characters, exit 0.
TEST_CASE("Issue 34 CLI: an --out or --set that is not UTF-8 is refused, nothing written",
          "[issue34][cli]") {
  const fs::path d = fresh_dir("not-utf8");
  fs::create_directories(d);
  const std::string latin1 = (d / "dir\xe9").string();
  CliOutcome o = cli("run " + sh(kRef) + " --t-end 0.001 --quiet --out " + sh(latin1));
  CHECK(o.code == 2);
  CHECK(has(o.err, "dir\\xE9"));
  CHECK(has(o.err, "UTF-8"));
  CHECK(has(o.err, "--out"));  // the option given, not the override it becomes
  CHECK_FALSE(has(o.err, "--set"));
  CHECK(fs::is_empty(d));  // neither dir\xe9 nor "dir\xe9" with its quotes
  o = cli("check " + sh(kRef) + " --set 'name=\"n\xe9\"'");
  CHECK(o.code == 2);
  CHECK(has(o.err, "UTF-8"));
  fs::remove_all(d);
}
