// The output contract (issue 12): exit 0 means a complete, correct result. Bad input exits 2
// naming the key and writes nothing; numerical trouble exits 3 with "complete": false; an
// interruption exits 4, a failed write 5; the folder is locked and prepared before writing.
#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "rubdyn/analysis/compare.hpp"
#include "rubdyn/analysis/postprocess.hpp"
#include "rubdyn/driver/sweep.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"
#include "rubdyn/stepping/fixed_step.hpp"
#include "support/cli.hpp"

namespace fs = std::filesystem;
using namespace rubdyn;

namespace {

const std::string kRef = std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml";

using namespace rubdyn::testing;  // fresh_dir, slurp, sh, has, cli (support/cli.hpp)
using Outcome = CliOutcome;

}  // namespace

// --- item 1: a fixed-step run ends exactly at t_end, or is refused ---------------------------

TEST_CASE("Contract: fixed-step options are checked at the library boundary", "[contract]") {
  const RotorStatorModel model(RotorStatorParams{});
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.v[TH] = 2000.0;
  FixedStepOptions o;
  MemorySink sink;
  for (double h : {0.0, -1e-6, std::nan("")}) {
    o.h = h;
    CHECK_THROWS_AS(run_fixed_step(model, s0, 1e-3, o, sink), std::invalid_argument);
  }
  o.h = 4e-3;  // 2.5 steps in 0.01 s: it would end at 0.012 (or 0.008) s
  CHECK_THROWS_AS(run_fixed_step(model, s0, 0.01, o, sink), std::invalid_argument);
  o.h = 1e-20;  // 1e18 steps
  CHECK_THROWS_AS(run_fixed_step(model, s0, 0.01, o, sink), std::invalid_argument);
  o.h = 1e-3;
  o.itmax = 0;
  o.theta = 0.2;
  try {
    run_fixed_step(model, s0, 0.01, o, sink);
    FAIL("no exception");
  } catch (const std::invalid_argument& e) {
    // every broken rule at once
    CHECK(has(e.what(), "itmax"));
    CHECK(has(e.what(), "theta"));
  }
  CHECK(sink.samples.empty());  // nothing handed out before the check
  // A whole number of steps: the run ends at t_end. 5e-3 s twice is 0.01 s; the time is
  // t_start + 2 (0.01 / 2), which is 0.01 up to one rounding (1 ulp of 0.01 ~ 1.7e-18).
  o = FixedStepOptions{};
  o.h = 5e-3;
  const RunSummary s = run_fixed_step(model, s0, 0.01, o, sink);
  CHECK(s.complete());
  CHECK(std::abs(s.t_reached - 0.01) <= 2e-18);
  CHECK(std::abs(sink.samples.back().t - 0.01) <= 2e-18);
}

TEST_CASE("Contract: rubdyn run refuses a step that does not end at t_end or is too small",
          "[contract][cli]") {
  const fs::path dir = fresh_dir("h");
  for (const std::string args :
       {"--t-end 1e-3 --h 1e-300", "--t-end 1e-3 --h 0.1", "--t-end 0.01 --h 4e-3",
        "--t-end 0.01 --h 4.5e-3", "--t-end 0.01 --h 1e-20", "--t-end 0.01 --h 0"}) {
    const Outcome o = cli("run " + sh(kRef) + " --solver mj " + args + " --out " + sh(dir));
    INFO(args << ": " << o.err);
    CHECK(o.code == 2);
    CHECK(has(o.err, "solver.h"));
    CHECK_FALSE(fs::exists(dir));
  }
}

// --- item 2: integers outside int are errors, not wrapped ------------------------------------

TEST_CASE("Contract: integer keys out of range are errors naming the key", "[contract]") {
  for (const std::string set :
       {"solver.itmax=4294967297", "output.every=4294967301", "output.every=-4294967295"}) {
    INFO(set);
    try {
      (void)load_case(kRef, {set});
      FAIL("accepted");
    } catch (const CaseError& e) {
      REQUIRE(e.issues().size() == 1);
      CHECK(e.issues()[0].key == set.substr(0, set.find('=')));
      CHECK(has(e.issues()[0].rule, "2147483647"));
    }
  }
  CHECK(cli("check " + sh(kRef) + " --set solver.itmax=4294967297").code == 2);
}

// --- items 3 and 4: paths and names are strings as given; case.resolved.toml round trips ----

TEST_CASE("Contract: --out is a path as given, never TOML text", "[contract][cli]") {
  const fs::path base = fresh_dir("paths");
  fs::create_directories(base);
  for (const std::string name : {"run\\new", "C:\\temp", "o\"q", "a'b"}) {
    const fs::path dir = base / name;
    INFO(name);
    CHECK(cli("run " + sh(kRef) + " --t-end 0.001 --quiet --out " + sh(dir)).code == 0);
    CHECK(fs::exists(dir / "summary.json"));
  }
  // exactly those four folders, no "run<newline>ew"
  int n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(base)) ++n;
  CHECK(n == 4);
  fs::remove_all(base);
}

TEST_CASE("Contract: a case name with quotes, backslashes and control characters round trips",
          "[contract]") {
  CaseSpec c = load_case(kRef);
  for (const std::string& name :
       {std::string("a\"b"), std::string("back\\slash"), std::string("new\nline"),
        std::string("ctl\x01\x1f\x7f"), std::string("tab\tcr\r")}) {
    c.name = name;
    c.output.folder = name + "/\\n";
    const CaseSpec back = parse_case(to_toml(c), "resolved");
    CHECK(back.name == name);
    CHECK(back.output.folder == c.output.folder);
  }
  CHECK(toml_quote("a\"\\\n") == "\"a\\\"\\\\\\n\"");
}

// --- item 5: SUNDIALS failures are typed results, not stderr noise ---------------------------

TEST_CASE("Contract: an absurd initial speed or load ends with exit 3, a summary, no CVODES noise",
          "[contract][cli]") {
  // (initial.omega0 = 1e300 is refused as a case now, exit 2: its rim speed and energy
  // overflow; an absurd speed of the rotor centre is accepted and ends the run)
  CHECK(cli("check " + sh(kRef) + " --set initial.omega0=1e300").code == 2);
  for (const std::string set :
       {"initial.vy_r=1e150", "loads.torque=1e300", "loads.gravity=1e300"}) {
    const fs::path dir = fresh_dir("huge");
    const Outcome o =
        cli("run " + sh(kRef) + " --t-end 0.01 --quiet --set " + set + " --out " + sh(dir));
    INFO(set << ": " << o.err);
    CHECK(o.code == 3);
    const std::string summary = slurp(dir / "summary.json");
    CHECK(has(summary, "\"complete\": false"));
    CHECK_FALSE(has(o.err, "[CVODES"));
    CHECK(has(o.err, "ended early"));
    fs::remove_all(dir);
  }
}

// --- item 6: compare refuses when nothing is comparable, and counts NaN as a difference -----

TEST_CASE("Contract: compare needs a common column, and a NaN is a difference", "[contract]") {
  const fs::path dir = fresh_dir("cmp");
  fs::create_directories(dir);
  {
    std::ofstream(dir / "only_t.csv") << "t\n0\n1\n2\n";
    std::ofstream(dir / "a.csv") << "t,x_r\n0,0\n1,1\n2,2\n";
    std::ofstream(dir / "b.csv") << "t,x_r\n0,0\n1,nan\n2,2\n";
  }
  const Series a = read_series((dir / "a.csv").string());
  const Series b = read_series((dir / "b.csv").string());
  const Series t = read_series((dir / "only_t.csv").string());
  CHECK_THROWS_WITH(compare_solutions(a, t, {}, {}, std::nullopt, 1e-3),
                    Catch::Contains("nothing to compare"));
  const Comparison c = compare_solutions(a, b, {}, {}, std::nullopt, 1e-3);
  REQUIRE(c.columns.size() == 1);
  CHECK(c.columns[0].non_finite == 1);
  CHECK(std::isinf(c.columns[0].sup));
  CHECK(c.columns[0].t_sup == 1.0);
  CHECK(has(comparison_json(c, "a", "b"), "\"non_finite\": 1"));
  CHECK(cli("compare " + sh(dir / "a.csv") + " " + sh(dir / "only_t.csv")).code == 2);
  fs::remove_all(dir);
}

// --- item 7: SIGINT / SIGTERM end a run cleanly; readers accept what a kill leaves -----------

namespace {
/// Starts `rubdyn run` on the reference case into `dir` for `t_end` seconds; returns its pid.
pid_t start_run(const fs::path& dir, const std::string& t_end, const std::string& solver) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    ::execl(RUBDYN_CLI, RUBDYN_CLI, "run", kRef.c_str(), "--quiet", "--t-end", t_end.c_str(),
            "--solver", solver.c_str(), "--out", dir.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

int wait_exit(pid_t pid) {
  int st = 0;
  ::waitpid(pid, &st, 0);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}
}  // namespace

TEST_CASE("Contract: SIGINT and SIGTERM stop a run at a sample with an incomplete summary",
          "[contract][cli]") {
  // 1000 s of simulated time is minutes of wall time: the signal always comes first. It is
  // sent once rows are on disk (the first 4 kB buffer flushed), so the handler is installed
  // and the run is in its loop, however loaded the machine is.
  for (const auto& [sig, solver] : {std::pair{SIGINT, "event"}, std::pair{SIGTERM, "mj"}}) {
    const fs::path dir = fresh_dir("sig" + std::to_string(sig));
    const pid_t pid = start_run(dir, "1000", solver);
    REQUIRE(pid > 0);
    const auto t0 = std::chrono::steady_clock::now();
    auto rows_on_disk = [&] {
      std::error_code ec;  // (file_size is -1, not 0, while the file does not exist)
      const auto n = fs::file_size(dir / "timeseries.csv", ec);
      return !ec && n >= 8192;
    };
    while (!rows_on_disk() && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60))
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    ::kill(pid, sig);
    INFO("signal " << sig << ", solver " << solver);
    CHECK(wait_exit(pid) == 4);
    const std::string summary = slurp(dir / "summary.json");
    CHECK(has(summary, "\"complete\": false"));
    CHECK(has(summary, "\"termination\": \"interrupted\""));
    // the folder is a valid (incomplete) run for the readers
    const RunRecord r = read_run(dir.string());
    CHECK_FALSE(r.complete);
    CHECK(r.warnings.empty());
    CHECK(r.samples.size() > 10);
    CHECK(cli("analyze " + sh(dir) + " --out " + sh(dir / "an")).code == 0);
    fs::remove_all(dir);
  }
}

TEST_CASE("Contract: readers accept a cut last row (with a warning) and an empty events file",
          "[contract]") {
  const fs::path dir = fresh_dir("cut");
  REQUIRE(cli("run " + sh(kRef) + " --t-end 0.01 --quiet --out " + sh(dir)).code == 0);
  const RunRecord whole = read_run(dir.string());
  // what SIGKILL leaves: no summary.json, the last row cut inside a number, events.csv as a
  // killed run of an older rubdyn left it (empty) or as this one does (header only)
  fs::remove(dir / "summary.json");
  std::string ts = slurp(dir / "timeseries.csv");
  ts.resize(ts.size() - 30);
  std::ofstream(dir / "timeseries.csv", std::ios::binary | std::ios::trunc) << ts;
  const std::string events = slurp(dir / "events.csv");
  for (const std::string& ev : {std::string(), events.substr(0, events.find('\n') + 1)}) {
    std::ofstream(dir / "events.csv", std::ios::binary | std::ios::trunc) << ev;
    const RunRecord r = read_run(dir.string());
    CHECK_FALSE(r.complete);
    CHECK(r.samples.size() + 1 == whole.samples.size());  // the cut row dropped, no other
    CHECK(r.events == 0);
    REQUIRE_FALSE(r.warnings.empty());
    CHECK(has(r.warnings[0], "no line end"));
    const Series s = read_series(dir.string());
    CHECK(s.t.size() + 1 == whole.samples.size());
    CHECK(read_events(dir.string()).empty());
    const Outcome o = cli("compare " + sh(dir) + " " + sh(dir));
    CHECK(o.code == 0);
    CHECK(has(o.err, "warning"));
    CHECK(cli("analyze " + sh(dir) + " --out " + sh(dir / "an")).code == 0);
  }
  fs::remove_all(dir);
}

// --- item 8: every write is checked ----------------------------------------------------------

TEST_CASE("Contract: a failed write is an error naming the file, never exit 0", "[contract][cli]") {
  // a full device at the start: the headers cannot be flushed, the run does not start
  const fs::path f = fresh_dir("full");
  fs::create_directories(f);
  fs::create_symlink("/dev/full", f / "timeseries.csv");
  Outcome o = cli("run " + sh(kRef) + " --t-end 0.03 --quiet --out " + sh(f));
  CHECK(o.code == 2);
  CHECK(has(o.err, "timeseries.csv"));
  CHECK_FALSE(fs::exists(f / "summary.json"));
  fs::remove_all(f);
  // a file size limit (ulimit -f, in 1 kB blocks) reached during the run: the write fails
  // with EFBIG (SIGXFSZ ignored), the run stops, summary.json (small) says why, exit 5
  const fs::path g = fresh_dir("fsize");
  o = cli("run " + sh(kRef) + " --t-end 1 --quiet --out " + sh(g), "ulimit -f 100; trap '' XFSZ; ");
  CHECK(o.code == 5);
  CHECK(has(o.err, "timeseries.csv"));
  const std::string summary = slurp(g / "summary.json");
  CHECK(has(summary, "\"complete\": false"));
  CHECK(has(summary, "\"termination\": \"output_failure\""));
  CHECK(has(summary, "timeseries.csv"));
  fs::remove_all(g);
}

// --- items 9 and 10: the folder is locked and prepared before anything is written ------------

TEST_CASE("Contract: a folder in use by another run is refused with exit 2", "[contract][cli]") {
  const fs::path dir = fresh_dir("lock");
  fs::create_directories(dir);
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  REQUIRE(fd >= 0);
  REQUIRE(::flock(fd, LOCK_EX | LOCK_NB) == 0);  // what a running rubdyn holds
  const Outcome o = cli("run " + sh(kRef) + " --t-end 0.001 --quiet --out " + sh(dir));
  CHECK(o.code == 2);
  CHECK(has(o.err, "in use by another rubdyn run"));
  CHECK(fs::is_empty(dir));
  ::close(fd);  // released: the run goes ahead
  CHECK(cli("run " + sh(kRef) + " --t-end 0.001 --quiet --out " + sh(dir)).code == 0);
  fs::remove_all(dir);
}

TEST_CASE("Contract: a folder whose old summary cannot be removed is refused before writing",
          "[contract][cli]") {
  // summary.json as a non-empty directory cannot be removed (even by root)
  const fs::path dir = fresh_dir("stale");
  fs::create_directories(dir / "summary.json" / "x");
  const Outcome o = cli("run " + sh(kRef) + " --t-end 0.001 --quiet --out " + sh(dir));
  CHECK(o.code == 2);
  CHECK(has(o.err, "summary.json"));
  CHECK_FALSE(fs::exists(dir / "timeseries.csv"));
  CHECK_FALSE(fs::exists(dir / "case.resolved.toml"));
  fs::remove_all(dir);
}

// --- Also: options that were silently ignored or defaulted ----------------------------------

TEST_CASE("Contract: an empty --solver and options of the other solver family are refused",
          "[contract][cli]") {
  const fs::path dir = fresh_dir("ignored");
  for (const std::string args : {"--solver ''", "--h 1e-6", "--output-every 3",
                                 "--solver mj --rtol 1e-8", "--solver mj --method bdf"}) {
    const Outcome o = cli("run " + sh(kRef) + " --t-end 0.001 " + args + " --out " + sh(dir));
    INFO(args << ": " << o.err);
    CHECK(o.code == 2);
    CHECK_FALSE(fs::exists(dir));
  }
  CHECK(has(cli("run " + sh(kRef) + " --solver ''").err, "solver.kind"));
  CHECK(has(cli("run " + sh(kRef) + " --h 1e-6").err, "--h"));
}

TEST_CASE("Contract: a wall-time budget stops a run at a sample, keeps it, exit 4",
          "[contract][cli]") {
  // Budgets far below the runs' cost: the event-driven run at mu = 0.25 (rolling) takes about
  // 0.8 s and mj at h = 1e-6 about 0.15 s on this machine, both against 1 ms of budget, so
  // neither can finish inside it on any machine this project targets.
  for (const std::string& extra :
       {std::string("--set contact.mu=0.25"), std::string("--solver mj --h 1e-6")}) {
    const fs::path dir = fresh_dir("budget");
    const Outcome o = cli("run " + sh(kRef) + " --t-end 0.5 --quiet --set run.max_wall=1e-3 " +
                          extra + " --out " + sh(dir));
    INFO(extra << ": " << o.err);
    CHECK(o.code == 4);
    CHECK(has(o.err, "wall-time budget of 0.001 s spent"));
    const RunRecord r = read_run(dir.string());
    CHECK_FALSE(r.complete);
    REQUIRE(r.samples.size() >= 2);  // the output so far is kept
    CHECK(r.samples.back().t < 0.5);
    CHECK(has(slurp(dir / "summary.json"), "\"termination\": \"time_budget\""));
    fs::remove_all(dir);
  }
  // a negative or non-finite budget is bad input, named by its key, nothing written
  for (const std::string bad : {"-1", "nan", "inf"}) {
    const fs::path dir = fresh_dir("budget-bad");
    const Outcome o =
        cli("run " + sh(kRef) + " --quiet --set run.max_wall=" + bad + " --out " + sh(dir));
    INFO(bad << ": " << o.err);
    CHECK(o.code == 2);
    CHECK(has(o.err, "run.max_wall"));
    CHECK_FALSE(fs::exists(dir / "summary.json"));
    fs::remove_all(dir);
  }
}

TEST_CASE("Contract: --help lists every exit code", "[contract][cli]") {
  const fs::path out = fresh_dir("help");
  REQUIRE(std::system((std::string(RUBDYN_CLI) + " --help > " + sh(out)).c_str()) == 0);
  const std::string help = slurp(out);
  for (const char* code :
       {"0 complete", "2 bad input", "3 run ended early", "4 interrupted", "5 a write failed"})
    CHECK(has(help, code));
  fs::remove(out);
}

// --- item 11: a sweep checks every option and its size before the first point ----------------

TEST_CASE("Contract: sweep options are all checked before the first point runs",
          "[contract][cli]") {
  const fs::path dir = fresh_dir("sweep");
  for (const std::string args :
       {"--vary contact.mu=0:0.2:1000 --vary stator.k=1e6:3e6:1000",      // 1e6 points
        "--vary contact.mu=0:0.2:100000 --vary stator.k=1e6:3e6:100000",  // 1e10: no bad_alloc
        "--vary contact.mu=0.1,0.2 --min-turns -1",
        "--vary contact.mu=0.1,0.2 --vary contact.mu=0.3",  // one key twice
        "--vary contact.mu=0.1 --shard 99999999999/99999999999"}) {
    const Outcome o = cli("sweep " + sh(kRef) + " --t-end 0.001 " + args + " --out " + sh(dir));
    INFO(args << ": " << o.err);
    CHECK(o.code == 2);
    CHECK_FALSE(has(o.err, "stoi"));
    CHECK_FALSE(fs::exists(dir));
  }
  // above the limit with --max-points: planned and run (3 points, printed before the first)
  const fs::path out = fresh_dir("sweep-out");
  REQUIRE(std::system((std::string(RUBDYN_CLI) + " sweep " + sh(kRef) +
                       " --t-end 0.001 --vary contact.mu=0.1,0.2,0.3 --max-points 3 --quiet"
                       " --out " +
                       sh(dir) + " > " + sh(out))
                          .c_str()) == 0);
  CHECK(has(slurp(out), "plan          3 points"));
  CHECK(cli("sweep " + sh(kRef) +
            " --t-end 0.001 --vary contact.mu=0.1,0.2,0.3 --max-points 2 "
            "--out " +
            sh(dir / "b"))
            .code == 2);
  fs::remove_all(dir);
  fs::remove(out);
}

TEST_CASE("Contract: sweep-merge names the file and line of a corrupted index", "[contract]") {
  const fs::path dir = fresh_dir("merge");
  fs::create_directories(dir);
  // a shard as run_sweep writes it (sidecar with its plan; point, varied key, ..., folder)
  std::ofstream(dir / "sweep-shard-1-of-1.json")
      << "{\"shard\": 1, \"shards\": 1, \"points_total\": 2, \"plan\": \"0123456789abcdef\"}\n";
  std::ofstream(dir / "sweep-shard-1-of-1.csv")
      << "point,x,termination,folder\n0,1,completed,out/p0000\nzz,2,completed,out/p0001\n";
  CHECK_THROWS_WITH(merge_sweep_shards(dir.string()),
                    Catch::Contains("sweep-shard-1-of-1.csv:3") && Catch::Contains("zz"));
  fs::remove_all(dir);
}

// --- Also: case files that are not files, unbounded sizes -------------------------------------

TEST_CASE("Contract: a directory or a device as the case file is refused, sizes are bounded",
          "[contract][cli]") {
  Outcome o = cli("check " + sh(fs::temp_directory_path()));
  CHECK(o.code == 2);
  CHECK(has(o.err, "is a directory"));
  o = cli("check /dev/zero");  // never ends: refused before a byte is read (not a regular file)
  CHECK(o.code == 2);
  CHECK(has(o.err, "is a device"));
  // output size: t_end = 1e300 or output.dt = 1e-300 ask for ~1e300 rows
  for (const std::string set : {"run.t_end=1e300", "output.dt=1e-300"}) {
    try {
      (void)load_case(kRef, {set});
      FAIL(set << " accepted");
    } catch (const CaseError& e) {
      REQUIRE(e.issues().size() == 1);
      CHECK(e.issues()[0].key == set.substr(0, set.find('=')));
      CHECK(has(e.issues()[0].rule, "rows"));
    }
  }
  CHECK(cli("campbell " + sh(kRef) + " --points 10000000 --out " + sh(fresh_dir("cb"))).code == 2);
  CHECK(cli("analyze " + sh(fs::temp_directory_path()) + " --window 0").code == 2);
  // a fixed-step run that ends deep in the stator says so (h = 5e-3: 0.24 g0 on this case)
  const fs::path dir = fresh_dir("pen");
  o = cli("run " + sh(kRef) + " --solver mj --h 5e-3 --t-end 0.01 --quiet --out " + sh(dir));
  CHECK(o.code == 0);
  CHECK(has(o.err, "times the clearance"));
  fs::remove_all(dir);
}

// --- restart: rubdyn run --from DIR [--at T] ------------------------------------------------

TEST_CASE("Contract: a run restarts exactly from a sample of another run", "[contract][cli]") {
  const fs::path a = fresh_dir("ra"), b = fresh_dir("rb"), c = fresh_dir("rc");
  REQUIRE(cli("run " + sh(kRef) + " --t-end 0.02 --quiet --out " + sh(a)).code == 0);
  // from the sample at 0.01 s to 0.02 s: the first row is that sample, digit for digit (the
  // event solver starts a contact phase in its chart coordinates and maps back, a few ulps off:
  // a state on its constraints to round-off is written as given)
  REQUIRE(
      cli("run " + sh(kRef) + " --t-end 0.02 --from " + sh(a) + " --at 0.01 --quiet --out " + sh(b))
          .code == 0);
  const RunRecord ra = read_run(a.string()), rb = read_run(b.string());
  const Sample* at = nullptr;
  for (const auto& s : ra.samples)
    if (std::abs(s.t - 0.01) < 1e-14) at = &s;
  REQUIRE(at != nullptr);
  CHECK(rb.samples.front().t == at->t);
  CHECK(rb.samples.front().q == at->q);
  CHECK(rb.samples.front().v == at->v);
  CHECK(rb.spec.run.t_start == at->t);
  // and it goes on like the original: the integrator's history is new, so the two differ at
  // the tolerance level (rtol 1e-10 on positions of ~1e-4 m: 1e-14 m; measured 9e-14 m over
  // 10 ms of rolling), far below the clearance 2e-4 m
  double d = 0;
  const Sample &ea = ra.samples.back(), &eb = rb.samples.back();
  CHECK(ea.t == Approx(eb.t).epsilon(1e-12));
  for (int i : {XR, YR, XS, YS}) d = std::max(d, std::abs(ea.q[i] - eb.q[i]));
  CHECK(d < 1e-11);
  // without --at: the last sample (t = 0.02) onwards
  REQUIRE(
      cli("run " + sh(kRef) + " --t-end 0.03 --from " + sh(a) + " --quiet --out " + sh(c)).code ==
      0);
  CHECK(read_run(c.string()).samples.front().q == ea.q);
  // a time that is no sample, --at without --from, --out onto --from: exit 2
  CHECK(cli("run " + sh(kRef) + " --from " + sh(a) + " --at 0.013333 --out " + sh(c)).code == 2);
  CHECK(cli("run " + sh(kRef) + " --at 0.01 --out " + sh(c)).code == 2);
  CHECK(cli("run " + sh(kRef) + " --t-end 0.03 --from " + sh(a) + " --out " + sh(a)).code == 2);
  CHECK(fs::exists(a / "summary.json"));
  for (const auto& p : {a, b, c}) fs::remove_all(p);
}

TEST_CASE("Contract: sweep --resume skips the points already complete for the same case",
          "[contract][cli]") {
  const fs::path dir = fresh_dir("resume");
  const std::string base =
      "sweep " + sh(kRef) + " --t-end 0.002 --vary contact.mu=0.1,0.2 --quiet --out " + sh(dir);
  REQUIRE(cli(base).code == 0);
  // point 1 loses its summary (killed), point 0 stays complete
  fs::remove(dir / "p0001" / "summary.json");
  const auto t0 = fs::last_write_time(dir / "p0000" / "timeseries.csv");
  const auto t1 = fs::last_write_time(dir / "p0001" / "case.resolved.toml");
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // distinct write times
  REQUIRE(cli(base + " --resume").code == 0);
  CHECK(fs::last_write_time(dir / "p0000" / "timeseries.csv") == t0);      // not run again
  CHECK(fs::last_write_time(dir / "p0001" / "case.resolved.toml") != t1);  // run again
  CHECK(fs::exists(dir / "p0001" / "summary.json"));
  const std::string table = slurp(dir / "sweep.csv");
  CHECK(std::count(table.begin(), table.end(), '\n') == 3);
  // both rows "termination,complete" = "completed,yes"
  std::size_t done = 0;
  for (auto p = table.find(",completed,yes,"); p != std::string::npos;
       p = table.find(",completed,yes,", p + 1))
    ++done;
  CHECK(done == 2);
  // another case (t_end changed) is not the same resolved case: both points run again
  REQUIRE(cli("sweep " + sh(kRef) +
              " --t-end 0.003 --vary contact.mu=0.1,0.2 --quiet --resume --out " + sh(dir))
              .code == 0);
  CHECK(fs::last_write_time(dir / "p0000" / "timeseries.csv") != t0);
  fs::remove_all(dir);
}

TEST_CASE("Contract: a run that reaches no sample after SIGTERM still ends (grace period)",
          "[contract][cli]") {
  // output.dt = 1000 s: no sample before t_end (the run takes minutes). SIGTERM must still end
  // the process, either between steps (exit 4: the stop flag is read between integrator steps)
  // or, RUBDYN_STOP_GRACE = 1 s later, by SIGALRM. 30 s bounds both on a loaded machine.
  // (rotor.Jp = 4294967297 served here before; it is no rigid body and refused as a case.)
  const fs::path dir = fresh_dir("stuck");
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setenv("RUBDYN_STOP_GRACE", "1", 1);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    ::execl(RUBDYN_CLI, RUBDYN_CLI, "run", kRef.c_str(), "--quiet", "--t-end", "1000", "--set",
            "output.dt=1000", "--out", dir.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  REQUIRE(pid > 0);
  const auto t0 = std::chrono::steady_clock::now();
  std::error_code ec;
  // the headers are flushed once the handler is installed and the folder prepared
  while (!fs::exists(dir / "events.csv", ec) &&
         std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ::kill(pid, SIGTERM);
  const auto t1 = std::chrono::steady_clock::now();
  int st = 0;
  pid_t done = 0;
  while ((done = ::waitpid(pid, &st, WNOHANG)) == 0 &&
         std::chrono::steady_clock::now() - t1 < std::chrono::seconds(30))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  if (done == 0) {  // still running: the contract is broken; do not leave it behind
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &st, 0);
  }
  CHECK(done == pid);
  CHECK(((WIFEXITED(st) && WEXITSTATUS(st) == 4) || (WIFSIGNALED(st) && WTERMSIG(st) == SIGALRM)));
  fs::remove_all(dir);
}

TEST_CASE("Contract: results on a full standard output are a failed write, not exit 0",
          "[contract][cli]") {
  const fs::path err = fresh_dir("full-stdout");
  const int st = std::system(
      (std::string(RUBDYN_CLI) + " check " + sh(kRef) + " 2> " + sh(err) + " > /dev/full").c_str());
  CHECK((WIFEXITED(st) && WEXITSTATUS(st) == 5));
  CHECK(has(slurp(err), "standard output"));
  fs::remove(err);
}

TEST_CASE("Contract: SIGINT ends a sweep with its table, the points not run listed, exit 4",
          "[contract][cli]") {
  // 4 points of 100 s each on one thread: minutes of work, so the signal (sent once the first
  // point has rows on disk) always comes first
  const fs::path dir = fresh_dir("sweep-int");
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    ::execl(RUBDYN_CLI, RUBDYN_CLI, "sweep", kRef.c_str(), "--quiet", "--t-end", "100", "--jobs",
            "1", "--vary", "contact.mu=0.1,0.11,0.12,0.13", "--out", dir.c_str(),
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  REQUIRE(pid > 0);
  const auto t0 = std::chrono::steady_clock::now();
  auto rows_on_disk = [&] {
    std::error_code ec;
    const auto n = fs::file_size(dir / "p0000" / "timeseries.csv", ec);
    return !ec && n >= 8192;
  };
  while (!rows_on_disk() && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ::kill(pid, SIGINT);
  CHECK(wait_exit(pid) == 4);
  const std::string table = slurp(dir / "sweep.csv");
  CHECK(has(table, ",interrupted,no,"));
  std::size_t not_run = 0;
  for (auto p = table.find(",not_run,"); p != std::string::npos; p = table.find(",not_run,", p + 1))
    ++not_run;
  CHECK(not_run == 3);
  CHECK(has(slurp(dir / "p0000" / "summary.json"), "\"termination\": \"interrupted\""));
  fs::remove_all(dir);
}
