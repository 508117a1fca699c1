#include "phase_system.hpp"

#include <algorithm>

#include "decision_tolerances.hpp"

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

// ---- PhaseSystem ------------------------------------------------------------------------------

PhaseSystem::PhaseSystem(const LagrangianModel& m, const WitnessSet& w)
    : m_(m),
      n_(m.num_dofs()),
      rheonomic_(m.rheonomic()),
      law_(m.contact_law(0)),
      wit_(w),
      query_(m.num_dofs()),
      roots_(m.num_dofs()),
      kin_(m.num_dofs()) {}

PhaseSystem::~PhaseSystem() = default;

void PhaseSystem::open(int size, CvodeMethod method, const SessionSettings& s,
                       const ChartScales& scales, const CvodeCallbacks& cb) {
  // Error weights of a session state (p, p', works) with d = size / 2 coordinates: a coordinate
  // that is a full one (length 0) has rtol |p| + atol_q; an angle that moves the contact point by
  // L per radian is weighted by the displacement it causes, absolutely, at the gap's scale:
  // (rtol g0 + atol_q) / L (contact_chart.hpp). Rates: rtol |p'| + atol_v; works:
  // rtol |W| + 1e-9 J.
  const int d = size / 2;
  const auto total = static_cast<std::size_t>(size + kNw);
  rtol_.assign(total, s.rtol);
  atol_.assign(total, 1e-9);
  for (int i = 0; i < d; ++i) {
    const double L = i < static_cast<int>(scales.length.size()) ? scales.length[i] : 0.0;
    rtol_[i] = L > 0.0 ? 0.0 : s.rtol;
    atol_[i] = L > 0.0 ? (s.rtol * s.g0 + s.atol_q) / L : s.atol_q;
    atol_[d + i] = s.atol_v;
  }
  ys_.assign(total, 0.0);
  ys_scratch_.assign(total, 0.0);
  CvodeConfig c;
  c.n = static_cast<int>(total);
  c.method = method;
  c.fixed_point = s.fixed_point;
  c.rtol = rtol_.data();
  c.atol = atol_.data();
  c.max_steps = s.max_steps;
  CvodeCallbacks cbw = cb;
  cbw.roots = &PhaseSystem::roots;
  cbw.user = static_cast<PhaseSystem*>(this);
  session_ = std::make_unique<CvodeSession>(c, cbw);
}

void PhaseSystem::to_full(const double* ys, Vec& q, Vec& v) const {
  q = CMap(ys, n_);
  v = CMap(ys + n_, n_);
}

void PhaseSystem::chart_in(const Vec& q, const Vec& v, Vec& q0, Vec& v0) {
  VMap(ys_.data(), n_) = q;
  VMap(ys_.data() + n_, n_) = v;
  q0 = q;
  v0 = v;
}

void PhaseSystem::enter(Phase phase, Vec& q, Vec& v) {
  phase_ = phase;
  const Vec q_in = q, v_in = v;  // (at events only)
  chart_in(q_in, v_in, q, v);
}

void PhaseSystem::restart(double t, const Works& w, double t_stop) {
  std::copy(w.begin(), w.end(), ys_.begin() + size());
  session_->restart(t, ys_.data(), wit_.size(), wit_.dirs.data(), projection(), 0.0, t_stop);
}

CvodeSession::Status PhaseSystem::advance(double tout, double& t, Vec& q, Vec& v, bool one_step) {
  const auto st = session_->advance(tout, t, ys_.data(), one_step);
  to_full(ys_.data(), q, v);
  return st;
}

void PhaseSystem::interpolate(double t, Vec& q, Vec& v) const {
  session_->dky(t, 0, ys_scratch_.data());
  to_full(ys_scratch_.data(), q, v);
}

Works PhaseSystem::works() const {
  Works w{};
  std::copy(ys_.begin() + size(), ys_.begin() + size() + kNw, w.begin());
  return w;
}

Works PhaseSystem::works_at(double t) const {
  session_->dky(t, 0, ys_scratch_.data());
  Works w{};
  std::copy(ys_scratch_.begin() + size(), ys_scratch_.begin() + size() + kNw, w.begin());
  return w;
}

void PhaseSystem::contact_point(double t, Vec& q, Vec& v, ContactOperators& op) const {
  compute_contact_operators(m_, t, q, v, op);
}

void PhaseSystem::forces(double t, const Vec& q, const Vec& v, double& F_N, double& F_T) const {
  F_N = F_T = 0.0;
  if (phase_ == Phase::Free) return;
  query_.q = q;
  query_.v = v;
  contact_point(t, query_.q, query_.v, query_.op);
  phase_dynamics(query_.op, phase_, law_.mu, query_.dyn);
  F_N = query_.dyn.F_N;
  F_T = query_.dyn.F_T;
}

double PhaseSystem::witness_value(Witness w, double t, const Vec& q, const Vec& v) const {
  if (w == Witness::Gap || w == Witness::GapRate) {
    m_.compute_contact(0, t, q, v, kin_);
    return w == Witness::Gap ? kin_.d_N + wit_.gap_offset : kin_.v_N;
  }
  query_.q = q;
  query_.v = v;
  contact_point(t, query_.q, query_.v, query_.op);
  const PhaseDynamics& d = query_.dyn;
  phase_dynamics(query_.op, phase_, law_.mu, query_.dyn);
  switch (w) {
    case Witness::NormalForce: return d.F_N;
    case Witness::ConeUpper: return law_.mu * d.F_N - d.F_T;
    case Witness::ConeLower: return law_.mu * d.F_N + d.F_T;
    case Witness::SlipSpeed: return query_.op.c.v_t;
    default: return 0.0;
  }
}

void PhaseSystem::powers(double t, VecIn q, VecIn v, VecIn a, double F_N, double F_T,
                         double friction, double* w) const {
  const SmoothPower p = m_.smooth_power(t, q, v);
  if (rheonomic_) {
    const ContactForce F{F_N, F_T};
    w[0] = m_.applied_power(t, q, v, a, &F);
  } else {
    w[0] = p.external;
  }
  w[1] = p.damping;
  w[2] = friction;
}

int PhaseSystem::roots(double t, const double* y, double* g, void* user) {
  const auto* self = static_cast<const PhaseSystem*>(user);
  const WitnessSet& ws = self->wit_;
  ContactScratch& s = self->roots_;
  self->to_full(y, s.q, s.v);
  // Witnesses of a contact phase are functions on the constraint manifold.
  if (self->phase_ != Phase::Free) {
    self->contact_point(t, s.q, s.v, s.op);
    phase_dynamics(s.op, self->phase_, self->law_.mu, s.dyn);
  } else {
    self->m_.compute_contact(0, t, s.q, s.v, s.op.c);
  }
  const double mu = self->law_.mu;
  const PhaseDynamics& dyn = s.dyn;
  for (int k = 0; k < ws.size(); ++k) {
    switch (ws.list[k]) {
      case Witness::Gap: g[k] = (s.op.c.d_N + ws.gap_offset) / ws.g0; break;
      case Witness::GapRate: g[k] = s.op.c.v_N / ws.v_ref; break;
      case Witness::NormalForce: g[k] = dyn.F_N / ws.F_ref; break;
      case Witness::ConeUpper: g[k] = (mu * dyn.F_N - dyn.F_T) / ws.F_ref; break;
      case Witness::ConeLower: g[k] = (mu * dyn.F_N + dyn.F_T) / ws.F_ref; break;
      case Witness::SlipSpeed: g[k] = s.op.c.v_t / ws.v_ref; break;
      case Witness::Omega: g[k] = (self->m_.spin(t, s.q, s.v) - ws.omega_lim) / ws.omega_lim; break;
    }
  }
  return 0;
}

// ---- FreeFlight -------------------------------------------------------------------------------

FreeFlight::FreeFlight(const LagrangianModel& m, const WitnessSet& w, const SessionSettings& s)
    : PhaseSystem(m, w),
      M_(n_, n_),
      dfdq_(n_, n_),
      dfdv_(n_, n_),
      dMa_(n_, n_),
      f_(n_),
      a_(n_),
      ldlt_(n_) {
  CvodeCallbacks cb;
  cb.rhs = &FreeFlight::rhs;
  cb.jac = &FreeFlight::jac;
  open(2 * n_, s.adams ? CvodeMethod::Adams : CvodeMethod::BDF, s, ChartScales{}, cb);
}

int FreeFlight::rhs(double t, const double* y, double* yd, void* user) {
  // Free flight needs only M and f: no contact quantities are built here. The acceleration is
  // computed in place, in the rates of the velocities.
  const auto* self = static_cast<const FreeFlight*>(static_cast<PhaseSystem*>(user));
  const int n = self->n_;
  const CMap q(y, n), v(y + n, n);
  VMap qd(yd, n), f(yd + n, n);
  Eigen::Map<Mat> a(yd + n, n, 1);  // f, then M^{-1} f in place
  qd = v;
  self->m_.smooth_forces(t, q, v, f);
  self->m_.solve_mass(q, a);
  self->powers(t, q, v, a.col(0), 0.0, 0.0, 0.0, yd + 2 * n);
  return all_finite(a) ? 0 : 1;
}

// Analytic Jacobian: d/dq (M^{-1} f) = M^{-1} (df/dq - d(M a)/dq), with a fixed.
int FreeFlight::jac(double t, const double* y, const double*, double* J, void* user) {
  auto* self = static_cast<FreeFlight*>(static_cast<PhaseSystem*>(user));
  const LagrangianModel& m = self->m_;
  const int n = self->n_;
  const CMap q(y, n), v(y + n, n);
  m.mass_matrix(q, self->M_);
  m.smooth_forces(t, q, v, self->f_);
  m.smooth_force_jacobians(t, q, v, self->dfdq_, self->dfdv_);
  self->ldlt_.compute(self->M_);
  self->a_ = self->ldlt_.solve(self->f_);
  m.mass_matrix_product_jacobian(q, self->a_, self->dMa_);
  // column-major N x N, as SUNDIALS' dense matrix; the rows of the works are left 0 (they feed
  // back into nothing, so Newton converges on them with the state)
  const int N = 2 * n + kNw;
  Eigen::Map<Mat> Jm(J, N, N);
  Jm.setZero();
  Jm.block(0, n, n, n).setIdentity();
  self->dfdq_ -= self->dMa_;
  Jm.block(n, 0, n, n) = self->ldlt_.solve(self->dfdq_);
  Jm.block(n, n, n, n) = self->ldlt_.solve(self->dfdv_);
  return 0;
}

// ---- ProjectedContact -------------------------------------------------------------------------

ProjectedContact::ProjectedContact(const LagrangianModel& m, const WitnessSet& w,
                                   const SessionSettings& s)
    : PhaseSystem(m, w), g0_(s.g0), rhs_(m.num_dofs()), proj_(m.num_dofs()) {
  CvodeCallbacks cb;
  cb.rhs = &ProjectedContact::rhs;
  cb.proj = &ProjectedContact::proj;
  open(2 * n_, CvodeMethod::BDF, s, ChartScales{}, cb);
}

/// Projects a state of the phase onto the constraints (positions onto d_N = 0, velocities
/// mass-weighted onto v_N = 0, and v_t = 0 in stick) and returns the contact operators at the
/// projected state: one structured solve with M(q) for three right-hand sides, then one.
void ProjectedContact::contact_point(double t, Vec& q, Vec& v, ContactOperators& op) const {
  project_position(m_, t, q, v, kProjectionRel * g0_, op.c);
  compute_contact_operators(m_, t, q, v, op);
  project_velocity(op, phase_ == Phase::Stick ? 2 : 1, v);
  update_contact_velocity(m_, t, q, v, op);
}

int ProjectedContact::rhs(double t, const double* y, double* yd, void* user) {
  auto* self = static_cast<ProjectedContact*>(static_cast<PhaseSystem*>(user));
  const int n = self->n_;
  ContactScratch& s = self->rhs_;
  const CMap q(y, n), v(y + n, n);
  compute_contact_operators(self->m_, t, q, v, s.op);
  phase_dynamics(s.op, self->phase_, self->law_.mu, s.dyn);
  if (!s.dyn.well_posed) return 1;  // recoverable: CVODE retries with a smaller step
  VMap(yd, n) = v;
  VMap(yd + n, n) = s.dyn.a;
  self->powers(t, q, v, s.dyn.a, s.dyn.F_N, s.dyn.F_T, s.dyn.F_T * s.op.c.v_t, yd + 2 * n);
  return all_finite(s.dyn.a) ? 0 : 1;
}

int ProjectedContact::proj(double t, const double* y, double* corr, void* user) {
  auto* self = static_cast<ProjectedContact*>(static_cast<PhaseSystem*>(user));
  const int n = self->n_;
  ContactScratch& s = self->proj_;
  const CMap q0(y, n), v0(y + n, n);
  s.q = q0;
  s.v = v0;
  self->contact_point(t, s.q, s.v, s.op);
  VMap(corr, n) = s.q - q0;
  VMap(corr + n, n) = s.v - v0;
  std::fill(corr + 2 * n, corr + 2 * n + kNw, 0.0);
  return all_finite(s.q) && all_finite(s.v) ? 0 : -1;
}

// ---- ReducedContact ---------------------------------------------------------------------------

ReducedContact::ReducedContact(const LagrangianModel& m, const WitnessSet& w,
                               const SessionSettings& s, const ContactChart& chart, ChartMode mode)
    : PhaseSystem(m, w),
      chart_(chart),
      mode_(mode),
      dim_(chart.dim(mode)),
      rhs_(m.num_dofs()),
      p_(Vec::Zero(dim_)),
      pd_(Vec::Zero(dim_)),
      pdd_(Vec::Zero(dim_)) {
  CvodeCallbacks cb;
  cb.rhs = &ReducedContact::rhs;
  open(2 * dim_, s.adams ? CvodeMethod::Adams : CvodeMethod::BDF, s, chart.scales(mode), cb);
}

void ReducedContact::to_full(const double* ys, Vec& q, Vec& v) const {
  chart_.embed(mode_, anchor_, CMap(ys, dim_), CMap(ys + dim_, dim_), q, v);
}

void ReducedContact::chart_in(const Vec& q, const Vec& v, Vec& q0, Vec& v0) {
  chart_.chart(mode_, q, v, anchor_, p_, pd_);
  VMap(ys_.data(), dim_) = p_;
  VMap(ys_.data() + dim_, dim_) = pd_;
  chart_.embed(mode_, anchor_, p_, pd_, q0, v0);
}

int ReducedContact::rhs(double t, const double* y, double* yd, void* user) {
  // The constrained acceleration of the full model at the embedded state, reduced to p''
  // (contact_chart.hpp).
  auto* self = static_cast<ReducedContact*>(static_cast<PhaseSystem*>(user));
  const int d = self->dim_;
  ContactScratch& s = self->rhs_;
  const CMap p(y, d), pd(y + d, d);
  self->chart_.embed(self->mode_, self->anchor_, p, pd, s.q, s.v);
  compute_contact_operators(self->m_, t, s.q, s.v, s.op);
  phase_dynamics(s.op, self->phase_, self->law_.mu, s.dyn);
  if (!s.dyn.well_posed) return 1;  // recoverable: CVODE retries with a smaller step
  VMap pdot(yd, d), pdd(yd + d, d);
  pdot = pd;
  self->chart_.reduce(self->mode_, self->anchor_, p, pd, s.q, s.dyn.a, pdd);
  self->powers(t, s.q, s.v, s.dyn.a, s.dyn.F_N, s.dyn.F_T, s.dyn.F_T * s.op.c.v_t, yd + 2 * d);
  return all_finite(pdd) ? 0 : 1;
}

}  // namespace rubdyn::detail
