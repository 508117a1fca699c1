#include "phase_system.hpp"

#include <Eigen/Cholesky>
#include <algorithm>

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

void split(const double* y, Vec7& q, Vec7& v) {
  q = Eigen::Map<const Vec7>(y);
  v = Eigen::Map<const Vec7>(y + kNumDofs);
}

void join(const Vec7& q, const Vec7& v, double* y) {
  Eigen::Map<Vec7> yq(y), yv(y + kNumDofs);
  yq = q;
  yv = v;
}

}  // namespace

// ---- PhaseSystem ------------------------------------------------------------------------------

PhaseSystem::PhaseSystem(const LagrangianModel& m, const WitnessSet& w)
    : m_(m), law_(m.contact_law()), wit_(w) {}

PhaseSystem::~PhaseSystem() = default;

void PhaseSystem::open(int n, CvodeMethod method, const SessionSettings& s,
                       const ChartScales& scales, const CvodeCallbacks& cb) {
  // Error weights of a session state (p, p', works) with d = n / 2 coordinates: a coordinate
  // that is a full one (length 0) has rtol |p| + atol_q; an angle that moves the contact point by
  // L per radian is weighted by the displacement it causes, absolutely, at the gap's scale:
  // (rtol g0 + atol_q) / L (contact_chart.hpp). Rates: rtol |p'| + atol_v; works:
  // rtol |W| + 1e-9 J.
  const int d = n / 2;
  rtol_.fill(s.rtol);
  atol_.fill(1e-9);
  for (int i = 0; i < d; ++i) {
    const double L = scales.length[i];
    rtol_[i] = L > 0.0 ? 0.0 : s.rtol;
    atol_[i] = L > 0.0 ? (s.rtol * s.g0 + s.atol_q) / L : s.atol_q;
    atol_[d + i] = s.atol_v;
  }
  CvodeConfig c;
  c.n = n + kNw;
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

void PhaseSystem::to_full(const double* ys, Vec7& q, Vec7& v) const {
  split(ys, q, v);
}

void PhaseSystem::chart_in(const Vec7& q, const Vec7& v, Vec7& q0, Vec7& v0) {
  join(q, v, ys_.data());
  q0 = q;
  v0 = v;
}

void PhaseSystem::enter(Phase phase, Vec7& q, Vec7& v) {
  phase_ = phase;
  const Vec7 q_in = q, v_in = v;
  chart_in(q_in, v_in, q, v);
}

void PhaseSystem::restart(double t, const Works& w, double t_stop) {
  std::copy(w.begin(), w.end(), ys_.begin() + n());
  session_->restart(t, ys_.data(), wit_.size(), wit_.dirs.data(), projection(), 0.0, t_stop);
}

CvodeSession::Status PhaseSystem::advance(double tout, double& t, Vec7& q, Vec7& v, bool one_step) {
  const auto st = session_->advance(tout, t, ys_.data(), one_step);
  to_full(ys_.data(), q, v);
  return st;
}

void PhaseSystem::interpolate(double t, Vec7& q, Vec7& v) const {
  SessionState ys{};
  session_->dky(t, 0, ys.data());
  to_full(ys.data(), q, v);
}

Works PhaseSystem::works() const {
  Works w{};
  std::copy(ys_.begin() + n(), ys_.begin() + n() + kNw, w.begin());
  return w;
}

Works PhaseSystem::works_at(double t) const {
  SessionState ys{};
  session_->dky(t, 0, ys.data());
  Works w{};
  std::copy(ys.begin() + n(), ys.begin() + n() + kNw, w.begin());
  return w;
}

void PhaseSystem::contact_point(double t, Vec7& q, Vec7& v, ContactOperators& op) const {
  compute_contact_operators(m_, t, q, v, op);
}

void PhaseSystem::forces(double t, Vec7 q, Vec7 v, double& F_N, double& F_T) const {
  F_N = F_T = 0.0;
  if (phase_ == Phase::Free) return;
  ContactOperators op;
  contact_point(t, q, v, op);
  const PhaseDynamics d = phase_dynamics(op, phase_, law_.mu);
  F_N = d.F_N;
  F_T = d.F_T;
}

double PhaseSystem::witness_value(Witness w, double t, Vec7 q, Vec7 v) const {
  if (w == Witness::Gap) return m_.contact(q, v).d_N + wit_.gap_offset;
  if (w == Witness::GapRate) return m_.contact(q, v).v_N;
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

void PhaseSystem::powers(double t, const Vec7& q, const Vec7& v, double friction, double* w) const {
  const SmoothPower p = m_.smooth_power(t, q, v);
  w[0] = p.external;
  w[1] = p.damping;
  w[2] = friction;
}

int PhaseSystem::roots(double t, const double* y, double* g, void* user) {
  const auto* self = static_cast<const PhaseSystem*>(user);
  const WitnessSet& ws = self->wit_;
  Vec7 q, v;
  self->to_full(y, q, v);
  // Witnesses of a contact phase are functions on the constraint manifold.
  ContactOperators op;
  PhaseDynamics dyn;
  if (self->phase_ != Phase::Free) {
    self->contact_point(t, q, v, op);
    dyn = phase_dynamics(op, self->phase_, self->law_.mu);
  }
  const double mu = self->law_.mu;
  for (int k = 0; k < ws.size(); ++k) {
    switch (ws.list[k]) {
      case Witness::Gap: g[k] = (self->m_.contact(q, v).d_N + ws.gap_offset) / ws.g0; break;
      case Witness::GapRate: g[k] = self->m_.contact(q, v).v_N / ws.v_ref; break;
      case Witness::NormalForce: g[k] = dyn.F_N / ws.F_ref; break;
      case Witness::ConeUpper: g[k] = (mu * dyn.F_N - dyn.F_T) / ws.F_ref; break;
      case Witness::ConeLower: g[k] = (mu * dyn.F_N + dyn.F_T) / ws.F_ref; break;
      case Witness::SlipSpeed: g[k] = op.c.v_t / ws.v_ref; break;
      case Witness::Omega: g[k] = (self->m_.spin(v) - ws.omega_lim) / ws.omega_lim; break;
    }
  }
  return 0;
}

// ---- FreeFlight -------------------------------------------------------------------------------

FreeFlight::FreeFlight(const LagrangianModel& m, const WitnessSet& w, const SessionSettings& s)
    : PhaseSystem(m, w) {
  CvodeCallbacks cb;
  cb.rhs = &FreeFlight::rhs;
  cb.jac = &FreeFlight::jac;
  open(kN, s.adams ? CvodeMethod::Adams : CvodeMethod::BDF, s, ChartScales{}, cb);
}

int FreeFlight::rhs(double t, const double* y, double* yd, void* user) {
  // Free flight needs only M and f: no contact quantities are built here.
  const auto* self = static_cast<const FreeFlight*>(static_cast<PhaseSystem*>(user));
  Vec7 q, v, f;
  split(y, q, v);
  Mat7x3 B;
  self->m_.smooth_forces(t, q, v, f);
  B.col(0) = f;
  self->m_.solve_mass(q, B, 1);
  join(v, B.col(0), yd);
  self->powers(t, q, v, 0.0, yd + kN);
  return B.col(0).allFinite() ? 0 : 1;
}

// Analytic Jacobian: d/dq (M^{-1} f) = M^{-1} (df/dq - d(M a)/dq), with a fixed.
int FreeFlight::jac(double t, const double* y, const double*, double* J, void* user) {
  const auto* self = static_cast<const FreeFlight*>(static_cast<PhaseSystem*>(user));
  const LagrangianModel& m = self->m_;
  Vec7 q, v, f;
  split(y, q, v);
  Mat7 M, dfdq, dfdv, dMa;
  m.mass_matrix(q, M);
  m.smooth_forces(t, q, v, f);
  m.smooth_force_jacobians(t, q, v, dfdq, dfdv);
  const Eigen::LDLT<Mat7> ldlt(M);
  const Vec7 a = ldlt.solve(f);
  m.mass_matrix_product_jacobian(q, a, dMa);
  // column-major kNy x kNy, as SUNDIALS' dense matrix; the rows of the works are left 0 (they
  // feed back into nothing, so Newton converges on them with the state)
  Eigen::Map<Eigen::Matrix<double, kNy, kNy>> Jm(J);
  Jm.setZero();
  Jm.topRightCorner<kNumDofs, kNumDofs>().setIdentity();
  Jm.bottomLeftCorner<kNumDofs, kNumDofs>() = ldlt.solve(dfdq - dMa);
  Jm.bottomRightCorner<kNumDofs, kNumDofs>() = ldlt.solve(dfdv);
  return 0;
}

// ---- ProjectedContact -------------------------------------------------------------------------

ProjectedContact::ProjectedContact(const LagrangianModel& m, const WitnessSet& w,
                                   const SessionSettings& s)
    : PhaseSystem(m, w), g0_(s.g0) {
  CvodeCallbacks cb;
  cb.rhs = &ProjectedContact::rhs;
  cb.proj = &ProjectedContact::proj;
  open(kN, CvodeMethod::BDF, s, ChartScales{}, cb);
}

/// Projects a state of the phase onto the constraints (positions onto d_N = 0, velocities
/// mass-weighted onto v_N = 0, and v_t = 0 in stick) and returns the contact operators at the
/// projected state: one structured solve with M(q) for three right-hand sides, then one.
void ProjectedContact::contact_point(double t, Vec7& q, Vec7& v, ContactOperators& op) const {
  project_position(m_, q, v, 1e-14 * g0_);
  compute_contact_operators(m_, t, q, v, op);
  project_velocity(op, phase_ == Phase::Stick ? 2 : 1, v);
  update_contact_velocity(m_, t, q, v, op);
}

int ProjectedContact::rhs(double t, const double* y, double* yd, void* user) {
  const auto* self = static_cast<const ProjectedContact*>(static_cast<PhaseSystem*>(user));
  Vec7 q, v;
  split(y, q, v);
  ContactOperators op;
  compute_contact_operators(self->m_, t, q, v, op);
  const PhaseDynamics d = phase_dynamics(op, self->phase_, self->law_.mu);
  if (!d.well_posed) return 1;  // recoverable: CVODE retries with a smaller step
  join(v, d.a, yd);
  self->powers(t, q, v, d.F_T * op.c.v_t, yd + kN);
  return d.a.allFinite() ? 0 : 1;
}

int ProjectedContact::proj(double t, const double* y, double* corr, void* user) {
  const auto* self = static_cast<const ProjectedContact*>(static_cast<PhaseSystem*>(user));
  Vec7 q, v;
  split(y, q, v);
  const Vec7 q0 = q, v0 = v;
  ContactOperators op;
  self->contact_point(t, q, v, op);
  join(q - q0, v - v0, corr);
  std::fill(corr + kN, corr + kNy, 0.0);
  return q.allFinite() && v.allFinite() ? 0 : -1;
}

// ---- ReducedContact ---------------------------------------------------------------------------

ReducedContact::ReducedContact(const LagrangianModel& m, const WitnessSet& w,
                               const SessionSettings& s, const ContactChart& chart, ChartMode mode)
    : PhaseSystem(m, w), chart_(chart), mode_(mode), dim_(chart.dim(mode)) {
  CvodeCallbacks cb;
  cb.rhs = &ReducedContact::rhs;
  open(2 * dim_, s.adams ? CvodeMethod::Adams : CvodeMethod::BDF, s, chart.scales(mode), cb);
}

void ReducedContact::unpack(const double* ys, Vec7& p, Vec7& pd) const {
  p.setZero();
  pd.setZero();
  for (int i = 0; i < dim_; ++i) {
    p[i] = ys[i];
    pd[i] = ys[dim_ + i];
  }
}

void ReducedContact::to_full(const double* ys, Vec7& q, Vec7& v) const {
  Vec7 p, pd;
  unpack(ys, p, pd);
  chart_.embed(mode_, anchor_, p, pd, q, v);
}

void ReducedContact::chart_in(const Vec7& q, const Vec7& v, Vec7& q0, Vec7& v0) {
  Vec7 p, pd;
  chart_.chart(mode_, q, v, anchor_, p, pd);
  for (int i = 0; i < dim_; ++i) {
    ys_[i] = p[i];
    ys_[dim_ + i] = pd[i];
  }
  chart_.embed(mode_, anchor_, p, pd, q0, v0);
}

int ReducedContact::rhs(double t, const double* y, double* yd, void* user) {
  // The constrained acceleration of the full model at the embedded state, reduced to p''
  // (contact_chart.hpp).
  const auto* self = static_cast<const ReducedContact*>(static_cast<PhaseSystem*>(user));
  const int d = self->dim_;
  Vec7 p, pd, pdd, q, v;
  self->unpack(y, p, pd);
  self->chart_.embed(self->mode_, self->anchor_, p, pd, q, v);
  ContactOperators op;
  compute_contact_operators(self->m_, t, q, v, op);
  const PhaseDynamics dyn = phase_dynamics(op, self->phase_, self->law_.mu);
  if (!dyn.well_posed) return 1;  // recoverable: CVODE retries with a smaller step
  self->chart_.reduce(self->mode_, self->anchor_, p, pd, q, dyn.a, pdd);
  for (int i = 0; i < d; ++i) {
    yd[i] = pd[i];
    yd[d + i] = pdd[i];
  }
  self->powers(t, q, v, dyn.F_T * op.c.v_t, yd + 2 * d);
  return pdd.allFinite() ? 0 : 1;
}

}  // namespace rubdyn::detail
