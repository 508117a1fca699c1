// rubdyn sweep CASE --vary KEY=VALUES ...: parametric sweeps in parallel, sharded for job arrays;
// rubdyn sweep-merge DIR: joins the shards' tables.
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>

#include "cli_common.hpp"
#include "commands.hpp"
#include "rubdyn/core/run_types.hpp"
#include "rubdyn/driver/sweep.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/solver_options.hpp"

namespace rubdyn::app {

namespace {

struct SweepArgs {
  CaseArgs c;
  std::vector<std::string> vary;
  std::string out = "out/sweep";
  // unset when not given: an empty value (an unset shell variable) is given, and refused
  std::optional<std::string> shard, solver, rtol, atol, h, t_end;
  int jobs = 0;
  long max_points = kDefaultMaxPoints;
  bool certify = false, quiet = false, resume = false;
  double min_turns = 1.0;
  EnsembleOptions ensemble;
};

int sweep_command(const SweepArgs& a) {
  SweepOptions o;
  o.case_path = a.c.path;
  o.sets = a.c.sets;
  if (a.solver) o.sets.push_back("solver.kind=" + toml_quote(*a.solver));
  if (a.rtol) o.sets.push_back("solver.rtol=" + *a.rtol);
  if (a.atol) o.sets.push_back("solver.atol=" + *a.atol);
  if (a.h) o.sets.push_back("solver.h=" + *a.h);
  if (a.t_end) o.sets.push_back("run.t_end=" + *a.t_end);
  for (const auto& v : a.vary) o.vary.push_back(parse_variation(v));
  if (o.vary.empty()) throw std::runtime_error("sweep: give at least one --vary");
  if (a.shard) o.shard = parse_shard(*a.shard);  // '' refused: it would run every point
  if (a.out.empty()) throw std::invalid_argument("--out '': an empty path is no sweep folder");
  if (a.jobs < 0) throw std::runtime_error("--jobs must be >= 0 (0: all cores)");
  o.jobs =
      a.jobs > 0 ? a.jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  o.out = a.out;
  o.certify = a.certify;
  o.analysis.min_turns = a.min_turns;
  if (a.max_points < 1) throw std::invalid_argument("--max-points must be >= 1");
  o.max_points = a.max_points;
  o.resume = a.resume;
  o.ensemble = a.ensemble;  // checked by run_sweep with the other options
  o.plan = [](const SweepPlan& p) {
    std::printf(
        "plan          %ld points; this run: %ld runs, %.6g s simulated, about %.3g "
        "output rows (%.3g MB); plan %s\n",
        p.points, p.runs, p.simulated_seconds, p.output_rows, p.output_bytes / 1e6, p.hash.c_str());
    std::fflush(stdout);
  };
  const bool tty = !a.quiet && isatty(fileno(stderr));
  if (tty) {
    const char* unit = o.ensemble.members > 0 ? "points and members" : "points";
    o.progress = [unit](long done, long total) {
      std::fprintf(stderr, "\r  sweep: %ld of %ld %s done", done, total, unit);
      std::fflush(stderr);
    };
  }
  stop_on_signals();
  o.stop = &stop_flag();
  const auto rows = run_sweep(o);
  if (tty) std::fprintf(stderr, "\r%60s\r", "");
  long bad = 0, uncertified = 0, not_run = 0, bad_members = 0;
  // the exit code of the worst point or member, as `run` (then `analyze`) would give it: a
  // failed write 5, a point that could not be run or analysed ("error") 2, a numerical end 3
  bool write_failed = false, errored = false;
  const std::string output_failure(to_string(Termination::OutputFailure));
  auto note = [&](const std::string& termination) {
    write_failed = write_failed || termination == output_failure;
    errored = errored || termination == "error";
  };
  for (const auto& r : rows) {
    note(r.termination);
    for (const auto& m : r.members) note(m.termination);
  }
  for (const auto& r : rows) {
    if (r.termination == "not_run") {
      ++not_run;
    } else if (!r.complete) {
      ++bad;
      std::fprintf(stderr, "rubdyn sweep: point %ld (%s) ended early: %s: %s\n", r.point.index,
                   r.folder.c_str(), r.termination.c_str(), r.message.c_str());
    }
    if (o.certify && !r.certified) ++uncertified;
    for (const auto& m : r.members) {
      if (m.termination == "not_run" || m.complete) continue;
      ++bad_members;
      std::fprintf(stderr,
                   "rubdyn sweep: ensemble member %s ended early: %s: %s (left out of its "
                   "point's P columns, counted in ensemble_incomplete)\n",
                   m.folder.c_str(), m.termination.c_str(), m.message.c_str());
    }
  }
  std::printf("sweep         %ld points run (%s), %ld ended early",
              static_cast<long>(rows.size()) - not_run,
              o.shard.count > 1 ? a.shard->c_str() : "all", bad);
  if (not_run > 0) std::printf(", %ld not run (interrupted)", not_run);
  if (o.certify) std::printf(", %ld verdicts depend on the tolerance", uncertified);
  if (o.ensemble.members > 0)
    std::printf("; %d ensemble members a point, %ld ended early", o.ensemble.members, bad_members);
  std::printf("\ntable         %s/%s\n", o.out.c_str(),
              o.shard.count > 1 ? "sweep-shard-*.csv (join with rubdyn sweep-merge)" : "sweep.csv");
  if (stop_flag().load()) {
    std::fprintf(stderr,
                 "rubdyn sweep: interrupted; the table lists the points not run (not_run); "
                 "run the same command with --resume to complete it\n");
    return write_failed ? kExitOutput : kExitInterrupted;
  }
  if (write_failed) return kExitOutput;
  if (errored) return kExitBadInput;
  return bad + bad_members > 0 ? kExitEarlyEnd : kExitOk;
}

}  // namespace

void add_sweep_commands(CLI::App& app, Action& action) {
  auto a = std::make_shared<SweepArgs>();
  auto* sub = app.add_subcommand("sweep", "Run the Cartesian product of case variations");
  add_case_options(*sub, a->c);
  sub->add_option("--vary", a->vary,
                  "SECTION.KEY=v1,v2,... or SECTION.KEY=a:b:n (repeatable; product)")
      ->allow_extra_args(false);
  sub->add_option("--jobs", a->jobs, "parallel runs (default: all cores)");
  sub->add_option("--out", a->out, "sweep folder (default out/sweep)");
  sub->add_option("--shard", a->shard, "run slice i of N only (i/N), for job arrays");
  sub->add_flag("--certify", a->certify,
                "re-run each point tighter and report whether its verdicts hold (numerics; "
                "--ensemble says whether they survive a perturbation: physics)");
  sub->add_option("--ensemble", a->ensemble.members,
                  "also run each point as N perturbed members in OUT/pNNNN-eKK (0: off, the "
                  "default; at most 1000): member k = 1..N starts at omega0 + domega (2 (k - 1) "
                  "/ (N - 1) - 1) (N = 1: + domega), the rotor moved by offset (cos a, sin a) at "
                  "R, a = 2 pi (k - 1) / N; sweep.csv adds ensemble_members (N + 1), "
                  "ensemble_incomplete, p_limited, p_backward, p_whip, p_rolling (fractions of "
                  "the complete runs), omega_max_min, omega_max_max")
      ->type_name("N");
  auto* domega = sub->add_option("--ensemble-domega", a->ensemble.domega,
                                 "largest change of omega0 in an ensemble [rad/s] (default 0.1)");
  auto* offset = sub->add_option("--ensemble-offset", a->ensemble.offset,
                                 "initial offset of the rotor at R in an ensemble [m] (default "
                                 "1e-7; below stator.gap)");
  sub->add_option("--solver", a->solver, solver_names(" | "));
  sub->add_option("--rtol", a->rtol, "event solver: relative tolerance");
  sub->add_option("--atol", a->atol, "event solver: absolute tolerance on positions [m]");
  sub->add_option("--h", a->h, "fixed-step schemes: time step [s]");
  sub->add_option("--t-end", a->t_end, "end time [s]");
  sub->add_option("--min-turns", a->min_turns,
                  "sustained whirl: orbit revolutions in one run (default 1)");
  sub->add_option("--max-points", a->max_points,
                  "run sweeps of more points than this (default 10000: larger ones are refused; "
                  "with --ensemble N, points x (N + 1) are counted)");
  sub->add_flag("--resume", a->resume,
                "skip the points (and members) whose folder holds a complete run of the same "
                "resolved case");
  sub->add_flag("--quiet", a->quiet, "no progress line");
  sub->callback([a, &action, domega, offset] {
    // an ensemble setting without an ensemble would be ignored silently: refused instead
    for (const auto* opt : {domega, offset})
      if (opt->count() > 0 && a->ensemble.members == 0)
        throw CLI::ValidationError(opt->get_name(), "applies to an ensemble: give --ensemble N");
    action = [a] { return sweep_command(*a); };
  });

  auto out = std::make_shared<std::string>();
  auto* merge = app.add_subcommand("sweep-merge", "Join the shard tables of a sweep folder");
  merge->add_option("dir", *out, "sweep folder holding sweep-shard-i-of-N.csv")->required();
  merge->callback([out, &action] {
    action = [out] {
      const long n = merge_sweep_shards(*out);
      std::printf("merged        %ld points into %s/sweep.csv\n", n, out->c_str());
      return 0;
    };
  });
}

}  // namespace rubdyn::app
