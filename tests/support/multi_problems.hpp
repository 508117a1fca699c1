#pragma once
// Test problems with several contacts (K > 1), with exact solutions or exact reductions to the
// one-contact problems of problems.hpp, for the solvers' K-contact paths.
//
// ProductModel  two models side by side, uncoupled: the dofs, contacts and coordinates of the
//               first, then those of the second. Each contact only sees its own model's dofs,
//               so every run of the product must give each part's own run (exactly in exact
//               arithmetic; to the solver's tolerance in floating point, since an adaptive step
//               is chosen on the joint state). Two copies with the same initial state make
//               contacts that close at the same instant: simultaneous impacts, exactly.
// FallingRod    a rigid rod in the vertical plane with two contact points (its ends) on the
//               ground: the two contacts are coupled through the rod's rotation (a full 4x4
//               Delassus matrix), the classic problem of simultaneous impacts, of stick at one
//               end while the other slips, and of Painleve's paradox at large mu.
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn::testing {

/// Two models side by side (see the file's comment). The spin coordinate, if any, is the first
/// model's (else the second's). No chart, no linearisation, no observables.
class ProductModel final : public LagrangianModel {
 public:
  ProductModel(std::shared_ptr<const LagrangianModel> a, std::shared_ptr<const LagrangianModel> b)
      : a_(std::move(a)),
        b_(std::move(b)),
        na_(a_->num_dofs()),
        nb_(b_->num_dofs()),
        ka_(a_->contact_count()),
        kb_(b_->contact_count()),
        name_(std::string(a_->name()) + " x " + std::string(b_->name())),
        ca_(na_),
        cb_(nb_) {
    for (const auto* part : {a_.get(), b_.get()}) {
      const int shift = part == a_.get() ? 0 : ka_;
      const std::string sfx = part == a_.get() ? "_a" : "_b";
      for (Coordinate c : part->coordinates()) {
        c.name += sfx;
        c.rate += sfx;
        c.rate_key += sfx;
        c.plane += shift;
        coords_.push_back(std::move(c));
      }
    }
  }
  std::string_view name() const override { return name_; }
  int num_dofs() const override { return na_ + nb_; }
  const std::vector<Coordinate>& coordinates() const override { return coords_; }

  void mass_matrix(VecIn q, MatOut M) const override {
    M.setZero();
    a_->mass_matrix(qa(q), M.topLeftCorner(na_, na_));
    b_->mass_matrix(qb(q), M.bottomRightCorner(nb_, nb_));
  }
  void mass_product(VecIn q, VecIn x, VecOut y) const override {
    a_->mass_product(qa(q), qa(x), y.head(na_));
    b_->mass_product(qb(q), qb(x), y.tail(nb_));
  }
  void solve_mass(VecIn q, MatOut B) const override {
    a_->solve_mass(qa(q), B.topRows(na_));
    b_->solve_mass(qb(q), B.bottomRows(nb_));
  }
  void mass_matrix_product_jacobian(VecIn q, VecIn x, MatOut J) const override {
    J.setZero();
    a_->mass_matrix_product_jacobian(qa(q), qa(x), J.topLeftCorner(na_, na_));
    b_->mass_matrix_product_jacobian(qb(q), qb(x), J.bottomRightCorner(nb_, nb_));
  }
  void smooth_forces(double t, VecIn q, VecIn v, VecOut f) const override {
    a_->smooth_forces(t, qa(q), qa(v), f.head(na_));
    b_->smooth_forces(t, qb(q), qb(v), f.tail(nb_));
  }
  void smooth_force_jacobians(double t, VecIn q, VecIn v, MatOut dfdq, MatOut dfdv) const override {
    dfdq.setZero();
    dfdv.setZero();
    a_->smooth_force_jacobians(t, qa(q), qa(v), dfdq.topLeftCorner(na_, na_),
                               dfdv.topLeftCorner(na_, na_));
    b_->smooth_force_jacobians(t, qb(q), qb(v), dfdq.bottomRightCorner(nb_, nb_),
                               dfdv.bottomRightCorner(nb_, nb_));
  }

  int contact_count() const override { return ka_ + kb_; }
  /// Not reentrant (a scratch per part): the tests run one solver per model at a time.
  void compute_contact(int k, double t, VecIn q, VecIn v, ContactKinematics& c) const override {
    const bool first = k < ka_;
    ContactKinematics& s = first ? ca_ : cb_;
    if (first)
      a_->compute_contact(k, t, qa(q), qa(v), s);
    else
      b_->compute_contact(k - ka_, t, qb(q), qb(v), s);
    c.W_N.setZero();
    c.W_T.setZero();
    (first ? c.W_N.head(na_) : c.W_N.tail(nb_)) = s.W_N;
    (first ? c.W_T.head(na_) : c.W_T.tail(nb_)) = s.W_T;
    c.d_N = s.d_N;
    c.v_N = s.v_N;
    c.v_t = s.v_t;
    c.b_N = s.b_N;
    c.b_T = s.b_T;
    c.wdot_N = s.wdot_N;
    c.wdot_T = s.wdot_T;
    c.normal_defined = s.normal_defined;
  }
  const ContactLaw& contact_law(int k = 0) const override {
    return k < ka_ ? a_->contact_law(k) : b_->contact_law(k - ka_);
  }
  double gap_scale(int k = 0) const override {
    return k < ka_ ? a_->gap_scale(k) : b_->gap_scale(k - ka_);
  }
  double contact_radius(int k = 0) const override {
    return k < ka_ ? a_->contact_radius(k) : b_->contact_radius(k - ka_);
  }

  double kinetic_energy(double t, VecIn q, VecIn v) const override {
    return a_->kinetic_energy(t, qa(q), qa(v)) + b_->kinetic_energy(t, qb(q), qb(v));
  }
  double potential_energy(double t, VecIn q) const override {
    return a_->potential_energy(t, qa(q)) + b_->potential_energy(t, qb(q));
  }
  SmoothPower smooth_power(double t, VecIn q, VecIn v) const override {
    const SmoothPower pa = a_->smooth_power(t, qa(q), qa(v)),
                      pb = b_->smooth_power(t, qb(q), qb(v));
    return {pa.external + pb.external, pa.damping + pb.damping};
  }
  int spin_coordinate() const override {
    const int ia = a_->spin_coordinate();
    if (ia >= 0) return ia;
    const int ib = b_->spin_coordinate();
    return ib >= 0 ? na_ + ib : -1;
  }

  /// The product's state from the parts' states.
  MechanicalState join(const MechanicalState& sa, const MechanicalState& sb) const {
    MechanicalState s(num_dofs(), sa.t);
    s.q << sa.q, sb.q;
    s.v << sa.v, sb.v;
    return s;
  }
  int dofs_a() const { return na_; }
  int contacts_a() const { return ka_; }

 private:
  // the parts' views of a product vector (contiguous segments: no copy)
  Eigen::Map<const Vec> qa(VecIn x) const { return {x.data(), na_}; }
  Eigen::Map<const Vec> qb(VecIn x) const { return {x.data() + na_, nb_}; }

  std::shared_ptr<const LagrangianModel> a_, b_;
  int na_, nb_, ka_, kb_;
  std::string name_;
  std::vector<Coordinate> coords_;
  mutable ContactKinematics ca_, cb_;
};

/// A uniform rigid rod of mass m and length 2 l in the vertical plane, q = (x, y, phi): centre
/// (x, y), angle phi from the horizontal; gravity g along -y; the ground y = 0 touched by its
/// two ends. Contact 0 is end A = (x - l cos phi, y - l sin phi), contact 1 end B = (x + l cos
/// phi, y + l sin phi). M = diag(m, m, J), J = m l^2 / 3. For end s = -1 (A), +1 (B):
///   d_N = y + s l sin phi,  W_N = (0, 1, s l cos phi),  wdot_N = -s l sin phi phi'^2
///   v_t = x' - s l sin phi phi',  W_T = (1, 0, -s l sin phi),  wdot_T = -s l cos phi phi'^2
/// (v_t: the end's horizontal speed, the ground at rest). Exact solutions used by the tests:
///   - dropped flat (phi = 0) from height h at rest: both ends reach the ground at
///     t1 = sqrt(2 h / g) with speed g t1, simultaneously; e_n = 0: it rests, F_N = m g / 2 at
///     each end; e_n > 0: both ends bounce together (the joint impact keeps phi' = 0);
///   - flat on the ground (y = 0, phi = 0) sliding at vx0 > 0 with friction mu: both ends slip,
///     x'' = -mu g, F_N = m g / 2 at each end (the rod lies on the ground, so the friction forces
///     act at the centre's height and have no moment about it), until both stick at
///     t = vx0 / (mu g), x = vx0^2 / (2 mu g).
class FallingRod final : public LagrangianModel {
 public:
  FallingRod(ContactLaw law, double m = 1.0, double l = 0.5, double g = 9.81)
      : law_(law), m_(m), l_(l), g_(g), J_(m * l * l / 3.0) {}
  std::string_view name() const override { return "falling-rod"; }
  int num_dofs() const override { return 3; }
  const std::vector<Coordinate>& coordinates() const override {
    static const std::vector<Coordinate> c = {
        {"x", "vx", "vx", "m", "centre, horizontal", CoordinateRole::Other, 0},
        {"y", "vy", "vy", "m", "centre height", CoordinateRole::Other, 0},
        {"phi", "vphi", "vphi", "rad", "angle from the horizontal", CoordinateRole::Other, 0}};
    return c;
  }
  void mass_matrix(VecIn, MatOut M) const override {
    M.setZero();
    M(0, 0) = M(1, 1) = m_;
    M(2, 2) = J_;
  }
  void mass_product(VecIn, VecIn x, VecOut y) const override {
    y[0] = m_ * x[0];
    y[1] = m_ * x[1];
    y[2] = J_ * x[2];
  }
  void solve_mass(VecIn, MatOut B) const override {
    B.row(0) /= m_;
    B.row(1) /= m_;
    B.row(2) /= J_;
  }
  void mass_matrix_product_jacobian(VecIn, VecIn, MatOut J) const override { J.setZero(); }
  void smooth_forces(double, VecIn, VecIn, VecOut f) const override {
    f.setZero();
    f[1] = -m_ * g_;
  }
  void smooth_force_jacobians(double, VecIn, VecIn, MatOut dfdq, MatOut dfdv) const override {
    dfdq.setZero();
    dfdv.setZero();
  }
  int contact_count() const override { return 2; }
  void compute_contact(int k, double, VecIn q, VecIn v, ContactKinematics& c) const override {
    const double s = k == 0 ? -1.0 : 1.0, sn = std::sin(q[2]), cs = std::cos(q[2]);
    const double w = v[2];
    c.d_N = q[1] + s * l_ * sn;
    c.W_N.setZero();
    c.W_T.setZero();
    c.W_N[1] = 1.0;
    c.W_N[2] = s * l_ * cs;
    c.W_T[0] = 1.0;
    c.W_T[2] = -s * l_ * sn;
    c.v_N = c.W_N.dot(v);
    c.v_t = c.W_T.dot(v);
    c.b_N = c.b_T = 0.0;
    c.wdot_N = -s * l_ * sn * w * w;
    c.wdot_T = -s * l_ * cs * w * w;
    c.normal_defined = true;
  }
  const ContactLaw& contact_law(int = 0) const override { return law_; }
  double gap_scale(int = 0) const override { return l_; }
  double kinetic_energy(double, VecIn, VecIn v) const override {
    return 0.5 * (m_ * (v[0] * v[0] + v[1] * v[1]) + J_ * v[2] * v[2]);
  }
  double potential_energy(double, VecIn q) const override { return m_ * g_ * q[1]; }
  SmoothPower smooth_power(double, VecIn, VecIn) const override { return {}; }

  /// At rest (or translating at vx) at height h, angle phi.
  MechanicalState initial(double h, double phi = 0.0, double vx = 0.0) const {
    MechanicalState s(3);
    s.q << 0.0, h, phi;
    s.v << vx, 0.0, 0.0;
    return s;
  }
  double mass() const { return m_; }
  double half_length() const { return l_; }
  double g() const { return g_; }

 private:
  ContactLaw law_;
  double m_, l_, g_, J_;
};

}  // namespace rubdyn::testing
