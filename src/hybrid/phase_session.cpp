#include "phase_session.hpp"

#include <algorithm>

#include "rubdyn/core/demand.hpp"

namespace rubdyn::detail {

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

namespace {

using CMap = Eigen::Map<const Vec>;
using VMap = Eigen::Map<Vec>;

}  // namespace

// ---- PhaseContext -----------------------------------------------------------------------------

PhaseContext::PhaseContext(const LagrangianModel& model, double rtol, double atol,
                           double omega_lim_)
    : m(model), K(model.contact_count()), omega_lim(omega_lim_) {
  modes.K = K;
  for (int k = 0; k < K; ++k) {
    laws.push_back(model.contact_law(k));
    tol.push_back(SwitchTolerances::derive(rtol, atol, model.gap_scale(k)));
  }
}

double PhaseContext::witness_value(const WitnessRef& w, const PhaseEval& e, double t, VecIn q,
                                   VecIn v) const {
  if (w.w == Witness::Omega) return arming.omega_done ? omega_lim : m.spin(t, q, v) - omega_lim;
  const int k = w.k;
  const ContactKinematics& c = e.c(k);
  const SwitchTolerances& tk = tl(k);
  const double mu = law(k).mu;
  switch (w.w) {
    case Witness::Gap: return c.d_N + (arming.gap_banded.test(k) ? tk.graze_tol : 0.0);
    case Witness::GapRate: return arming.rate_deferred.test(k) ? tk.v_ref : c.v_N;
    case Witness::NormalForce: return e.F_N(k);
    case Witness::SlipSpeed:
      return c.v_t + (arming.slip_banded.test(k) ? slip_sign(modes[k]) * tk.v_tol : 0.0);
    case Witness::ConeUpper: return mu * e.F_N(k) - e.F_T(k);
    case Witness::ConeLower: return mu * e.F_N(k) + e.F_T(k);
    case Witness::Omega: break;
  }
  return 0.0;
}

// ---- PhaseSession -----------------------------------------------------------------------------

PhaseSession::PhaseSession(const PhaseContext& ctx, const SessionSettings& s, SessionKind kind,
                           std::unique_ptr<PhaseChart> chart, int dim)
    : ctx_(ctx),
      m_(ctx.m),
      n_(ctx.m.num_dofs()),
      K_(ctx.K),
      kind_(kind),
      rheonomic_(ctx.m.rheonomic()),
      chart_(kind == SessionKind::Reduced ? std::move(chart) : nullptr),
      dim_(kind == SessionKind::Reduced ? dim : ctx.m.num_dofs()),
      settings_(s),
      rhs_(ctx.m, ctx.K),
      proj_(ctx.m, ctx.K),
      roots_(ctx.m, ctx.K),
      query_(ctx.m, ctx.K),
      q_rhs_(Vec::Zero(n_)),
      v_rhs_(Vec::Zero(n_)),
      q_proj_(Vec::Zero(n_)),
      v_proj_(Vec::Zero(n_)),
      q_roots_(Vec::Zero(n_)),
      v_roots_(Vec::Zero(n_)),
      forces_(static_cast<std::size_t>(K_)),
      p_(Vec::Zero(dim_)),
      pd_(Vec::Zero(dim_)),
      lengths_(static_cast<std::size_t>(dim_), 0.0),
      copies_(static_cast<std::size_t>(dim_), -1) {
  RUBDYN_DEMAND(kind != SessionKind::Reduced || chart_ != nullptr);
  // Error weights of a session state (p, p', works) with dim coordinates: a coordinate that is a
  // full one has rtol |p| + atol_q / l, l its Coordinate::length (1 but for a matrices model's
  // rotations); an angle of a chart is weighted at each restart (restart()); rates rtol |p'| +
  // atol_v / l; works rtol |W| + 1e-9 J.
  const int N = 2 * dim_ + kNw;
  rtol_.assign(static_cast<std::size_t>(N), s.rtol);
  atol_.assign(static_cast<std::size_t>(N), kWorkAtol);
  for (int i = 0; i < dim_; ++i) {
    const double l = kind == SessionKind::Reduced ? 1.0 : length_of(i);
    atol_[static_cast<std::size_t>(i)] = s.atol_q / l;
    atol_[static_cast<std::size_t>(dim_ + i)] = s.atol_v / l;
  }
  ys_.assign(static_cast<std::size_t>(N), 0.0);
  scratch_.assign(static_cast<std::size_t>(N), 0.0);
  CvodeConfig c;
  c.n = N;
  const bool adams = s.adams && kind != SessionKind::Projected;
  c.method = adams ? CvodeMethod::Adams : CvodeMethod::BDF;
  c.fixed_point = adams && s.fixed_point;
  c.rtol = rtol_.data();
  c.atol = atol_.data();
  c.max_steps = s.max_steps;
  CvodeCallbacks cb;
  const bool reduced_newton =
      kind == SessionKind::Reduced && !c.fixed_point && !s.dense_reduced_newton;
  const bool newton = kind == SessionKind::Projected ||
                      (kind == SessionKind::Free && !c.fixed_point) || reduced_newton;
  if (newton) {
    // the structured Newton systems' workspaces (lsys_free, lsys_projected)
    rhs_n_.setZero(n_);
    dv_.setZero(n_);
    f_.setZero(n_);
    a_.setZero(n_);
    // (the dense blocks M_, dfdq_, dfdv_, dMa_: at the first Jacobian that needs them, none
    // where the model's entry lists fill a band: 4 n^2 doubles, 4.8 MB at n = 388)
    band_ = std::make_unique<BorderedBand>(n_, m_.spin_coordinate());
  }
  switch (kind) {
    case SessionKind::Free:
      cb.rhs = &PhaseSession::rhs_free;
      if (newton) {
        cb.lsys = &PhaseSession::lsys_free;
        cb.lsolve = &PhaseSession::lsolve_free;
      }
      break;
    case SessionKind::Projected:
      cb.rhs = &PhaseSession::rhs_projected;
      cb.proj = &PhaseSession::proj;
      cb.lsys = &PhaseSession::lsys_projected;
      cb.lsolve = &PhaseSession::lsolve_projected;
      break;
    case SessionKind::Reduced:
      cb.rhs = &PhaseSession::rhs_reduced;
      if (reduced_newton) {
        cb.lsys = &PhaseSession::lsys_reduced;
        cb.lsolve = &PhaseSession::lsolve_reduced;
        p_jac_.setZero(dim_);
        pd_jac_.setZero(dim_);
        x_red_.setZero(dim_);
        y_jac_.setZero(2 * n_);
        b_full_.setZero(2 * n_);
        q_tan_.setZero(n_);
      }
      break;
  }
  if (kind == SessionKind::Projected || reduced_newton) {
    // the bordered Newton systems' workspaces (lsys_projected, lsys_reduced)
    jac_eval_ = std::make_unique<PhaseEval>(m_, K_);
    Wf_.setZero(n_, 2 * K_);
    Ht_.setZero(n_, 2 * K_);
    Y_.setZero(n_, 2 * K_);
    E_.setZero(2 * K_, 2 * K_);
    E_lu_.compute(E_);  // (sized here)
    res_.setZero(2 * K_);
    mu_.setZero(2 * K_);
  }
  cb.roots = &PhaseSession::roots;
  cb.user = this;
  session_ = std::make_unique<CvodeSession>(c, cb);
}

void PhaseSession::to_full(double t, const double* y, Vec& q, Vec& v) const {
  if (chart_) {
    chart_->embed(t, CMap(y, dim_), CMap(y + dim_, dim_), q, v);
  } else {
    q = CMap(y, n_);
    v = CMap(y + n_, n_);
  }
}

void PhaseSession::restart(double t, Vec& q, Vec& v, const Works& w, double t_stop) {
  if (kind_ == SessionKind::Projected) query_.place(t, q, v, ctx_.modes, ctx_.laws, ctx_.tol);
  if (chart_) {
    chart_->enter(ctx_.modes, t, q, v, p_, pd_, lengths_, copies_);
    chart_->embed(t, p_, pd_, q, v);
    VMap(ys_.data(), dim_) = p_;
    VMap(ys_.data() + dim_, dim_) = pd_;
    // error weights of this phase's coordinates: a copied coordinate as the coordinate it
    // copies, rtol |p| + atol_q / l (and its rate atol_v / l); an angle that moves a contact
    // point by L per radian by the displacement it causes, absolutely, at the gap's scale:
    // (rtol g0 + atol_q) / L (contact_chart.hpp), its rate atol_v
    for (int i = 0; i < dim_; ++i) {
      const auto u = static_cast<std::size_t>(i);
      const double L = lengths_[u];
      const int c = copies_[u];
      const double l = L > 0.0 || c < 0 ? 1.0 : length_of(c);
      rtol_[u] = L > 0.0 ? 0.0 : settings_.rtol;
      atol_[u] =
          L > 0.0 ? (settings_.rtol * settings_.g0 + settings_.atol_q) / L : settings_.atol_q / l;
      atol_[static_cast<std::size_t>(dim_ + i)] = settings_.atol_v / l;
    }
    session_->set_tolerances(rtol_.data(), atol_.data());
  } else {
    VMap(ys_.data(), n_) = q;
    VMap(ys_.data() + n_, n_) = v;
  }
  std::copy(w.begin(), w.end(), ys_.begin() + 2 * dim_);
  session_->restart(t, ys_.data(), ctx_.witnesses.size(), ctx_.witnesses.dirs.data(),
                    kind_ == SessionKind::Projected, 0.0, t_stop);
}

CvodeSession::Status PhaseSession::advance(double tout, double& t, Vec& q, Vec& v, bool one_step) {
  const CvodeSession::Status st = session_->advance(tout, t, ys_.data(), one_step);
  to_full(t, ys_.data(), q, v);
  return st;
}

void PhaseSession::interpolate(double t, Vec& q, Vec& v) const {
  session_->dky(t, 0, scratch_.data());
  to_full(t, scratch_.data(), q, v);
  if (kind_ == SessionKind::Projected) query_.place(t, q, v, ctx_.modes, ctx_.laws, ctx_.tol);
}

Works PhaseSession::works() const {
  Works w{};
  std::copy_n(ys_.begin() + 2 * dim_, kNw, w.begin());
  return w;
}

Works PhaseSession::works_at(double t) const {
  session_->dky(t, 0, scratch_.data());
  Works w{};
  std::copy_n(scratch_.begin() + 2 * dim_, kNw, w.begin());
  return w;
}

bool PhaseSession::evaluate(double t, Vec& q, Vec& v) const {
  if (kind_ == SessionKind::Projected)
    return query_.place(t, q, v, ctx_.modes, ctx_.laws, ctx_.tol);
  return query_.dynamics(t, q, v, ctx_.modes, ctx_.laws);
}

void PhaseSession::evaluate_witnesses(double t, Vec& q, Vec& v) const {
  if (kind_ == SessionKind::Free) {
    query_.kinematics(t, q, v);
    return;
  }
  evaluate(t, q, v);
}

void PhaseSession::powers(double t, VecIn q, VecIn v, const PhaseEval& e, double* w) const {
  const SmoothPower p = m_.smooth_power(t, q, v);
  double friction = 0.0;
  for (int k = 0; k < K_; ++k) {
    forces_[static_cast<std::size_t>(k)] = {e.F_N(k), e.F_T(k)};
    friction += e.F_T(k) * e.c(k).v_t;
  }
  w[0] = rheonomic_ ? m_.applied_power(t, q, v, e.a(), forces_.data()) : p.external;
  w[1] = p.damping;
  w[2] = friction;
}

int PhaseSession::rhs_free(double t, const double* y, double* yd, void* user) {
  // Free flight needs only M and f: no contact quantities are built here. The acceleration is
  // computed in place, in the rates of the velocities.
  const auto* self = static_cast<const PhaseSession*>(user);
  const int n = self->n_;
  const CMap q(y, n), v(y + n, n);
  VMap qd(yd, n), f(yd + n, n);
  Eigen::Map<Mat> a(yd + n, n, 1);  // f, then M^{-1} f in place
  qd = v;
  self->m_.smooth_forces(t, q, v, f);
  self->m_.solve_mass(q, a);
  const SmoothPower p = self->m_.smooth_power(t, q, v);
  if (self->rheonomic_) {
    for (auto& F : self->forces_) F = {0.0, 0.0};
    yd[2 * n] = self->m_.applied_power(t, q, v, a.col(0), self->forces_.data());
  } else {
    yd[2 * n] = p.external;
  }
  yd[2 * n + 1] = p.damping;
  yd[2 * n + 2] = 0.0;
  return all_finite(a) ? 0 : 1;
}

void PhaseSession::size_dense_blocks() {
  if (M_.rows() == n_) return;
  M_.setZero(n_, n_);
  dfdq_.setZero(n_, n_);
  dfdv_.setZero(n_, n_);
  dMa_.setZero(n_, n_);
}

// Free flight's Jacobian blocks at y (header); the band of S is detected from them.
void PhaseSession::free_jacobians(double t, const double* y, const Vec* a, bool lists) {
  const int n = n_;
  const CMap q(y, n), v(y + n, n);
  if (a) {
    a_ = *a;
  } else {
    m_.smooth_forces(t, q, v, f_);
    a_ = f_;
    Eigen::Map<Mat> am(a_.data(), n, 1);
    m_.solve_mass(q, am);
  }
  band_->reset_pattern();
  entries_ = lists && m_.newton_entries(t, q, v, a_, ne_);
  if (entries_) {
    band_->detect(ne_.M);
    band_->detect(ne_.dq);
    band_->detect(ne_.dv);
  } else {
    size_dense_blocks();
    m_.mass_matrix(q, M_);
    m_.smooth_force_jacobians(t, q, v, dfdq_, dfdv_);
    m_.mass_matrix_product_jacobian(q, a_, dMa_);
    dfdq_ -= dMa_;
    band_->detect(M_);
    band_->detect(dfdq_);
    band_->detect(dfdv_);
  }
  band_->finish_pattern();
  if (entries_ && !band_->banded() && n >= kDenseKernelSize) {
    // S is factored densely (a reduced model's dense matrices): the lists into the dense blocks,
    // whose products are then a dense kernel's instead of one scattered update per entry
    size_dense_blocks();
    for (auto [list, A] : {std::pair{&ne_.M, &M_}, {&ne_.dq, &dfdq_}, {&ne_.dv, &dfdv_}}) {
      A->setZero();
      for (const MatrixEntry& e : *list) (*A)(e.i, e.j) += e.v;
    }
    entries_ = false;
  }
}

// Analytic Jacobian: d/dq (M^{-1} f) = M^{-1} (df/dq - d(M a)/dq), with a fixed.
int PhaseSession::jac_free(double t, const double* y, const double*, double* J, void* user) {
  auto* self = static_cast<PhaseSession*>(user);
  const int n = self->n_;
  self->free_jacobians(t, y, nullptr, false);
  const Eigen::LDLT<Mat> ldlt(self->M_);  // (a test's reference: allocates)
  // column-major N x N, as SUNDIALS' dense matrix; the rows of the works are left 0 (they feed
  // back into nothing, so Newton converges on them with the state)
  const int N = 2 * n + kNw;
  Eigen::Map<Mat> Jm(J, N, N);
  Jm.setZero();
  Jm.block(0, n, n, n).setIdentity();
  Jm.block(n, 0, n, n) = ldlt.solve(self->dfdq_);
  Jm.block(n, n, n, n) = ldlt.solve(self->dfdv_);
  return 0;
}

// The Newton system of free flight, (I - gamma J) x = b with J = [[0, I, 0], [A_q, A_v, 0],
// [0, 0, 0]] on (q, v, works) (the works' rows left 0 as in jac_free), A_q = M^-1 (df/dq -
// d(M a)/dq), A_v = M^-1 df/dv: the first block row gives x_q = b_q + gamma x_v, and M times the
// second, (M - gamma df/dv - gamma^2 (df/dq - d(M a)/dq)) x_v = M b_v + gamma (df/dq - d(M a)/dq)
// b_q, one n x n factorisation instead of one of 2n + 3 (8x fewer operations), and no M^-1 J;
// banded with the spin as its border where the model's matrices are (bordered_band.hpp).
int PhaseSession::lsys_free(double t, const double* y, double gamma, int jok, int* jcur,
                            void* user) {
  auto* self = static_cast<PhaseSession*>(user);
  if (!jok) self->free_jacobians(t, y);
  *jcur = jok ? 0 : 1;
  self->gamma_ = gamma;
  return self->factor_newton(gamma) ? 0 : 1;
}

bool PhaseSession::factor_newton(double gamma) {
  if (entries_) return band_->factor(ne_.M, -gamma, ne_.dv, -gamma * gamma, ne_.dq);
  return band_->factor(M_, -gamma, dfdv_, -gamma * gamma, dfdq_);
}

// x_v of the first block row: S x_v = M b_v + gamma (df/dq - d(M a)/dq) b_q.
void PhaseSession::newton_velocities(const double* b) {
  const int n = n_;
  rhs_n_.setZero();
  if (entries_) {
    band_->product(ne_.M, 1.0, b + n, rhs_n_.data());
    band_->product(ne_.dq, gamma_, b, rhs_n_.data());
  } else {
    band_->product(M_, 1.0, b + n, rhs_n_.data());
    band_->product(dfdq_, gamma_, b, rhs_n_.data());
  }
  band_->solve(rhs_n_.data(), dv_.data());
}

int PhaseSession::lsolve_free(const double* b, double* x, void* user) {
  auto* self = static_cast<PhaseSession*>(user);
  const int n = self->n_;
  self->newton_velocities(b);
  VMap(x, n) = CMap(b, n) + self->gamma_ * self->dv_;
  VMap(x + n, n) = self->dv_;
  for (int i = 2 * n; i < 2 * n + kNw; ++i) x[i] = b[i];
  return all_finite(self->dv_) ? 0 : 1;
}

bool PhaseSession::constrained_jacobians(double t, const double* y) {
  const int n = n_;
  const PhaseContext& ctx = ctx_;
  const CMap q(y, n), v(y + n, n);
  PhaseEval& e = *jac_eval_;
  if (!e.dynamics(t, q, v, ctx.modes, ctx.laws)) return false;
  free_jacobians(t, y, &e.a());
  int mc = 0;
  for (int k = 0; k < K_; ++k) {
    const Phase p = ctx.modes[k];
    if (!closed(p)) continue;
    const ContactKinematics& c = e.c(k);
    Ht_.col(mc) = c.W_N;
    Wf_.col(mc) = c.W_N;
    if (slipping(p)) Wf_.col(mc) -= (ctx.law(k).mu * slip_sign(p)) * c.W_T;
    ++mc;
    if (p == Phase::Stick) {
      Ht_.col(mc) = c.W_T;
      Wf_.col(mc) = c.W_T;
      ++mc;
    }
  }
  mc_ = mc;
  return true;
}

bool PhaseSession::factor_bordered(double gamma) {
  gamma_ = gamma;
  if (!factor_newton(gamma)) return false;
  const int mc = mc_;
  if (mc == 0) return true;
  for (int j = 0; j < mc; ++j) band_->solve(Wf_.col(j).data(), Y_.col(j).data());
  E_.resize(mc, mc);
  E_.noalias() = Ht_.leftCols(mc).transpose() * Y_.leftCols(mc);
  if (!E_.allFinite()) return false;
  // rank-revealing: redundant constraints (a rod's two ends on one line) make E singular but
  // their right-hand sides consistent, and any solution gives the same x_v (as the contact
  // problem's minimum-norm forces give the same motion)
  E_lu_.compute(E_);
  return E_lu_.rank() > 0;
}

void PhaseSession::solve_bordered(const double* b) {
  const int n = n_;
  const int mc = mc_;
  newton_velocities(b);
  if (mc > 0) {
    // mu = (H S^-1 W_f)^-1 (H b_v - H x0), x_v = x0 + S^-1 W_f mu
    const CMap bv(b + n, n);
    res_.resize(mc);
    for (int j = 0; j < mc; ++j) res_[j] = Ht_.col(j).dot(bv - dv_);
    mu_ = E_lu_.solve(res_);
    dv_.noalias() += Y_.leftCols(mc) * mu_;
  }
}

int PhaseSession::lsys_projected(double t, const double* y, double gamma, int jok, int* jcur,
                                 void* user) {
  auto* self = static_cast<PhaseSession*>(user);
  if (!jok && !self->constrained_jacobians(t, y))
    return 1;  // recoverable: CVODE retries with a smaller step
  *jcur = jok ? 0 : 1;
  return self->factor_bordered(gamma) ? 0 : 1;
}

int PhaseSession::lsolve_projected(const double* b, double* x, void* user) {
  auto* self = static_cast<PhaseSession*>(user);
  const int n = self->n_;
  self->solve_bordered(b);
  VMap(x, n) = CMap(b, n) + self->gamma_ * self->dv_;
  VMap(x + n, n) = self->dv_;
  for (int i = 2 * n; i < 2 * n + kNw; ++i) x[i] = b[i];
  return all_finite(self->dv_) ? 0 : 1;
}

int PhaseSession::lsys_reduced(double t, const double* y, double gamma, int jok, int* jcur,
                               void* user) {
  auto* self = static_cast<PhaseSession*>(user);
  const int d = self->dim_, n = self->n_;
  if (!jok) {
    self->t_jac_ = t;
    self->p_jac_ = CMap(y, d);
    self->pd_jac_ = CMap(y + d, d);
    self->chart_->embed(t, self->p_jac_, self->pd_jac_, self->y_jac_.head(n), self->y_jac_.tail(n));
    if (!self->constrained_jacobians(t, self->y_jac_.data()))
      return 1;  // recoverable: CVODE retries with a smaller step
  }
  *jcur = jok ? 0 : 1;
  return self->factor_bordered(gamma) ? 0 : 1;
}

int PhaseSession::lsolve_reduced(const double* b, double* x, void* user) {
  auto* self = static_cast<PhaseSession*>(user);
  const int d = self->dim_, n = self->n_;
  const PhaseChart& chart = *self->chart_;
  // (b_q, b_v) = (T b_p, T b_p') at the Jacobian's p
  chart.tangent(self->t_jac_, self->p_jac_, CMap(b, d), self->q_tan_, self->b_full_.head(n));
  chart.tangent(self->t_jac_, self->p_jac_, CMap(b + d, d), self->q_tan_, self->b_full_.tail(n));
  self->solve_bordered(self->b_full_.data());
  chart.reduce_linear(self->p_jac_, self->pd_jac_, self->y_jac_.head(n), self->dv_, self->x_red_);
  VMap(x, d) = CMap(b, d) + self->gamma_ * self->x_red_;
  VMap(x + d, d) = self->x_red_;
  for (int i = 2 * d; i < 2 * d + kNw; ++i) x[i] = b[i];
  return all_finite(self->x_red_) ? 0 : 1;
}

int PhaseSession::rhs_projected(double t, const double* y, double* yd, void* user) {
  const auto* self = static_cast<const PhaseSession*>(user);
  const int n = self->n_;
  const CMap q(y, n), v(y + n, n);
  PhaseEval& e = self->rhs_;
  if (!e.dynamics(t, q, v, self->ctx_.modes, self->ctx_.laws))
    return 1;  // recoverable: CVODE retries with a smaller step
  VMap(yd, n) = v;
  VMap(yd + n, n) = e.a();
  self->powers(t, q, v, e, yd + 2 * n);
  return all_finite(e.a()) ? 0 : 1;
}

int PhaseSession::rhs_reduced(double t, const double* y, double* yd, void* user) {
  // The constrained acceleration of the full model at the embedded state, reduced to p''
  // (contact_chart.hpp, ring_chart.hpp).
  const auto* self = static_cast<const PhaseSession*>(user);
  const int d = self->dim_;
  const CMap p(y, d), pd(y + d, d);
  Vec& q = self->q_rhs_;
  Vec& v = self->v_rhs_;
  self->chart_->embed(t, p, pd, q, v);
  PhaseEval& e = self->rhs_;
  if (!e.dynamics(t, q, v, self->ctx_.modes, self->ctx_.laws))
    return 1;  // recoverable: CVODE retries with a smaller step
  VMap pdot(yd, d), pdd(yd + d, d);
  pdot = pd;
  self->chart_->reduce(p, pd, q, e.a(), pdd);
  self->powers(t, q, v, e, yd + 2 * d);
  return all_finite(pdd) ? 0 : 1;
}

int PhaseSession::proj(double t, const double* y, double* corr, void* user) {
  const auto* self = static_cast<const PhaseSession*>(user);
  const int n = self->n_;
  Vec& q = self->q_proj_;
  Vec& v = self->v_proj_;
  q = CMap(y, n);
  v = CMap(y + n, n);
  self->proj_.place(t, q, v, self->ctx_.modes, self->ctx_.laws, self->ctx_.tol);
  VMap(corr, n) = q - CMap(y, n);
  VMap(corr + n, n) = v - CMap(y + n, n);
  std::fill(corr + 2 * n, corr + 2 * n + kNw, 0.0);
  return all_finite(q) && all_finite(v) ? 0 : -1;
}

int PhaseSession::roots(double t, const double* y, double* g, void* user) {
  const auto* self = static_cast<const PhaseSession*>(user);
  const PhaseContext& ctx = self->ctx_;
  Vec& q = self->q_roots_;
  Vec& v = self->v_roots_;
  PhaseEval& e = self->roots_;
  self->to_full(t, y, q, v);
  // the witnesses of a contact phase are functions on its constraint manifold: a Reduced state
  // is on it by construction, a Projected one is projected first
  switch (self->kind_) {
    case SessionKind::Free: e.kinematics(t, q, v); break;
    case SessionKind::Reduced: e.dynamics(t, q, v, ctx.modes, ctx.laws); break;
    case SessionKind::Projected: e.place(t, q, v, ctx.modes, ctx.laws, ctx.tol); break;
  }
  for (int i = 0; i < ctx.witnesses.size(); ++i) {
    const WitnessRef& w = ctx.witnesses[i];
    const SwitchTolerances& tl = ctx.tl(w.k < 0 ? 0 : w.k);
    g[i] = ctx.witness_value(w, e, t, q, v) / witness_scale(w.w, tl, ctx.F_ref, ctx.omega_lim);
  }
  return 0;
}

}  // namespace rubdyn::detail
