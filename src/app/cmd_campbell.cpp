// rubdyn campbell CASE: Campbell diagram of the coupled rotor-stator system -> campbell.csv.
#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "commands.hpp"
#include "rubdyn/analysis/campbell.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"

namespace rubdyn::app {

namespace {

struct CampbellArgs {
  std::string case_path, out;
  std::vector<std::string> sets;
  int points = 201;
  double omega_max = 0.0;  // 0: run.omega_lim
  bool damped = false;
};

int campbell_command(const CampbellArgs& a) {
  std::vector<CaseIssue> bad;
  if (a.points < 2)
    bad.push_back({"--points", 0, "--points", std::to_string(a.points), "must be >= 2"});
  if (!(a.omega_max >= 0.0))
    bad.push_back({"--omega-max", 0, "--omega-max", fmt::format("{}", a.omega_max), "must be > 0"});
  if (!bad.empty()) throw CaseError(bad);
  const CaseSpec spec = load_case(a.case_path, a.sets);
  const double omega_max = a.omega_max > 0.0 ? a.omega_max : spec.run.omega_lim;
  const auto d = campbell_diagram(spec.params, omega_max, a.points, a.damped);
  for (const auto& c : d) {
    if (!c.labels_ok) {
      throw std::runtime_error(fmt::format(
          "at omega = {} rad/s the modes are not two forward and two backward", c.omega));
    }
  }
  const std::string dir = a.out.empty() ? output_folder(spec) : a.out;
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/campbell.csv";
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw std::runtime_error("cannot write " + path);
  const std::string text = campbell_csv(d, a.damped);
  std::fwrite(text.data(), 1, text.size(), f);
  std::fclose(f);
  const auto& z = d.front();
  const auto& e = d.back();
  std::printf("Campbell diagram of the coupled system (%d points, %s)\n", a.points,
              a.damped ? "damped" : "undamped");
  std::printf("  omega = %8.2f rad/s: f1b %8.3f  f1f %8.3f  f2b %8.3f  f2f %8.3f Hz\n", z.omega,
              z.f1b, z.f1f, z.f2b, z.f2f);
  std::printf("  omega = %8.2f rad/s: f1b %8.3f  f1f %8.3f  f2b %8.3f  f2f %8.3f Hz\n", e.omega,
              e.f1b, e.f1f, e.f2b, e.f2f);
  std::printf("  written to %s\n", path.c_str());
  return 0;
}

}  // namespace

void add_campbell_command(CLI::App& app, Action& action) {
  auto a = std::make_shared<CampbellArgs>();
  auto* sub = app.add_subcommand("campbell", "Campbell diagram of the coupled system");
  sub->add_option("case", a->case_path, "Case file (TOML)")->required();
  sub->add_option("--out", a->out, "output folder (default out/<case name>)");
  sub->add_option("--points", a->points, "number of speeds from 0 to omega-max (default 201)");
  sub->add_option("--omega-max", a->omega_max, "largest speed [rad/s] (default run.omega_lim)");
  sub->add_flag("--damped", a->damped, "include the bearing and stator dampers");
  sub->add_option("--set", a->sets, "override a case key: section.key=value (repeatable)");
  sub->callback([a, &action] { action = [a] { return campbell_command(*a); }; });
}

}  // namespace rubdyn::app
