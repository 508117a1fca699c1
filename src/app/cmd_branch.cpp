// rubdyn branch CASE --vary KEY: a branch of periodic orbits (forced, or autonomous with --period)
// followed in a case key by pseudo-arclength continuation, with folds, period doublings and
// Neimark-Sacker points located (analysis/continuation.hpp, docs/orbits.md section 10).
#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
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
#include "rubdyn/io/text_files.hpp"

namespace rubdyn::app {

namespace {

/// branch.csv of 10 000 points of a 1000-coordinate model is about 400 MB; more is not a branch.
constexpr std::size_t kMaxBranchBytes = std::size_t{1} << 30;

struct BranchArgs {
  CaseArgs c;
  std::string key;
  std::optional<std::string> out, from, at, rtol, atol, switch_dir;
  std::optional<double> to;
  bool down = false, resume = false;
  std::string monodromy = "differences";
  CaseBranchOptions o;
};

int branch_command(BranchArgs& a) {
  std::vector<std::string> sets;
  if (a.from) {
    sets = restart_overrides_keeping_length(*a.from, a.at, a.c.path, a.c.sets, "rubdyn branch");
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
  a.o.key = a.key;
  a.o.to = a.to.value_or(std::numeric_limits<double>::quiet_NaN());
  a.o.direction = a.down ? -1 : +1;
  static const SensitivityMonodromy sensitivities;
  if (a.monodromy == "sensitivities") a.o.orbit.orbit.provider = &sensitivities;
  if (bad.empty()) {
    const auto more = branch_issues(spec, a.o);
    bad.insert(bad.end(), more.begin(), more.end());
  }
  const std::string dir = a.out ? *a.out : output_folder(spec) + "-branch";
  // the earlier branch to resume (this folder's) or to switch from (--switch's folder)
  std::optional<CaseBranch> earlier;
  if (bad.empty() && (a.resume || a.switch_dir)) {
    const std::string src = a.resume ? dir : *a.switch_dir;
    const std::string opt = a.resume ? "--resume" : "--switch";
    const auto read = [&](const std::string& name, std::size_t max_bytes) {
      try {
        return read_input_file(src + "/" + name, max_bytes, "branch folder's");
      } catch (const InputRefused& e) {
        throw CaseError({{"command line", 0, opt, src,
                          fmt::format("needs a folder that rubdyn branch wrote: {}/{}: {}", src,
                                      name, e.what())}});
      }
    };
    const std::string json = read("branch.json", kMaxBranchBytes);
    const std::string csv = read("branch.csv", kMaxBranchBytes);
    // the same case and settings as the branch in the folder (its case.resolved.toml): the
    // forcing's phase at a section time, the tolerances, the model
    if (read("case.resolved.toml", kMaxCaseBytes) != to_toml(spec))
      bad.push_back({"command line", 0, opt, src,
                     "the folder's branch is of another case or other settings (its "
                     "case.resolved.toml differs from this command's case, with its --set, "
                     "--from and tolerances): use those of the command that wrote it"});
    earlier = read_case_branch(json, csv, src);
    (a.resume ? a.o.resume : a.o.switch_from) = &*earlier;
    const auto more = branch_issues(spec, a.o);
    bad.insert(bad.end(), more.begin(), more.end());
  }
  if (!bad.empty()) throw CaseError(bad);  // exit 2, nothing written
  const std::string text = read_input_file(a.c.path, kMaxCaseBytes, "case");

  stop_on_signals();
  a.o.orbit.stop = &stop_flag();
  // (a resumed branch's files stay until its longer version replaces them)
  const auto folder =
      open_orbit_folder(dir, spec,
                        a.resume ? std::vector<std::string>{}
                                 : std::vector<std::string>{"branch.csv", "branch.json"});
  const CaseBranch b = find_case_branch(text, a.c.path, sets, a.o);
  const Branch& r = b.branch;
  if (b.nothing_to_resume) {
    std::printf("resume        nothing to do: the branch in %s has %zu points and ended: %s\n",
                dir.c_str(), r.points.size(), r.outcome.c_str());
    return 0;
  }
  write_branch_files(*folder, b);
  if (!b.started.empty()) std::printf("started       %s\n", b.started.c_str());
  std::printf("branch        %s from %.10g: %zu points, %s (%s)\n", b.key.c_str(), b.lambda0,
              r.points.size(), r.outcome.c_str(), r.message.c_str());
  if (!r.points.empty()) {
    double lo = r.points.front().lambda, hi = lo;
    for (const auto& p : r.points) lo = std::min(lo, p.lambda), hi = std::max(hi, p.lambda);
    std::printf("range         %s in [%.10g, %.10g]\n", b.key.c_str(), lo, hi);
  }
  for (const auto& s : r.specials) {
    // (a special beyond the last point: the corrector's iterates crossed it, no point after it)
    const std::string where = s.after + 1 < static_cast<int>(r.points.size())
                                  ? fmt::format("between points {} and {}", s.after, s.after + 1)
                                  : fmt::format("after point {}, the last", s.after);
    std::printf("%-13s %s = %.12g %s: %s\n", s.kind.c_str(), b.key.c_str(), s.lambda, where.c_str(),
                s.how.c_str());
  }
  std::printf("cost          %ld runs of the return map in %.2f s\n", r.runs, r.wall_seconds);
  std::printf("output        %s/\n", dir.c_str());
  const int code = exit_code(b);
  if (code != 0)
    std::fprintf(stderr, "rubdyn branch: %s: %s\n", r.outcome.c_str(), r.message.c_str());
  return code;
}

}  // namespace

void add_branch_command(CLI::App& app, Action& action) {
  auto a = std::make_shared<BranchArgs>();
  auto* sub = app.add_subcommand(
      "branch",
      "Follow a case's periodic orbit (forced; or autonomous, a free spin with --period) in a "
      "case key (pseudo-arclength continuation), "
      "locating folds, period doublings and Neimark-Sacker points (docs/orbits.md)");
  add_case_options(*sub, a->c);
  sub->add_option("--vary", a->key, "the case key to follow the orbit in, e.g. initial.omega0")
      ->required();
  sub->add_option("--to", a->to, "stop beyond this value of the key");
  sub->add_flag("--down", a->down, "the first step decreases the key (default: increases)");
  sub->add_option("--points", a->o.points, "points on the branch, the first included");
  sub->add_option("--ds", a->o.ds, "first arclength step (scaled units)");
  sub->add_option("--ds-max", a->o.ds_max, "largest arclength step");
  sub->add_option("--scale", a->o.scale,
                  "the key's unit in the arclength (default: 1 % of its value in the case)");
  sub->add_option("--periods", a->o.orbit.periods, "k: the orbits' period is 2 pi k / omega0");
  sub->add_option("--period", a->o.orbit.period,
                  "a free spin's orbits (loads.spin = \"torque\", autonomous): the guess of the "
                  "first one's period [s]");
  sub->add_option("--tol", a->o.orbit.orbit.tol, "Newton's and the corrector's tolerance");
  sub->add_option("--monodromy", a->monodromy,
                  "every point's monodromy (its multipliers, the corrector's Jacobian) from finite "
                  "differences of the return map (default) or from the flow's sensitivities")
      ->check(CLI::IsMember({"differences", "sensitivities"}));
  sub->add_flag("--resume", a->resume,
                "continue the branch in the output folder (an interrupted or shorter run of the "
                "same command) from its last point, to --points in all");
  sub->add_option("--switch", a->switch_dir,
                  "branch switching: follow the orbits of twice the period that leave the first "
                  "period doubling of the branch in this folder (a forced orbit)");
  sub->add_option("--special", a->o.special,
                  "with --switch: the period doubling's index among the folder's special points "
                  "(branch.json, from 0)");
  sub->add_option("--switch-offset", a->o.switch_offset,
                  "with --switch: the first orbit's distance from the doubling in the key "
                  "(default: half the distance of the two points around it)");
  sub->add_option("--switch-eps", a->o.switch_eps,
                  "with --switch: the step from the doubling's orbit along its multiplier -1's "
                  "direction, in the scaled state (default 0.05)");
  sub->add_option("--out", a->out, "output folder (default: the case's output folder + -branch)");
  sub->add_option("--from", a->from, "start from the last complete sample of this output folder");
  sub->add_option("--at", a->at, "with --from: start from the sample at this time [s]");
  sub->add_option("--rtol", a->rtol, "the runs' relative tolerance (overrides solver.rtol)");
  sub->add_option("--atol", a->atol, "the runs' absolute tolerance (overrides solver.atol)");
  sub->footer(
      "Writes branch.csv (one row per point: the key's value, the orbit's amplitude and normal "
      "forces, period, multipliers with error bounds, stability, the state, the events), "
      "branch.json (outcome, special points) and case.resolved.toml; plots: "
      "validation/orbits/plot.py DIR. Exit 0: the branch ended as asked (its points, --to, or "
      "where the orbit's events change); 3: a step failed; 4: interrupted (--resume continues it); "
      "2: bad input.");
  sub->callback([a, sub, &action] {
    if (a->at && !a->from) throw CLI::ValidationError("--at", "needs --from");
    for (const char* o : {"--special", "--switch-offset", "--switch-eps"})
      if (sub->count(o) && !a->switch_dir) throw CLI::ValidationError(o, "needs --switch");
    action = [a] { return branch_command(*a); };
  });
}

}  // namespace rubdyn::app
