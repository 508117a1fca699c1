// rubdyn campbell CASE: Campbell diagram of the coupled rotor-stator system -> DIR/campbell.csv.
#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>

#include "cli_common.hpp"
#include "commands.hpp"
#include "rubdyn/analysis/campbell.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/text_files.hpp"

namespace rubdyn::app {

namespace {

struct CampbellArgs {
  CaseArgs c;
  std::string out;
  int points = 201;
  double omega_max = 0.0;
  bool omega_max_given = false;
  bool damped = false;
};

void print_point(const CampbellPoint& p, bool damped) {
  std::string f, z;
  for (std::size_t k = 0; k < p.f_forward.size(); ++k) {
    f += fmt::format("  f{}b {:8.3f}  f{}f {:8.3f}", k + 1, p.f_backward[k], k + 1, p.f_forward[k]);
    z += fmt::format("  zeta {:8.5f}       {:8.5f}", p.zeta_backward[k], p.zeta_forward[k]);
  }
  std::printf("  Omega %9.2f rad/s (%8.0f rpm):%s Hz\n", p.omega, p.omega * 30.0 / std::numbers::pi,
              f.c_str());
  if (damped) std::printf("  %33s%s\n", "", z.c_str());
}

int campbell_command(const CampbellArgs& a) {
  // Every problem with the options and the case is reported at once; nothing is written.
  std::vector<CaseIssue> bad;
  // 1e5 speeds: a 14 x 14 eigenproblem each, seconds of work and a 10 MB CSV; more is a typo
  constexpr int kMaxPoints = 100'000;
  if (a.points < 2 || a.points > kMaxPoints) {
    bad.push_back({"command line", 0, "--points", std::to_string(a.points),
                   fmt::format("must lie in [2, {}]", kMaxPoints)});
  }
  if (a.omega_max_given && !(std::isfinite(a.omega_max) && a.omega_max > 0.0)) {
    bad.push_back({"command line", 0, "--omega-max", fmt::format("{}", a.omega_max),
                   "must be finite and > 0 [rad/s]"});
  }
  CaseSpec spec;
  try {
    spec = load_case(a.c.path, a.c.sets);
  } catch (const CaseError& e) {
    bad.insert(bad.end(), e.issues().begin(), e.issues().end());
  }
  if (!bad.empty()) throw CaseError(bad);

  const double omega_max = a.omega_max_given ? a.omega_max : spec.run.omega_lim;
  // the model's linearisation with the stator tied to the rotor (the paper's coupled system),
  // or its free modes where that does not exist (analysis/campbell.hpp); CaseError: exit 2
  const CampbellModel cm = campbell_model(spec);
  const LinearModel* lm = &cm.lm;
  const bool tied = cm.tied;
  const CampbellDiagram d = compute_campbell_diagram(*lm, omega_max, a.points, a.damped);

  const std::string dir = a.out.empty() ? output_folder(spec) : a.out;
  std::filesystem::create_directories(dir);
  const std::string path = (std::filesystem::path(dir) / "campbell.csv").string();
  write_file_atomic(path, campbell_csv(d));  // every write checked, close included

  const CampbellSolver solver(*lm, a.damped);
  std::printf("Campbell diagram of %s (%s): %s, %s, %d speeds from 0 to %g rad/s\n",
              spec.name.c_str(), spec.model.c_str(),
              tied ? "the stator tied to the rotor" : "no contact (the stator is rigid)",
              a.damped ? "damped" : "undamped", a.points, omega_max);
  print_point(solver.solve(0.0), a.damped);
  print_point(solver.solve(omega_max), a.damped);
  std::printf("  written to %s\n", path.c_str());
  if (!d.labels_ok()) {
    std::fprintf(stderr,
                 "rubdyn campbell: at %zu of %d speeds (first: %g rad/s) the modes are not %d "
                 "forward and %d backward with a clear whirl (NaN or doubtful labels there)\n",
                 d.unlabelled.size(), a.points, d.unlabelled.front(), solver.nodes(),
                 solver.nodes());
    return 3;
  }
  return 0;
}

}  // namespace

void add_campbell_command(CLI::App& app, Action& action) {
  auto a = std::make_shared<CampbellArgs>();
  auto* sub = app.add_subcommand(
      "campbell",
      "Campbell diagram of the coupled rotor-stator system (paper, section 5.1.2): the four "
      "whirl-labelled frequencies f1b, f1f, f2b, f2f versus the spin speed, to DIR/campbell.csv");
  add_case_options(*sub, a->c);
  sub->add_option("--out", a->out, "output folder DIR (default: the case's output folder)")
      ->check(non_empty_path());
  sub->add_option("--points", a->points, "number of speeds from 0 to omega-max, in [2, 100000]")
      ->capture_default_str();
  auto* om = sub->add_option("--omega-max", a->omega_max,
                             "largest speed [rad/s], > 0 (default: run.omega_lim of the case)");
  sub->add_flag("--damped", a->damped,
                "include the bearing and stator dampers: damped frequencies |Im lambda| / 2 pi "
                "and damping ratios zeta_* in the CSV");
  sub->callback([a, om, &action] {
    a->omega_max_given = om->count() > 0;
    action = [a] { return campbell_command(*a); };
  });
}

}  // namespace rubdyn::app
