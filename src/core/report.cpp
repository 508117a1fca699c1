#include "rubdyn/core/report.hpp"

#include <fmt/format.h>

#include <cmath>

namespace rubdyn {

std::string brief_report(const RunSummary& s) {
  std::string r;
  auto line = [&r](const std::string& l) { r += l + "\n"; };
  line(fmt::format("solver        {}  {}", s.solver, s.options));
  if (!s.model.empty()) line("model         " + s.model);
  line(fmt::format("termination   {}{}", to_string(s.termination),
                   s.message.empty() ? "" : ": " + s.message));
  line(fmt::format("time          {:.9g} s of {:.9g} s simulated in {:.4g} s wall", s.t_reached,
                   s.t_end_requested, s.wall_seconds));
  line(fmt::format("work          {} steps, {} rhs, {} jac, {} root evals, {} newton iters",
                   s.steps, s.rhs_evals, s.jac_evals, s.root_evals, s.newton_iters));
  if (s.err_test_fails + s.conv_fails > 0)
    line(fmt::format("rejected      {} steps (error test), {} steps (no convergence)",
                     s.err_test_fails, s.conv_fails));
  std::string ev;
  for (int k = 0; k < kNumEventKinds; ++k)
    if (s.events[k] > 0)
      ev += fmt::format("{} {}, ", to_string(static_cast<EventKind>(k)), s.events[k]);
  if (ev.empty()) ev = "none  ";
  line("events        " + ev.substr(0, ev.size() - 2));
  const double span = s.t_reached - s.t_start;
  std::string ph;
  for (int k = 0; k < kNumPhases; ++k)
    ph += fmt::format("{} {:.4g}%, ", to_string(static_cast<Phase>(k)),
                      span > 0 ? 100.0 * s.phase_time[k] / span : 0.0);
  line("phases        " + ph.substr(0, ph.size() - 2));
  std::string cost;
  for (int k = 0; k < kNumPhases; ++k)
    if (s.phase_steps[k] > 0)
      cost += fmt::format("{} {:.3g} us ({} steps), ", to_string(static_cast<Phase>(k)),
                          1e6 * s.phase_wall[k] / static_cast<double>(s.phase_steps[k]),
                          s.phase_steps[k]);
  if (!cost.empty()) line("cost/step     " + cost.substr(0, cost.size() - 2));
  line(fmt::format("omega         max {:.10g} rad/s, final {:.10g} rad/s, omega_lim crossed {}",
                   s.omega_max, s.omega_final,
                   std::isnan(s.t_omega_lim) ? std::string("never")
                                             : fmt::format("at {:.9g} s", s.t_omega_lim)));
  line(
      fmt::format("invariants    penetration {:.3g} m, min F_N {:.3g} N, cone excess {:.3g}, "
                  "drift {:.3g} m / {:.3g} m/s",
                  s.max_penetration, s.min_F_N_in_contact, s.max_cone_violation,
                  s.max_drift_position, s.max_drift_velocity));
  line(
      fmt::format("energy        dE {:.9g} J = torque {:.9g} + dampers {:.6g} + friction {:.6g} "
                  "+ impacts {:.6g} + residual {:.3g} J",
                  s.energy_final - s.energy_initial, s.work_torque, s.work_damping, s.work_friction,
                  s.work_impacts, s.energy_residual));
  return r;
}

}  // namespace rubdyn
