#include "rubdyn/core/run_envelope.hpp"

#include <fmt/format.h>

#include <numeric>

namespace rubdyn {

RunEnvelope::RunEnvelope(const RunControls& c, OutputSink& sink, double t_start, double t_end,
                         double energy_initial, double mu, std::string solver, std::string options,
                         long first_output)
    : c_(c),
      sink_(sink),
      mon_(mu, c.omega_lim),
      wall0_(std::chrono::steady_clock::now()),
      t0_(t_start),
      next_out_(t_start + static_cast<double>(first_output) * c.output_dt),
      k_out_(first_output) {
  sum_.solver = std::move(solver);
  sum_.options = std::move(options);
  sum_.t_start = t_start;
  sum_.t_end_requested = t_end;
  sum_.t_reached = t_start;
  sum_.energy_initial = energy_initial;
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
  sum_.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  sink_.end(sum_);
  return sum_;
}

}  // namespace rubdyn
