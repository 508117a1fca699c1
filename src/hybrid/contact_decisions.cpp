#include "contact_decisions.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "phase_session.hpp"

namespace rubdyn::detail {

namespace {

bool sliding_at(const ContactKinematics& c, const ContactLaw& law, const SwitchTolerances& tl) {
  return law.has_friction() && std::abs(c.v_t) > tl.v_tol;
}

EventKind switch_kind(Phase before, Phase after) {
  return after == Phase::Free                  ? EventKind::Liftoff
         : after == Phase::Stick               ? EventKind::Stick
         : slipping(before) && after != before ? EventKind::Reversal
                                               : EventKind::Slip;
}

}  // namespace

ContactDecider::ContactDecider(const LagrangianModel& m, const PhaseContext& ctx)
    : m_(m),
      ctx_(ctx),
      n_(m.num_dofs()),
      K_(ctx.K),
      set_(m.num_dofs(), ctx.K),
      fd_op_(m.num_dofs(), ctx.K),
      fd_ms_(m.num_dofs(), ctx.K),
      solver_(ctx.K) {}

const SwitchTolerances& ContactDecider::tol(int k) const {
  return ctx_.tl(k);
}
const ContactLaw& ContactDecider::law(int k) const {
  return ctx_.law(k);
}

void ContactDecider::constraint_set(const MultiOps& op, const Modes& modes, ContactSet& S) const {
  for (int k = 0; k < K_; ++k) {
    const ContactKinematics& c = op.at(k);
    if (closed(modes[k])) S.set(k);
    if (!S.test(k) && c.normal_defined && c.d_N <= tol(k).graze_tol && c.v_N <= tol(k).v_tol)
      S.set(k);
  }
}

void ContactDecider::painleve_record(Transition& tr, double t, const std::vector<int>& idx,
                                     const std::string& what) const {
  EventRecord e;
  e.t = t;
  e.kind = EventKind::Painleve;
  std::string who;
  for (std::size_t a = 0; a < idx.size(); ++a) {
    if (!solver_.involved(static_cast<int>(a))) continue;
    if (who.empty()) e.contact = idx[a];
    who += fmt::format("{}{}", who.empty() ? "" : ", ", idx[a] + 1);
  }
  e.note = fmt::format("{} (contacts involved: {}; set outcome {})", what,
                       who.empty() ? std::string("none named") : who, to_string(solver_.outcome()));
  tr.events.push_back(e);
}

Transition ContactDecider::painleve(double t, const std::vector<int>& idx,
                                    const std::string& what) const {
  Transition tr;
  painleve_record(tr, t, idx, what);
  tr.first_contact_event = static_cast<int>(tr.events.size());
  tr.ok = false;
  tr.why = Termination::Painleve;
  tr.message = fmt::format("at t = {:.17g}: {}", t, tr.events.back().note);
  return tr;
}

bool ContactDecider::project_velocities(double t, const Vec& q, Vec& v, ContactSet set,
                                        ContactSet stick_rows, double& work) {
  for (int k = 0; k < K_; ++k) {
    set_.kind[static_cast<std::size_t>(k)] = stick_rows.test(k) ? RowKind::Stick
                                             : sliding_at(set_.op.at(k), law(k), tol(k))
                                                 ? RowKind::Sliding
                                                 : RowKind::Normal;
  }
  const double T_before = m_.kinetic_energy(t, q, v);
  const bool ok = set_.velocities(m_, t, q, v, set, ctx_.laws);
  work += m_.kinetic_energy(t, q, v) - T_before;
  return ok;
}

Transition ContactDecider::arrive(double t, const Vec& q_in, const Vec& v_in, const Modes& modes,
                                  ContactSet S, const std::string& witness, double dt_ref) {
  Vec q = q_in;
  const Vec& v = v_in;
  set_.op.compute(m_, t, q, v);
  constraint_set(set_.op, modes, S);
  set_.positions(m_, t, q, v, S, ctx_.tol);  // positions on the constraint; op there, at v-
  const MultiOps& op = set_.op;
  PendingList ev{};
  ContactSet band_release;
  std::vector<int> idx;
  bool impact = false;
  for (int k = 0; k < K_; ++k) {
    if (!S.test(k)) continue;
    idx.push_back(k);
    const ContactKinematics& c = op.at(k);
    if (closed(modes[k])) continue;
    Pending& p = ev[static_cast<std::size_t>(k)];
    p.active = true;
    p.e.t = t;
    p.e.contact = k;
    p.e.phase_before = Phase::Free;
    p.e.d_N = c.d_N;
    p.e.v_N_minus = c.v_N;
    p.e.v_t_minus = c.v_t;
    p.e.witness = witness;
    if (c.v_N < -tol(k).v_tol) {
      p.e.kind = EventKind::Impact;
      impact = true;
    } else {
      p.e.kind = EventKind::Contact;
      p.e.note = "arrival with |v_N| below the velocity tolerance";
      // released at once, its d_N crossing was the integrator's error: the next free phase
      // bands this contact's onset (Arming::gap_banded)
      band_release.set(k);
    }
  }
  auto finish = [&](Transition tr, const Transition& head, double work) {
    tr.pre_sample = true;
    tr.q_pre = q;
    tr.v_pre = v;
    tr.impulse_work += work;
    if (!head.events.empty()) {
      tr.events.insert(tr.events.begin(), head.events.begin(), head.events.end());
      tr.first_contact_event += static_cast<int>(head.events.size());
    }
    tr.decided = tr.decided | head.decided;
    tr.arming.gap_banded = tr.arming.gap_banded | head.arming.gap_banded;
    return tr;
  };
  if (!impact)
    return finish(on_constraint(t, q, v, modes, S, std::nullopt, false, kDecisionBandRel,
                                ctx_.F_ref, ev, dt_ref, "", band_release),
                  Transition{}, 0.0);

  // the joint impulse problem of the contacts at the constraint
  Transition head;  // Painleve records of the impact and the contacts that leave
  const int m = static_cast<int>(idx.size());
  ContactSet plastic;
  Vec v_plus = v;
  const double T_minus = m_.kinetic_energy(t, q, v);
  for (int pass = 0; pass < 2; ++pass) {
    Mat Wm(2 * m, 2 * m);
    Vec u0(2 * m);
    std::vector<SetContact> sc(static_cast<std::size_t>(m));
    for (int a = 0; a < m; ++a) {
      const int k = idx[static_cast<std::size_t>(a)];
      const Pending& p = ev[static_cast<std::size_t>(k)];
      const bool hits = p.active && p.e.kind == EventKind::Impact;
      const double en = hits && !plastic.test(k) ? law(k).e_n : 0.0;
      const double et = hits ? law(k).e_t : 0.0;
      u0(2 * a) = (1.0 + en) * op.at(k).v_N;
      u0(2 * a + 1) = (1.0 + et) * op.at(k).v_t;
      sc[static_cast<std::size_t>(a)].mu = law(k).mu;
      for (int b = 0; b < m; ++b) {
        const int l = idx[static_cast<std::size_t>(b)];
        Wm.block<2, 2>(2 * a, 2 * b) = op.W.block<2, 2>(2 * k, 2 * l);
      }
    }
    const SetOutcome out = solver_.solve(Wm, u0, sc, contact_set_band(Wm, u0));
    if (!has_solution(out))
      return finish(painleve(t, idx, "impact problem without solution"), head, 0.0);
    if (out == SetOutcome::NonUnique)
      painleve_record(head, t, idx, "several impulses solve the impact");
    v_plus = v;
    for (int a = 0; a < m; ++a) {
      const int k = idx[static_cast<std::size_t>(a)];
      v_plus.noalias() +=
          op.B.col(1 + 2 * k) * solver_.r_N(a) + op.B.col(2 + 2 * k) * solver_.r_T(a);
      Pending& p = ev[static_cast<std::size_t>(k)];
      if (!p.active) continue;
      p.e.P_N = solver_.r_N(a);
      p.e.P_T = solver_.r_T(a);
      if (p.e.kind == EventKind::Impact)
        p.e.note = solver_.mode(a) == Phase::Stick ? "sticking impulse" : "sliding impulse";
    }
    // Zeno, per contact: a bounce lower than collapse_height is truncated by a plastic impact
    fd_op_.compute(m_, t, q, v_plus);
    bool again = false;
    for (int k : idx) {
      Pending& p = ev[static_cast<std::size_t>(k)];
      if (plastic.test(k) || !p.active || p.e.kind != EventKind::Impact ||
          !law(k).has_restitution())
        continue;
      const double vN = fd_op_.at(k).v_N, bN = fd_op_.b(2 * k);
      if (!(vN > tol(k).v_tol)) continue;
      const double height = bN < 0.0 ? vN * vN / (-2.0 * bN) : 1e300;
      if (height >= tol(k).collapse_height) continue;
      plastic.set(k);
      again = true;
      p.e.kind = EventKind::Zeno;
      p.e.t_accumulation = t + 2.0 * vN / (-bN * (1.0 - law(k).e_n));
      p.e.note = fmt::format(
          "accumulation of impacts: bounce height {:.3g} m below {:.3g} m; extrapolated "
          "accumulation time {:.17g} s (truncated {:.3g} s)",
          height, tol(k).collapse_height, p.e.t_accumulation, p.e.t_accumulation - t);
    }
    if (!again) break;
  }
  double work = m_.kinetic_energy(t, q, v_plus) - T_minus;
  // Contacts leaving with v_N below the velocity tolerance stay on the constraint; so do those
  // pushed off by the others' impulses whose flight would be lower than collapse_height (the
  // cascade, collapsed below). The others leave, with the banded onset witness (they leave from
  // a gap that is 0 only to round-off).
  fd_op_.compute(m_, t, q, v_plus);
  ContactSet C, collapse, leaving;
  Modes after = modes;
  for (int k : idx) {
    const double vN = fd_op_.at(k).v_N, bN = fd_op_.b(2 * k);
    Pending& p = ev[static_cast<std::size_t>(k)];
    const double height = bN < 0.0 ? vN * vN / (-2.0 * bN) : 1e300;
    if (vN <= tol(k).v_tol) {
      C.set(k);
      continue;
    }
    if (height < tol(k).collapse_height) {
      C.set(k);
      collapse.set(k);
      if (p.active)
        p.e.note += fmt::format(
            "; pushed off at {:.3g} m/s by the joint impulses, a flight of {:.3g} m: the "
            "cascade collapsed by an impulse of the slip law",
            vN, height);
      continue;
    }
    leaving.set(k);
    if (!p.active) {
      p.active = true;
      p.e.t = t;
      p.e.contact = k;
      p.e.kind = EventKind::Liftoff;
      p.e.phase_before = modes[k];
      p.e.witness = witness;
      p.e.note = "opened by the impulses of an impact at another contact";
    }
    p.e.v_N_plus = vN;
    p.e.v_t_plus = fd_op_.at(k).v_t;
    p.e.phase_after = Phase::Free;
    after[k] = Phase::Free;
  }
  if (collapse.any()) {
    // the cascade's collapse: the normal speeds of every contact staying on the constraint to 0
    // by impulses of the slip law (D_eff P = -v_N, contact_decisions.hpp)
    set_.op.compute(m_, t, q, v_plus);
    ContactSet stick_rows;
    for (int k = 0; k < K_; ++k)
      if (C.test(k) && law(k).has_friction() && !sliding_at(set_.op.at(k), law(k), tol(k)))
        stick_rows.set(k);
    project_velocities(t, q, v_plus, C, stick_rows, work);
  }
  head.decided = S;
  head.arming.gap_banded = leaving;
  return finish(on_constraint(t, q, v_plus, after, C, std::nullopt, false, kDecisionBandRel,
                              ctx_.F_ref, ev, dt_ref, "", band_release),
                head, work);
}

Transition ContactDecider::on_constraint(
    double t, const Vec& q_in, const Vec& v_in, const Modes& modes, ContactSet C,
    std::optional<std::pair<int, Phase>> ending, bool at_slip_zero, double rel_tol, double F_ref,
    PendingList& ev, double dt_ref, const std::string& ending_witness, ContactSet band_on_release) {
  Transition tr;
  Vec q = q_in, v = v_in;
  // velocities onto the constraints of C: v_N = 0; v_t = 0 too near stick or at the end of the
  // ending contact's slip; the slip friction at the sliding ones
  set_.op.compute(m_, t, q, v);
  ContactSet stick_rows;
  for (int k = 0; k < K_; ++k) {
    if (!C.test(k) || !law(k).has_friction()) continue;
    const bool slip_zero = at_slip_zero && ending && ending->first == k;
    if (slip_zero || std::abs(set_.op.at(k).v_t) <= tol(k).v_tol) stick_rows.set(k);
  }
  set_.positions(m_, t, q, v, C, ctx_.tol);
  double work = 0.0;
  project_velocities(t, q, v, C, stick_rows, work);
  tr.impulse_work = work;  // the (tiny) projection
  const MultiOps& op = set_.op;
  std::vector<int> idx;
  for (int k = 0; k < K_; ++k)
    if (C.test(k)) idx.push_back(k);
  const int m = static_cast<int>(idx.size());
  Modes next = modes;
  for (int k : idx) next[k] = Phase::Free;
  bool boundary = false;  // no strictly consistent combination: a zero margin, decided by rule
  if (m > 0) {
    Mat Wm(2 * m, 2 * m);
    Vec u0(2 * m);
    std::vector<SetContact> sc(static_cast<std::size_t>(m));
    double acc = 0.0, diag_max = 0.0, diag_min = 1e300;
    for (int a = 0; a < m; ++a) {
      const int k = idx[static_cast<std::size_t>(a)];
      u0(2 * a) = op.b(2 * k);
      u0(2 * a + 1) = op.b(2 * k + 1);
      acc += std::abs(u0(2 * a)) + std::abs(u0(2 * a + 1));
      diag_max = std::max(diag_max, op.W(2 * k, 2 * k));
      diag_min = std::min(diag_min, op.W(2 * k, 2 * k));
      SetContact& s = sc[static_cast<std::size_t>(a)];
      s.mu = law(k).mu;
      const double vt = op.at(k).v_t;
      if (sliding_at(op.at(k), law(k), tol(k))) s.sliding = vt > 0.0 ? 1 : -1;
      if (ending && ending->first == k) s.excluded = ending->second;
      for (int b = 0; b < m; ++b) {
        const int l = idx[static_cast<std::size_t>(b)];
        Wm.block<2, 2>(2 * a, 2 * b) = op.W.block<2, 2>(2 * k, 2 * l);
      }
    }
    const double F_scale = ending ? F_ref : 0.0;
    SetBand band;
    band.tol_u = rel_tol * (acc + F_scale * diag_max) + 1e-300;
    band.tol_r = band.tol_u / std::max(diag_min, 1e-300);
    // The decision, and where it is degenerate (no strictly consistent combination) the next
    // order: a chosen mode whose zero margin falls is dropped (tie rule 1) while another
    // combination remains, and the problem solved again.
    for (int round = 0; round <= 2 * m; ++round) {
      const SetOutcome out = solver_.solve(Wm, u0, sc, band);
      if (!has_solution(out)) {
        Transition p = painleve(t, idx, "no consistent set of contact modes");
        p.events.insert(p.events.begin(), tr.events.begin(), tr.events.end());
        return p;
      }
      if (out == SetOutcome::NonUnique && round == 0)
        painleve_record(tr, t, idx,
                        "several consistent sets of contact modes; the tie rule picked one");
      for (int a = 0; a < m; ++a) next[idx[static_cast<std::size_t>(a)]] = solver_.mode(a);
      boundary = out == SetOutcome::Boundary;
      if (!boundary || !(dt_ref > 0.0)) break;
      std::array<std::uint8_t, kMaxContacts> falling{};
      if (!falling_margins(t, q, v, next, idx, band.tol_u, band.tol_r, dt_ref, falling)) break;
      bool more = false;
      for (int a = 0; a < m; ++a) {
        const int k = idx[static_cast<std::size_t>(a)];
        SetContact& s = sc[static_cast<std::size_t>(a)];
        const std::uint8_t add = falling[static_cast<std::size_t>(k)] & ~s.excluded_modes;
        if (add == 0) continue;
        s.excluded_modes |= add;
        more = true;
      }
      if (!more) break;
    }
  }
  tr.first_contact_event = static_cast<int>(tr.events.size());
  // the events: every contact whose mode changes, and every pending one
  for (int k = 0; k < K_; ++k) {
    Pending& p = ev[static_cast<std::size_t>(k)];
    const Phase before = modes[k], after = next[k];
    const bool is_ending = ending && ending->first == k;
    if (!p.active && before == after && !is_ending) continue;
    if (!p.active) {
      p.active = true;
      p.e.t = t;
      p.e.contact = k;
      p.e.phase_before = before;
      p.e.d_N = op.at(k).d_N;
      p.e.v_N_minus = op.at(k).v_N;
      p.e.v_t_minus = op.at(k).v_t;
      p.e.witness = is_ending ? ending_witness : "joint decision at another contact's event";
      p.e.kind = switch_kind(before, after);
    }
    if (C.test(k)) {
      p.e.v_N_plus = op.at(k).v_N;
      p.e.v_t_plus = op.at(k).v_t;
      p.e.phase_after = after;
      if (boundary)
        p.e.note += std::string(p.e.note.empty() ? "" : "; ") +
                    "boundary case: a margin zero at the event, the mode decided by the next "
                    "order and the order free, stick, slip";
    }
    tr.events.push_back(p.e);
  }
  // how the decided contacts' witnesses start: a release on the constraint with degenerate gap
  // witnesses; a slip from rest with a slip speed that is 0
  tr.decided = C;
  for (int k : idx) {
    if (next[k] == Phase::Free) {
      tr.arming.rate_deferred.set(k);
      // a release on the constraint (d_N within the integrator's position resolution) bands
      // its onset witness: with projected positions d_N starts at +-round-off and would fire
      // at once
      tr.arming.gap_banded.set(k, band_on_release.test(k) || op.at(k).d_N <= tol(k).graze_tol);
    } else if (slipping(next[k]) && law(k).has_friction() &&
               std::abs(op.at(k).v_t) <= tol(k).v_tol) {
      tr.arming.slip_banded.set(k);
    }
  }
  tr.next = next;
  tr.q = q;
  tr.v = v;
  return tr;
}

bool ContactDecider::falling_margins(double t, const Vec& q, const Vec& v, const Modes& chosen,
                                     const std::vector<int>& idx, double tol_u, double tol_r,
                                     double dt, std::array<std::uint8_t, kMaxContacts>& falling) {
  // the margins of each contact's chosen mode (coulomb_signorini.hpp): free u_N (= d_N''); stick
  // r_N and mu r_N - |r_T|; slip r_N, and s u_T unless it slides (u_T = v_t')
  constexpr double kNone = std::numeric_limits<double>::infinity();
  const int m = static_cast<int>(idx.size());
  using Margins = std::array<double, 2 * kMaxContacts>;
  auto margins = [&](double tt, const Vec& qq, const Vec& vv, Margins& mg) {
    fd_op_.compute(m_, tt, qq, vv);
    if (!fd_ms_.solve(fd_op_, chosen, ctx_.laws)) return false;
    const Vec& a = fd_ms_.a;
    for (int i = 0; i < m; ++i) {
      const int k = idx[static_cast<std::size_t>(i)];
      const ContactKinematics& c = fd_op_.at(k);
      const double FN = fd_ms_.r(2 * k), FT = fd_ms_.r(2 * k + 1);
      auto& m0 = mg[static_cast<std::size_t>(2 * i)];
      auto& m1 = mg[static_cast<std::size_t>(2 * i + 1)];
      switch (chosen[k]) {
        case Phase::Free:
          m0 = c.W_N.dot(a) + c.wdot_N;
          m1 = kNone;
          break;
        case Phase::Stick:
          m0 = FN;
          m1 = law(k).mu * FN - std::abs(FT);
          break;
        case Phase::SlipPos:
        case Phase::SlipNeg:
          m0 = FN;
          m1 = sliding_at(c, law(k), tol(k)) || !law(k).has_friction()
                   ? kNone
                   : slip_sign(chosen[k]) * (c.W_T.dot(a) + c.wdot_T);
          break;
      }
    }
    return true;
  };
  Margins m_0{}, m_p{}, m_m{};
  if (!margins(t, q, v, m_0)) return false;
  const Vec a0 = fd_ms_.a;
  const Vec qp = q + dt * v + (0.5 * dt * dt) * a0, vp = v + dt * a0;
  const Vec qm = q - dt * v + (0.5 * dt * dt) * a0, vm = v - dt * a0;
  if (!margins(t + dt, qp, vp, m_p) || !margins(t - dt, qm, vm, m_m)) return false;
  bool any = false;
  for (int i = 0; i < m; ++i) {
    const int k = idx[static_cast<std::size_t>(i)];
    const Phase p = chosen[k];
    for (int j = 0; j < 2; ++j) {
      const auto s = static_cast<std::size_t>(2 * i + j);
      if (!std::isfinite(m_0[s])) continue;
      // the margin's band: tol_u on u, tol_r on r (times mu on the cone)
      const bool on_u = p == Phase::Free || (j == 1 && slipping(p));
      const double band = on_u ? tol_u : (j == 1 ? law(k).mu * tol_r : tol_r);
      if (std::abs(m_0[s]) > band) continue;  // not a zero of the decision
      // falling: its change over 2 dt is negative beyond the noise of its evaluation, a ten
      // thousandth of the band (the band is rel_tol >= 1e-9 of the data's scale, the noise a few
      // eps of it)
      if (m_p[s] - m_m[s] < -1e-4 * band) {
        falling[static_cast<std::size_t>(k)] |=
            static_cast<std::uint8_t>(1u << static_cast<int>(p));
        any = true;
      }
    }
  }
  return any;
}

// ---- grazing, guard ---------------------------------------------------------------------------

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
