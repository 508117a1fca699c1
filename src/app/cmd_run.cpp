// rubdyn run CASE: one run of the rotor-stator case with the event-driven integrator (default)
// or a fixed-step scheme, written to an output folder.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "commands.hpp"
#include "restart.hpp"
#include "rubdyn/analysis/postprocess.hpp"
#include "rubdyn/core/report.hpp"
#include "rubdyn/driver/simulate.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/columns.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/output_folder.hpp"
#include "rubdyn/io/solver_options.hpp"
#include "rubdyn/io/text_files.hpp"

namespace rubdyn::app {

namespace {

struct RunArgs {
  CaseArgs c;  // CASE and --set
  // kept as text: they become overrides of case keys and are validated (and reported) as such;
  // unset when not given (an empty --solver '' is given, and rejected as a kind)
  std::optional<std::string> solver, method, out, rtol, atol, t_end, h, output_every;
  std::optional<std::string> from, at;  // restart: output folder of another run, sample time
  bool quiet = false;
};

int run_command(const RunArgs& a) {
  // Command-line solver options are overrides of the case's keys: validated like the file.
  // a restart's state first: an explicit --set of the same key wins
  // the case file is read once (a FIFO, <(gen-case), can be read only once)
  const std::string text = read_case_file(a.c.path);  // CaseError: exit 2
  std::vector<std::string> sets;
  if (a.from) {
    std::optional<CaseSpec> plain;
    try {
      plain = parse_case(text, a.c.path, a.c.sets);
    } catch (const CaseError&) {
      // reported by the load below, with the restart's keys
    }
    sets = restart_overrides(*a.from, a.at, plain ? &*plain : nullptr, "rubdyn run");
  }
  sets.insert(sets.end(), a.c.sets.begin(), a.c.sets.end());
  if (a.solver) sets.push_back("solver.kind=" + toml_quote(*a.solver));
  if (a.method) sets.push_back("solver.method=" + toml_quote(*a.method));
  if (a.rtol) sets.push_back("solver.rtol=" + *a.rtol);
  if (a.atol) sets.push_back("solver.atol=" + *a.atol);
  if (a.h) sets.push_back("solver.h=" + *a.h);
  if (a.t_end) sets.push_back("run.t_end=" + *a.t_end);
  if (a.output_every) sets.push_back("output.every=" + *a.output_every);
  // a path is a string as given, never TOML text ('run\new' is not run<newline>ew); one that is
  // not UTF-8 (a Latin-1 name) cannot go into case.resolved.toml: refused here, naming --out
  // (as an override it would be named --set)
  const bool out_utf8 = !a.out || valid_utf8(*a.out);
  if (a.out && out_utf8) sets.push_back("output.folder=" + toml_quote(*a.out));
  std::vector<CaseIssue> bad;
  if (a.out && a.out->empty())  // an unset variable: not the case's default folder in silence
    bad.push_back({"command line", 0, "--out", "", "an empty path is no output folder"});
  if (!out_utf8)
    bad.push_back({"command line", 0, "--out", printable_text(*a.out),
                   "a folder name is UTF-8 text (case.resolved.toml, which names it, is TOML): "
                   "a byte of another encoding, shown as \\xHH, cannot be written back"});
  CaseSpec spec;
  try {
    spec = parse_case(text, a.c.path, sets);
  } catch (const CaseError& e) {
    bad.insert(bad.end(), e.issues().begin(), e.issues().end());
  }
  // an option the chosen solver does not read would be silently ignored: refused (the
  // solver registry says which keys each solver reads)
  if (bad.empty()) {
    const SolverEntry& solver = *find_solver(spec.solver.kind);  // validated by load_case
    const std::pair<const std::optional<std::string>&, const char*> given[] = {
        {a.rtol, "solver.rtol"},
        {a.atol, "solver.atol"},
        {a.method, "solver.method"},
        {a.h, "solver.h"},
        {a.output_every, "output.every"}};
    const char* flag_of[] = {"--rtol", "--atol", "--method", "--h", "--output-every"};
    for (size_t i = 0; i < std::size(given); ++i) {
      const std::string_view key = given[i].second;
      const bool reads = key == "output.every" ? solver.fixed_step : solver.reads(key);
      if (given[i].first && !reads) {
        std::vector<std::string> readers;
        for (const auto& e : solver_registry())
          if (key == "output.every" ? e.fixed_step : e.reads(key)) readers.emplace_back(e.name);
        std::string who;
        for (const auto& r : readers) who += (who.empty() ? "" : ", ") + r;
        bad.push_back({"command line", 0, flag_of[i], *given[i].first,
                       fmt::format("solver {} does not read {} (it applies to: {})",
                                   spec.solver.kind, key, who)});
      }
    }
  }
  if (!bad.empty()) throw CaseError(bad);  // exit 2, nothing written

  const std::string dir = output_folder(spec);
  if (a.from) {
    std::error_code ec;
    if (std::filesystem::equivalent(*a.from, dir, ec))
      throw CaseError({{"command line", 0, "--out", dir,
                        "is the folder given to --from: the restart would overwrite its own "
                        "start; give another --out"}});
  }
  stop_on_signals();
  OutputFolder sink(dir, spec, &stop_flag());  // FolderError: exit 2, nothing written

  const bool show_progress = !a.quiet && isatty(fileno(stderr));
  auto last = std::chrono::steady_clock::now();
  auto progress = [&](double t, long events, double omega, Phase phase) {
    const auto now = std::chrono::steady_clock::now();
    if (now - last < std::chrono::milliseconds(100)) return;
    last = now;
    std::fprintf(stderr, "\r  t = %.6f s  events %ld  omega %.3f rad/s  phase %-6s", t, events,
                 omega, std::string(to_string(phase)).c_str());
    std::fflush(stderr);
  };

  RunSummary summary =
      simulate(spec, sink, show_progress ? ProgressFn(progress) : ProgressFn(), &stop_flag());
  if (show_progress) std::fprintf(stderr, "\r%80s\r", "");
  if (!sink.error().empty()) {
    // the sink stopped the run: what summary.json says (OutputFolder::end)
    summary.message = sink.error();
    summary.termination = Termination::OutputFailure;
  }
  std::printf("%s", brief_report(summary).c_str());
  std::printf("output        %s/\n", dir.c_str());
  // A fixed-step scheme with too large a step can end far inside the stator and still
  // "complete": say so. A tenth of the clearance: beyond it the contact normal and the gap of
  // the scheme's state no longer describe the same geometry (mj at h = 5e-3 reached 79 g0).
  const double g0 = build_model(spec)->gap_scale(0);
  if (summary.max_penetration > 0.1 * g0) {
    std::fprintf(stderr,
                 "rubdyn run: warning: the largest penetration, %.3g m, is %.3g times the "
                 "clearance g0 = %.3g m: the result is not a resolved solution (reduce h)\n",
                 summary.max_penetration, summary.max_penetration / g0, g0);
  }
  if (!summary.complete()) {
    std::fprintf(stderr, "rubdyn run: ended early (%s): %s\n",
                 std::string(to_string(summary.termination)).c_str(), summary.message.c_str());
  }
  return exit_code(summary.termination);
}

}  // namespace

void add_run_command(CLI::App& app, Action& action) {
  auto a = std::make_shared<RunArgs>();
  auto* sub = app.add_subcommand("run", "Run a case and write its output folder");
  add_case_options(*sub, a->c);
  sub->add_option("--solver", a->solver, solver_names(" | "));
  sub->add_option(
      "--method", a->method,
      "event solver, free flight: auto (default: bdf when the model is stiff) | adams | bdf");
  sub->add_option("--rtol", a->rtol, "event solver: relative tolerance");
  sub->add_option("--atol", a->atol, "event solver: absolute tolerance on positions [m]");
  sub->add_option("--h", a->h, "fixed-step schemes: time step [s]");
  sub->add_option("--output-every", a->output_every, "fixed-step schemes: write every N-th step");
  sub->add_option("--t-end", a->t_end, "end time [s] (overrides run.t_end)");
  sub->add_option("--out", a->out, "output folder (default out/<case name>)");
  sub->add_option("--from", a->from,
                  "restart: start from the last complete sample of this output folder");
  sub->add_option("--at", a->at, "restart: start from the sample of --from at this time [s]");
  sub->add_flag("--quiet", a->quiet, "no progress line");
  sub->callback([a, &action] {
    if (a->at && !a->from) throw CLI::ValidationError("--at", "needs --from");
    action = [a] { return run_command(*a); };
  });
}

}  // namespace rubdyn::app
