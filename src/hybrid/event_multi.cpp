// The event-driven integrator with K > 1 contacts (event_multi.hpp). The loop mirrors the
// one-contact integrator of event_driven.cpp (advance -> classify -> dispatch -> restart); the
// phases are tuples of contact modes and every decision is the K-contact problem of
// contact/contact_set.hpp.
#include "event_multi.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include "cvode_session.hpp"
#include "decision_tolerances.hpp"
#include "event_locator.hpp"
#include "mode_switching.hpp"
#include "phase_system.hpp"
#include "rubdyn/contact/contact_set.hpp"
#include "rubdyn/contact/min_norm.hpp"
#include "rubdyn/core/run_envelope.hpp"

namespace rubdyn::detail {

namespace {

using Status = CvodeSession::Status;
using CMap = Eigen::Map<const Vec>;
using VMap = Eigen::Map<Vec>;
// The small dense systems of the closed contacts (at most 2K unknowns, K <= kMaxSetK).
constexpr int kMaxSetK = 8;
using SmallMat =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 2 * kMaxSetK, 2 * kMaxSetK>;
using SmallVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 2 * kMaxSetK, 1>;

/// Solves G x = b in place: the minimum-norm solution when G is singular (redundant contacts:
/// their forces indeterminate, the motion not; contact/min_norm.hpp). False when the system is
/// inconsistent (a Painleve slip, or constraints that cannot all hold).
bool solve_dense(const SmallMat& G, SmallVec& b) {
  SmallVec x;
  const MinNormResult r = min_norm_solve<2 * kMaxSetK>(G, b, x, kSingularPivot);
  if (!r.consistent) return false;
  b = x;
  return true;
}

bool closed(Phase p) {
  return p != Phase::Free;
}
int slip_sign(Phase p) {
  return p == Phase::SlipPos ? 1 : -1;
}

/// Every contact's kinematics and the Delassus operator of all K contacts at one state:
/// B = M^{-1} (f, W_N0, W_T0, W_N1, ...), W = H B(:, 1:), b = H M^{-1} f + wdot (H: rows W_N,k,
/// W_T,k). Sized when built; compute() allocates nothing (with the model's structured solve).
struct MultiOps {
  MultiOps(int n, int K)
      : K(K),
        c(static_cast<std::size_t>(K), ContactKinematics(n)),
        B(Mat::Zero(n, 1 + 2 * K)),
        W(Mat::Zero(2 * K, 2 * K)),
        b(Vec::Zero(2 * K)) {}
  int K;
  std::vector<ContactKinematics> c;
  Mat B, W;
  Vec b;
  const ContactKinematics& at(int k) const { return c[static_cast<std::size_t>(k)]; }
  const Vec& row(int i) const { return i % 2 == 0 ? at(i / 2).W_N : at(i / 2).W_T; }
  void compute(const LagrangianModel& m, double t, VecIn q, VecIn v) {
    m.smooth_forces(t, q, v, B.col(0));
    for (int k = 0; k < K; ++k) {
      ContactKinematics& ck = c[static_cast<std::size_t>(k)];
      m.compute_contact(k, t, q, v, ck);
      B.col(1 + 2 * k) = ck.W_N;
      B.col(2 + 2 * k) = ck.W_T;
    }
    m.solve_mass(q, B);
    for (int i = 0; i < 2 * K; ++i) {
      const Vec& h = row(i);
      for (int j = 0; j < 2 * K; ++j) W(i, j) = h.dot(B.col(1 + j));
      const ContactKinematics& ck = at(i / 2);
      b(i) = h.dot(B.col(0)) + (i % 2 == 0 ? ck.wdot_N : ck.wdot_T);
    }
  }
  /// The speed (v_N or v_t) of row i.
  double speed(int i) const { return i % 2 == 0 ? at(i / 2).v_N : at(i / 2).v_t; }
};

/// A witness of one contact (k = -1: omega).
struct WitnessRef {
  Witness w = Witness::Gap;
  int k = -1;
};

/// What the sessions share with the integrator: the contacts' modes and laws, the witnesses.
struct Shared {
  int K = 0;
  std::vector<Phase> modes;
  std::vector<ContactLaw> laws;
  std::vector<SwitchTolerances> tol;
  std::vector<double> gap_offset;  ///< the Gap witness of contact k is d_N,k + gap_offset[k]
  std::vector<WitnessRef> list;
  std::vector<int> dirs;
  double F_ref = 1.0, omega_lim = 0.0;
  bool any_closed() const {
    return std::any_of(modes.begin(), modes.end(), [](Phase p) { return closed(p); });
  }
  void clear() {
    list.clear();
    dirs.clear();
  }
  void add(Witness w, int k, int dir) {
    list.push_back({w, k});
    dirs.push_back(dir);
  }
};

/// The contact forces and the acceleration in the modes of `sh` at an evaluated state: r (2K,
/// 0 for open contacts), a (n). False: the closed set's equations are singular.
struct ModeSolve {
  ModeSolve(int n, int K) : r(Vec::Zero(2 * K)), a(Vec::Zero(n)) {}
  Vec r, a;
  SmallMat G;
  SmallVec x;
  std::array<int, 2 * kMaxSetK> rows{}, cols{};
  bool solve(const MultiOps& op, const std::vector<Phase>& modes,
             const std::vector<ContactLaw>& laws) {
    // unknowns: r_N,k of a slipping contact (r_T,k = -mu s r_N,k), r_N,k and r_T,k of a sticking
    // one; equations: u_N,k = 0 (and u_T,k = 0 in stick), u = b + W r
    int m = 0;
    for (int k = 0; k < op.K; ++k) {
      const Phase p = modes[static_cast<std::size_t>(k)];
      if (!closed(p)) continue;
      rows[m] = 2 * k;
      cols[m++] = 2 * k;
      if (p == Phase::Stick) {
        rows[m] = 2 * k + 1;
        cols[m++] = 2 * k + 1;
      }
    }
    r.setZero();
    a = op.B.col(0);
    if (m == 0) return true;
    G.resize(m, m);
    x.resize(m);
    for (int i = 0; i < m; ++i) {
      x[i] = -op.b(rows[i]);
      for (int j = 0; j < m; ++j) {
        const int c = cols[j];
        const int k = c / 2;
        const Phase p = modes[static_cast<std::size_t>(k)];
        double g = op.W(rows[i], c);
        if (c % 2 == 0 && p != Phase::Stick)
          g -= laws[static_cast<std::size_t>(k)].mu * slip_sign(p) * op.W(rows[i], c + 1);
        G(i, j) = g;
      }
    }
    if (!solve_dense(G, x)) return false;
    for (int j = 0; j < m; ++j) r(cols[j]) = x[j];
    for (int k = 0; k < op.K; ++k) {
      const Phase p = modes[static_cast<std::size_t>(k)];
      if (closed(p) && p != Phase::Stick)
        r(2 * k + 1) = -laws[static_cast<std::size_t>(k)].mu * slip_sign(p) * r(2 * k);
    }
    a.noalias() += op.B.rightCols(2 * op.K) * r;
    return true;
  }
};

/// Projects (q, v) onto the constraints of the closed contacts of `modes` (positions: joint
/// Gauss-Newton steps along the W_N,k; velocities: mass-weighted onto v_N,k = 0 and, in stick or
/// when `tangential` says so, v_t,k = 0) and leaves `op` evaluated at the projected state.
struct Projector {
  Projector(int n, int K) : op(n, K), J(Mat::Zero(K, n)), d(Vec::Zero(K)) {}
  MultiOps op;
  Mat J;
  Vec d;
  SmallMat G;
  SmallVec x;
  std::array<int, 2 * kMaxSetK> rows{};
  /// `set`: the contacts on the constraint; `tangential`: those whose v_t is set to 0.
  void project(const LagrangianModel& m, double t, Vec& q, Vec& v, const std::vector<char>& set,
               const std::vector<char>& tangential, const std::vector<SwitchTolerances>& tol) {
    const int K = op.K;
    int nc = 0;
    for (int k = 0; k < K; ++k) nc += set[static_cast<std::size_t>(k)] ? 1 : 0;
    if (nc == 0) {
      op.compute(m, t, q, v);
      return;
    }
    for (int it = 0; it < 3; ++it) {
      bool done = true;
      int i = 0;
      for (int k = 0; k < K; ++k) {
        if (!set[static_cast<std::size_t>(k)]) continue;
        ContactKinematics& ck = op.c[static_cast<std::size_t>(k)];
        m.compute_contact(k, t, q, v, ck);
        if (!ck.normal_defined) return;
        d[i] = ck.d_N;
        J.row(i) = ck.W_N.transpose();
        if (std::abs(ck.d_N) > kProjectionRel * tol[static_cast<std::size_t>(k)].g0) done = false;
        ++i;
      }
      if (done) break;
      G.resize(nc, nc);
      x.resize(nc);
      for (int a = 0; a < nc; ++a) {
        x[a] = d[a];
        for (int b = 0; b < nc; ++b) G(a, b) = J.row(a).dot(J.row(b));
      }
      if (!solve_dense(G, x)) break;
      for (int a = 0; a < nc; ++a) q.noalias() -= J.row(a).transpose() * x[a];
    }
    op.compute(m, t, q, v);
    int mr = 0;
    for (int k = 0; k < K; ++k) {
      if (!set[static_cast<std::size_t>(k)]) continue;
      rows[mr++] = 2 * k;
      if (tangential[static_cast<std::size_t>(k)]) rows[mr++] = 2 * k + 1;
    }
    G.resize(mr, mr);
    x.resize(mr);
    for (int a = 0; a < mr; ++a) {
      x[a] = op.speed(rows[a]);
      for (int b = 0; b < mr; ++b) G(a, b) = op.W(rows[a], rows[b]);
    }
    if (!solve_dense(G, x)) return;
    for (int a = 0; a < mr; ++a) v.noalias() -= op.B.col(1 + rows[a]) * x[a];
    op.compute(m, t, q, v);
  }
};

/// One CVODE session: free flight in full coordinates (q, v, works; Adams or BDF, no contact
/// forces), the contact DAE in full coordinates (BDF with projection, the closed contacts of
/// the shared modes), or, with a RingChart, a contact phase in its reduced coordinates
/// (p, p', works) of size `dim` (ring_chart.hpp: closed contacts on sprung or fixed rings;
/// Adams or BDF, no projection: the constraints hold by construction). A reduced session serves
/// every mode tuple of its dimension: its error weights are set at each restart. Every buffer
/// is sized when built: rhs, roots and projection allocate nothing.
class MultiSystem {
 public:
  MultiSystem(const LagrangianModel& m, const Shared& sh, const SessionSettings& s, bool contact,
              const RingChart* chart = nullptr, int dim = 0)
      : m_(m),
        n_(m.num_dofs()),
        K_(sh.K),
        sh_(sh),
        contact_(contact),
        rheonomic_(m.rheonomic()),
        chart_(contact ? chart : nullptr),
        dim_(chart_ ? dim : n_),
        settings_(s),
        op_(n_, K_),
        ms_(n_, K_),
        pr_(n_, K_),
        q_(Vec::Zero(n_)),
        v_(Vec::Zero(n_)),
        p_(Vec::Zero(dim_)),
        pd_(Vec::Zero(dim_)),
        set_(static_cast<std::size_t>(K_), 0),
        tang_(static_cast<std::size_t>(K_), 0),
        forces_(static_cast<std::size_t>(K_)),
        lengths_(static_cast<std::size_t>(dim_), 0.0) {
    const int N = 2 * dim_ + kNw;
    rtol_.assign(static_cast<std::size_t>(N), s.rtol);
    atol_.assign(static_cast<std::size_t>(N), 1e-9);
    for (int i = 0; i < dim_; ++i) {
      atol_[static_cast<std::size_t>(i)] = s.atol_q;
      atol_[static_cast<std::size_t>(dim_ + i)] = s.atol_v;
    }
    ys_.assign(static_cast<std::size_t>(N), 0.0);
    scratch_.assign(static_cast<std::size_t>(N), 0.0);
    CvodeConfig c;
    c.n = N;
    const bool adams = s.adams && (!contact || chart_ != nullptr);
    c.method = adams ? CvodeMethod::Adams : CvodeMethod::BDF;
    c.fixed_point = adams && s.fixed_point;
    c.rtol = rtol_.data();
    c.atol = atol_.data();
    c.max_steps = s.max_steps;
    CvodeCallbacks cb;
    cb.rhs = chart_    ? &MultiSystem::rhs_reduced
             : contact ? &MultiSystem::rhs_contact
                       : &MultiSystem::rhs_free;
    cb.roots = &MultiSystem::roots;
    if (contact && !chart_) cb.proj = &MultiSystem::proj;
    cb.user = this;
    session_ = std::make_unique<CvodeSession>(c, cb);
  }

  CvodeSession& session() { return *session_; }
  const CvodeSession& session() const { return *session_; }
  double step_start() const { return session_->current_time() - session_->last_step(); }

  /// Projects (q, v) onto the shared modes' constraints (contact sessions) and restarts there;
  /// a reduced session restarts from the chart of the projected state, and (q, v) become its
  /// embedding (equal to the projected state to round-off).
  void restart(double t, Vec& q, Vec& v, const Works& w, double t_stop) {
    if (contact_) place(t, q, v);
    if (chart_) {
      chart_->plan(sh_.modes, plan_);  // the modes' eliminations, for every rhs of the phase
      chart_->chart(sh_.modes, plan_, q, v, anchor_, p_, pd_);
      chart_->embed(sh_.modes, plan_, anchor_, p_, pd_, q, v);
      VMap(ys_.data(), dim_) = p_;
      VMap(ys_.data() + dim_, dim_) = pd_;
      // error weights of this mode tuple's coordinates: a copied coordinate rtol |p| + atol_q,
      // an angle by the displacement it causes, (rtol g0 + atol_q) / L (phase_system.cpp's
      // rule); rates rtol |p'| + atol_v; works rtol |W| + 1e-9 J
      chart_->lengths(sh_.modes, plan_, lengths_);
      for (int i = 0; i < dim_; ++i) {
        const double L = lengths_[static_cast<std::size_t>(i)];
        rtol_[static_cast<std::size_t>(i)] = L > 0.0 ? 0.0 : settings_.rtol;
        atol_[static_cast<std::size_t>(i)] =
            L > 0.0 ? (settings_.rtol * settings_.g0 + settings_.atol_q) / L : settings_.atol_q;
      }
      session_->set_tolerances(rtol_.data(), atol_.data());
    } else {
      VMap(ys_.data(), n_) = q;
      VMap(ys_.data() + n_, n_) = v;
    }
    std::copy(w.begin(), w.end(), ys_.begin() + 2 * dim_);
    session_->restart(t, ys_.data(), static_cast<int>(sh_.list.size()), sh_.dirs.data(),
                      contact_ && !chart_, 0.0, t_stop);
  }
  Status advance(double tout, double& t, Vec& q, Vec& v, bool one_step) {
    const Status st = session_->advance(tout, t, ys_.data(), one_step);
    to_full(ys_.data(), q, v);
    return st;
  }
  /// The state at t inside the last step (projected onto the constraints in a contact phase;
  /// on them by construction in a reduced one).
  void interpolate(double t, Vec& q, Vec& v) const {
    session_->dky(t, 0, scratch_.data());
    to_full(scratch_.data(), q, v);
    if (contact_ && !chart_) place(t, q, v);
  }
  Works works() const {
    Works w{};
    std::copy_n(ys_.begin() + 2 * dim_, kNw, w.begin());
    return w;
  }
  Works works_at(double t) const {
    session_->dky(t, 0, scratch_.data());
    Works w{};
    std::copy_n(scratch_.begin() + 2 * dim_, kNw, w.begin());
    return w;
  }
  bool reduced() const { return chart_ != nullptr; }
  /// Evaluates the phase at a state of it (projected first in a contact phase): forces in
  /// ms().r, accelerations in ms().a, kinematics in ops(). False: singular closed set.
  bool evaluate(double t, Vec& q, Vec& v) const {
    if (contact_) {
      place(t, q, v);
      return ms_.solve(pr_.op, sh_.modes, sh_.laws);
    }
    op_.compute(m_, t, q, v);
    return ms_.solve(op_, sh_.modes, sh_.laws);
  }
  /// What the witnesses need: evaluate() in a contact phase; in free flight the contacts'
  /// kinematics only (no solve with M, forces 0).
  void evaluate_witnesses(double t, Vec& q, Vec& v) const {
    if (contact_) {
      evaluate(t, q, v);
      return;
    }
    for (int k = 0; k < K_; ++k) m_.compute_contact(k, t, q, v, op_.c[static_cast<std::size_t>(k)]);
    ms_.r.setZero();
  }
  const MultiOps& ops() const { return contact_ ? pr_.op : op_; }
  const ModeSolve& ms() const { return ms_; }
  /// The unscaled value of a witness at a state of the phase (after evaluate()).
  double witness_value(const WitnessRef& w, double t, const Vec& q, const Vec& v) const {
    if (w.w == Witness::Omega) return m_.spin(t, q, v) - sh_.omega_lim;
    const ContactKinematics& c = ops().at(w.k);
    const double mu = sh_.laws[static_cast<std::size_t>(w.k)].mu;
    const double FN = ms_.r(2 * w.k), FT = ms_.r(2 * w.k + 1);
    switch (w.w) {
      case Witness::Gap: return c.d_N + sh_.gap_offset[static_cast<std::size_t>(w.k)];
      case Witness::GapRate: return c.v_N;
      case Witness::NormalForce: return FN;
      case Witness::SlipSpeed: return c.v_t;
      case Witness::ConeUpper: return mu * FN - FT;
      case Witness::ConeLower: return mu * FN + FT;
      default: return 0.0;
    }
  }

 private:
  /// The full state of a session state y (the embedding of the chart in a reduced session).
  void to_full(const double* y, Vec& q, Vec& v) const {
    if (chart_) {
      chart_->embed(sh_.modes, plan_, anchor_, CMap(y, dim_), CMap(y + dim_, dim_), q, v);
    } else {
      q = CMap(y, n_);
      v = CMap(y + n_, n_);
    }
  }
  void place(double t, Vec& q, Vec& v) const {
    for (int k = 0; k < K_; ++k) {
      const Phase p = sh_.modes[static_cast<std::size_t>(k)];
      set_[static_cast<std::size_t>(k)] = closed(p) ? 1 : 0;
      tang_[static_cast<std::size_t>(k)] = p == Phase::Stick ? 1 : 0;
    }
    pr_.project(m_, t, q, v, set_, tang_, sh_.tol);
  }
  void powers(double t, VecIn q, VecIn v, VecIn a, const MultiOps& op, double* w) const {
    const SmoothPower p = m_.smooth_power(t, q, v);
    double friction = 0.0;
    for (int k = 0; k < K_; ++k) {
      forces_[static_cast<std::size_t>(k)] = {ms_.r(2 * k), ms_.r(2 * k + 1)};
      friction += ms_.r(2 * k + 1) * op.at(k).v_t;
    }
    w[0] = rheonomic_ ? m_.applied_power(t, q, v, a, forces_.data()) : p.external;
    w[1] = p.damping;
    w[2] = friction;
  }
  static int rhs_free(double t, const double* y, double* yd, void* user) {
    auto* self = static_cast<MultiSystem*>(user);
    const int n = self->n_;
    const CMap q(y, n), v(y + n, n);
    VMap qd(yd, n), f(yd + n, n);
    Eigen::Map<Mat> a(yd + n, n, 1);
    qd = v;
    self->m_.smooth_forces(t, q, v, f);
    self->m_.solve_mass(q, a);
    self->ms_.r.setZero();
    self->powers(t, q, v, a.col(0), self->op_, yd + 2 * n);
    return all_finite(a) ? 0 : 1;
  }
  static int rhs_contact(double t, const double* y, double* yd, void* user) {
    auto* self = static_cast<MultiSystem*>(user);
    const int n = self->n_;
    const CMap q(y, n), v(y + n, n);
    self->op_.compute(self->m_, t, q, v);
    if (!self->ms_.solve(self->op_, self->sh_.modes, self->sh_.laws)) return 1;
    VMap(yd, n) = v;
    VMap(yd + n, n) = self->ms_.a;
    self->powers(t, q, v, self->ms_.a, self->op_, yd + 2 * n);
    return all_finite(self->ms_.a) ? 0 : 1;
  }
  static int rhs_reduced(double t, const double* y, double* yd, void* user) {
    auto* self = static_cast<MultiSystem*>(user);
    const int d = self->dim_;
    self->to_full(y, self->q_, self->v_);
    self->op_.compute(self->m_, t, self->q_, self->v_);
    if (!self->ms_.solve(self->op_, self->sh_.modes, self->sh_.laws)) return 1;
    VMap(yd, d) = CMap(y + d, d);
    self->chart_->reduce(self->sh_.modes, self->plan_, self->q_, self->ms_.a, VMap(yd + d, d));
    self->powers(t, self->q_, self->v_, self->ms_.a, self->op_, yd + 2 * d);
    return all_finite(self->ms_.a) ? 0 : 1;
  }
  static int proj(double t, const double* y, double* corr, void* user) {
    auto* self = static_cast<MultiSystem*>(user);
    const int n = self->n_;
    self->q_ = CMap(y, n);
    self->v_ = CMap(y + n, n);
    self->place(t, self->q_, self->v_);
    VMap(corr, n) = self->q_ - CMap(y, n);
    VMap(corr + n, n) = self->v_ - CMap(y + n, n);
    std::fill(corr + 2 * n, corr + 2 * n + kNw, 0.0);
    return all_finite(self->q_) && all_finite(self->v_) ? 0 : -1;
  }
  static int roots(double t, const double* y, double* g, void* user) {
    const auto* self = static_cast<const MultiSystem*>(user);
    const Shared& sh = self->sh_;
    self->to_full(y, self->q_, self->v_);
    if (self->chart_) {  // on the constraints by construction: no projection
      self->pr_.op.compute(self->m_, t, self->q_, self->v_);
      self->ms_.solve(self->pr_.op, sh.modes, sh.laws);
    } else {
      self->evaluate_witnesses(t, self->q_, self->v_);
    }
    for (std::size_t i = 0; i < sh.list.size(); ++i) {
      const WitnessRef& w = sh.list[i];
      const double x = self->witness_value(w, t, self->q_, self->v_);
      double scale = 1.0;
      if (w.w == Witness::Omega) {
        scale = sh.omega_lim;
      } else {
        const SwitchTolerances& tl = sh.tol[static_cast<std::size_t>(w.k)];
        scale = w.w == Witness::Gap                                    ? tl.g0
                : w.w == Witness::GapRate || w.w == Witness::SlipSpeed ? tl.v_ref
                                                                       : sh.F_ref;
      }
      g[i] = x / scale;
    }
    return 0;
  }

  const LagrangianModel& m_;
  const int n_, K_;
  const Shared& sh_;
  const bool contact_, rheonomic_;
  const RingChart* chart_;  ///< reduced session: the model's chart; else null
  const int dim_;           ///< coordinates of the session state (n_ unless reduced)
  SessionSettings settings_;
  RingAnchor anchor_;
  RingChart::Plan plan_;  // the chart's eliminations for the modes of the last restart
  mutable MultiOps op_;
  mutable ModeSolve ms_;
  mutable Projector pr_;
  mutable Vec q_, v_, p_, pd_;
  mutable std::vector<char> set_, tang_;
  mutable std::vector<ContactForce> forces_;
  std::vector<double> lengths_;
  std::vector<double> rtol_, atol_, ys_;
  mutable std::vector<double> scratch_;
  std::unique_ptr<CvodeSession> session_;
};

class MultiIntegrator {
 public:
  MultiIntegrator(const LagrangianModel& m, const EventDrivenOptions& opt, OutputSink& sink)
      : m_(m),
        n_(m.num_dofs()),
        K_(m.contact_count()),
        opt_(opt),
        sink_(sink),
        guard_(opt.max_events_per_second),
        sample_(n_, K_, static_cast<int>(m.observables().size())),
        set_(n_, K_),
        kin_(n_),
        solver_(K_),
        q_restart_(Vec::Zero(n_)),
        v_restart_(Vec::Zero(n_)),
        q_tmp_(Vec::Zero(n_)),
        v_tmp_(Vec::Zero(n_)),
        q_ev_(Vec::Zero(n_)),
        v_ev_(Vec::Zero(n_)),
        deferred_(static_cast<std::size_t>(K_), 0),
        banded_(static_cast<std::size_t>(K_), 0),
        forces_(static_cast<std::size_t>(K_)) {
    sh_.K = K_;
    sh_.modes.assign(static_cast<std::size_t>(K_), Phase::Free);
    sh_.gap_offset.assign(static_cast<std::size_t>(K_), 0.0);
    for (int k = 0; k < K_; ++k) {
      sh_.laws.push_back(m.contact_law(k));
      sh_.tol.push_back(SwitchTolerances::derive(opt.rtol, opt.atol, m.gap_scale(k)));
    }
    sh_.omega_lim = opt.omega_lim;
    sh_.list.reserve(static_cast<std::size_t>(5 * K_ + 1));
    sh_.dirs.reserve(static_cast<std::size_t>(5 * K_ + 1));
    omega_pending_ = opt.omega_lim > 0.0 && m.spin_coordinate() >= 0;
  }

  RunSummary run(const MechanicalState& init, double t_end);

 private:
  const SwitchTolerances& tol(int k) const { return sh_.tol[static_cast<std::size_t>(k)]; }
  const ContactLaw& law(int k) const { return sh_.laws[static_cast<std::size_t>(k)]; }
  Phase& mode(int k) { return sh_.modes[static_cast<std::size_t>(k)]; }
  /// The phase the books (phase_time, phase_steps) count: the first closed contact's mode.
  Phase books() const {
    for (Phase p : sh_.modes)
      if (closed(p)) return p;
    return Phase::Free;
  }

  void open_sessions() {
    SessionSettings s;
    const SwitchTolerances& t0 = tol(0);
    s.rtol = opt_.rtol;
    s.atol_q = opt_.atol;
    s.atol_v = t0.atol_v;
    s.g0 = t0.g0;
    s.adams = opt_.adams;
    s.fixed_point = opt_.fixed_point;
    s.max_steps = std::min(opt_.max_steps_per_call, kCheckSteps);
    free_ = std::make_unique<MultiSystem>(m_, sh_, s, false);
    contact_ = std::make_unique<MultiSystem>(m_, sh_, s, true);
    // minimal coordinates (ring_chart.hpp): one session per dimension n - r, r = 1 .. 2K
    // coordinates removed, built here so that no switch allocates
    chart_ = opt_.contact_phases == ContactFormulation::Reduced ? m_.ring_chart() : nullptr;
    if (chart_ != nullptr && chart_->contact_count() == K_) {
      SessionSettings sr = s;
      sr.adams = opt_.contact_adams;
      reduced_.resize(static_cast<std::size_t>(2 * K_ + 1));
      for (int r = 1; r <= 2 * K_ && r < n_; ++r)
        reduced_[static_cast<std::size_t>(r)] =
            std::make_unique<MultiSystem>(m_, sh_, sr, true, chart_, n_ - r);
    } else {
      chart_ = nullptr;
    }
  }
  /// The session of the shared modes: free flight, a reduced contact phase where the chart
  /// composes, the projection formulation otherwise.
  MultiSystem* session_for_modes() {
    if (!sh_.any_closed()) return free_.get();
    if (chart_ != nullptr && chart_->applies(sh_.modes)) {
      const auto r = static_cast<std::size_t>(n_ - chart_->dim(sh_.modes));
      if (r < reduced_.size() && reduced_[r]) return reduced_[r].get();
    }
    return contact_.get();
  }

  void build_witnesses() {
    sh_.clear();
    for (int k = 0; k < K_; ++k) {
      const auto ku = static_cast<std::size_t>(k);
      switch (sh_.modes[ku]) {
        case Phase::Free:
          // after a release the gap and its rate start at degenerate zeros (event_driven.cpp,
          // build_witnesses): the same banding, per contact
          sh_.gap_offset[ku] = banded_[ku] ? tol(k).graze_tol : 0.0;
          sh_.add(Witness::Gap, k, -1);
          if (!deferred_[ku]) sh_.add(Witness::GapRate, k, +1);
          break;
        case Phase::SlipPos:
        case Phase::SlipNeg:
          sh_.add(Witness::NormalForce, k, -1);
          if (law(k).has_friction())
            sh_.add(Witness::SlipSpeed, k, sh_.modes[ku] == Phase::SlipPos ? -1 : +1);
          break;
        case Phase::Stick:
          sh_.add(Witness::NormalForce, k, -1);
          sh_.add(Witness::ConeUpper, k, -1);
          sh_.add(Witness::ConeLower, k, -1);
          break;
      }
    }
    if (omega_pending_) sh_.add(Witness::Omega, -1, +1);
  }

  /// Starts the phase of the shared modes at (t, q, v) (projected onto its constraints).
  void start_phase(double t, const Vec& q, const Vec& v) {
    phase_start_ = t;
    build_witnesses();
    cur_ = session_for_modes();
    if (&q != &q_restart_) q_restart_ = q;
    if (&v != &v_restart_) v_restart_ = v;
    if (sh_.any_closed()) {
      cur_->evaluate(t, q_restart_, v_restart_);
      double F = 0.0;
      for (int k = 0; k < K_; ++k) F = std::max(F, std::abs(cur_->ms().r(2 * k)));
      sh_.F_ref = std::max({sh_.F_ref, F, kForceRefFloor});
    } else {
      sh_.F_ref = 0.0;
    }
    t_restart_ = t;
    cur_->restart(t, q_restart_, v_restart_, work_, t_end_);
    books_ = books();
  }

  void arm(double t, const Vec& q, const Vec& v) {
    bool changed = false;
    ContactKinematics& c = kin_;
    for (int k = 0; k < K_; ++k) {
      const auto ku = static_cast<std::size_t>(k);
      if (!deferred_[ku] && !banded_[ku]) continue;
      m_.compute_contact(k, t, q, v, c);
      if (deferred_[ku] && c.v_N > tol(k).v_tol) {
        deferred_[ku] = 0;
        changed = true;
      }
      if (banded_[ku] && c.d_N > tol(k).graze_tol) {
        banded_[ku] = 0;
        changed = true;
      }
    }
    if (!changed) return;
    build_witnesses();
    cur_->session().set_roots(static_cast<int>(sh_.list.size()), sh_.dirs.data());
  }
  bool arming() const {
    for (int k = 0; k < K_; ++k)
      if (deferred_[static_cast<std::size_t>(k)] || banded_[static_cast<std::size_t>(k)])
        return true;
    return false;
  }

  void close_phase(double t) {
    emit_outputs_before(t);
    work_ = cur_->works_at(t);
    end_phase(t);
  }
  void end_phase(double t) {
    env_->summary().phase_time[static_cast<int>(books_)] += t - phase_start_;
  }

  // ---- output ----
  void emit_sample(double t, const Vec& q, const Vec& v) {
    Sample& s = sample_;
    s.t = t;
    s.q = q;
    s.v = v;
    cur_->evaluate(t, s.q, s.v);
    const MultiOps& op = cur_->ops();
    const ModeSolve& ms = cur_->ms();
    const double omega = m_.spin(t, s.q, s.v);
    RunMonitor& mon = env_->monitor();
    mon.observe_spin(t, omega);
    for (int k = 0; k < K_; ++k) {
      ContactSample& cs = s.contacts[static_cast<std::size_t>(k)];
      const ContactKinematics& c = op.at(k);
      cs.F_N = ms.r(2 * k);
      cs.F_T = ms.r(2 * k + 1);
      cs.d_N = c.d_N;
      cs.v_N = c.v_N;
      cs.v_t = c.v_t;
      cs.phase = sh_.modes[static_cast<std::size_t>(k)];
      forces_[static_cast<std::size_t>(k)] = {cs.F_N, cs.F_T};
      mon.observe_contact(c.d_N, c.v_N, cs.F_N, cs.F_T, closed(cs.phase), law(k).mu);
      env_->check_speed(t, c.v_N, c.v_t);
    }
    if (s.observables.size() > 0)
      m_.compute_observables(t, s.q, s.v, ms.a, forces_.data(), s.observables);
    env_->output(s);
  }
  void emit_outputs_before(double t) {
    while (env_->next_output() < t && env_->next_output() < t_end_) {
      const double tout = env_->next_output();
      cur_->interpolate(tout, q_tmp_, v_tmp_);
      emit_sample(tout, q_tmp_, v_tmp_);
      env_->advance_output();
    }
  }
  void fail(Termination why, const std::string& msg) { env_->fail(why, msg); }
  bool guard(double t) {
    if (auto why = guard_.record(t)) {
      fail(Termination::Chattering, *why);
      return false;
    }
    return true;
  }

  // ---- locating ----
  double locate(const WitnessRef& w, double hi, Vec& q, Vec& v) {
    auto g = [&](double t) {
      cur_->interpolate(t, q_tmp_, v_tmp_);
      cur_->evaluate_witnesses(t, q_tmp_, v_tmp_);
      return cur_->witness_value(w, t, q_tmp_, v_tmp_);
    };
    const double lo = cur_->step_start();
    const double t = last_time_with_sign(lo, hi, g(lo), g(hi), g);
    cur_->interpolate(t, q, v);
    return t;
  }
  /// Contact onset of contact k found at hi: the last time with d_N,k > 0 in the step (after a
  /// release: the banded witness, as in the one-contact integrator).
  double locate_onset(int k, double hi, Vec& q, Vec& v) {
    ContactKinematics& c = kin_;
    auto gap = [&](double t) {
      cur_->interpolate(t, q_tmp_, v_tmp_);
      m_.compute_contact(k, t, q_tmp_, v_tmp_, c);
      return c.d_N;
    };
    const double lo = cur_->step_start();
    const double g_lo = gap(lo);
    if (sh_.gap_offset[static_cast<std::size_t>(k)] == 0.0 || g_lo > 0.0) {
      const double t = last_time_with_sign(lo, hi, g_lo, gap(hi), gap);
      cur_->interpolate(t, q, v);
      return t;
    }
    return locate({Witness::Gap, k}, hi, q, v);
  }

  // ---- decisions ----
  struct Pending {  // one contact's event being built
    bool active = false;
    EventRecord e;
  };

  /// The contacts at the constraint: the closed ones, those in `extra`, and any open contact
  /// within its position tolerance of 0 that is not opening.
  void constraint_set(const MultiOps& op, std::vector<char>& S) const {
    for (int k = 0; k < K_; ++k) {
      const auto ku = static_cast<std::size_t>(k);
      const ContactKinematics& c = op.at(k);
      if (closed(sh_.modes[ku])) S[ku] = 1;
      if (!S[ku] && c.normal_defined && c.d_N <= tol(k).graze_tol && c.v_N <= tol(k).v_tol)
        S[ku] = 1;
    }
  }

  /// Contact onset: (q, v-) with the contacts `S` at the constraint (S[k] set for the arriving
  /// ones; constraint_set adds the rest). Impact of those closing, then the decision.
  bool arrive(double t, const Vec& q_in, const Vec& v_in, std::vector<char> S,
              const std::string& witness) {
    Vec q = q_in, v = v_in;
    set_.op.compute(m_, t, q, v);
    constraint_set(set_.op, S);
    no_tangential_.assign(static_cast<std::size_t>(K_), 0);
    set_.project(m_, t, q, v, S, no_tangential_, sh_.tol);  // positions (and v_N of the set)
    // (the velocity projection above removes the closing speed: redo from v-, positions only)
    v = v_in;
    set_.op.compute(m_, t, q, v);
    emit_sample(t, q, v);
    const MultiOps& op = set_.op;
    std::vector<Pending> ev(static_cast<std::size_t>(K_));
    std::vector<int> idx;
    bool impact = false;
    for (int k = 0; k < K_; ++k) {
      const auto ku = static_cast<std::size_t>(k);
      if (!S[ku]) continue;
      idx.push_back(k);
      const ContactKinematics& c = op.at(k);
      if (closed(sh_.modes[ku])) continue;
      Pending& p = ev[ku];
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
        // bands this contact's onset (event_driven.cpp, build_witnesses)
        band_next_release_[ku] = 1;
      }
    }
    if (!impact) return on_constraint(t, q, v, S, std::nullopt, false, kDecisionBandRel, ev);
    // the joint impulse problem of the contacts at the constraint
    const int m = static_cast<int>(idx.size());
    std::vector<char> plastic(static_cast<std::size_t>(K_), 0);
    Vec v_plus = v;
    const double T_minus = m_.kinetic_energy(t, q, v);
    for (int pass = 0; pass < 2; ++pass) {
      Mat Wm(2 * m, 2 * m);
      Vec u0(2 * m);
      std::vector<SetContact> sc(static_cast<std::size_t>(m));
      for (int a = 0; a < m; ++a) {
        const int k = idx[static_cast<std::size_t>(a)];
        const auto ku = static_cast<std::size_t>(k);
        const bool hits = ev[ku].active && ev[ku].e.kind == EventKind::Impact;
        const double en = hits && !plastic[ku] ? law(k).e_n : 0.0;
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
      if (!has_solution(out)) return painleve(t, idx, "impact problem without solution");
      if (out == SetOutcome::NonUnique) log_painleve(t, idx, "several impulses solve the impact");
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
      // Zeno, per contact: a bounce below the position tolerance is truncated (event_driven.cpp)
      set_.op.compute(m_, t, q, v_plus);
      bool again = false;
      for (int k : idx) {
        const auto ku = static_cast<std::size_t>(k);
        const Pending& p = ev[ku];
        if (plastic[ku] || !p.active || p.e.kind != EventKind::Impact || !law(k).has_restitution())
          continue;
        const double vN = set_.op.at(k).v_N, bN = set_.op.b(2 * k);
        if (!(vN > tol(k).v_tol)) continue;
        const double height = bN < 0.0 ? vN * vN / (-2.0 * bN) : 1e300;
        if (height >= tol(k).graze_tol) continue;
        plastic[ku] = 1;
        again = true;
        EventRecord& e = ev[ku].e;
        e.kind = EventKind::Zeno;
        e.t_accumulation = t + 2.0 * vN / (-bN * (1.0 - law(k).e_n));
        e.note = fmt::format(
            "accumulation of impacts: bounce height {:.3g} m below tolerance; extrapolated "
            "accumulation time {:.17g} s",
            height, e.t_accumulation);
      }
      if (!again) break;
      set_.op.compute(m_, t, q, v);  // the second pass solves from v- again
    }
    work_impacts_ += m_.kinetic_energy(t, q, v_plus) - T_minus;
    // Contacts leaving with v_N above the velocity tolerance open; the others are decided. A
    // contact pushed off by the others' impulses (e_n = 0 at it: no restitution truncation above)
    // whose flight would rise less than the position tolerance under its free normal
    // acceleration stays on the constraint, its v_N projected to 0 with the others'
    // (on_constraint): the joint impacts of coupled contacts can accumulate, each pushing the
    // other off ever more gently (two rings at one plane: measured pushes falling from 1e-4 to
    // 1e-6 m/s within 7 us), and a flight below the integrator's resolution would be missed by
    // the gap's witness. Every contact that does leave starts with the banded onset witness
    // (d_N + graze_tol, unbanded once the gap exceeds graze_tol: arm()), since it leaves from a
    // gap that is 0 only to round-off.
    set_.op.compute(m_, t, q, v_plus);
    std::vector<char> C(static_cast<std::size_t>(K_), 0);
    for (int k : idx) {
      const auto ku = static_cast<std::size_t>(k);
      const double vN = set_.op.at(k).v_N, bN = set_.op.b(2 * k);
      Pending& p = ev[ku];
      const double height = bN < 0.0 ? vN * vN / (-2.0 * bN) : 1e300;
      if (vN <= tol(k).v_tol || height < tol(k).graze_tol) {
        C[ku] = 1;
        if (vN > tol(k).v_tol && p.active)
          p.e.note += fmt::format(
              "; left at {:.3g} m/s by the joint impulses, a flight of "
              "{:.3g} m below tolerance: kept on the constraint",
              vN, height);
        continue;
      }
      banded_[ku] = 1;
      // a bounce (or a closed contact pushed off by the others' impulses)
      if (!p.active) {
        p.active = true;
        p.e.t = t;
        p.e.contact = k;
        p.e.kind = EventKind::Liftoff;
        p.e.phase_before = sh_.modes[ku];
        p.e.witness = witness;
        p.e.note = "opened by the impulses of an impact at another contact";
      }
      p.e.v_N_plus = vN;
      p.e.v_t_plus = set_.op.at(k).v_t;
      p.e.phase_after = Phase::Free;
      mode(k) = Phase::Free;
    }
    return on_constraint(t, q, v_plus, C, std::nullopt, false, kDecisionBandRel, ev);
  }

  /// The contacts `C` on the constraint at (q, v): velocities projected (v_N,k = 0; v_t,k = 0 near
  /// stick or for the ending contact at the end of its slip), then the acceleration-level problem
  /// of the set picks every contact's mode. `ending`: (contact, mode) a witness ended.
  bool on_constraint(double t, const Vec& q_in, const Vec& v_in, const std::vector<char>& C,
                     std::optional<std::pair<int, Phase>> ending, bool at_slip_zero, double rel_tol,
                     std::vector<Pending>& ev) {
    Vec q = q_in, v = v_in;
    std::vector<char> tang(static_cast<std::size_t>(K_), 0);
    set_.op.compute(m_, t, q, v);
    for (int k = 0; k < K_; ++k) {
      const auto ku = static_cast<std::size_t>(k);
      if (!C[ku] || !law(k).has_friction()) continue;
      const bool slip_zero = at_slip_zero && ending && ending->first == k;
      tang[ku] = slip_zero || std::abs(set_.op.at(k).v_t) <= tol(k).v_tol ? 1 : 0;
    }
    const double T_before = m_.kinetic_energy(t, q, v);
    set_.project(m_, t, q, v, C, tang, sh_.tol);
    work_impacts_ += m_.kinetic_energy(t, q, v) - T_before;  // the (tiny) projection
    const MultiOps& op = set_.op;
    std::vector<int> idx;
    for (int k = 0; k < K_; ++k)
      if (C[static_cast<std::size_t>(k)]) idx.push_back(k);
    const int m = static_cast<int>(idx.size());
    std::vector<Phase> next = sh_.modes;
    for (int k : idx) next[static_cast<std::size_t>(k)] = Phase::Free;
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
        if (law(k).has_friction() && std::abs(vt) > tol(k).v_tol) s.sliding = vt > 0.0 ? 1 : -1;
        if (ending && ending->first == k) s.excluded = ending->second;
        for (int b = 0; b < m; ++b) {
          const int l = idx[static_cast<std::size_t>(b)];
          Wm.block<2, 2>(2 * a, 2 * b) = op.W.block<2, 2>(2 * k, 2 * l);
        }
      }
      const double F_scale = ending ? sh_.F_ref : 0.0;
      SetBand band;
      band.tol_u = rel_tol * (acc + F_scale * diag_max) + 1e-300;
      band.tol_r = band.tol_u / std::max(diag_min, 1e-300);
      const SetOutcome out = solver_.solve(Wm, u0, sc, band);
      if (!has_solution(out)) return painleve(t, idx, "no consistent set of contact modes");
      if (out == SetOutcome::NonUnique)
        log_painleve(t, idx, "several consistent sets of contact modes; the tie rule picked one");
      for (int a = 0; a < m; ++a)
        next[static_cast<std::size_t>(idx[static_cast<std::size_t>(a)])] = solver_.mode(a);
    }
    // the events: every contact whose mode changes, and every pending one
    for (int k = 0; k < K_; ++k) {
      const auto ku = static_cast<std::size_t>(k);
      Pending& p = ev[ku];
      const Phase before = sh_.modes[ku], after = next[ku];
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
        p.e.witness = is_ending ? ending_witness_ : "joint decision at another contact's event";
        const bool slip_before = before == Phase::SlipPos || before == Phase::SlipNeg;
        p.e.kind = after == Phase::Free             ? EventKind::Liftoff
                   : after == Phase::Stick          ? EventKind::Stick
                   : slip_before && after != before ? EventKind::Reversal
                                                    : EventKind::Slip;
      }
      if (C[ku]) {
        p.e.v_N_plus = op.at(k).v_N;
        p.e.v_t_plus = op.at(k).v_t;
        p.e.phase_after = after;
      }
    }
    // releases: a contact that opens on the constraint starts with degenerate witnesses
    for (int k = 0; k < K_; ++k) {
      const auto ku = static_cast<std::size_t>(k);
      if (C[ku] && next[ku] == Phase::Free) {
        deferred_[ku] = 1;
        banded_[ku] = band_next_release_[ku];
      }
      band_next_release_[ku] = 0;
    }
    sh_.modes = next;
    start_phase(t, q, v);
    // forces after the event, from the phase just started
    cur_->evaluate(t, q_restart_, v_restart_);
    for (int k = 0; k < K_; ++k) {
      Pending& p = ev[static_cast<std::size_t>(k)];
      if (!p.active) continue;
      p.e.F_N = cur_->ms().r(2 * k);
      p.e.F_T = cur_->ms().r(2 * k + 1);
      env_->event(p.e);
    }
    emit_sample(t, q_restart_, v_restart_);
    return guard(t);
  }

  void log_painleve(double t, const std::vector<int>& idx, const std::string& what) {
    EventRecord e;
    e.t = t;
    e.kind = EventKind::Painleve;
    std::string who;
    for (std::size_t a = 0; a < idx.size(); ++a) {
      if (!solver_.involved(static_cast<int>(a))) continue;
      if (who.empty()) e.contact = idx[a];
      who += fmt::format("{}{}", who.empty() ? "" : ", ", idx[a] + 1);
    }
    e.note =
        fmt::format("{} (contacts involved: {}; set outcome {})", what,
                    who.empty() ? std::string("none named") : who, to_string(solver_.outcome()));
    env_->event(e);
    last_painleve_ = e.note;
  }
  bool painleve(double t, const std::vector<int>& idx, const std::string& what) {
    log_painleve(t, idx, what);
    fail(Termination::Painleve, fmt::format("at t = {:.17g}: {}", t, last_painleve_));
    return false;
  }

  bool on_gap_minimum(int k, double t, const Vec& q, const Vec& v, bool& restarted) {
    if (t - phase_start_ <= kPhaseStartRel * std::max(1.0, std::abs(t))) {
      ++env_->summary().suppressed_witnesses;
      return true;
    }
    q_tmp_ = q;
    v_tmp_ = v;
    cur_->evaluate(t, q_tmp_, v_tmp_);
    const ContactKinematics& c = cur_->ops().at(k);
    const SwitchTolerances& tl = tol(k);
    if (c.d_N > tl.graze_band) return true;
    EventRecord e = grazing_event(t, c);
    e.contact = k;
    if (c.d_N < -tl.graze_tol) {
      restarted = true;
      const double tc = locate_onset(k, t, q_ev_, v_ev_);
      close_phase(tc);
      std::vector<char> S(static_cast<std::size_t>(K_), 0);
      S[static_cast<std::size_t>(k)] = 1;
      return arrive(tc, q_ev_, v_ev_, S,
                    "v_N (gap minimum below 0: double crossing inside a step)");
    }
    // the normal acceleration of contact k in the running phase
    const double acc = c.W_N.dot(cur_->ms().a) + c.wdot_N;
    if (c.d_N > tl.graze_tol || acc >= 0.0) {
      e.phase_after = Phase::Free;
      e.note = "touch and go: the normal acceleration is >= 0";
      env_->event(e);
      return guard(t);
    }
    restarted = true;
    close_phase(t);
    emit_sample(t, q, v);
    std::vector<char> C(static_cast<std::size_t>(K_), 0);
    for (int l = 0; l < K_; ++l) C[static_cast<std::size_t>(l)] = closed(mode(l)) ? 1 : 0;
    C[static_cast<std::size_t>(k)] = 1;
    std::vector<Pending> ev(static_cast<std::size_t>(K_));
    ev[static_cast<std::size_t>(k)] = {true, e};
    return on_constraint(t, q, v, C, std::nullopt, false, kDecisionBandRel, ev);
  }

  bool on_contact_witness(const WitnessRef& w, double t_root) {
    const double t = locate(w, t_root, q_ev_, v_ev_);
    close_phase(t);
    emit_sample(t, q_ev_, v_ev_);
    std::vector<char> C(static_cast<std::size_t>(K_), 0);
    for (int l = 0; l < K_; ++l) C[static_cast<std::size_t>(l)] = closed(mode(l)) ? 1 : 0;
    std::vector<Pending> ev(static_cast<std::size_t>(K_));
    ending_witness_ = witness_name(w.w);
    return on_constraint(t, q_ev_, v_ev_, C, std::make_pair(w.k, mode(w.k)),
                         w.w == Witness::SlipSpeed, kWitnessBandRel, ev);
  }

  bool on_root(const WitnessRef& w, double t, const Vec& q, const Vec& v, bool& restarted) {
    if (w.w == Witness::Omega) {
      env_->monitor().set_omega_lim_time(t);
      omega_pending_ = false;
      return true;
    }
    if (w.w == Witness::GapRate) return on_gap_minimum(w.k, t, q, v, restarted);
    restarted = true;
    if (w.w != Witness::Gap) return on_contact_witness(w, t);
    const double tc = locate_onset(w.k, t, q_ev_, v_ev_);
    close_phase(tc);
    std::vector<char> S(static_cast<std::size_t>(K_), 0);
    S[static_cast<std::size_t>(w.k)] = 1;
    return arrive(tc, q_ev_, v_ev_, S, "d_N");
  }

  bool start(const MechanicalState& init) {
    const double t = init.t;
    set_.op.compute(m_, t, init.q, init.v);
    std::vector<char> S(static_cast<std::size_t>(K_), 0);
    bool any = false, closing = false;
    for (int k = 0; k < K_; ++k) {
      const ContactKinematics& c = set_.op.at(k);
      if (c.d_N < -tol(k).graze_tol) {
        fail(Termination::SolverFailure,
             fmt::format("initial state penetrates contact {}: d_N = {:.6g} m", k + 1, c.d_N));
        return false;
      }
      if (c.normal_defined && c.d_N <= tol(k).graze_tol && c.v_N <= tol(k).v_tol) {
        S[static_cast<std::size_t>(k)] = 1;
        any = true;
        closing = closing || c.v_N < -tol(k).v_tol;
      }
    }
    phase_start_ = t;
    if (!any) {
      cur_ = free_.get();
      start_phase(t, init.q, init.v);
      emit_sample(t, q_restart_, v_restart_);
      return true;
    }
    cur_ = free_.get();
    if (closing) return arrive(t, init.q, init.v, S, "initial state on the constraint, closing");
    std::vector<Pending> ev(static_cast<std::size_t>(K_));
    for (int k = 0; k < K_; ++k) {
      if (!S[static_cast<std::size_t>(k)]) continue;
      Pending& p = ev[static_cast<std::size_t>(k)];
      p.active = true;
      p.e.t = t;
      p.e.contact = k;
      p.e.kind = EventKind::Contact;
      p.e.witness = "initial state on the constraint";
    }
    return on_constraint(t, init.q, init.v, S, std::nullopt, false, kDecisionBandRel, ev);
  }

  const LagrangianModel& m_;
  const int n_, K_;
  const EventDrivenOptions& opt_;
  OutputSink& sink_;
  std::optional<RunEnvelope> env_;
  EventGuard guard_;
  Shared sh_;
  std::unique_ptr<MultiSystem> free_, contact_;
  std::vector<std::unique_ptr<MultiSystem>> reduced_;  ///< by coordinates removed (chart_)
  const RingChart* chart_ = nullptr;
  MultiSystem* cur_ = nullptr;
  Phase books_ = Phase::Free;
  bool omega_pending_ = false;
  double t_end_ = 0, phase_start_ = 0, t_restart_ = 0;
  Sample sample_;
  Projector set_;
  ContactKinematics kin_;  // scratch of arm(), locate_onset() and the speed check  // the
                           // decisions' projections and operators
  ContactSetSolver solver_;
  Vec q_restart_, v_restart_, q_tmp_, v_tmp_, q_ev_, v_ev_;
  std::vector<char> deferred_, banded_;
  std::vector<char> band_next_release_ = std::vector<char>(static_cast<std::size_t>(K_), 0);
  std::vector<char> no_tangential_;
  std::vector<ContactForce> forces_;
  std::string ending_witness_, last_painleve_;
  Works work_{};
  double work_impacts_ = 0.0;
};

RunSummary MultiIntegrator::run(const MechanicalState& init, double t_end) {
  t_end_ = t_end;
  // contact phases: minimal coordinates where the model's ring chart applies (closed contacts
  // on sprung rings of their own or on fixed rings of full rank), the projection formulation
  // for the other phases
  const RingChart* rc = m_.ring_chart();
  const bool reduced = opt_.contact_phases == ContactFormulation::Reduced && rc != nullptr &&
                       rc->contact_count() == K_;
  const std::string phases =
      reduced ? fmt::format("reduced+{} (bdf+projection where the ring chart does not apply)",
                            opt_.contact_adams ? "adams" : "bdf")
              : std::string("bdf+projection");
  env_.emplace(opt_, sink_, init.t, t_end, m_.mechanical_energy(init.t, init.q, init.v), law(0).mu,
               "event",
               fmt::format("{{\"rtol\": {:.3g}, \"atol\": {:.3g}, \"free_flight\": \"{}\", "
                           "\"contact_phases\": \"{}\", \"contacts\": {}, "
                           "\"adams_iteration\": \"{}\", \"output_dt\": {:.6g}}}",
                           opt_.rtol, opt_.atol, opt_.adams ? "adams" : "bdf", phases, K_,
                           opt_.fixed_point ? "fixed-point" : "newton", opt_.output_dt));
  RunSummary& sum = env_->summary();
  Plausibility plaus;
  double pen = 0.0;
  for (int k = 0; k < K_; ++k) pen = std::max(pen, 1e-6 * m_.gap_scale(k) + tol(k).graze_tol);
  plaus.max_penetration = pen;
  env_->set_plausibility(plaus);
  auto steps_so_far = [&sum] {
    return std::accumulate(sum.phase_steps.begin(), sum.phase_steps.end(), 0L);
  };
  long call_steps = 0;
  double t = init.t;
  Vec q = init.q, v = init.v;
  bool ok = true;
  bool root_without_restart = false;
  int recoveries = 0;
  double t_root = 0.0;
  Vec q_root = q, v_root = v;
  Works work_root{};
  std::vector<int> info(static_cast<std::size_t>(5 * K_ + 1), 0);
  std::vector<WitnessRef> fired;
  fired.reserve(static_cast<std::size_t>(5 * K_ + 1));
  try {
    open_sessions();
    ok = start(init);
    if (ok) {
      t = t_restart_;
      q = q_restart_;
      v = v_restart_;
    }
    while (ok && t < t_end_) {
      const long steps = steps_so_far();
      if (env_->check_due(steps)) {
        for (int k = 0; k < K_; ++k) {
          m_.compute_contact(k, t, q, v, kin_);
          env_->check_speed(t, kin_.v_N, kin_.v_t);
        }
      }
      if (!sum.complete() || env_->watch(t, steps)) {
        if (!(t <= env_->last_output_time())) emit_sample(t, q, v);
        break;
      }
      const double tout = std::min(env_->next_output(), t_end_);
      const bool arming_now = arming();
      const int ph = static_cast<int>(books_);
      const long steps0 = cur_->session().steps_since_restart();
      const auto wall_adv = std::chrono::steady_clock::now();
      const Status st = cur_->advance(tout, t, q, v, arming_now);
      sum.phase_wall[ph] +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_adv).count();
      const long taken = cur_->session().steps_since_restart() - steps0;
      sum.phase_steps[ph] += taken;
      if (st == Status::Failure && cur_->session().last_error().rfind("CV_TOO_MUCH_WORK", 0) == 0 &&
          (call_steps += taken) < opt_.max_steps_per_call) {
        if (!all_finite(q) || !all_finite(v)) {
          fail(Termination::NonFinite, fmt::format("non-finite state at t = {:.17g}", t));
          break;
        }
        continue;
      }
      call_steps = 0;
      if (st == Status::Failure && root_without_restart && recoveries < 100) {
        ++recoveries;
        ++sum.suppressed_witnesses;
        root_without_restart = false;
        end_phase(t_root);
        work_ = work_root;
        start_phase(t_root, q_root, v_root);
        t = t_restart_;
        q = q_restart_;
        v = v_restart_;
        continue;
      }
      if (st == Status::Failure) {
        t = cur_->session().current_time();
        fail(Termination::SolverFailure,
             fmt::format("CVODE failed at t = {:.17g} in phase {}: {}", t, to_string(books_),
                         cur_->session().last_error()));
        break;
      }
      if (!all_finite(q) || !all_finite(v)) {
        fail(Termination::NonFinite, fmt::format("non-finite state at t = {:.17g}", t));
        break;
      }
      if (arming_now && st != Status::Root) arm(t, q, v);
      if (st != Status::Root) root_without_restart = false;
      if (st == Status::Step) continue;
      if (st == Status::Reached) {
        emit_sample(t, q, v);
        env_->progress(t, m_.spin(t, q, v), books_);
        if (t < t_end_ && (env_->stop_requested(t) || env_->budget_spent(t))) break;
        if (t >= tout && tout == env_->next_output()) env_->advance_output();
        continue;
      }
      emit_outputs_before(t);
      info.assign(sh_.list.size(), 0);
      cur_->session().root_info(info.data());
      fired.assign(sh_.list.begin(), sh_.list.end());
      bool restarted = false;
      for (std::size_t i = 0; i < fired.size() && ok && !restarted; ++i)
        if (info[i] != 0) ok = on_root(fired[i], t, q, v, restarted);
      if (!ok) break;
      if (restarted) {
        t = t_restart_;
        q = q_restart_;
        v = v_restart_;
        root_without_restart = false;
        continue;
      }
      root_without_restart = true;
      t_root = t;
      q_root = q;
      v_root = v;
      work_root = cur_->works();
      if (!omega_pending_ && !sh_.list.empty() && sh_.list.back().w == Witness::Omega) {
        sh_.list.pop_back();
        sh_.dirs.pop_back();
        cur_->session().set_roots(static_cast<int>(sh_.list.size()), sh_.dirs.data());
      }
    }
  } catch (const std::exception& ex) {
    fail(Termination::SolverFailure, fmt::format("at t = {:.17g}: {}", t, ex.what()));
  }
  end_phase(t);
  if (cur_) work_ = cur_->works();
  auto add_stats = [&sum](const MultiSystem* s) {
    if (!s) return;
    const auto st = s->session().stats();
    sum.steps += st.steps;
    sum.rhs_evals += st.rhs_evals;
    sum.jac_evals += st.jac_evals;
    sum.root_evals += st.root_evals;
    sum.newton_iters += st.newton_iters;
  };
  add_stats(free_.get());
  add_stats(contact_.get());
  for (const auto& s : reduced_) add_stats(s.get());
  return env_->finish(t, m_.mechanical_energy(t, q, v),
                      {work_[0], work_[1], work_[2], work_impacts_});
}

}  // namespace

RunSummary run_event_driven_multi(const LagrangianModel& model, const MechanicalState& initial,
                                  double t_end, const EventDrivenOptions& opt, OutputSink& sink) {
  if (model.contact_count() > kMaxSetK)
    throw std::invalid_argument(
        fmt::format("the event-driven solver handles up to {} contacts; model '{}' has {}",
                    kMaxSetK, model.name(), model.contact_count()));
  MultiIntegrator integ(model, opt, sink);
  return integ.run(initial, t_end);
}

}  // namespace rubdyn::detail
