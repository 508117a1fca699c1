// rubdyn check CASE: validate a case and print its derived quantities (analysis/derived.hpp).
#include <fmt/format.h>

#include <memory>
#include <numbers>
#include <string>

#include "cli_common.hpp"
#include "commands.hpp"
#include "rubdyn/analysis/derived.hpp"
#include "rubdyn/io/case_io.hpp"

namespace rubdyn::app {

namespace {

void row(const std::string& label, double value, const std::string& unit) {
  fmt::print("  {:<36}{:>14.6g} {}\n", label, value, unit);
}

int check_command(const CaseArgs& a) {
  const CaseSpec c = load_case(a.path, a.sets);  // throws CaseError: exit 2
  const double omega0 = c.initial.v0[TH], omega_lim = c.run.omega_lim;
  const DerivedQuantities d = compute_derived_quantities(c.params, omega0, omega_lim);
  const double rpm = 30.0 / std::numbers::pi;

  fmt::print("case {} ({}): valid\n", c.name, c.source);
  fmt::print("geometry and inertia (paper eq. 9-11)\n");
  row("l = L - delta", d.l, "m");
  row("nu = d / l", d.nu, "-");
  row("M11 = (1-nu)^2 m + Jd/l^2", d.M11, "kg");
  row("M12 = nu (1-nu) m - Jd/l^2", d.M12, "kg");
  row("M22 = nu^2 m + Jd/l^2", d.M22, "kg");
  row("H = Jp / l^2", d.H, "kg");
  fmt::print("static equilibrium under gravity, rotor at rest\n");
  if (d.rests_on_stator) {
    fmt::print(
        "  the rotor pivots about its bearing and rests on the stator (bottom of the gap)\n");
    row("contact force F_N = nu m g", d.F_N, "N");
    row("bearing y_b = -(1-nu) m g / k_b", d.y_b, "m");
    row("stator  y_s = -F_N / k_s", d.y_s, "m");
    row("rotor   y_r = y_s - g0", d.y_r, "m");
  } else {
    fmt::print("  no gravity: the rotor stays centred, no contact (F_N = 0)\n");
  }
  fmt::print("natural frequencies at rest\n");
  row("coupled rotor + stator, f1 (double)", d.f1, "Hz");
  row("coupled rotor + stator, f2 (double)", d.f2, "Hz");
  row("stator alone, sqrt(k_s/m_s) / 2pi", d.f_stator, "Hz");
  row("rotor on its bearing, no stator", d.f_bearing_rotor, "Hz (and 0 Hz: free pivot)");
  fmt::print("spin speed\n");
  row("omega0", omega0, fmt::format("rad/s = {:.6g} rpm", omega0 * rpm));
  row("omega_lim", omega_lim, fmt::format("rad/s = {:.6g} rpm", omega_lim * rpm));
  switch (d.free_acceleration) {
    case FreeAcceleration::reaches:
      row("free acceleration to omega_lim", d.t_free_to_omega_lim,
          "s = (omega_lim - omega0) Jp / tau_a");
      break;
    case FreeAcceleration::already_reached:
      fmt::print("  free acceleration: omega0 >= omega_lim, already reached (0 s)\n");
      break;
    case FreeAcceleration::never:
      fmt::print("  free acceleration: never reaches omega_lim (tau_a <= 0)\n");
      break;
  }
  return 0;
}

}  // namespace

void add_check_command(CLI::App& app, Action& action) {
  auto a = std::make_shared<CaseArgs>();
  auto* sub = app.add_subcommand(
      "check", "Validate a case and print its derived quantities (inertia, statics, frequencies)");
  add_case_options(*sub, *a);
  sub->callback([a, &action] { action = [a] { return check_command(*a); }; });
}

}  // namespace rubdyn::app
