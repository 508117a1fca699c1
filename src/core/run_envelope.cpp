#include "rubdyn/core/run_envelope.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

namespace rubdyn {

RunEnvelope::RunEnvelope(const RunControls& c, OutputSink& sink, double t_start, double t_end,
                         double energy_initial, double mu, std::string solver, std::string options,
                         long first_output)
    : c_(c),
      sink_(sink),
      mon_(mu, c.omega_lim),
      wall0_(std::chrono::steady_clock::now()),
      t0_(t_start),
      t_end_(t_end),
      next_out_(t_start + static_cast<double>(first_output) * c.output_dt),
      k_out_(first_output) {
  sum_.solver = std::move(solver);
  sum_.options = std::move(options);
  sum_.t_start = t_start;
  sum_.t_end_requested = t_end;
  sum_.t_reached = t_start;
  sum_.energy_initial = energy_initial;
  check_t_ = t_start;
}

double default_wall_budget(double simulated_seconds, double fixed_steps) {
  const double expected = fixed_steps > 0.0 ? 2e-6 * fixed_steps : 10.0 * simulated_seconds;
  return std::max(60.0, 10.0 * expected);
}

long RunEnvelope::event_count() const {
  return std::accumulate(sum_.events.begin(), sum_.events.end(), 0L);
}

bool RunEnvelope::interrupt(double t) {
  fail(Termination::Interrupted, fmt::format("interrupted at t = {:.17g}", t));
  return true;
}

bool RunEnvelope::budget_spent(double t) {
  if (!(c_.max_wall > 0.0)) return false;
  const double spent =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  if (!(spent > c_.max_wall)) return false;
  fail(Termination::TimeBudget,
       fmt::format("wall-time budget of {} s spent ({:.3g} s) at t = {:.17g}", c_.max_wall, spent,
                   t));
  return true;
}

bool RunEnvelope::check_rate(double t, long steps) {
  const double dt = t - check_t_;
  const long dn = steps - check_steps_;
  check_t_ = t;
  check_steps_ = steps;
  if (budget_spent(t)) return true;
  const double remaining = t_end_ - t;
  if (!(remaining > 0.0)) return false;
  const double h_mean = dt / static_cast<double>(dn);
  const double need = static_cast<double>(steps) + remaining / h_mean;  // dt <= 0: inf
  std::string why;
  if (static_cast<double>(steps) >= kMaxRunSteps) {
    why = fmt::format("the run has taken {} steps, the most a run may take", steps);
  } else if (need <= kMaxRunSteps) {
    over_windows_ = 0;  // within the bound: whatever came before was a burst
    return false;
  } else {
    // over the bound: a collapse only if the step is below round-off, or has fallen by
    // kCollapseFall over the last kCollapseWindows windows, all over the bound
    const double oldest = over_h_[static_cast<std::size_t>(over_windows_ % kCollapseWindows)];
    over_h_[static_cast<std::size_t>(over_windows_ % kCollapseWindows)] = h_mean;
    ++over_windows_;
    // (not h_mean > ...: a window that did not advance, dt <= 0, is below round-off too)
    const double t_scale = std::max(std::abs(t), std::abs(t_end_));
    if (!(h_mean > kRoundoffSteps * std::numeric_limits<double>::epsilon() * t_scale)) {
      why = fmt::format("its mean step is below {:.0f} ulps of the run's time {:.3g} s",
                        kRoundoffSteps, t_scale);
    } else if (over_windows_ > kCollapseWindows && h_mean * kCollapseFall <= oldest) {
      why = fmt::format("the mean step fell from {:.3g} s over the last {} windows of {} steps",
                        oldest, kCollapseWindows, kCheckSteps);
    } else {
      return false;  // small steps, not (yet) a collapse: the onset of rolling, an impact
    }
  }
  fail(Termination::StepCollapse,
       fmt::format("the step size collapsed at t = {:.17g}: {} steps advanced {:.3g} s (mean "
                   "step {:.3g} s), so the {:.3g} s left would take {:.3g} steps, above the limit "
                   "of {:.3g}, and {}; likely a stiff or degenerate parameter (a tiny inertia, a "
                   "huge stiffness, load, length or speed)",
                   t, dn, dt, h_mean, remaining, need, kMaxRunSteps, why));
  return true;
}

bool RunEnvelope::speed_failure(double t, double v_N, double v_t) {
  if (!std::isfinite(v_N) || !std::isfinite(v_t)) return true;  // finite_sample's to report
  fail(Termination::Implausible,
       fmt::format("the contact speed reached {:.3g} m/s (v_N = {:.3g}, v_t = {:.3g} m/s) at t = "
                   "{:.17g}, above {:.3g} m/s: no solid is rigid at that speed; likely a "
                   "degenerate parameter (a torque, speed or length many orders off the others)",
                   std::max(std::abs(v_N), std::abs(v_t)), v_N, v_t, t, kMaxContactSpeed));
  return false;
}

bool RunEnvelope::finite_sample(const Sample& s) {
  const char* bad = nullptr;
  if (!std::isfinite(s.t) || !all_finite(s.q) || !all_finite(s.v)) bad = "state";
  for (const ContactSample& k : s.contacts) {
    if (bad) break;
    if (!std::isfinite(k.d_N))
      bad = "d_N";
    else if (!std::isfinite(k.v_N))
      bad = "v_N";
    else if (!std::isfinite(k.v_t))
      bad = "v_t";
    else if (!std::isfinite(k.F_N))
      bad = "F_N";
    else if (!std::isfinite(k.F_T))
      bad = "F_T";
  }
  if (!bad && !all_finite(s.observables)) bad = "observable";
  if (!bad) return true;
  fail(Termination::NonFinite,
       fmt::format("non-finite {} at t = {:.17g} (not written): an input far outside the "
                   "model's range (a speed, length or load whose products overflow)",
                   bad, s.t));
  return false;
}

void RunEnvelope::check_plausible() {
  if (!sum_.complete()) return;  // the first reason stands
  const std::pair<const char*, double> numbers[] = {
      {"t_reached", sum_.t_reached},
      {"energy_initial", sum_.energy_initial},
      {"energy_final", sum_.energy_final},
      {"work_torque", sum_.work_torque},
      {"work_damping", sum_.work_damping},
      {"work_friction", sum_.work_friction},
      {"work_impacts", sum_.work_impacts},
      {"energy_residual", sum_.energy_residual},
      {"omega_max", sum_.omega_max},
      {"omega_final", sum_.omega_final},
      {"max_penetration", sum_.max_penetration},
      {"max_cone_violation", sum_.max_cone_violation},
      {"max_drift_position", sum_.max_drift_position},
      {"max_drift_velocity", sum_.max_drift_velocity},
      // NaN means "none" for these two; an infinity is an overflow
      {"t_omega_lim", std::isnan(sum_.t_omega_lim) ? 0.0 : sum_.t_omega_lim},
      {"min_F_N_in_contact", std::isnan(sum_.min_F_N_in_contact) ? 0.0 : sum_.min_F_N_in_contact},
  };
  for (const auto& [name, x] : numbers) {
    if (std::isfinite(x)) continue;
    fail(Termination::NonFinite,
         fmt::format("the summary's {} is not finite ({}): an input far outside the model's "
                     "range (a speed, inertia, damping or load whose products overflow)",
                     name, x));
    return;
  }
  if (sum_.max_penetration > plaus_.max_penetration) {
    fail(Termination::Implausible,
         fmt::format("the penetration reached {:.3g} m, above this solver's bound of {:.3g} m "
                     "(round-off of the gap): the contact was not resolved; likely a degenerate "
                     "parameter (a length or stiffness many orders off the others)",
                     sum_.max_penetration, plaus_.max_penetration));
    return;
  }
  const double flow = std::max({std::abs(sum_.energy_initial), std::abs(sum_.energy_final),
                                std::abs(sum_.work_torque), std::abs(sum_.work_damping),
                                std::abs(sum_.work_friction), std::abs(sum_.work_impacts)});
  if (std::abs(sum_.energy_residual) >
      std::max(plaus_.energy_residual_rel * flow, plaus_.energy_residual_abs)) {
    fail(Termination::Implausible,
         fmt::format("the energy balance does not close: residual {:.3g} J against a largest "
                     "flow of {:.3g} J (bound: {} of it); likely a degenerate parameter (a "
                     "damping, stiffness or load many orders off the others) or a step too "
                     "large for the scheme",
                     sum_.energy_residual, flow, plaus_.energy_residual_rel));
  }
}

void RunEnvelope::fail(Termination why, const std::string& message) {
  if (!sum_.complete()) return;  // the first reason stands
  sum_.termination = why;
  sum_.message = message;
}

RunSummary RunEnvelope::finish(double t_reached, double energy_final, const RunWorks& w) {
  sum_.t_reached = t_reached;
  sum_.energy_final = energy_final;
  sum_.work_torque = w.torque;
  sum_.work_damping = w.damping;
  sum_.work_friction = w.friction;
  sum_.work_impacts = w.impacts;
  sum_.close_energy_balance();
  mon_.fill(sum_);
  check_plausible();
  sum_.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  sink_.end(sum_);
  return sum_;
}

}  // namespace rubdyn
