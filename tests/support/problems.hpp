#pragma once
// Reusable problems with exact solutions, as LagrangianModels of their own size (a point in the
// plane: 2 dofs). Every solver is tested on them through the same interface as the rotor models.
#include <cmath>
#include <limits>
#include <numbers>

#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn::testing {

/// Minimal coordinates of the plane contact y = q[1] >= 0 with tangent q[0], for a model of n
/// dofs: slip drops q[1] (p = q without dof 1), stick also fixes q[0] at its value where stick
/// began (the anchor). For the 2-dof problems below a stick phase has no coordinate left.
class PlaneChart final : public ContactChart {
 public:
  explicit PlaneChart(int n = 2) : n_(n) {}
  int dim(ChartMode mode) const override { return mode == ChartMode::Slip ? n_ - 1 : n_ - 2; }
  void chart(ChartMode mode, VecIn q, VecIn v, ChartAnchor& anchor, VecOut p,
             VecOut pd) const override {
    anchor.fill(0.0);
    anchor[0] = q[0];
    for (int i = 0, k = 0; i < n_; ++i) {
      if (!coordinate(mode, i)) continue;
      p[k] = q[i];
      pd[k++] = v[i];
    }
  }
  void embed(ChartMode mode, const ChartAnchor& anchor, VecIn p, VecIn pd, VecOut q,
             VecOut v) const override {
    q.setZero();
    v.setZero();
    if (mode == ChartMode::Stick) q[0] = anchor[0];
    for (int i = 0, k = 0; i < n_; ++i) {
      if (!coordinate(mode, i)) continue;
      q[i] = p[k];
      v[i] = pd[k++];
    }
  }
  void reduce(ChartMode mode, const ChartAnchor&, VecIn, VecIn, VecIn, VecIn a,
              VecOut pdd) const override {
    for (int i = 0, k = 0; i < n_; ++i) {
      if (!coordinate(mode, i)) continue;
      pdd[k++] = a[i];
    }
  }
  ChartScales scales(ChartMode) const override { return {}; }

 private:
  /// Whether dof i is one of the reduced coordinates: never the normal dof 1; dof 0 only in slip.
  static bool coordinate(ChartMode mode, int i) {
    return i != 1 && (i != 0 || mode == ChartMode::Slip);
  }
  int n_;
};

/// Base of the test problems: a point of mass m in the plane, q = (x, y), on the ground y >= 0
/// (the contact: normal dof 1, tangent dof 0, unless a problem overrides compute_contact() and
/// then contact_chart(), which describes that plane).
class PlaneModel : public LagrangianModel {
 public:
  PlaneModel(ContactLaw law, double gap_scale) : law_(law), gap_scale_(gap_scale) {}
  int num_dofs() const override { return 2; }
  const std::vector<Coordinate>& coordinates() const override {
    static const std::vector<Coordinate> c = {
        {"x", "vx", "vx", "m", "along the ground", CoordinateRole::Other, 0},
        {"y", "vy", "vy", "m", "height above the ground", CoordinateRole::Other, 0}};
    return c;
  }
  void mass_matrix(VecIn /*q*/, MatOut M) const override {
    M.setZero();
    M(0, 0) = M(1, 1) = mass_;
  }
  void mass_product(VecIn /*q*/, VecIn x, VecOut y) const override { y = mass_ * x; }
  void solve_mass(VecIn /*q*/, MatOut B) const override { B /= mass_; }
  void mass_matrix_product_jacobian(VecIn, VecIn, MatOut J) const override { J.setZero(); }
  void compute_contact(int, double, VecIn q, VecIn v, ContactKinematics& c) const override {
    c.d_N = q[1];
    c.W_N.setZero();
    c.W_T.setZero();
    c.W_N[1] = 1.0;
    c.W_T[0] = 1.0;
    c.v_N = v[1];
    c.v_t = v[0];
    c.b_N = c.b_T = c.wdot_N = c.wdot_T = 0.0;
    c.normal_defined = true;
  }
  double kinetic_energy(double, VecIn, VecIn v) const override {
    return 0.5 * mass_ * v.squaredNorm();
  }
  double gap_scale(int = 0) const override { return gap_scale_; }
  const ContactLaw& contact_law(int = 0) const override { return law_; }
  const ContactChart* contact_chart() const override { return &chart_; }
  MechanicalState state() const { return MechanicalState(num_dofs()); }

 protected:
  PlaneChart chart_;
  double mass_ = 1.0;
  ContactLaw law_;
  double gap_scale_;
};

/// Undamped harmonic oscillator on dof 0: x'' = -w^2 x; the contact (y >= 0 on dof 1, y = 1
/// at rest) never closes. Exact: x = x0 cos(w t) + v0/w sin(w t). Energy is conserved.
class SpringMass final : public PlaneModel {
 public:
  explicit SpringMass(double w = 2.0 * std::numbers::pi) : PlaneModel({}, 1.0), w_(w) {}
  std::string_view name() const override { return "spring-mass"; }
  void smooth_forces(double, VecIn q, VecIn, VecOut f) const override {
    f.setZero();
    f[0] = -w_ * w_ * q[0];
  }
  void smooth_force_jacobians(double, VecIn, VecIn, MatOut dfdq, MatOut dfdv) const override {
    dfdq.setZero();
    dfdv.setZero();
    dfdq(0, 0) = -w_ * w_;
  }
  double potential_energy(double, VecIn q) const override { return 0.5 * w_ * w_ * q[0] * q[0]; }
  SmoothPower smooth_power(double, VecIn, VecIn) const override { return {}; }
  MechanicalState initial(double x0 = 1.0, double v0 = 0.0) const {
    MechanicalState s = state();
    s.q[0] = x0;
    s.q[1] = 1.0;
    s.v[0] = v0;
    return s;
  }
  double exact_x(double t, double x0 = 1.0, double v0 = 0.0) const {
    return x0 * std::cos(w_ * t) + v0 / w_ * std::sin(w_ * t);
  }
  double exact_v(double t, double x0 = 1.0, double v0 = 0.0) const {
    return -x0 * w_ * std::sin(w_ * t) + v0 * std::cos(w_ * t);
  }
  double omega() const { return w_; }

 private:
  double w_;
};

/// A ball dropped from height h0 at rest onto the ground y = 0 under gravity g, restitution e_n.
/// Exact: first impact at t1 = sqrt(2 h0 / g) with speed V1 = g t1; the k-th flight after it lasts
/// 2 e^k V1 / g; impacts accumulate at t_inf = t1 + 2 e V1 / (g (1 - e)).
class BouncingBall final : public PlaneModel {
 public:
  BouncingBall(double e_n, double h0 = 1.0, double g = 9.81)
      : PlaneModel({0.0, e_n, 0.0}, h0), h0_(h0), g_(g) {}
  std::string_view name() const override { return "bouncing-ball"; }
  void smooth_forces(double, VecIn, VecIn, VecOut f) const override {
    f.setZero();
    f[1] = -mass_ * g_;
  }
  void smooth_force_jacobians(double, VecIn, VecIn, MatOut dfdq, MatOut dfdv) const override {
    dfdq.setZero();
    dfdv.setZero();
  }
  double potential_energy(double, VecIn q) const override { return mass_ * g_ * q[1]; }
  SmoothPower smooth_power(double, VecIn, VecIn) const override { return {}; }
  MechanicalState initial() const {
    MechanicalState s = state();
    s.q[1] = h0_;
    return s;
  }
  double first_impact_time() const { return std::sqrt(2.0 * h0_ / g_); }
  /// Time of the k-th impact (k = 1, 2, ...).
  double impact_time(int k) const {
    const double t1 = first_impact_time(), V1 = g_ * t1, e = law_.e_n;
    double t = t1, ek = 1.0;
    for (int i = 1; i < k; ++i) {
      ek *= e;
      t += 2.0 * ek * V1 / g_;
    }
    return t;
  }
  double accumulation_time() const {
    const double t1 = first_impact_time(), e = law_.e_n;
    return t1 + 2.0 * e * g_ * t1 / (g_ * (1.0 - e));
  }
  double g() const { return g_; }

 private:
  double h0_, g_;
};

/// A block of mass m on a belt moving at speed v_b, tied to a fixed wall by a spring k, Coulomb
/// friction mu (static = kinetic), gravity g pressing it on the belt (normal force m g).
/// Written in the belt's frame (a Galilean change of frame, so the contact is scleronomous):
/// X = block position relative to the belt, the wall moves at -v_b: m X'' = -k (X + v_b t) + F_T,
/// v_t = X'. Starting at rest in the lab (X = 0, X' = -v_b): slip- until the block reaches the
/// belt speed at t1 = asin(v_b / (x_e w)) / w (x_e = mu g / w^2, w^2 = k / m; requires
/// x_e w > v_b), then stick (carried by the belt) until k x = mu m g, at t2 = t1 + (x_e - x1)/v_b
/// with x1 = x_e (1 - cos(w t1)), then slip- again: x = x_e + v_b/w sin(w (t - t2)) in the lab,
/// which touches the belt speed again tangentially at t2 + 2 pi / w (a degenerate point: tests
/// stop before it).
class BlockOnBelt final : public PlaneModel {
 public:
  BlockOnBelt(double mu = 0.5, double k = 100.0, double m = 1.0, double v_b = 1.0, double g = 9.81)
      : PlaneModel({mu, 0.0, 0.0}, 0.01), k_(k), v_b_(v_b), g_(g) {
    mass_ = m;
  }
  std::string_view name() const override { return "block-on-belt"; }
  void smooth_forces(double t, VecIn q, VecIn, VecOut f) const override {
    f.setZero();
    f[0] = -k_ * (q[0] + v_b_ * t);
    f[1] = -mass_ * g_;
  }
  void smooth_force_jacobians(double, VecIn, VecIn, MatOut dfdq, MatOut dfdv) const override {
    dfdq.setZero();
    dfdv.setZero();
    dfdq(0, 0) = -k_;
  }
  /// Gravity only: the spring to the moving wall is a non-conservative applied load here.
  double potential_energy(double, VecIn q) const override { return mass_ * g_ * q[1]; }
  SmoothPower smooth_power(double t, VecIn q, VecIn v) const override {
    return {-k_ * (q[0] + v_b_ * t) * v[0], 0.0};
  }
  MechanicalState initial() const {
    MechanicalState s = state();
    s.v[0] = -v_b_;
    return s;
  }
  double w() const { return std::sqrt(k_ / mass_); }
  double x_e() const { return law_.mu * g_ / (w() * w()); }
  double stick_time() const { return std::asin(v_b_ / (x_e() * w())) / w(); }
  double slip_time() const {
    const double t1 = stick_time(), x1 = x_e() * (1.0 - std::cos(w() * t1));
    return t1 + (x_e() - x1) / v_b_;
  }
  /// Lab position of the block for t in [0, t2 + 2 pi / w).
  double exact_lab_x(double t) const {
    const double t1 = stick_time(), t2 = slip_time();
    if (t <= t1) return x_e() * (1.0 - std::cos(w() * t));
    if (t <= t2) return x_e() * (1.0 - std::cos(w() * t1)) + v_b_ * (t - t1);
    return x_e() + v_b_ / w() * std::sin(w() * (t - t2));
  }
  double belt_speed() const { return v_b_; }
  double normal_force() const { return mass_ * g_; }

 private:
  double k_, v_b_, g_;
};

/// Free fall on dof 1 above the plane y = 0 (PlaneModel's contact) with no spin coordinate,
/// claiming `contacts` contacts; its force turns NaN after t_poison (a model failing mid-run).
class FreeFall final : public PlaneModel {
 public:
  explicit FreeFall(int contacts = 1, double t_poison = std::numeric_limits<double>::infinity())
      : PlaneModel(ContactLaw{}, 1.0), contacts_(contacts), t_poison_(t_poison) {}
  std::string_view name() const override { return "free fall"; }
  void smooth_forces(double t, VecIn, VecIn, VecOut f) const override {
    f.setZero();
    f[1] = t > t_poison_ ? std::numeric_limits<double>::quiet_NaN() : -9.81;
  }
  void smooth_force_jacobians(double, VecIn, VecIn, MatOut dfdq, MatOut dfdv) const override {
    dfdq.setZero();
    dfdv.setZero();
  }
  double potential_energy(double, VecIn q) const override { return 9.81 * q[1]; }
  SmoothPower smooth_power(double, VecIn, VecIn) const override { return {}; }
  int contact_count() const override { return contacts_; }

 private:
  int contacts_;
  double t_poison_;
};

}  // namespace rubdyn::testing
