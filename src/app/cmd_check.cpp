// rubdyn check CASE: validate a case and print its derived quantities.
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

#include "commands.hpp"
#include "rubdyn/analysis/derived.hpp"
#include "rubdyn/io/case_io.hpp"

namespace rubdyn::app {

namespace {

struct CheckArgs {
  std::string case_path;
  std::vector<std::string> sets;
};

int check_command(const CheckArgs& a) {
  const CaseSpec c = load_case(a.case_path, a.sets);
  const DerivedQuantities d = derive(c.params, c.initial.v0[4], c.run.omega_lim);
  std::printf("case %s (%s): valid\n", c.name.c_str(), c.source.c_str());
  std::printf("  l = L - delta      %12.6g m\n", d.l);
  std::printf("  nu = d / l         %12.6g\n", d.nu);
  std::printf("  M11, M12, M22      %12.6g %12.6g %12.6g kg\n", d.M11, d.M12, d.M22);
  std::printf("  H = Jp / l^2       %12.6g kg\n", d.H);
  std::printf("static equilibrium under gravity, at rest:\n");
  std::printf("  bearing  y_b       %12.6g m\n", d.y_b);
  if (d.rests_on_stator) {
    std::printf("  the rotor rests on the stator (it pivots freely about the bearing):\n");
    std::printf("  contact  F_N       %12.6g N  (nu m g)\n", d.F_N);
    std::printf("  stator   y_s       %12.6g m\n", d.y_s);
    std::printf("  rotor    y_r       %12.6g m  (y_s - g0)\n", d.y_r);
  } else {
    std::printf("  no gravity: the rotor stays centred, no contact\n");
  }
  std::printf("natural frequencies at rest:\n");
  std::printf("  coupled system     f1 %10.4f Hz, f2 %10.4f Hz (double modes)\n", d.f1, d.f2);
  std::printf("  stator alone       %10.4f Hz\n", d.f_stator);
  std::printf("  rotor on bearing   %10.4f Hz (and a 0 Hz pivot mode)\n", d.f_bearing_rotor);
  std::printf("spin: omega0 = %.6g rad/s (%.6g rpm), omega_lim = %.6g rad/s (%.6g rpm)\n",
              c.initial.v0[4], c.initial.v0[4] * 30 / std::numbers::pi, c.run.omega_lim,
              c.run.omega_lim * 30 / std::numbers::pi);
  if (std::isinf(d.t_free_to_omega_lim)) {
    std::printf("  free acceleration never reaches omega_lim (tau_a <= 0)\n");
  } else if (d.t_free_to_omega_lim == 0.0) {
    std::printf("  omega0 is already at or above omega_lim\n");
  } else {
    std::printf("  free acceleration to omega_lim: %.6g s ((omega_lim - omega0) Jp / tau_a)\n",
                d.t_free_to_omega_lim);
  }
  return 0;
}

}  // namespace

void add_check_command(CLI::App& app, Action& action) {
  auto a = std::make_shared<CheckArgs>();
  auto* sub = app.add_subcommand("check", "Validate a case and print derived quantities");
  sub->add_option("case", a->case_path, "Case file (TOML)")->required();
  sub->add_option("--set", a->sets, "override a case key: section.key=value (repeatable)");
  sub->callback([a, &action] { action = [a] { return check_command(*a); }; });
}

}  // namespace rubdyn::app
