#pragma once
// RunMonitor: the physics invariants and spin statistics every solver reports in summary.json,
// computed the same way for all solvers. Solvers call observe() at every step end (or event and
// output sample) and fill() once at the end; the energy balance is integrated by each solver
// (it needs its own quadrature) and written into RunSummary directly.
#include <algorithm>
#include <cmath>
#include <limits>

#include "rubdyn/core/run_types.hpp"

namespace rubdyn {

class RunMonitor {
 public:
  RunMonitor(double mu, double omega_lim) : mu_(mu), omega_lim_(omega_lim) {}

  /// One observation of the state at time t. `in_contact` marks a closed contact (persistent
  /// contact phase for event-driven solvers, an active contact for fixed-step ones); d_N and
  /// v_N then measure the constraint drift.
  void observe(double t, double omega, double d_N, double v_N, double F_N, double F_T,
               bool in_contact) {
    if (!std::isfinite(omega) || !std::isfinite(d_N)) return;
    max_pen_ = std::max(max_pen_, -d_N);
    observe_spin(t, omega);
    observe_contact_forces(d_N, v_N, F_N, F_T, in_contact, mu_);
  }

  /// The same for a model with several contacts: the spin once per state (observe_spin), then
  /// each contact with its own friction coefficient (observe_contact); the invariants are the
  /// worst over the contacts.
  void observe_spin(double t, double omega) {
    if (!std::isfinite(omega)) return;
    if (first_) {
      omega_max_ = omega;
      if (omega >= omega_lim_) t_lim_ = t;
      first_ = false;
    } else if (std::isnan(t_lim_) && omega >= omega_lim_ && omega_prev_ < omega_lim_) {
      // linear interpolation between observations; event-driven solvers refine it from dense output
      t_lim_ = t_prev_ + (t - t_prev_) * (omega_lim_ - omega_prev_) / (omega - omega_prev_);
    }
    omega_max_ = std::max(omega_max_, omega);
    omega_final_ = omega;
    t_prev_ = t;
    omega_prev_ = omega;
  }
  void observe_contact(double d_N, double v_N, double F_N, double F_T, bool in_contact, double mu) {
    if (!std::isfinite(d_N)) return;
    max_pen_ = std::max(max_pen_, -d_N);
    observe_contact_forces(d_N, v_N, F_N, F_T, in_contact, mu);
  }

 private:
  void observe_contact_forces(double d_N, double v_N, double F_N, double F_T, bool in_contact,
                              double mu) {
    if (in_contact) {
      min_FN_ = std::isnan(min_FN_) ? F_N : std::min(min_FN_, F_N);
      // Cone violation relative to the largest contact force of the run so far: at a lift-off
      // or a stick-to-slip switch F_N and F_T are both ~0 and a ratio to mu F_N is meaningless.
      F_scale_ = std::max({F_scale_, std::abs(F_N), std::abs(F_T)});
      const double excess = std::abs(F_T) - mu * std::max(F_N, 0.0);
      if (excess > 0.0 && F_scale_ > 0.0) max_cone_ = std::max(max_cone_, excess / F_scale_);
      max_drift_q_ = std::max(max_drift_q_, std::abs(d_N));
      max_drift_v_ = std::max(max_drift_v_, std::abs(v_N));
    }
  }

 public:
  /// Sets t_omega_lim directly (when a solver locates the crossing more accurately).
  void set_omega_lim_time(double t) { t_lim_ = t; }
  bool omega_lim_crossed() const { return !std::isnan(t_lim_); }

  void fill(RunSummary& s) const {
    s.max_penetration = std::max(max_pen_, 0.0);
    s.min_F_N_in_contact = min_FN_;
    s.max_cone_violation = max_cone_;
    s.max_drift_position = max_drift_q_;
    s.max_drift_velocity = max_drift_v_;
    s.omega_max = omega_max_;
    s.omega_final = omega_final_;
    s.t_omega_lim = t_lim_;
  }

 private:
  double mu_, omega_lim_;
  bool first_ = true;
  double F_scale_ = 0.0;
  double max_pen_ = 0.0, max_cone_ = 0.0, max_drift_q_ = 0.0, max_drift_v_ = 0.0;
  double min_FN_ = std::numeric_limits<double>::quiet_NaN();
  double omega_max_ = 0.0, omega_final_ = 0.0, t_prev_ = 0.0, omega_prev_ = 0.0;
  double t_lim_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace rubdyn
