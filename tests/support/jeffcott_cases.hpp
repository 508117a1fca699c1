#pragma once
// Jeffcott-rotor cases written in code for the tests (the model registry builds them as it does
// a case file): a disc of 5 kg on a shaft of 5e6 N/m and 300 N s/m, seal radius 0.05 m, spin
// inertia 0.06 kg m^2, clearance 2e-4 m, mu = 0.3, no gravity.
#include <fmt/format.h>

#include <string>

namespace rubdyn::testing {

/// The case text with the given [stator] keys (besides the gap), [loads] keys (besides gravity),
/// [initial] keys and any further sections.
inline std::string jeffcott_case(const std::string& stator, const std::string& loads,
                                 const std::string& initial, const std::string& more = "") {
  return "name = \"jeffcott-test\"\n[model]\nkind = \"jeffcott\"\n"
         "[rotor]\nmass = 5.0\nk = 5.0e6\nc = 300.0\nradius = 0.05\nJp = 0.06\n"
         "[stator]\n" +
         stator + "gap = 2.0e-4\n[contact]\nmu = 0.3\n[loads]\ngravity = 0.0\n" + loads +
         "[initial]\n" + initial + "[run]\nt_end = 1.0\nomega_lim = 2000.0\n" + more;
}

/// Steady rolling on a rigid ring driven by 2000 N m: the spin tau / (c_r R^2) = 2666.67 rad/s
/// (the power balance of rolling, docs/closed-forms.md), the disc started on that orbit (on the
/// ring at +X, its centre moving at -R Omega along Y: no slip).
struct SteadyRoll {
  static constexpr double tau = 2000.0, c = 300.0, R = 0.05, g0 = 2.0e-4;
  static constexpr double omega = tau / (c * R * R);
  static std::string text(const std::string& more = "") {
    return jeffcott_case("rigid = true\n", fmt::format("torque = {}\n", tau),
                         fmt::format("x_r = {}\nvy_r = {}\nomega0 = {}\n", g0, -R * omega, omega),
                         more);
  }
};

}  // namespace rubdyn::testing
