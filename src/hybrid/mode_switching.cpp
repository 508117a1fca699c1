#include "mode_switching.hpp"

#include <fmt/format.h>

#include <cmath>

namespace rubdyn::detail {

ModeSwitcher::ModeSwitcher(const LagrangianModel& m, const SwitchTolerances& tol)
    : m_(m), law_(m.contact_law(0)), tol_(tol), kin_(m.num_dofs()), op_(m.num_dofs()) {}

void ModeSwitcher::project_position(double t, VecOut q, VecIn v) const {
  ContactKinematics c(m_.num_dofs());
  rubdyn::project_position(m_, t, q, v, kProjectionRel * tol_.g0, c);
}

Transition ModeSwitcher::gap_closed(double t, VecIn q, VecIn v_minus, EventRecord e) const {
  ContactOperators op(m_.num_dofs());
  compute_contact_operators(m_, t, q, v_minus, op);
  e.d_N = op.c.d_N;
  e.v_N_minus = op.c.v_N;
  e.v_t_minus = op.c.v_t;
  if (op.c.v_N >= -tol_.v_tol) {
    e.kind = EventKind::Contact;  // arrival with v_N ~ 0: no impact
    e.note = "arrival with |v_N| below the velocity tolerance";
    return on_constraint(t, q, v_minus, e, kDecisionBandRel);
  }
  e.kind = EventKind::Impact;
  const ImpactResult r = impact_map(op, v_minus, law_);
  if (!r.ok) {
    Transition tr;
    e.kind = EventKind::Painleve;
    e.note = "impact problem without solution (Painleve-type Delassus matrix)";
    tr.log(e);
    tr.ok = false;
    tr.why = Termination::Painleve;
    tr.message = fmt::format("at t = {:.17g}: {}", t, e.note);
    return tr;
  }
  Vec v_plus = r.v_plus;
  e.P_N = r.P_N;
  e.P_T = r.P_T;
  e.note = r.sticking ? "sticking impulse" : "sliding impulse";
  if (r.nonunique) e.note += "; several impulses solve the impact (tie rule applied)";
  const double T_minus = m_.kinetic_energy(t, q, v_minus);
  ContactOperators opp(m_.num_dofs());
  compute_contact_operators(m_, t, q, v_plus, opp);
  if (law_.has_restitution() && opp.c.v_N > tol_.v_tol) {
    // Accumulation (Zeno): the next bounce rises h = v_N+^2 / (2 |b_N|) under the free normal
    // acceleration b_N < 0. Below the position tolerance it cannot be resolved: the remaining
    // sequence (total duration 2 v_N+ / (|b_N| (1 - e_n)) for a constant b_N) is truncated by
    // a plastic impact and the contact persists.
    const double bN = opp.b_N;
    const double height = bN < 0.0 ? opp.c.v_N * opp.c.v_N / (-2.0 * bN) : 1e300;
    if (height >= tol_.graze_tol) {
      Transition tr;  // a bounce: free flight leaves the constraint with v_N > 0
      e.v_N_plus = opp.c.v_N;
      e.v_t_plus = opp.c.v_t;
      e.phase_after = Phase::Free;
      if (r.nonunique) {
        EventRecord p = e;
        p.kind = EventKind::Painleve;
        tr.log(p);
      }
      tr.log(e);
      tr.q = q;
      tr.v = v_plus;
      tr.impulse_work = m_.kinetic_energy(t, q, v_plus) - T_minus;
      return tr;
    }
    const double t_inf = t + 2.0 * opp.c.v_N / (-bN * (1.0 - law_.e_n));
    ContactLaw plastic = law_;
    plastic.e_n = 0.0;
    const ImpactResult rp = impact_map(op, v_minus, plastic);
    v_plus = rp.v_plus;
    e.kind = EventKind::Zeno;
    e.t_accumulation = t_inf;
    e.P_N = rp.P_N;
    e.P_T = rp.P_T;
    e.note = fmt::format(
        "accumulation of impacts: bounce height {:.3g} m below tolerance; extrapolated "
        "accumulation time {:.17g} s (truncated {:.3g} s)",
        height, t_inf, t_inf - t);
  }
  Transition tr = on_constraint(t, q, v_plus, e, kDecisionBandRel);
  tr.impulse_work += m_.kinetic_energy(t, q, v_plus) - T_minus;
  return tr;
}

Transition ModeSwitcher::on_constraint(double t, VecIn q_in, VecIn v_in, EventRecord e,
                                       double rel_tol, bool at_slip_zero,
                                       std::optional<Phase> ending, double F_ref) const {
  Transition tr;
  Vec q = q_in, v = v_in;
  project_position(t, q, v);
  ContactOperators op(m_.num_dofs());
  compute_contact_operators(m_, t, q, v, op);
  const double T_before = m_.kinetic_energy(t, q, v);
  const bool near_stick = law_.has_friction() && (at_slip_zero || std::abs(op.c.v_t) <= tol_.v_tol);
  project_velocity(op, near_stick ? 2 : 1, v);
  tr.impulse_work = m_.kinetic_energy(t, q, v) - T_before;  // the (tiny) projection is an impulse
  update_contact_velocity(m_, t, q, v, op);
  const ModeDecision d =
      select_mode(op, law_.mu, tol_.v_tol, rel_tol, ending, ending ? F_ref : 0.0);
  e.v_N_plus = op.c.v_N;
  e.v_t_plus = op.c.v_t;
  e.phase_after = d.phase;
  if (ending) {
    // a contact phase ended by its witness: the kind is what the contact problem decided
    const bool slip_before = *ending == Phase::SlipPos || *ending == Phase::SlipNeg;
    e.kind = d.phase == Phase::Free              ? EventKind::Liftoff
             : d.phase == Phase::Stick           ? EventKind::Stick
             : slip_before && d.phase != *ending ? EventKind::Reversal
                                                 : EventKind::Slip;
  }
  e.F_N = d.dyn.F_N;
  e.F_T = d.dyn.F_T;
  if (!d.note.empty()) e.note += (e.note.empty() ? "" : "; ") + d.note;
  if (d.painleve) {
    EventRecord p = e;
    p.kind = EventKind::Painleve;
    tr.log(p);
    if (d.n_consistent == 0) {
      tr.ok = false;
      tr.why = Termination::Painleve;
      tr.message = fmt::format("at t = {:.17g}: {}", t, d.note);
      return tr;
    }
  }
  tr.log(e);
  tr.next = d.phase;
  tr.release = d.phase == Phase::Free;  // the free phase starts at d_N = 0 with v_N = 0
  tr.q = q;
  tr.v = v;
  return tr;
}

ModeSwitcher::GapMinimum ModeSwitcher::classify_gap_minimum(double t, VecIn q, VecIn v) const {
  m_.compute_contact(0, t, q, v, kin_);
  const ContactKinematics& c = kin_;
  if (c.d_N > tol_.graze_band) return GapMinimum::Clear;
  if (c.d_N < -tol_.graze_tol) return GapMinimum::Crossed;
  if (c.d_N > tol_.graze_tol) return GapMinimum::TouchAndGo;
  compute_contact_operators(m_, t, q, v, op_);
  return op_.b_N >= 0.0 ? GapMinimum::TouchAndGo : GapMinimum::Grazing;
}

EventRecord grazing_event(double t, const ContactKinematics& c) {
  EventRecord e;
  e.t = t;
  e.kind = EventKind::Grazing;
  e.phase_before = Phase::Free;
  e.d_N = c.d_N;
  e.v_N_minus = e.v_N_plus = c.v_N;
  e.v_t_minus = e.v_t_plus = c.v_t;
  e.witness = "v_N (gap minimum within tolerance of 0)";
  return e;
}

EventRecord ModeSwitcher::grazing_record(double t, VecIn q, VecIn v, bool touch_and_go) const {
  EventRecord e = grazing_event(t, m_.contact(0, t, q, v));
  if (touch_and_go) {
    e.phase_after = Phase::Free;
    e.note = "touch and go: the free normal acceleration is >= 0";
  }
  return e;
}

std::optional<std::string> EventGuard::record(double t) {
  if (std::abs(t - last_t_) <= kSameInstantRel * std::max(1.0, std::abs(t))) {
    if (++same_time_ > kMaxSameInstant)
      return fmt::format("more than {} events at t = {:.17g}: mode switching loops",
                         kMaxSameInstant, t);
  } else {
    same_time_ = 0;
  }
  last_t_ = t;
  times_[n_ % times_.size()] = t;
  ++n_;
  if (n_ < static_cast<long>(times_.size())) return std::nullopt;
  const double oldest = times_[n_ % times_.size()];
  const double window = static_cast<double>(times_.size()) / max_per_second_;
  if (t - oldest < window)
    return fmt::format("event rate above {:.3g} per second of simulated time at t = {:.17g}",
                       max_per_second_, t);
  return std::nullopt;
}

}  // namespace rubdyn::detail
