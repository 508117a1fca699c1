// rubdyn orbit CASE: a periodic orbit of the case's event-driven flow by Newton's method on its
// return map, with its Floquet multipliers and stability (analysis/orbit_case.hpp,
// docs/orbits.md), written to an output folder.
#include <fmt/format.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "commands.hpp"
#include "restart.hpp"
#include "rubdyn/analysis/orbit_case.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/output_folder.hpp"

namespace rubdyn::app {

namespace {

struct OrbitArgs {
  CaseArgs c;
  std::optional<std::string> out, from, at, rtol, atol;
  int periods = 1, settle = 0, max_iter = OrbitOptions{}.max_iterations,
      samples = OrbitOptions{}.samples;
  double tol = OrbitOptions{}.tol;
  std::string monodromy = "differences";
  std::optional<double> period;
};

std::string phase_words(const std::vector<Phase>& p) {
  std::string s;
  for (std::size_t k = 0; k < p.size(); ++k) {
    if (k) s += ", ";
    s += to_string(p[k]);
  }
  return s.empty() ? "-" : s;
}

void print_report(const CaseOrbit& o, const std::string& dir) {
  const OrbitResult& r = o.result;
  std::printf(
      "orbit         forced, period %.10g s (%d x 2 pi / %.10g rad/s), section at t0 = "
      "%.10g s\n",
      r.period, o.periods, o.omega, r.t0);
  std::printf("outcome       %s: %s\n", std::string(to_string(r.outcome)).c_str(),
              r.message.c_str());
  if (!r.section_phases.empty())
    std::printf("section       %s: %d coordinates on %d constraints\n",
                phase_words(r.section_phases).c_str(), r.chart_dim, r.constraints);
  std::string hist;
  for (const auto& h : r.history) hist += fmt::format(" {:.2e}", h.residual);
  std::printf("newton        residual per iterate:%s (tol %.3g)\n", hist.c_str(), o.tol);
  if (r.monodromy.ok) {
    std::printf("monodromy     %s, error %.2g, %ld runs\n", r.monodromy.method.c_str(),
                r.monodromy.error, r.monodromy.runs);
    std::printf("multipliers   %12s  %28s  %9s\n", "|mu|", "mu", "error");
    for (const auto& f : r.floquet.multipliers)
      std::printf("              %12.8f  %13.8f %+13.8fi  %9.2e\n", std::abs(f.value),
                  f.value.real(), f.value.imag(), f.error);
  }
  std::printf("stability     %s: %s\n", std::string(to_string(r.floquet.stability)).c_str(),
              r.floquet.reason.c_str());
  std::string ev;
  for (int k = 0; k < kNumEventKinds; ++k)
    if (const long c = r.event_counts[static_cast<std::size_t>(k)])
      ev += fmt::format("{}{} {}", ev.empty() ? "" : ", ", to_string(static_cast<EventKind>(k)), c);
  std::string ph;
  const double T = r.period > 0 ? r.period : 1.0;
  for (int k = 0; k < kNumPhases; ++k)
    if (const double t = r.phase_time[static_cast<std::size_t>(k)]; t > 0)
      ph += fmt::format("{}{} {:.0f}%", ph.empty() ? "" : ", ", to_string(static_cast<Phase>(k)),
                        100.0 * t / T);
  std::printf("per period    events: %s; phases: %s\n", ev.empty() ? "none" : ev.c_str(),
              ph.empty() ? "-" : ph.c_str());
  std::printf("cost          %ld runs of the return map in %.3f s\n", r.runs, r.wall_seconds);
  std::printf("output        %s/\n", dir.c_str());
}

int orbit_command(const OrbitArgs& a) {
  std::vector<std::string> sets;
  if (a.from) {
    sets = restart_overrides_keeping_length(*a.from, a.at, a.c.path, a.c.sets, "rubdyn orbit");
  }
  sets.insert(sets.end(), a.c.sets.begin(), a.c.sets.end());
  if (a.rtol) sets.push_back("solver.rtol=" + *a.rtol);
  if (a.atol) sets.push_back("solver.atol=" + *a.atol);
  std::vector<CaseIssue> bad;
  if (a.out && a.out->empty())
    bad.push_back({"command line", 0, "--out", "", "an empty path is no output folder"});
  CaseSpec spec;
  try {
    spec = load_case(a.c.path, sets);
  } catch (const CaseError& e) {
    bad.insert(bad.end(), e.issues().begin(), e.issues().end());
  }
  CaseOrbitOptions opt;
  opt.periods = a.periods;
  opt.settle = a.settle;
  opt.orbit.tol = a.tol;
  opt.orbit.max_iterations = a.max_iter;
  opt.orbit.samples = a.samples;
  if (a.period) opt.period = *a.period;
  static const SensitivityMonodromy sensitivities;
  if (a.monodromy == "sensitivities") opt.orbit.provider = &sensitivities;
  if (bad.empty()) {
    const auto more = orbit_issues(spec, opt);
    bad.insert(bad.end(), more.begin(), more.end());
  }
  if (!bad.empty()) throw CaseError(bad);  // exit 2, nothing written

  const std::string dir = a.out ? *a.out : output_folder(spec) + "-orbit";
  if (a.from) {
    std::error_code ec;
    if (std::filesystem::equivalent(*a.from, dir, ec))
      throw CaseError(
          {{"command line", 0, "--out", dir, "is the folder given to --from; give another --out"}});
  }
  stop_on_signals();
  opt.stop = &stop_flag();
  const std::unique_ptr<HeldFolder> folder = open_orbit_folder(dir, spec);  // FolderError: 2
  const CaseOrbit o = find_case_orbit(spec, opt);
  write_orbit_files(*folder, spec, o);  // OutputError: exit 5
  print_report(o, dir);
  if (!o.result.converged())
    std::fprintf(stderr, "rubdyn orbit: %s: %s\n", std::string(to_string(o.result.outcome)).c_str(),
                 o.result.message.c_str());
  return exit_code(o.result);
}

}  // namespace

void add_orbit_command(CLI::App& app, Action& action) {
  auto a = std::make_shared<OrbitArgs>();
  auto* sub = app.add_subcommand(
      "orbit",
      "A periodic orbit of a case (a prescribed constant spin, or a free spin with --period) by "
      "Newton on the event-driven flow's return map, with its Floquet multipliers and stability "
      "(docs/orbits.md)");
  add_case_options(*sub, a->c);
  sub->add_option("--out", a->out, "output folder (default: the case's output folder + -orbit)");
  sub->add_option("--from", a->from,
                  "start Newton from the last complete sample of this output folder (its time "
                  "is the section's)");
  sub->add_option("--at", a->at, "with --from: start from the sample at this time [s]");
  sub->add_option("--periods", a->periods,
                  "k: the orbit's period is 2 pi k / omega0 (k > 1: a subharmonic)");
  sub->add_option("--period", a->period,
                  "a free spin's orbit (loads.spin = \"torque\"): the guess of its period [s]");
  sub->add_option("--settle", a->settle,
                  "periods of a transient run before Newton starts (from the initial state)");
  sub->add_option("--tol", a->tol,
                  "Newton's tolerance on |P(x) - x| per state scale (gap g0, g0 omega0)");
  sub->add_option("--max-iter", a->max_iter, "Newton iterations at most");
  sub->add_option("--samples", a->samples, "samples of the orbit per period in orbit.csv");
  sub->add_option("--monodromy", a->monodromy,
                  "the final monodromy from finite differences of the return map (default) or "
                  "from the flow's sensitivities (variational equations and saltation matrices)")
      ->check(CLI::IsMember({"differences", "sensitivities"}));
  sub->add_option("--rtol", a->rtol, "the runs' relative tolerance (overrides solver.rtol)");
  sub->add_option("--atol", a->atol, "the runs' absolute tolerance (overrides solver.atol)");
  sub->footer(
      "Writes orbit.csv (one period of the orbit), orbit.json (period, Newton's residuals, "
      "multipliers with their error bounds and the stability verdict, events per period) and "
      "case.resolved.toml. Exit 0: converged; 3: no convergence or another numerical outcome "
      "(orbit.json says which, with the last iterate); 4: interrupted; 2: bad input.");
  sub->callback([a, &action] {
    if (a->at && !a->from) throw CLI::ValidationError("--at", "needs --from");
    action = [a] { return orbit_command(*a); };
  });
}

}  // namespace rubdyn::app
