#include "rubdyn/hybrid/event_driven.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>

#include "cvode_session.hpp"
#include "rubdyn/core/run_monitor.hpp"
#include "rubdyn/hybrid/contact_problem.hpp"

namespace rubdyn {

namespace {

constexpr int kN = 2 * kNumDofs;  // full state y = (q, v)
// The works of the applied loads, the dampers and friction are integrated with the state, as
// its last kNw components (error-controlled like the rest). Carried in the state they ride on
// the integrator's vector operations; as CVODES quadratures they cost a second Nordsieck array
// (measured: 30 % of the run time in the rolling regime).
constexpr int kNw = 3;
constexpr int kNy = kN + kNw;  // largest session state
using SessionState = std::array<double, kNy>;

// Witness identifiers (what fired), in the order they are built for each phase.
enum class Witness { Gap, GapRate, NormalForce, SlipSpeed, ConeUpper, ConeLower, Omega };

const char* witness_name(Witness w) {
  switch (w) {
    case Witness::Gap: return "d_N";
    case Witness::GapRate: return "v_N";
    case Witness::NormalForce: return "F_N";
    case Witness::SlipSpeed: return "v_t";
    case Witness::ConeUpper: return "mu*F_N-F_T";
    case Witness::ConeLower: return "mu*F_N+F_T";
    case Witness::Omega: return "omega-omega_lim";
  }
  return "?";
}

class Integrator {
 public:
  Integrator(const LagrangianModel& m, const EventDrivenOptions& opt, OutputSink& sink)
      : m_(m), opt_(opt), sink_(sink), law_(m.contact_law()), mon_(law_.mu, opt.omega_lim) {
    g0_ = m.gap_scale();
    atol_q_ = opt.atol;
    atol_v_ = opt.atol * 1e3;
    v_tol_ = 10.0 * atol_v_;
    // positions are resolved to about atol + rtol |q| with |q| ~ the gap scale near contact
    graze_tol_ = 10.0 * (atol_q_ + opt.rtol * g0_);
    // A gap minimum within this band of 0 is logged as grazing (and decided by the contact
    // problem). The band is wider than the local tolerance because the global error of the
    // orbit is (measured: 1e-8 on a unit amplitude at rtol 1e-10); logging a near-miss changes
    // nothing in the motion, since at a minimum of free flight d_N'' >= 0.
    graze_band_ = std::max(graze_tol_, 1e-6 * g0_);
    v_ref_ = std::max(1e3 * g0_, 1e-300);
    omega_pending_ = opt.omega_lim > 0.0;
    if (opt.contact_phases == ContactFormulation::Reduced) chart_ = m.contact_chart();
  }

  RunSummary run(const MechanicalState& init, double t_end);

 private:
  // ---- callbacks (user = this) ----
  static int rhs(double t, const double* y, double* yd, void* u) {
    auto* self = static_cast<Integrator*>(u);
    return self->eval_rhs(t, y, yd);
  }
  static int jac(double t, const double* y, const double*, double* J, void* u) {
    return static_cast<Integrator*>(u)->eval_jac(t, y, J);
  }
  static int roots(double t, const double* y, double* g, void* u) {
    return static_cast<Integrator*>(u)->eval_roots(t, y, g);
  }
  static int proj(double t, const double* y, double* corr, void* u) {
    return static_cast<Integrator*>(u)->eval_proj(t, y, corr);
  }

  static void split(const double* y, Vec7& q, Vec7& v) {
    q = Eigen::Map<const Vec7>(y);
    v = Eigen::Map<const Vec7>(y + kNumDofs);
  }

  int eval_rhs(double t, const double* y, double* yd) {
    Vec7 q, v;
    if (reduced_phase()) {
      // Minimal coordinates: the constrained acceleration of the full model at the embedded
      // state, reduced to p'' (contact_chart.hpp); the constraints hold by construction.
      Vec7 p, pd, pdd;
      unpack(y, p, pd);
      chart_->embed(mode_, anchor_, p, pd, q, v);
      ContactOperators op;
      compute_contact_operators(m_, t, q, v, op);
      const PhaseDynamics d = phase_dynamics(op, phase_, law_.mu);
      if (!d.well_posed) return 1;  // recoverable: CVODE retries with a smaller step
      chart_->reduce(mode_, anchor_, p, pd, q, d.a, pdd);
      for (int i = 0; i < dim_; ++i) {
        yd[i] = pd[i];
        yd[dim_ + i] = pdd[i];
      }
      powers(t, q, v, d.F_T * op.c.v_t, yd + n_);
      return pdd.allFinite() ? 0 : 1;
    }
    split(y, q, v);
    Vec7 a;
    double friction_power = 0.0;
    if (phase_ == Phase::Free) {
      // Free flight needs only M and f: no contact quantities are built here.
      Mat7x3 B;
      Vec7 f;
      m_.smooth_forces(t, q, v, f);
      B.col(0) = f;
      m_.solve_mass(q, B, 1);
      a = B.col(0);
    } else {
      ContactOperators op;
      compute_contact_operators(m_, t, q, v, op);
      const PhaseDynamics d = phase_dynamics(op, phase_, law_.mu);
      if (!d.well_posed) return 1;  // recoverable: CVODE retries with a smaller step
      a = d.a;
      friction_power = d.F_T * op.c.v_t;
    }
    Eigen::Map<Vec7> yd_q(yd), yd_v(yd + kNumDofs);
    yd_q = v;
    yd_v = a;
    powers(t, q, v, friction_power, yd + kN);
    return a.allFinite() ? 0 : 1;
  }

  /// Rates of the works carried in the state: applied loads, dampers, friction.
  void powers(double t, const Vec7& q, const Vec7& v, double friction, double* w) const {
    const SmoothPower p = m_.smooth_power(t, q, v);
    w[0] = p.external;
    w[1] = p.damping;
    w[2] = friction;
  }

  // Analytic Jacobian of free flight: d/dq (M^{-1} f) = M^{-1} (df/dq - d(M a)/dq), with a fixed.
  int eval_jac(double t, const double* y, double* J) {
    Vec7 q, v;
    split(y, q, v);
    Mat7 M, dfdq, dfdv, dMa;
    Vec7 f;
    m_.mass_matrix(q, M);
    m_.smooth_forces(t, q, v, f);
    m_.smooth_force_jacobians(t, q, v, dfdq, dfdv);
    const Eigen::LDLT<Mat7> ldlt(M);
    const Vec7 a = ldlt.solve(f);
    m_.mass_matrix_product_jacobian(q, a, dMa);
    const Mat7 daq = ldlt.solve(dfdq - dMa);
    const Mat7 dav = ldlt.solve(dfdv);
    // column-major kNy x kNy, as SUNDIALS' dense matrix; the rows of the works are left 0 (they
    // feed back into nothing, so Newton converges on them with the state)
    Eigen::Map<Eigen::Matrix<double, kNy, kNy>> Jm(J);
    Jm.setZero();
    Jm.topRightCorner<kNumDofs, kNumDofs>().setIdentity();
    Jm.bottomLeftCorner<kNumDofs, kNumDofs>() = daq;
    Jm.bottomRightCorner<kNumDofs, kNumDofs>() = dav;
    return 0;
  }

  // ---- formulations ----
  /// True while a contact phase is integrated in the chart's minimal coordinates.
  bool reduced_phase() const { return chart_ != nullptr && phase_ != Phase::Free; }
  /// Reduced coordinates p and rates p' of a session state (first dim_ entries).
  void unpack(const double* y, Vec7& p, Vec7& pd) const {
    p.setZero();
    pd.setZero();
    for (int i = 0; i < dim_; ++i) {
      p[i] = y[i];
      pd[i] = y[dim_ + i];
    }
  }
  /// The full state of a session state of the current phase.
  void to_full(const double* y, Vec7& q, Vec7& v) const {
    if (!reduced_phase()) {
      split(y, q, v);
      return;
    }
    Vec7 p, pd;
    unpack(y, p, pd);
    chart_->embed(mode_, anchor_, p, pd, q, v);
  }
  /// The full state interpolated at t inside the last step of the current session.
  void interp(double t, Vec14& y) const {
    SessionState ys{};
    cur_->dky(t, 0, ys.data());
    Vec7 q, v;
    to_full(ys.data(), q, v);
    y << q, v;
  }
  /// Contact operators of a contact phase at (q, v): the DAE formulation first projects the
  /// state onto the constraints (its interpolant between step ends is not projected); the
  /// reduced one is on them by construction.
  void contact_point(double t, Vec7& q, Vec7& v, ContactOperators& op) const {
    if (chart_ != nullptr)
      compute_contact_operators(m_, t, q, v, op);
    else
      project_state(t, q, v, op);
  }

  /// Projects a state of a contact phase onto the constraints (positions onto d_N = 0,
  /// velocities mass-weighted onto v_N = 0, and v_t = 0 in stick) and returns the contact
  /// operators at the projected state: one LDLT.
  void project_state(double t, Vec7& q, Vec7& v, ContactOperators& op) const {
    project_position(q, v);
    compute_contact_operators(m_, t, q, v, op);
    project_velocity(op, phase_ == Phase::Stick ? 2 : 1, v);
    update_contact_velocity(m_, t, q, v, op);
  }

  int eval_roots(double t, const double* y, double* g) {
    Vec7 q, v;
    to_full(y, q, v);
    // Witnesses of a contact phase are functions on the constraint manifold.
    ContactOperators op;
    PhaseDynamics dyn;
    if (phase_ != Phase::Free) {
      contact_point(t, q, v, op);
      dyn = phase_dynamics(op, phase_, law_.mu);
    }
    int k = 0;
    for (Witness w : witnesses_) {
      switch (w) {
        case Witness::Gap: {
          const ContactKinematics c = m_.contact(q, v);
          g[k] = c.d_N / g0_;
          break;
        }
        case Witness::GapRate: {
          const ContactKinematics c = m_.contact(q, v);
          g[k] = c.v_N / v_ref_;
          break;
        }
        case Witness::NormalForce: g[k] = dyn.F_N / F_ref_; break;
        case Witness::ConeUpper: g[k] = (law_.mu * dyn.F_N - dyn.F_T) / F_ref_; break;
        case Witness::ConeLower: g[k] = (law_.mu * dyn.F_N + dyn.F_T) / F_ref_; break;
        case Witness::SlipSpeed: g[k] = op.c.v_t / v_ref_; break;
        case Witness::Omega: g[k] = (v[TH] - opt_.omega_lim) / opt_.omega_lim; break;
      }
      ++k;
    }
    return 0;
  }

  // Projection onto the contact constraints (contact phases only): positions onto d_N = 0 by a
  // mass-weighted Newton step, velocities onto v_N = 0 (and v_t = 0 in stick), mass-weighted.
  int eval_proj(double t, const double* y, double* corr) {
    Vec7 q, v;
    split(y, q, v);
    const Vec7 q0 = q, v0 = v;
    ContactOperators op;
    project_state(t, q, v, op);
    Eigen::Map<Vec7> corr_q(corr), corr_v(corr + kNumDofs);
    corr_q = q - q0;
    corr_v = v - v0;
    std::fill(corr + kN, corr + kNy, 0.0);
    return q.allFinite() && v.allFinite() ? 0 : -1;
  }

  // ---- helpers ----
  void state_from(const Vec14& y, Vec7& q, Vec7& v) const { split(y.data(), q, v); }

  /// Contact forces of the current phase at (t, q, v).
  void forces(double t, const Vec7& q, const Vec7& v, double& FN, double& FT) const {
    FN = FT = 0.0;
    if (phase_ == Phase::Free) return;
    ContactOperators op;
    Vec7 qc = q, vc = v;
    contact_point(t, qc, vc, op);
    const PhaseDynamics d = phase_dynamics(op, phase_, law_.mu);
    FN = d.F_N;
    FT = d.F_T;
  }

  void emit_sample(double t, const Vec14& y) {
    Sample s;
    s.t = t;
    state_from(y, s.q, s.v);
    // Dense output inside a contact phase of the DAE formulation is CVODE's interpolant, which
    // is not projected: project it like a step end, so that every output state satisfies the
    // constraints (contact_point).
    if (phase_ != Phase::Free) {
      ContactOperators op;
      contact_point(t, s.q, s.v, op);
      const PhaseDynamics d = phase_dynamics(op, phase_, law_.mu);
      s.F_N = d.F_N;
      s.F_T = d.F_T;
    }
    const ContactKinematics c = m_.contact(s.q, s.v);
    s.d_N = c.d_N;
    s.v_N = c.v_N;
    s.v_t = c.v_t;
    s.phase = phase_;
    mon_.observe(t, s.v[TH], s.d_N, s.v_N, s.F_N, s.F_T, phase_ != Phase::Free);
    sink_.sample(s);
  }

  void build_witnesses() {
    witnesses_.clear();
    dirs_.clear();
    auto add = [&](Witness w, int dir) {
      witnesses_.push_back(w);
      dirs_.push_back(dir);
    };
    switch (phase_) {
      case Phase::Free:
        add(Witness::Gap, -1);
        // After a release on the constraint (lift-off, v_N = 0 and F_N = 0, so d_N'' = 0 too)
        // the gap rate starts at a degenerate zero that round-off may cross back and forth:
        // the gap-minimum witness is armed after the first step (see the main loop).
        if (!gap_rate_deferred_) add(Witness::GapRate, +1);
        break;
      case Phase::SlipPos:
      case Phase::SlipNeg:
        add(Witness::NormalForce, -1);
        // mu = 0: no tangential witness (the slip direction is irrelevant without friction)
        if (law_.has_friction()) add(Witness::SlipSpeed, phase_ == Phase::SlipPos ? -1 : +1);
        break;
      case Phase::Stick:
        add(Witness::NormalForce, -1);
        add(Witness::ConeUpper, -1);
        add(Witness::ConeLower, -1);
        break;
    }
    if (omega_pending_) add(Witness::Omega, +1);
  }

  /// Starts (or restarts) integration of the current phase at (t, y).
  /// In minimal coordinates the state is mapped into the chart of the phase (and the restart
  /// state is its embedding, equal to y to round-off).
  void start_phase(double t, const Vec14& y) {
    phase_start_ = t;
    t_restart_ = t;
    y_restart_ = y;
    build_witnesses();
    SessionState& ys = ys_;
    std::copy(y.data(), y.data() + kN, ys.begin());
    detail::CvodeSession* s = phase_ == Phase::Free ? free_.get() : contact_.get();
    n_ = kN;
    if (reduced_phase()) {
      mode_ = phase_ == Phase::Stick ? ChartMode::Stick : ChartMode::Slip;
      dim_ = chart_->dim(mode_);
      n_ = 2 * dim_;
      Vec7 q, v, p, pd;
      state_from(y, q, v);
      chart_->chart(mode_, q, v, anchor_, p, pd);
      for (int i = 0; i < dim_; ++i) {
        ys[i] = p[i];
        ys[dim_ + i] = pd[i];
      }
      chart_->embed(mode_, anchor_, p, pd, q, v);
      y_restart_ << q, v;
      s = mode_ == ChartMode::Stick ? stick_.get() : slip_.get();
    }
    std::copy(work_.begin(), work_.end(), ys.begin() + n_);
    // F_ref_: the scale of the contact forces since the contact closed (witness scaling and
    // the decision band at contact witnesses); a phase that starts with a vanishing force,
    // e.g. slip at the instant stick ends with F_N -> 0, keeps the scale of the contact.
    if (phase_ == Phase::Free) {
      F_ref_ = 0.0;
    } else {
      Vec7 q, v;
      state_from(y_restart_, q, v);
      double FN = 0, FT = 0;
      forces(t, q, v, FN, FT);
      F_ref_ = std::max({F_ref_, std::abs(FN), 1e-6});
    }
    cur_ = s;
    s->restart(t, ys.data(), static_cast<int>(witnesses_.size()), dirs_.data(),
               phase_ != Phase::Free && !reduced_phase(), 0.0, t_end_);
  }

  /// Puts q on d_N = 0 by a step along W_N (Euclidean metric): q <- q - W_N d_N / |W_N|^2.
  /// For the circular clearance this moves the rotor and stator centres apart along the normal
  /// and is exact in one step; for any model it is a Newton step, repeated while it matters.
  void project_position(Vec7& q, const Vec7& v) const {
    for (int it = 0; it < 3; ++it) {
      const ContactKinematics c = m_.contact(q, v);
      // 1e-14 g0 is 100x below the drift bound we promise (1e-12 g0), 1e6x above round-off
      if (!c.normal_defined || std::abs(c.d_N) <= 1e-14 * g0_) return;
      q -= c.W_N * (c.d_N / c.W_N.squaredNorm());
    }
  }

  /// Writes the output times before t, interpolated in the last step, before an event at t
  /// restarts the integration there: the step that found a root may have passed output times
  /// before it, and polishing may move the event past an output time after the root; either
  /// would leave an output time behind the restarted integrator.
  void emit_outputs_before(double t) {
    while (next_out_ < t && next_out_ < t_end_) {
      Vec14 yo;
      interp(next_out_, yo);
      emit_sample(next_out_, yo);
      next_out_ = t_init_ + static_cast<double>(++k_out_) * opt_.output_dt;
    }
  }

  void end_phase(double t) { sum_.phase_time[static_cast<int>(phase_)] += t - phase_start_; }

  /// The works carried in a session state of the current phase.
  std::array<double, kNw> works_of(const SessionState& ys) const {
    std::array<double, kNw> w{};
    std::copy(ys.begin() + n_, ys.begin() + n_ + kNw, w.begin());
    return w;
  }
  /// Works at t inside the last step of the current session.
  void works_at(double t) {
    SessionState ys{};
    cur_->dky(t, 0, ys.data());
    work_ = works_of(ys);
  }

  void fail(Termination why, const std::string& msg) {
    sum_.termination = why;
    sum_.message = msg;
  }

  bool chattering(double t) {
    event_times_[n_events_ % event_times_.size()] = t;
    ++n_events_;
    if (n_events_ < static_cast<long>(event_times_.size())) return false;
    const double oldest = event_times_[n_events_ % event_times_.size()];
    const double window = static_cast<double>(event_times_.size()) / opt_.max_events_per_second;
    return t - oldest < window;
  }

  void log_event(EventRecord& e) {
    ++sum_.events[static_cast<int>(e.kind)];
    sink_.event(e);
  }

  // Event handlers return false when the run must end.
  bool on_gap_closing(double t, Vec14 y, bool missed_crossing);
  /// at_slip_zero: the event is the zero of v_t (slip ending): v_t is set to 0 exactly, whatever
  /// its value at the located time (with a huge tangential acceleration the time resolution of
  /// the root leaves |v_t| above the velocity tolerance).
  bool switch_on_constraint(double t, Vec14 y, EventRecord e, double rel_tol,
                            bool at_slip_zero = false, std::optional<Phase> ending = std::nullopt);
  bool on_contact_witness(double t_root, const Vec14& y_root, Witness w);
  /// Value of a contact-phase witness (unscaled) at an interpolated state.
  double witness_value(Witness w, double t, const Vec14& y) const;

  const LagrangianModel& m_;
  const EventDrivenOptions& opt_;
  OutputSink& sink_;
  const ContactLaw law_;
  RunMonitor mon_;
  RunSummary sum_;
  double g0_ = 1, atol_q_ = 0, atol_v_ = 0, v_tol_ = 0, graze_tol_ = 0, graze_band_ = 0, v_ref_ = 1,
         F_ref_ = 0;
  double t_end_ = 0, phase_start_ = 0, t_restart_ = 0;
  double t_init_ = 0, next_out_ = 0;  // output grid t_init_ + k output_dt, next time to write
  long k_out_ = 1;
  Vec14 y_restart_ = Vec14::Zero();
  bool omega_pending_ = false;
  bool gap_rate_deferred_ = false;
  bool root_without_restart_ = false;  // the last return was a root handled without restart
  int recoveries_ = 0;
  double t_last_root_ = 0.0;
  Vec14 y_last_root_ = Vec14::Zero();
  std::array<double, kNw> work_last_root_{};
  SessionState ys_{};  // the session's state (minimal coordinates in reduced phases, works)
  // minimal coordinates (null chart_: contact phases as the DAE with projection)
  const ContactChart* chart_ = nullptr;
  ChartMode mode_ = ChartMode::Slip;
  int dim_ = kNumDofs, n_ = kN;  // reduced dimension, size of the mechanical session state
  Vec7 anchor_ = Vec7::Zero();
  Phase phase_ = Phase::Free;
  std::vector<Witness> witnesses_;
  std::vector<int> dirs_;
  std::array<double, kNw> work_{};
  double work_impacts_ = 0.0;
  std::unique_ptr<detail::CvodeSession> free_, contact_, slip_, stick_;
  detail::CvodeSession* cur_ = nullptr;
  std::array<double, 64> event_times_{};
  long n_events_ = 0;
  int same_time_events_ = 0;
  double last_event_t_ = -1e300;
};

/// Contact onset at the root of d_N (or at a missed double crossing): polish, impact or not,
/// decide the next phase.
bool Integrator::on_gap_closing(double t, Vec14 y, bool missed_crossing) {
  Vec7 q, v;
  // Polish the event time: Newton on d_N(t) along the interpolant (inside the last step).
  const double t_hi = cur_->current_time(), t_lo = t_hi - cur_->last_step();
  for (int it = 0; it < 3; ++it) {
    state_from(y, q, v);
    const ContactKinematics c = m_.contact(q, v);
    if (c.v_N == 0.0) break;
    const double tn = std::clamp(t - c.d_N / c.v_N, t_lo, t_hi);
    if (tn == t) break;
    t = tn;
    interp(t, y);
  }
  emit_outputs_before(t);
  works_at(t);
  end_phase(t);
  state_from(y, q, v);
  project_position(q, v);
  ContactOperators op;
  compute_contact_operators(m_, t, q, v, op);
  y.head<kNumDofs>() = q;
  emit_sample(t, y);

  EventRecord e;
  e.t = t;
  e.phase_before = phase_;
  e.d_N = op.c.d_N;
  e.v_N_minus = op.c.v_N;
  e.v_t_minus = op.c.v_t;
  e.witness = missed_crossing ? "v_N (gap minimum below 0: double crossing inside a step)" : "d_N";
  if (op.c.v_N < -v_tol_) {
    e.kind = EventKind::Impact;
    const ImpactResult r = impact_map(op, v, law_);
    if (!r.ok) {
      e.kind = EventKind::Painleve;
      e.note = "impact problem ill-posed: the sliding impact mass A_NN + sigma mu A_NT <= 0";
      log_event(e);
      fail(Termination::Painleve, fmt::format("at t = {:.17g}: {}", t, e.note));
      return false;
    }
    const double T_minus = m_.kinetic_energy(q, v);
    Vec7 vp = r.v_plus;
    e.P_N = r.P_N;
    e.P_T = r.P_T;
    e.note = r.sticking ? "sticking impulse" : "sliding impulse";
    ContactOperators opp;
    compute_contact_operators(m_, t, q, vp, opp);
    if (law_.has_restitution() && opp.c.v_N > v_tol_) {
      // Accumulation (Zeno): the next bounce rises h = v_N+^2 / (2 |b_N|) under the free normal
      // acceleration b_N < 0. Below the position tolerance it cannot be resolved: the remaining
      // sequence (total duration 2 v_N+ / (|b_N| (1 - e_n)) for a constant b_N) is truncated by
      // a plastic impact and the contact persists.
      const double bN = opp.b_N;
      const double height = bN < 0.0 ? opp.c.v_N * opp.c.v_N / (-2.0 * bN) : 1e300;
      if (height < graze_tol_) {
        const double t_inf = t + 2.0 * opp.c.v_N / (-bN * (1.0 - law_.e_n));
        ContactLaw plastic = law_;
        plastic.e_n = 0.0;
        const ImpactResult rp = impact_map(op, v, plastic);
        vp = rp.v_plus;
        e.kind = EventKind::Zeno;
        e.t_accumulation = t_inf;
        e.P_N = rp.P_N;
        e.P_T = rp.P_T;
        e.note = fmt::format(
            "accumulation of impacts: bounce height {:.3g} m below tolerance; extrapolated "
            "accumulation time {:.17g} s (truncated {:.3g} s)",
            height, t_inf, t_inf - t);
      } else {
        work_impacts_ += m_.kinetic_energy(q, vp) - T_minus;
        y.tail<kNumDofs>() = vp;
        e.v_N_plus = opp.c.v_N;
        e.v_t_plus = opp.c.v_t;
        e.phase_after = Phase::Free;
        log_event(e);
        phase_ = Phase::Free;
        gap_rate_deferred_ = false;  // a bounce leaves with v_N > 0: no degenerate start
        emit_sample(t, y);
        start_phase(t, y);
        return true;
      }
    }
    work_impacts_ += m_.kinetic_energy(q, vp) - T_minus;
    y.tail<kNumDofs>() = vp;
  } else {
    e.kind = EventKind::Contact;  // arrival with v_N ~ 0: no impact
    e.note = "arrival with |v_N| below the velocity tolerance";
  }
  return switch_on_constraint(t, y, e, 1e-9);
}

/// On the constraint (d_N = 0): make v_N exactly 0, let the contact problem decide the phase,
/// log the event and restart.
bool Integrator::switch_on_constraint(double t, Vec14 y, EventRecord e, double rel_tol,
                                      bool at_slip_zero, std::optional<Phase> ending) {
  Vec7 q, v;
  state_from(y, q, v);
  project_position(q, v);
  y.head<kNumDofs>() = q;
  ContactOperators op;
  compute_contact_operators(m_, t, q, v, op);
  const double T_before = m_.kinetic_energy(q, v);
  const bool near_stick = law_.has_friction() && (at_slip_zero || std::abs(op.c.v_t) <= v_tol_);
  project_velocity(op, near_stick ? 2 : 1, v);
  work_impacts_ += m_.kinetic_energy(q, v) - T_before;  // the (tiny) projection is an impulse
  compute_contact_operators(m_, t, q, v, op);
  const ModeDecision d = select_mode(op, law_.mu, v_tol_, rel_tol, ending, ending ? F_ref_ : 0.0);
  y.tail<kNumDofs>() = v;
  e.v_N_plus = op.c.v_N;
  e.v_t_plus = op.c.v_t;
  e.phase_after = d.phase;
  e.F_N = d.dyn.F_N;
  e.F_T = d.dyn.F_T;
  if (!d.note.empty()) e.note += (e.note.empty() ? "" : "; ") + d.note;
  if (d.painleve) {
    EventRecord p = e;
    p.kind = EventKind::Painleve;
    log_event(p);
    if (d.n_consistent == 0) {
      fail(Termination::Painleve, fmt::format("at t = {:.17g}: {}", t, d.note));
      return false;
    }
  }
  log_event(e);
  // a release with the state exactly on the constraint: the free phase starts at d_N = 0
  phase_ = d.phase;
  gap_rate_deferred_ = phase_ == Phase::Free;
  emit_sample(t, y);
  start_phase(t, y);
  return true;
}

double Integrator::witness_value(Witness w, double t, const Vec14& y) const {
  Vec7 q, v;
  state_from(y, q, v);
  ContactOperators op;
  contact_point(t, q, v, op);
  const PhaseDynamics d = phase_dynamics(op, phase_, law_.mu);
  switch (w) {
    case Witness::NormalForce: return d.F_N;
    case Witness::ConeUpper: return law_.mu * d.F_N - d.F_T;
    case Witness::ConeLower: return law_.mu * d.F_N + d.F_T;
    case Witness::SlipSpeed: return op.c.v_t;
    default: return 0.0;
  }
}

bool Integrator::on_contact_witness(double t_root, const Vec14& y_root, Witness w) {
  // CVODE reports the root just past the sign change. Move the event to the last time at which
  // the witness still has its phase's sign (bisection on the projected interpolant to a few
  // ulps), so that the state logged before the event is a valid state of the ending phase
  // (F_N >= 0 before a lift-off, |F_T| <= mu F_N before a stick-to-slip switch).
  double t = t_root;
  Vec14 y = y_root;
  {
    double lo = cur_->current_time() - cur_->last_step(), hi = t_root;
    Vec14 yl;
    interp(lo, yl);
    const double g_lo = witness_value(w, lo, yl);
    if (g_lo != 0.0 && g_lo * witness_value(w, hi, y_root) <= 0.0) {
      for (int it = 0; it < 200 && hi - lo > 4e-16 * std::max(1.0, std::abs(hi)); ++it) {
        const double mid = 0.5 * (lo + hi);
        Vec14 ym;
        interp(mid, ym);
        (witness_value(w, mid, ym) * g_lo > 0.0 ? lo : hi) = mid;
      }
      t = lo;
      interp(t, y);
    }
  }
  works_at(t);
  end_phase(t);
  Vec7 q, v;
  state_from(y, q, v);
  emit_sample(t, y);
  const ContactKinematics c = m_.contact(q, v);
  EventRecord e;
  e.t = t;
  e.phase_before = phase_;
  e.d_N = c.d_N;
  e.v_N_minus = c.v_N;
  e.v_t_minus = c.v_t;
  e.witness = witness_name(w);
  switch (w) {
    case Witness::NormalForce: e.kind = EventKind::Liftoff; break;
    case Witness::SlipSpeed: e.kind = EventKind::Stick; break;  // refined below
    default: e.kind = EventKind::Slip; break;
  }
  // Decide with a band of 1e-7 relative: the witness is zero at the event to the accuracy of
  // the root location on the interpolant, so a margin of that size is a zero, not a sign.
  // The phase whose witness fired cannot continue (select_mode: `ending`).
  return switch_on_constraint(t, y, e, 1e-7, w == Witness::SlipSpeed, phase_);
}

RunSummary Integrator::run(const MechanicalState& init, double t_end) {
  const auto wall0 = std::chrono::steady_clock::now();
  t_end_ = t_end;
  sum_.solver = "event";
  sum_.options = fmt::format(
      "{{\"rtol\": {:.3g}, \"atol\": {:.3g}, \"free_flight\": \"{}\", \"contact_phases\": "
      "\"{}\", \"adams_iteration\": \"{}\", \"output_dt\": {:.6g}}}",
      opt_.rtol, opt_.atol, opt_.adams ? "adams" : "bdf",
      chart_ ? (opt_.contact_adams ? "reduced+adams" : "reduced+bdf") : "bdf+projection",
      opt_.fixed_point ? "fixed-point" : "newton", opt_.output_dt);
  sum_.t_start = init.t;
  sum_.t_end_requested = t_end;

  // sessions: free flight and the contact phases of the chosen formulation.
  // Error weights of a session state (p, p', works) with d coordinates: a coordinate that is a
  // full one (length 0) has rtol |p| + atol_q; an angle that moves the contact point by L per
  // radian is weighted by the displacement it causes, absolutely, at the gap's scale:
  // (rtol g0 + atol_q) / L (contact_chart.hpp). Rates: rtol |p'| + atol_v; works: rtol |W| + 1e-9
  // J.
  auto weights = [&](int d, const ChartScales& sc, SessionState& rt, SessionState& at) {
    rt.fill(opt_.rtol);
    at.fill(1e-9);
    for (int i = 0; i < d; ++i) {
      const double L = sc.length[i];
      rt[i] = L > 0.0 ? 0.0 : opt_.rtol;
      at[i] = L > 0.0 ? (opt_.rtol * g0_ + atol_q_) / L : atol_q_;
      at[d + i] = atol_v_;
    }
  };
  SessionState rtol{}, atol{};
  weights(kNumDofs, ChartScales{}, rtol, atol);
  const detail::CvodeCallbacks cb_free{&rhs, &jac, &roots, nullptr, this};
  const detail::CvodeCallbacks cb_contact{&rhs, nullptr, &roots, &proj, this};
  const detail::CvodeCallbacks cb_reduced{&rhs, nullptr, &roots, nullptr, this};
  auto config = [&](int n, detail::CvodeMethod method, const double* rt, const double* at) {
    detail::CvodeConfig c;
    c.n = n + kNw;
    c.method = method;
    c.fixed_point = opt_.fixed_point;
    c.rtol = rt;
    c.atol = at;
    c.max_steps = opt_.max_steps_per_phase;
    return c;
  };
  const auto method = [](bool adams) {
    return adams ? detail::CvodeMethod::Adams : detail::CvodeMethod::BDF;
  };
  try {
    free_ = std::make_unique<detail::CvodeSession>(
        config(kN, method(opt_.adams), rtol.data(), atol.data()), cb_free);
    if (chart_ == nullptr) {
      contact_ = std::make_unique<detail::CvodeSession>(
          config(kN, detail::CvodeMethod::BDF, rtol.data(), atol.data()), cb_contact);
    } else {
      for (ChartMode mode : {ChartMode::Slip, ChartMode::Stick}) {
        const int d = chart_->dim(mode);
        SessionState rt{}, at{};
        weights(d, chart_->scales(mode), rt, at);
        (mode == ChartMode::Slip ? slip_ : stick_) = std::make_unique<detail::CvodeSession>(
            config(2 * d, method(opt_.contact_adams), rt.data(), at.data()), cb_reduced);
      }
    }
  } catch (const std::exception& ex) {
    fail(Termination::SolverFailure, ex.what());
    sink_.end(sum_);
    return sum_;
  }

  Vec14 y;
  y.head<kNumDofs>() = init.q;
  y.tail<kNumDofs>() = init.v;
  double t = init.t;
  const double E0 = m_.kinetic_energy(init.q, init.v) + m_.potential_energy(init.q);
  sum_.energy_initial = E0;
  bool ok = true;

  try {
    t_init_ = init.t;
    k_out_ = 1;
    next_out_ = init.t + opt_.output_dt;
    // Initial phase: free unless the state is on the constraint.
    const ContactKinematics c0 = m_.contact(init.q, init.v);
    phase_ = Phase::Free;
    if (c0.d_N < -graze_tol_) {
      fail(Termination::SolverFailure,
           fmt::format("initial state penetrates the stator: d_N = {:.6g} m", c0.d_N));
      ok = false;
    } else if (c0.normal_defined && c0.d_N <= graze_tol_ && c0.v_N <= v_tol_) {
      // starts in contact: impact if closing, else the contact problem decides
      phase_start_ = t;
      std::copy(y.data(), y.data() + kN, ys_.begin());
      n_ = kN;
      free_->restart(t, ys_.data(), 0, nullptr, false, 0.0, t_end_);
      cur_ = free_.get();
      if (c0.v_N < -v_tol_) {
        ok = on_gap_closing(t, y, false);
      } else {
        EventRecord e;
        e.t = t;
        e.kind = EventKind::Contact;
        e.witness = "initial state on the constraint";
        ok = switch_on_constraint(t, y, e, 1e-9);
      }
    } else {
      emit_sample(t, y);
      start_phase(t, y);
    }

    std::vector<int> info;
    while (ok && t < t_end_) {
      const double tout = std::min(next_out_, t_end_);
      const bool arming = gap_rate_deferred_;
      // per-phase cost: steps and wall time of the integration itself
      const int ph = static_cast<int>(phase_);
      const long steps0 = cur_->steps_since_restart();
      const auto wall_adv = std::chrono::steady_clock::now();
      const auto st = cur_->advance(tout, t, ys_.data(), arming);
      sum_.phase_wall[ph] +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_adv).count();
      sum_.phase_steps[ph] += cur_->steps_since_restart() - steps0;
      {
        Vec7 q, v;
        to_full(ys_.data(), q, v);
        y << q, v;
      }
      if (st == detail::CvodeSession::Status::Failure && root_without_restart_ &&
          recoveries_ < 100) {
        // CVODE stops when a witness is zero both at the last root and just after it ("root
        // found at and very near"), which a degenerate witness can do. Restarting the phase at
        // that root makes the witness inactive until it moves away (half-open interval rule).
        ++recoveries_;
        ++sum_.suppressed_witnesses;
        root_without_restart_ = false;
        end_phase(t_last_root_);
        work_ = work_last_root_;
        start_phase(t_last_root_, y_last_root_);
        t = t_restart_;
        y = y_restart_;
        continue;
      }
      if (st == detail::CvodeSession::Status::Failure) {
        t = cur_->current_time();
        fail(Termination::SolverFailure, fmt::format("CVODE failed at t = {:.17g} in phase {}: {}",
                                                     t, to_string(phase_), cur_->last_error()));
        break;
      }
      if (!y.allFinite()) {
        fail(Termination::NonFinite, fmt::format("non-finite state at t = {:.17g}", t));
        break;
      }
      if (arming && st != detail::CvodeSession::Status::Root) {
        // a free phase after a release: arm the gap-minimum witness once the gap is clearly
        // opening (v_N above the velocity tolerance); until then a closing gap is still seen by
        // the d_N witness, and only a touch-and-go without any crossing could pass unlogged
        Vec7 q, v;
        state_from(y, q, v);
        if (m_.contact(q, v).v_N > v_tol_) {
          gap_rate_deferred_ = false;
          build_witnesses();
          cur_->set_roots(static_cast<int>(witnesses_.size()), dirs_.data());
        }
      }
      if (st != detail::CvodeSession::Status::Root) root_without_restart_ = false;
      if (st == detail::CvodeSession::Status::Step) continue;
      if (st == detail::CvodeSession::Status::Reached) {
        emit_sample(t, y);
        if (opt_.progress) opt_.progress(t, n_events_, y[kNumDofs + TH], phase_);
        if (opt_.stop && t < t_end_ && opt_.stop->load(std::memory_order_relaxed)) {
          fail(Termination::Interrupted, fmt::format("interrupted at t = {:.17g}", t));
          break;
        }
        if (t >= tout && tout == next_out_)
          next_out_ = t_init_ + static_cast<double>(++k_out_) * opt_.output_dt;
        continue;
      }
      // Root return. In single-step mode (arming the gap-rate witness) the step that found the
      // root may have passed output times before the root: write them first, interpolated on
      // that step (CVODE's interpolant covers [t_n - h_u, t_n], which holds them), or the
      // restart at the event would leave them behind the integrator.
      emit_outputs_before(t);
      root_without_restart_ = false;
      info.assign(witnesses_.size(), 0);
      cur_->root_info(info.data());
      bool restart_needed = false;
      for (size_t i = 0; i < witnesses_.size() && ok && !restart_needed; ++i) {
        if (info[i] == 0) continue;
        const Witness w = witnesses_[i];
        if (w == Witness::Omega) {
          mon_.set_omega_lim_time(t);
          omega_pending_ = false;
          continue;
        }
        // event bookkeeping: a bounded number of events per unit of simulated time
        if (std::abs(t - last_event_t_) <= 1e-14 * std::max(1.0, std::abs(t))) {
          if (++same_time_events_ > 20) {
            fail(Termination::Chattering,
                 fmt::format("more than 20 events at t = {:.17g}: mode switching loops", t));
            ok = false;
            break;
          }
        } else {
          same_time_events_ = 0;
        }
        if (phase_ == Phase::Free && w == Witness::GapRate &&
            t - phase_start_ <= 1e-12 * std::max(1.0, std::abs(t))) {
          // Half-open interval rule: right after a release on the constraint (v_N = 0, and the
          // free normal acceleration ~ 0 at a lift-off) the gap rate may dip by round-off and
          // come back: that is the phase's own start, not a new gap minimum. Counted.
          ++sum_.suppressed_witnesses;
          continue;
        }
        if (phase_ == Phase::Free && w == Witness::GapRate) {
          // A gap minimum. Far from contact: nothing to do. Touching: grazing. Below zero: the
          // gap closed and reopened inside one step (an even crossing the root finder cannot
          // see): go back to the first crossing.
          Vec7 q, v;
          state_from(y, q, v);
          const ContactKinematics c = m_.contact(q, v);
          if (c.d_N > graze_band_) continue;
          if (c.d_N >= -graze_tol_) {
            ContactOperators op;
            compute_contact_operators(m_, t, q, v, op);
            EventRecord e;
            e.t = t;
            e.kind = EventKind::Grazing;
            e.phase_before = Phase::Free;
            e.d_N = c.d_N;
            e.v_N_minus = e.v_N_plus = c.v_N;
            e.v_t_minus = e.v_t_plus = c.v_t;
            e.witness = "v_N (gap minimum within tolerance of 0)";
            if (op.b_N >= 0.0 || c.d_N > graze_tol_) {
              e.phase_after = Phase::Free;
              e.note = "touch and go: the free normal acceleration is >= 0";
              log_event(e);
              last_event_t_ = t;
              if (chattering(t)) {
                fail(Termination::Chattering,
                     fmt::format("event rate above {:.3g} per second at t = {:.17g}",
                                 opt_.max_events_per_second, t));
                ok = false;
              }
              continue;
            }
            works_at(t);
            end_phase(t);
            ok = switch_on_constraint(t, y, e, 1e-9);
            restart_needed = true;
          } else {
            // bisection for the first zero of d_N inside the last step
            double lo = cur_->current_time() - cur_->last_step(), hi = t;
            Vec14 yl;
            for (int it = 0; it < 100 && hi - lo > 1e-15 * std::max(1.0, std::abs(t)); ++it) {
              const double mid = 0.5 * (lo + hi);
              interp(mid, yl);
              Vec7 ql, vl;
              state_from(yl, ql, vl);
              (m_.contact(ql, vl).d_N > 0.0 ? lo : hi) = mid;
            }
            interp(hi, yl);
            ok = on_gap_closing(hi, yl, true);
            restart_needed = true;
          }
        } else if (phase_ == Phase::Free && w == Witness::Gap) {
          ok = on_gap_closing(t, y, false);
          restart_needed = true;
        } else {
          ok = on_contact_witness(t, y, w);
          restart_needed = true;
        }
        if (restart_needed) {
          last_event_t_ = t;
          if (ok && chattering(t)) {
            fail(Termination::Chattering,
                 fmt::format("event rate above {:.3g} per second of simulated time at t = {:.17g}",
                             opt_.max_events_per_second, t));
            ok = false;
          }
        }
      }
      if (!ok) break;
      if (!restart_needed) {
        root_without_restart_ = true;
        t_last_root_ = t;
        y_last_root_ = y;
        work_last_root_ = works_of(ys_);
      }
      if (restart_needed) {
        // the event handler restarted the integration at its (polished) event time
        t = t_restart_;
        y = y_restart_;
      } else if (!omega_pending_ && !witnesses_.empty() && witnesses_.back() == Witness::Omega) {
        // roots that needed no restart (omega crossing, far gap minimum, touch and go)
        witnesses_.pop_back();
        dirs_.pop_back();
        cur_->set_roots(static_cast<int>(witnesses_.size()), dirs_.data());
      }
    }
  } catch (const std::exception& ex) {
    fail(Termination::SolverFailure, fmt::format("at t = {:.17g}: {}", t, ex.what()));
  }

  // Close the books.
  end_phase(t);
  sum_.t_reached = t;
  if (cur_) work_ = works_of(ys_);
  Vec7 q, v;
  state_from(y, q, v);
  sum_.energy_final = m_.kinetic_energy(q, v) + m_.potential_energy(q);
  sum_.work_torque = work_[0];
  sum_.work_damping = work_[1];
  sum_.work_friction = work_[2];
  sum_.work_impacts = work_impacts_;
  sum_.close_energy_balance();
  mon_.fill(sum_);
  for (const auto* s : {free_.get(), contact_.get(), slip_.get(), stick_.get()}) {
    if (!s) continue;
    const auto st = s->stats();
    sum_.steps += st.steps;
    sum_.rhs_evals += st.rhs_evals;
    sum_.jac_evals += st.jac_evals;
    sum_.root_evals += st.root_evals;
    sum_.newton_iters += st.newton_iters;
  }
  sum_.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  sink_.end(sum_);
  return sum_;
}

}  // namespace

RunSummary run_event_driven(const LagrangianModel& model, const MechanicalState& initial,
                            double t_end, const EventDrivenOptions& opt, OutputSink& sink) {
  Integrator integ(model, opt, sink);
  return integ.run(initial, t_end);
}

}  // namespace rubdyn
