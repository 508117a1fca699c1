// Moreau-Jean with several contacts: MoreauJean<N>::step_multi and its stepper (the scheme is
// moreau_jean.cpp's; docs/time-steppers.md, section 3.1). A translation unit of its own, so that
// the one-contact step is compiled as before (sharing the unit changed how GCC inlines its Eigen
// kernels: measured 5-13 % more instructions per step on the reference case).
#include "moreau_jean_class.hpp"
#include "rubdyn/contact/coulomb_signorini.hpp"

namespace rubdyn::detail {

template <int N, bool Multi>
StepOutcome MoreauJean<N, Multi>::step_multi(double t, StepReport& r, std::string& message) {
  // The scheme of step() with K contacts: every contact's index set by its predicted gap, the
  // impulses of the active ones solved jointly at every Newton iterate (contact_set.hpp: the
  // Delassus matrix W^T Mt^-1 W of all active contacts, Newton's law per contact), and with
  // mj-proj every penetrating contact projected jointly.
  const double h = o_.h, th = o_.theta;
  MultiWork<N, true>& w = mw_;
  m_.smooth_forces(t, q_, v_, fi_);
  w.act.clear();
  for (int k = 0; k < K_; ++k) {
    ContactKinematics& c = w.cik[static_cast<std::size_t>(k)];
    m_.compute_contact(k, t, q_, v_, c);
    w.bN1k[static_cast<std::size_t>(k)] = c.b_N;
    w.bT1k[static_cast<std::size_t>(k)] = c.b_T;
    if (rheonomic_) {
      m_.compute_contact(k, t + h, q_, v_, kin_);
      w.bN1k[static_cast<std::size_t>(k)] = kin_.b_N;
      w.bT1k[static_cast<std::size_t>(k)] = kin_.b_T;
    }
    if (c.normal_defined && c.d_N + 0.5 * h * c.v_N <= 0.0) w.act.push_back(k);
  }
  const int na = static_cast<int>(w.act.size());
  for (int a = 0; a < na; ++a) {
    const auto k = static_cast<std::size_t>(w.act[static_cast<std::size_t>(a)]);
    w.WNk[static_cast<std::size_t>(a)] = w.cik[k].W_N;
    w.WTk[static_cast<std::size_t>(a)] = w.cik[k].W_T;
    w.sc[static_cast<std::size_t>(a)] = SetContact{m_.contact_law(static_cast<int>(k)).mu, 0, {}};
  }
  V& v = v_it_;
  v = v_;
  if (prev_impulse_free_) v += v_ - v_prev_;
  newton_.begin_step();
  auto delassus = [&] {  // W^T Mt^{-1} W of the active contacts, with the current matrix
    for (int a = 0; a < na; ++a) {
      const auto ia = static_cast<std::size_t>(a);
      newton_.apply_inverse_sparse(w.WNk[ia], w.XNk[ia]);
      newton_.apply_inverse_sparse(w.WTk[ia], w.XTk[ia]);
    }
    for (int a = 0; a < na; ++a)
      for (int b = 0; b < na; ++b) {
        const auto ia = static_cast<std::size_t>(a), ib = static_cast<std::size_t>(b);
        w.Wd(2 * a, 2 * b) = w.WNk[ia].dot(w.XNk[ib]);
        w.Wd(2 * a, 2 * b + 1) = w.WNk[ia].dot(w.XTk[ib]);
        w.Wd(2 * a + 1, 2 * b) = w.WTk[ia].dot(w.XNk[ib]);
        w.Wd(2 * a + 1, 2 * b + 1) = w.WTk[ia].dot(w.XTk[ib]);
      }
    // the uniqueness certificate depends on W only: once per W, not at every Newton iterate
    // that reuses it (contact_set.hpp, solve_guess's known_unique)
    if (na > 1)
      w.unique = unique_by_monotonicity(
          w.Wd.topLeftCorner(2 * na, 2 * na),
          std::span<const SetContact>(w.sc.data(), static_cast<std::size_t>(na)));
  };
  if (!newton_.needs_matrix() && na > 0) delassus();
  bool solved = false;  // the last iterate solved a contact problem (w.set holds it)
  r.reset();
  for (;;) {
    free_velocity(t, v, [&] {
      if (na > 0) delassus();
    });
    V& vn = vn_;
    vn = vfree_;
    solved = false;
    if (na > 0) {
      for (int a = 0; a < na; ++a) {
        const auto ia = static_cast<std::size_t>(a);
        const int k = w.act[ia];
        const ContactKinematics& c = w.cik[static_cast<std::size_t>(k)];
        const ContactLaw& law = m_.contact_law(k);
        w.u0[2 * a] = w.WNk[ia].dot(vfree_) + w.bN1k[static_cast<std::size_t>(k)] + law.e_n * c.v_N;
        w.u0[2 * a + 1] =
            w.WTk[ia].dot(vfree_) + w.bT1k[static_cast<std::size_t>(k)] + law.e_t * c.v_t;
      }
      const auto W = w.Wd.topLeftCorner(2 * na, 2 * na);
      const auto u0 = w.u0.head(2 * na);
      SetOutcome o = SetOutcome::Unique;
      if (na == 1) {
        // one active contact: the one-contact kernel, which the set solver reduces to for K = 1
        // (the same modes and flags: contact_set.hpp's tie rule), at a tenth of the cost
        const LocalSolution sol = solve_coulomb_signorini(
            make_local_problem(W(0, 0), W(0, 1), W(1, 1), u0[0], u0[1], w.sc[0].mu));
        o = !sol.ok()         ? SetOutcome::NoSolution
            : sol.nonunique() ? SetOutcome::NonUnique
                              : SetOutcome::Unique;
        w.rN[0] = sol.r_N;
        w.rT[0] = sol.r_T;
        w.mode[0] = sol.phase;
      } else {
        // the last modes first: taken when the problem is certified to have one solution and
        // they still solve it strictly (contact_set.hpp, solve_guess: the enumeration's answer)
        const auto una = static_cast<std::size_t>(na);
        for (std::size_t a = 0; a < una; ++a)
          w.guess[a] = w.last_mode[static_cast<std::size_t>(w.act[a])];
        o = w.set.solve_guess(W, u0, std::span<const SetContact>(w.sc.data(), una),
                              contact_set_band(W, u0), std::span<const Phase>(w.guess.data(), una),
                              w.unique);
        if (has_solution(o))
          for (int a = 0; a < na; ++a) {
            const auto ia = static_cast<std::size_t>(a);
            w.rN[ia] = w.set.r_N(a);
            w.rT[ia] = w.set.r_T(a);
            w.mode[ia] = w.set.mode(a);
          }
      }
      std::fill(w.last_mode.begin(), w.last_mode.end(), Phase::Free);
      if (has_solution(o))
        for (int a = 0; a < na; ++a)
          w.last_mode[static_cast<std::size_t>(w.act[static_cast<std::size_t>(a)])] =
              w.mode[static_cast<std::size_t>(a)];
      if (!has_solution(o)) {
        std::string who;
        for (int a = 0; a < na; ++a)
          if (na == 1 || w.set.involved(a))
            who += fmt::format("{}{}", who.empty() ? "" : ", ",
                               w.act[static_cast<std::size_t>(a)] + 1);
        message = fmt::format(
            "mj: the joint contact problem has no solution at t = {:.17g} ({}; contacts "
            "involved: {})",
            t, to_string(o), who.empty() ? "none named" : who);
        return StepOutcome::Painleve;
      }
      r.nonunique = r.nonunique || o == SetOutcome::NonUnique;
      for (int a = 0; a < na; ++a) {
        const auto ia = static_cast<std::size_t>(a);
        vn += w.XNk[ia] * w.rN[ia] + w.XTk[ia] * w.rT[ia];
      }
      solved = true;
    }
    StepOutcome out = StepOutcome::Ok;
    const Iterate it = accept(t, v, vn, r, out, message);
    if (it == Iterate::Converged) break;
    if (it == Iterate::Failed) return out;
  }
  V& q = q_it_;
  q = q_ + h * ((1.0 - th) * v_ + th * v);
  if (project_) {
    // every penetrating contact onto d_N = 0 at once: q += X lambda with X = M^-1 W_N (or W_N,
    // identity metric) of those contacts and W_N^T X lambda = -d_N (a Newton step; at most 3)
    for (int it = 0; it < 3; ++it) {
      w.pen.clear();
      for (int k = 0; k < K_; ++k) {
        ContactKinematics& c = w.pk[static_cast<std::size_t>(k)];
        m_.compute_contact(k, t + h, q, v, c);
        if (c.normal_defined && c.d_N < 0.0) w.pen.push_back(k);
      }
      const int np = static_cast<int>(w.pen.size());
      if (np == 0) break;
      for (int a = 0; a < np; ++a)
        w.Xp.col(a) = w.pk[static_cast<std::size_t>(w.pen[static_cast<std::size_t>(a)])].W_N;
      if (o_.project_with_mass) m_.solve_mass(q, w.Xp.leftCols(np));
      SmallMat G(np, np);
      SmallVec rhs(np);
      for (int a = 0; a < np; ++a) {
        const ContactKinematics& ca =
            w.pk[static_cast<std::size_t>(w.pen[static_cast<std::size_t>(a)])];
        rhs[a] = -ca.d_N;
        for (int b = 0; b < np; ++b) G(a, b) = ca.W_N.dot(w.Xp.col(b));
      }
      if (!solve_small(G, rhs)) break;  // redundant constraints: left as they are
      for (int a = 0; a < np; ++a) q += w.Xp.col(a) * rhs[a];
    }
  }
  if (!all_finite(q) || !all_finite(v)) {
    message = fmt::format("non-finite state at t = {:.17g}", t + h);
    return StepOutcome::NonFinite;
  }
  // the impulses' work with the mid-step velocity, contact by contact
  dv_ = 0.5 * (v_ + v);
  bool impulse_free = true;
  for (int k = 0; k < K_; ++k) {
    ContactStep& cs = r.contacts[static_cast<std::size_t>(k)];
    cs.v_N_before = w.cik[static_cast<std::size_t>(k)].v_N;
  }
  if (solved) {
    for (int a = 0; a < na; ++a) {
      const auto ia = static_cast<std::size_t>(a);
      const int k = w.act[ia];
      const ContactKinematics& c = w.cik[static_cast<std::size_t>(k)];
      const double rN = w.rN[ia], rT = w.rT[ia];
      ContactStep& cs = r.contacts[static_cast<std::size_t>(k)];
      cs.P_N = rN;
      cs.P_T = rT;
      cs.F_N = rN / h;
      cs.F_T = rT / h;
      cs.phase = rN != 0.0 || rT != 0.0 ? w.mode[ia] : Phase::Free;
      if (rN != 0.0 || rT != 0.0) {
        impulse_free = false;
        r.contact_work +=
            rN * (w.WNk[ia].dot(dv_) + 0.5 * (c.b_N + w.bN1k[static_cast<std::size_t>(k)])) +
            rT * (w.WTk[ia].dot(dv_) + 0.5 * (c.b_T + w.bT1k[static_cast<std::size_t>(k)]));
      }
    }
  }
  r.a = (v - v_) / h;
  v_prev_ = v_;
  q_ = q;
  v_ = v;
  prev_impulse_free_ = impulse_free;
  r.index = ++index_;
  r.q = q_;
  r.v = v_;
  return StepOutcome::Ok;
}

template <>
StepOutcome MoreauJean<Eigen::Dynamic, true>::step(double t, StepReport& r, std::string& message) {
  return step_multi(t, r, message);
}
template <>
StepOutcome MoreauJean<9, true>::step(double t, StepReport& r, std::string& message) {
  return step_multi(t, r, message);
}

std::unique_ptr<Stepper> make_moreau_jean_multi(const LagrangianModel& m,
                                                const FixedStepOptions& o) {
  // the rigid rotor with two planes on sprung rings (9 dofs): fixed-size vectors, as the
  // one-plane rotor's 7 (moreau_jean.cpp)
  if (m.num_dofs() == 9) return std::make_unique<MoreauJean<9, true>>(m, o);
  return std::make_unique<MoreauJean<Eigen::Dynamic, true>>(m, o);
}

}  // namespace rubdyn::detail
