// The derivative of a run of the event-driven flow with respect to its initial state, from the
// flow's sensitivities (hybrid/flow_sensitivity.hpp; docs/orbits.md section 7): the variational
// equations of every phase of the run, integrated along it, and the saltation matrix of every
// event. It lives beside the engine because it evaluates the engine's own phases (PhaseEval) and
// impact decisions (ContactDecider); its CVODE session is the engine's RAII wrapper
// (cvode_session.hpp).
#include "rubdyn/hybrid/flow_sensitivity.hpp"

#include <fmt/format.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <vector>

#include "contact_decisions.hpp"
#include "cvode_session.hpp"
#include "phase_eval.hpp"
#include "phase_session.hpp"

namespace rubdyn {

namespace {

using detail::ContactDecider;
using detail::ContactSet;
using detail::Modes;
using detail::PhaseContext;
using detail::PhaseEval;

// Central differences of the vector field along a column of V, and of the witness and the
// impact decision along a state direction, take this step of the direction's scaled size
// (|D^-1 u|_inf). The functions differentiated are smooth at the gap's scale (the unit of D), so
// the truncation error is ~h^2 = 4e-11 relative and the round-off ~eps / h = 3.5e-11: the
// cube root of eps balances the two.
constexpr double kVariationalStep = 6e-6;

Modes modes_of(const Sample& s) {
  Modes m;
  m.K = static_cast<int>(s.contacts.size());
  for (int k = 0; k < m.K; ++k) m[k] = s.contacts[static_cast<std::size_t>(k)].phase;
  return m;
}

// The variational equations of one run, at one tolerance.
class Variational {
 public:
  Variational(const LagrangianModel& m, VecIn D, int d, double rtol, double atol_q)
      : n_(m.num_dofs()),
        N_(2 * n_),
        d_(d),
        eval_(m, m.contact_count()),
        laws_(),
        D_(D),
        Jf_(Mat::Zero(N_, N_)),
        A_(Mat::Zero(N_, N_)),
        xp_(N_),
        xm_(N_),
        f_(N_),
        fp_(N_),
        fm_(N_) {
    for (int k = 0; k < m.contact_count(); ++k) laws_.push_back(m.contact_law(k));
    const int size = N_ * (1 + d_);
    rtol_.assign(static_cast<std::size_t>(size), rtol);
    atol_.resize(static_cast<std::size_t>(size));
    // x's absolute tolerance per component: atol_q per gap scale, i.e. atol_q D_i / L; every
    // column of V is a derivative of x per unit of a scaled coordinate, of the size of D, so
    // its rows are weighted as x's.
    const double L = m.gap_scale(0);
    for (int c = 0; c <= d_; ++c)
      for (int i = 0; i < N_; ++i) atol_[static_cast<std::size_t>(c * N_ + i)] = atol_q * D_(i) / L;
    detail::CvodeConfig cfg;
    cfg.n = size;
    cfg.method = detail::CvodeMethod::BDF;
    cfg.rtol = rtol_.data();
    cfg.atol = atol_.data();
    cfg.max_steps = 1'000'000;
    detail::CvodeCallbacks cb;
    cb.rhs = &Variational::rhs;
    cb.lsys = &Variational::lsys;
    cb.lsolve = &Variational::lsolve;
    cb.user = this;
    cv_ = std::make_unique<detail::CvodeSession>(cfg, cb);
    y_.resize(size);
  }

  /// Integrates (x, V) from t_a to t_b in `modes`; x and V in and out. False: CVODE failed
  /// (message in why).
  bool advance(double t_a, double t_b, const Modes& modes, Vec& x, Mat& V, std::string& why) {
    if (t_b <= t_a) return true;
    modes_ = modes;
    y_.head(N_) = x;
    for (int j = 0; j < d_; ++j) y_.segment(N_ * (1 + j), N_) = V.col(j);
    cv_->restart(t_a, y_.data(), 0, nullptr, false, 0.0, t_b);
    double t = t_a;
    const auto st = cv_->advance(t_b, t, y_.data());
    if (st != detail::CvodeSession::Status::Reached || failed_) {
      why = failed_ ? "the phase's contact problem is singular along the orbit (Painleve)"
                    : "CVODE: " + cv_->last_error();
      return false;
    }
    x = y_.head(N_);
    for (int j = 0; j < d_; ++j) V.col(j) = y_.segment(N_ * (1 + j), N_);
    return true;
  }

  /// The vector field f = (v, a) of `modes` at (t, x). False: singular (Painleve).
  bool field(double t, VecIn x, const Modes& modes, Vec& f) {
    if (!eval_.dynamics(t, x.head(n_), x.tail(n_), modes, laws_)) return false;
    f.head(n_) = x.tail(n_);
    f.tail(n_) = eval_.a();
    return true;
  }
  PhaseEval& eval() { return eval_; }
  const std::vector<ContactLaw>& laws() const { return laws_; }
  long steps() const { return cv_->stats().steps; }

 private:
  double step_along(VecIn u) const {
    const double s = (u.array() / D_.array()).abs().maxCoeff();
    return s > 0.0 ? kVariationalStep / s : 0.0;
  }
  static int rhs(double t, const double* y, double* ydot, void* user) {
    auto& self = *static_cast<Variational*>(user);
    const int N = self.N_;
    const Eigen::Map<const Vec> x(y, N);
    Eigen::Map<Vec> out(ydot, N * (1 + self.d_));
    if (!self.field(t, x, self.modes_, self.f_)) {
      self.failed_ = true;
      return 1;
    }
    out.head(N) = self.f_;
    for (int j = 0; j < self.d_; ++j) {
      const Eigen::Map<const Vec> Vj(y + N * (1 + j), N);
      auto dj = out.segment(N * (1 + j), N);
      const double h = self.step_along(Vj);
      if (h == 0.0) {
        dj.setZero();
        continue;
      }
      self.xp_ = x + h * Vj;
      self.xm_ = x - h * Vj;
      if (!self.field(t, self.xp_, self.modes_, self.fp_) ||
          !self.field(t, self.xm_, self.modes_, self.fm_)) {
        self.failed_ = true;
        return 1;
      }
      dj = (self.fp_ - self.fm_) / (2.0 * h);
      dj.head(self.n_) = Vj.tail(self.n_);  // the kinematic rows are exact
    }
    return 0;
  }
  // Newton on the augmented system with the block-diagonal matrix diag(I - gamma f_x): the
  // coupling of V's rows to x (second derivatives of f) is left out, as CVODES' simultaneous
  // corrector does; f_x by central differences along the unit directions of D.
  static int lsys(double t, const double* y, double gamma, int jok, int* jcur, void* user) {
    auto& self = *static_cast<Variational*>(user);
    const int N = self.N_;
    const Eigen::Map<const Vec> x(y, N);
    if (!jok) {
      for (int i = 0; i < N; ++i) {
        const double h = kVariationalStep * self.D_(i);
        self.xp_ = x;
        self.xm_ = x;
        self.xp_(i) += h;
        self.xm_(i) -= h;
        if (!self.field(t, self.xp_, self.modes_, self.fp_) ||
            !self.field(t, self.xm_, self.modes_, self.fm_))
          return 1;
        self.Jf_.col(i) = (self.fp_ - self.fm_) / (2.0 * h);
      }
      *jcur = 1;
    } else {
      *jcur = 0;
    }
    self.A_ = Mat::Identity(N, N) - gamma * self.Jf_;
    self.lu_.compute(self.A_);
    return 0;
  }
  static int lsolve(const double* b, double* xout, void* user) {
    auto& self = *static_cast<Variational*>(user);
    const int N = self.N_;
    for (int c = 0; c <= self.d_; ++c) {
      const Eigen::Map<const Vec> bc(b + N * c, N);
      Eigen::Map<Vec> xc(xout + N * c, N);
      xc = self.lu_.solve(bc);
    }
    return 0;
  }

  const int n_, N_, d_;
  PhaseEval eval_;
  std::vector<ContactLaw> laws_;
  Vec D_;
  Modes modes_;
  Mat Jf_, A_;
  Eigen::PartialPivLU<Mat> lu_;
  Vec xp_, xm_, f_, fp_, fm_, y_;
  std::vector<double> rtol_, atol_;
  std::unique_ptr<detail::CvodeSession> cv_;
  bool failed_ = false;
};

// The witness of an event as a function of the state: which one fired, and its value.
struct EventWitness {
  EventKind kind;
  int k;
  int cone_sign = 1;  // Slip: mu F_N - s F_T with s the sign of F_T at the event
  double value(PhaseEval& e, const std::vector<ContactLaw>& laws, const Modes& before, double t,
               VecIn x, bool& ok) const {
    const int n = static_cast<int>(x.size()) / 2;
    ok = true;
    switch (kind) {
      case EventKind::Impact:
      case EventKind::Contact: e.kinematics(t, x.head(n), x.tail(n)); return e.c(k).d_N;
      case EventKind::Stick:
      case EventKind::Reversal: e.kinematics(t, x.head(n), x.tail(n)); return e.c(k).v_t;
      case EventKind::Liftoff:
        ok = e.dynamics(t, x.head(n), x.tail(n), before, laws);
        return e.F_N(k);
      case EventKind::Slip:
        ok = e.dynamics(t, x.head(n), x.tail(n), before, laws);
        return laws[static_cast<std::size_t>(k)].mu * e.F_N(k) - cone_sign * e.F_T(k);
      default: ok = false; return 0.0;
    }
  }
};

class SaltationBuilder {
 public:
  SaltationBuilder(const LagrangianModel& m, const EventDrivenOptions& opt, VecIn D, double F_ref)
      : n_(m.num_dofs()), D_(D), ctx_(m, opt.rtol, opt.atol, opt.omega_lim), decider_(m, ctx_) {
    ctx_.F_ref = F_ref;
  }

  /// S at an event group: its first record `ev` (the trigger), the states before (x_m, modes
  /// `before`) and after (x_p, `after`). False with why.
  bool build(Variational& var, const EventRecord& ev, double t, VecIn x_m, const Modes& before,
             VecIn x_p, const Modes& after, double dt_ref, Mat& S, std::string& why) {
    const int N = 2 * n_;
    PhaseEval& e = var.eval();
    const auto& laws = var.laws();
    EventWitness w{ev.kind, ev.contact};
    switch (ev.kind) {
      case EventKind::Impact:
      case EventKind::Contact:
      case EventKind::Liftoff:
      case EventKind::Stick:
      case EventKind::Reversal: break;
      case EventKind::Slip: {
        bool ok = false;
        (void)w.value(e, laws, before, t, x_m, ok);
        w.cone_sign = e.F_T(ev.contact) >= 0.0 ? 1 : -1;
        break;
      }
      default:
        why = fmt::format("a {} event at t = {:.17g}: the return map has no derivative there",
                          to_string(ev.kind), t);
        return false;
    }
    Vec f_m(N), f_p(N);
    if (!var.field(t, x_m, before, f_m) || !var.field(t, x_p, after, f_p)) {
      why = fmt::format("the contact problem is singular at the {} event at t = {:.17g}",
                        to_string(ev.kind), t);
      return false;
    }
    // g_x by central differences along the scaled unit directions; g' along the flow before
    Vec gx(N);
    bool ok1 = true, ok2 = true;
    for (int i = 0; i < N; ++i) {
      const double h = kVariationalStep * D_(i);
      Vec xp = x_m, xm = x_m;
      xp(i) += h;
      xm(i) -= h;
      gx(i) =
          (w.value(e, laws, before, t, xp, ok1) - w.value(e, laws, before, t, xm, ok2)) / (2.0 * h);
      if (!ok1 || !ok2) {
        why = fmt::format("the witness of the {} event at t = {:.17g} cannot be evaluated",
                          to_string(ev.kind), t);
        return false;
      }
    }
    const double hs = kVariationalStep / std::max((f_m.array() / D_.array()).abs().maxCoeff(),
                                                  std::numeric_limits<double>::min());
    const double g_plus = w.value(e, laws, before, t + hs, Vec(x_m + hs * f_m), ok1);
    const double g_minus = w.value(e, laws, before, t - hs, Vec(x_m - hs * f_m), ok2);
    const double g_rate = (g_plus - g_minus) / (2.0 * hs);
    // the rate's scale: |g_x| |f-| (componentwise in the scaled state)
    const double rate_scale = (gx.array() * f_m.array()).abs().sum();
    if (!ok1 || !ok2 || !(std::abs(g_rate) > 1e-6 * rate_scale)) {
      why = fmt::format(
          "grazing: the {} witness of contact {} crosses with zero rate at t = {:.17g} "
          "(rate {:.3g} of its scale {:.3g}): the return map has no derivative there",
          to_string(ev.kind), ev.contact + 1, t, g_rate, rate_scale);
      return false;
    }
    const Mat P = Mat::Identity(N, N) - f_m * gx.transpose() / g_rate;
    if (ev.kind == EventKind::Impact || ev.kind == EventKind::Contact) {
      // the surface d_N = 0 does not move with time in the models (no explicit t in d_N), so
      // P's columns are tangent to it and R is evaluated at the event's time
      if (std::abs(g_rate - gx.dot(f_m)) > 1e-6 * rate_scale) {
        why = fmt::format("the contact surface moves with time at the impact at t = {:.17g}", t);
        return false;
      }
      Mat RP(N, N);
      Vec r_p(N), r_m(N);
      for (int i = 0; i < N; ++i) {
        const Vec u = P.col(i);
        const double s = (u.array() / D_.array()).abs().maxCoeff();
        if (s == 0.0) {
          RP.col(i).setZero();
          continue;
        }
        const double h = kVariationalStep / s;
        if (!reset(ev, t, Vec(x_m + h * u), before, after, dt_ref, r_p, why) ||
            !reset(ev, t, Vec(x_m - h * u), before, after, dt_ref, r_m, why))
          return false;
        RP.col(i) = (r_p - r_m) / (2.0 * h);
      }
      S = RP + f_p * gx.transpose() / g_rate;
    } else {
      S = P + f_p * gx.transpose() / g_rate;
    }
    return true;
  }

 private:
  // The engine's decision at the onset of contact ev.contact from x: the state after it, which
  // must end in `after` (else the decision is not smooth there).
  bool reset(const EventRecord& ev, double t, VecIn x, const Modes& before, const Modes& after,
             double dt_ref, Vec& out, std::string& why) {
    const Vec q = x.head(n_), v = x.tail(n_);
    const detail::Transition tr =
        decider_.arrive(t, q, v, before, ContactSet::of(ev.contact), ev.witness, dt_ref);
    if (!tr.ok || !(tr.next == after)) {
      why = fmt::format("the impact's decision at t = {:.17g} changes within the difference step{}",
                        t, tr.ok ? "" : ": " + tr.message);
      return false;
    }
    out.resize(2 * n_);
    out.head(n_) = tr.q;
    out.tail(n_) = tr.v;
    return true;
  }
  const int n_;
  Vec D_;
  PhaseContext ctx_;
  ContactDecider decider_;
};

}  // namespace

FlowSensitivity flow_sensitivity(const LagrangianModel& m, const EventDrivenOptions& opt,
                                 const std::vector<Sample>& smp,
                                 const std::vector<EventRecord>& events, double t_end, MatIn V0,
                                 VecIn D, double rtol) {
  FlowSensitivity res;
  std::string& why = res.why;
  const int d = static_cast<int>(V0.cols());
  const double atol = opt.atol * rtol / opt.rtol;
  if (smp.empty()) {
    why = "the run has no sample";
    return res;
  }
  Variational var(m, D, d, rtol, atol);
  double F_ref = 0.0;
  for (const Sample& s : smp)
    for (const ContactSample& c : s.contacts) F_ref = std::max(F_ref, std::abs(c.F_N));
  SaltationBuilder salt(m, opt, D, F_ref > 0.0 ? F_ref : 1.0);
  // the start: the last sample at the first time (after the integrator's decision there)
  std::size_t i = 0;
  while (i + 1 < smp.size() && smp[i + 1].t == smp[0].t) ++i;
  Vec x = stacked_state(smp[i]);
  Modes modes = modes_of(smp[i]);
  double t = smp[i].t;
  Mat& V = res.V;
  V = V0;
  const double dt_ref = 1e-6 * (t_end - t);
  std::size_t e = 0;
  while (e < events.size() && events[e].t <= t) ++e;  // the decision at the start
  while (e < events.size()) {
    const double te = events[e].t;
    if (te >= t_end) break;
    const EventRecord& trigger = events[e];
    while (e < events.size() && events[e].t == te) ++e;
    // the samples at te: the first is the state before the event, the last after it
    std::size_t a = i;
    while (a < smp.size() && smp[a].t < te) ++a;
    std::size_t b = a;
    while (b + 1 < smp.size() && smp[b + 1].t == te) ++b;
    if (a >= smp.size() || smp[a].t != te) {
      why = fmt::format("no sample of the run at its event at t = {:.17g}", te);
      return res;
    }
    if (!var.advance(t, te, modes, x, V, why)) return res;
    const Vec x_m = stacked_state(smp[a]), x_p = stacked_state(smp[b]);
    const Modes after = modes_of(smp[b]);
    Mat S;
    if (!salt.build(var, trigger, te, x_m, modes, x_p, after, dt_ref, S, why)) {
      res.not_smooth =
          why.rfind("grazing", 0) == 0 || why.find("changes within") != std::string::npos;
      return res;
    }
    V = S * V;
    x = x_p;
    modes = after;
    t = te;
    i = b;
    ++res.events;
  }
  if (!var.advance(t, t_end, modes, x, V, why)) return res;
  res.steps = var.steps();
  res.ok = true;
  return res;
}

}  // namespace rubdyn
