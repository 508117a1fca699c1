#include "rubdyn/model/prescribed_spin.hpp"

#include <stdexcept>

#include "rubdyn/core/demand.hpp"

namespace rubdyn {

/// Vectors and matrices of the inner model's size. One per thread: the wrapper's methods are
/// const and a model may serve several runs at once; after the first call of a thread nothing
/// is allocated (the sizes do not change).
struct PrescribedSpin::Scratch {
  Vec qf, vf, af, xf, yf, ff;
  Mat Mf, dqf, dvf, Jf, Bf;
  ContactKinematics cf;
  NewtonEntries ne;
  void size(int nf) {
    if (qf.size() == nf) return;
    for (Vec* x : {&qf, &vf, &af, &xf, &yf, &ff}) x->setZero(nf);
    for (Mat* A : {&Mf, &dqf, &dvf, &Jf}) A->setZero(nf, nf);
    Bf.setZero(nf, 4);  // the solves' right-hand sides: up to 3, and the spin's unit vector
    cf = ContactKinematics(nf);
  }
};

PrescribedSpin::Scratch& PrescribedSpin::scratch() const {
  thread_local Scratch s;
  s.size(n_ + 1);
  return s;
}

PrescribedSpin::PrescribedSpin(std::unique_ptr<LagrangianModel> inner, double t0, double theta0,
                               double omega0, double alpha)
    : inner_(std::move(inner)), law_{t0, theta0, omega0, alpha} {
  s_ = inner_->spin_coordinate();
  if (s_ < 0)
    throw std::invalid_argument("a prescribed spin needs a model with a spin coordinate; '" +
                                std::string(inner_->name()) + "' has none");
  n_ = inner_->num_dofs() - 1;
  observables_ = {
      {"theta", "rad", "the prescribed spin angle"},
      {"omega", "rad/s", "the prescribed spin speed"},
      {"drive_torque", "N m", "the torque that holds the prescribed speed"},
  };
  const std::vector<Observable>& own = inner_->observables();
  observables_.insert(observables_.end(), own.begin(), own.end());
  for (int i = 0; i <= n_; ++i)
    if (i != s_) coords_.push_back(inner_->coordinates()[static_cast<std::size_t>(i)]);
  // the inner ring chart with the spin dropped: every index above s_ moves down by one; a point
  // or ring that involves the spin cannot be charted (it would move with theta(t))
  if (const RingChart* inner_chart = inner_->ring_chart()) {
    std::vector<RingContact> rc = inner_chart->contacts();
    bool ok = true;
    const auto shift = [&](int& i) {
      if (i < 0) return;
      if (i == s_) ok = false;
      if (i > s_) --i;
    };
    for (RingContact& c : rc) {
      for (std::size_t j = 0; j < 2; ++j) {
        shift(c.ix[j]);
        shift(c.iy[j]);
      }
      if (c.ring >= 0 && (c.ring == s_ || c.ring + 1 == s_)) ok = false;
      shift(c.ring);
    }
    // no spin coordinate: theta(t) is the prescription's, the stick constraint rheonomic
    if (ok) ring_chart_.emplace(n_, -1, std::move(rc), law_);
  }
}

namespace {

/// The full vector of x with `value` inserted at s.
void insert(VecIn x, int s, double value, Vec& full) {
  const auto n = x.size();
  RUBDYN_DEMAND(full.size() == n + 1);  // a vector of the model's size (num_dofs())
  for (Eigen::Index i = 0, j = 0; j <= n; ++j) full[j] = j == s ? value : x[i++];
}

/// x without its entry s.
void drop(const Vec& full, int s, VecOut x) {
  for (Eigen::Index i = 0, j = 0; j < full.size(); ++j)
    if (j != s) x[i++] = full[j];
}

/// A without its row and column s.
void drop(const Mat& full, int s, MatOut A) {
  const auto n = full.rows();
  for (Eigen::Index c = 0, jc = 0; jc < n; ++jc) {
    if (jc == s) continue;
    for (Eigen::Index r = 0, jr = 0; jr < n; ++jr)
      if (jr != s) A(r++, c) = full(jr, jc);
    ++c;
  }
}

}  // namespace

void PrescribedSpin::embed(double t, VecIn q, VecIn v, Scratch& s) const {
  insert(q, s_, theta(t), s.qf);
  insert(v, s_, omega(t), s.vf);
}

void PrescribedSpin::mass_matrix(VecIn q, MatOut M) const {
  Scratch& s = scratch();
  insert(q, s_, law_.theta0, s.qf);  // (M without the spin's row and column does not depend on it)
  inner_->mass_matrix(s.qf, s.Mf);
  drop(s.Mf, s_, M);
}

void PrescribedSpin::mass_product(VecIn q, VecIn x, VecOut y) const {
  Scratch& s = scratch();
  insert(q, s_, law_.theta0, s.qf);
  insert(x, s_, 0.0, s.xf);
  inner_->mass_product(s.qf, s.xf, s.yf);
  drop(s.yf, s_, y);
}

void PrescribedSpin::solve_mass(VecIn q, MatOut B) const {
  Scratch& s = scratch();
  insert(q, s_, law_.theta0, s.qf);
  if (inner_->solve_mass_without(s_, s.qf, B)) return;  // (the inner's block without the spin)
  // Else with the inner inverse [[A, u], [u^T, sigma]] (spin last, for the argument), the
  // inverse of the block without the spin is A - u u^T / sigma: the inner solve of (b, 0) gives
  // (A b, u^T b), of e_spin gives (u, sigma).
  const Eigen::Index k = B.cols();
  if (s.Bf.cols() < k + 1) s.Bf.resize(n_ + 1, k + 1);  // (more right-hand sides than ever)
  auto Bk = s.Bf.leftCols(k + 1);
  for (Eigen::Index j = 0; j < k; ++j) {
    insert(B.col(j), s_, 0.0, s.xf);
    Bk.col(j) = s.xf;
  }
  Bk.col(k).setZero();
  Bk(s_, k) = 1.0;
  inner_->solve_mass(s.qf, Bk);
  const double sigma = Bk(s_, k);
  for (Eigen::Index j = 0; j < k; ++j) {
    const double w = Bk(s_, j) / sigma;
    for (Eigen::Index i = 0, r = 0; r <= n_; ++r)
      if (r != s_) B(i++, j) = Bk(r, j) - Bk(r, k) * w;
  }
}

void PrescribedSpin::mass_matrix_product_jacobian(VecIn q, VecIn a, MatOut J) const {
  Scratch& s = scratch();
  insert(q, s_, law_.theta0, s.qf);
  insert(a, s_, 0.0, s.af);
  inner_->mass_matrix_product_jacobian(s.qf, s.af, s.Jf);
  drop(s.Jf, s_, J);
}

void PrescribedSpin::smooth_forces(double t, VecIn q, VecIn v, VecOut f) const {
  // f = f_f - M_f e_spin alpha, without the spin's row
  Scratch& s = scratch();
  embed(t, q, v, s);
  inner_->smooth_forces(t, s.qf, s.vf, s.ff);
  if (law_.alpha != 0.0) {
    s.xf.setZero();
    s.xf[s_] = law_.alpha;
    inner_->mass_product(s.qf, s.xf, s.yf);
    s.ff -= s.yf;
  }
  drop(s.ff, s_, f);
}

void PrescribedSpin::smooth_force_jacobians(double t, VecIn q, VecIn v, MatOut dfdq,
                                            MatOut dfdv) const {
  Scratch& s = scratch();
  embed(t, q, v, s);
  inner_->smooth_force_jacobians(t, s.qf, s.vf, s.dqf, s.dvf);
  if (law_.alpha != 0.0) {
    s.af.setZero();
    s.af[s_] = law_.alpha;
    inner_->mass_matrix_product_jacobian(s.qf, s.af, s.Jf);
    s.dqf -= s.Jf;
  }
  drop(s.dqf, s_, dfdq);
  drop(s.dvf, s_, dfdv);
}

bool PrescribedSpin::newton_entries(double t, VecIn q, VecIn v, VecIn a, NewtonEntries& e) const {
  // the inner's entries at the full state with the spin's acceleration alpha (d(M a)/dq is
  // linear in a: smooth_force_jacobians' alpha term and mass_matrix_product_jacobian's in one),
  // without the spin's row and column
  Scratch& s = scratch();
  embed(t, q, v, s);
  insert(a, s_, law_.alpha, s.af);
  if (!inner_->newton_entries(t, s.qf, s.vf, s.af, s.ne)) return false;
  e.clear();
  const auto keep = [this](const std::vector<MatrixEntry>& in, std::vector<MatrixEntry>& out) {
    for (const MatrixEntry& x : in) {
      if (x.i == s_ || x.j == s_) continue;
      out.push_back({x.i - (x.i > s_ ? 1 : 0), x.j - (x.j > s_ ? 1 : 0), x.v});
    }
  };
  keep(s.ne.M, e.M);
  keep(s.ne.dq, e.dq);
  keep(s.ne.dv, e.dv);
  return true;
}

void PrescribedSpin::compute_contact(int k, double t, VecIn q, VecIn v,
                                     ContactKinematics& c) const {
  Scratch& s = scratch();
  embed(t, q, v, s);
  inner_->compute_contact(k, t, s.qf, s.vf, s.cf);
  drop(s.cf.W_N, s_, c.W_N);
  drop(s.cf.W_T, s_, c.W_T);
  const double wn = s.cf.W_N[s_], wt = s.cf.W_T[s_], om = omega(t);
  c.d_N = s.cf.d_N;
  c.v_N = s.cf.v_N;
  c.v_t = s.cf.v_t;
  c.b_N = s.cf.b_N + wn * om;
  c.b_T = s.cf.b_T + wt * om;
  c.wdot_N = s.cf.wdot_N + wn * law_.alpha;
  c.wdot_T = s.cf.wdot_T + wt * law_.alpha;
  c.normal_defined = s.cf.normal_defined;
}

bool PrescribedSpin::plane_motion(int k, double t, VecIn q, VecIn v, PlaneMotion& out) const {
  Scratch& s = scratch();
  embed(t, q, v, s);
  return inner_->plane_motion(k, t, s.qf, s.vf, out);
}

double PrescribedSpin::kinetic_energy(double t, VecIn q, VecIn v) const {
  Scratch& s = scratch();
  embed(t, q, v, s);
  return inner_->kinetic_energy(t, s.qf, s.vf);
}

double PrescribedSpin::potential_energy(double t, VecIn q) const {
  Scratch& s = scratch();
  insert(q, s_, theta(t), s.qf);
  return inner_->potential_energy(t, s.qf);
}

SmoothPower PrescribedSpin::smooth_power(double t, VecIn q, VecIn v) const {
  // the dampers' (the inner model has no drive torque; the drive's power is applied_power)
  Scratch& s = scratch();
  embed(t, q, v, s);
  return {0.0, inner_->smooth_power(t, s.qf, s.vf).damping};
}

double PrescribedSpin::drive_torque(double t, VecIn q, VecIn v, VecIn a,
                                    const ContactForce* F) const {
  // tau_d = [M_f a_f]_theta - f_f,theta - sum_k (W_N,theta F_N + W_T,theta F_T) (header)
  Scratch& s = scratch();
  embed(t, q, v, s);
  insert(a, s_, law_.alpha, s.af);
  double Ma, f;
  if (!inner_->spin_row(t, s.qf, s.vf, s.af, Ma, f)) {
    inner_->mass_product(s.qf, s.af, s.yf);
    inner_->smooth_forces(t, s.qf, s.vf, s.ff);
    Ma = s.yf[s_];
    f = s.ff[s_];
  }
  double tau = Ma - f;
  for (int k = 0; k < inner_->contact_count(); ++k) {
    if (F[k].F_N == 0.0 && F[k].F_T == 0.0) continue;
    inner_->compute_contact(k, t, s.qf, s.vf, s.cf);
    tau -= s.cf.W_N[s_] * F[k].F_N + s.cf.W_T[s_] * F[k].F_T;
  }
  return tau;
}

double PrescribedSpin::applied_power(double t, VecIn q, VecIn v, VecIn a,
                                     const ContactForce* F) const {
  return drive_torque(t, q, v, a, F) * omega(t);
}

const std::vector<Observable>& PrescribedSpin::observables() const {
  return observables_;
}

void PrescribedSpin::compute_observables(double t, VecIn q, VecIn v, VecIn a, const ContactForce* F,
                                         VecOut out) const {
  out[0] = theta(t);
  out[1] = omega(t);
  out[2] = drive_torque(t, q, v, a, F);
  const auto m = static_cast<Eigen::Index>(observables_.size()) - 3;
  if (m == 0) return;
  // the inner model's, at the full state (the spin's entries inserted)
  Scratch& s = scratch();
  embed(t, q, v, s);
  insert(a, s_, law_.alpha, s.af);
  inner_->compute_observables(t, s.qf, s.vf, s.af, F, out.segment(3, m));
}

double PrescribedSpin::spin(double t, VecIn /*q*/, VecIn /*v*/) const {
  return omega(t);
}

}  // namespace rubdyn
