#pragma once
// LagrangianModel: what every solver may know about the mechanics. Solvers see the model only
// through this interface (they never include the rotor-stator header), so that test problems
// with exact solutions (bouncing ball, block on a belt, spring-mass) run through the same solvers.
//
// Equations of motion with one unilateral contact (paper eq. 21):
//     M(q) dv/dt = f(t, q, v) + W_N(q) F_N + W_T(q) F_T,     dq/dt = v
// f collects every smooth force: external loads, gyroscopic, damping, stiffness, gravity.
// Energy audit: d(T + V)/dt = P_ext + P_damp + F_N v_N + F_T v_t, where T = 1/2 v^T M(q) v, V is
// the potential of the conservative forces inside f, P_ext the power of the non-conservative
// applied loads (driving torque) and P_damp <= 0 the power of the viscous dampers.
#include <Eigen/Cholesky>
#include <string_view>

#include "rubdyn/contact/contact_chart.hpp"
#include "rubdyn/contact/contact_kinematics.hpp"
#include "rubdyn/contact/contact_law.hpp"
#include "rubdyn/core/types.hpp"

namespace rubdyn {

/// Power of the smooth non-conservative forces [W].
struct SmoothPower {
  double external = 0.0;  ///< applied loads (driving torque)
  double damping = 0.0;   ///< viscous dampers, <= 0
};

class LagrangianModel {
 public:
  virtual ~LagrangianModel() = default;

  virtual std::string_view name() const = 0;

  /// M(q), symmetric positive definite.
  virtual void mass_matrix(const Vec7& q, Mat7& M) const = 0;
  /// Solves M(q) X = B in place for the first `ncols` columns of B (no allocation). The default
  /// factors M (LDLT); a model with a structured mass matrix overrides it.
  virtual void solve_mass(const Vec7& q, Mat7x3& B, int ncols) const {
    Mat7 M;
    mass_matrix(q, M);
    const Eigen::LDLT<Mat7> ldlt(M);
    for (int j = 0; j < ncols; ++j) B.col(j) = ldlt.solve(B.col(j));
  }
  /// J = d(M(q) a)/dq for a fixed vector a (needed by implicit schemes and analytic Jacobians).
  virtual void mass_matrix_product_jacobian(const Vec7& q, const Vec7& a, Mat7& J) const = 0;
  /// Smooth forces f(t, q, v) (no contact).
  virtual void smooth_forces(double t, const Vec7& q, const Vec7& v, Vec7& f) const = 0;
  /// df/dq and df/dv.
  virtual void smooth_force_jacobians(double t, const Vec7& q, const Vec7& v, Mat7& dfdq,
                                      Mat7& dfdv) const = 0;
  /// Contact kinematics at (q, v).
  virtual ContactKinematics contact(const Vec7& q, const Vec7& v) const = 0;
  /// Kinetic energy 1/2 v^T M(q) v.
  double kinetic_energy(const Vec7& q, const Vec7& v) const {
    Mat7 M;
    mass_matrix(q, M);
    return 0.5 * v.dot(M * v);
  }
  /// Potential energy of the conservative forces included in f [J].
  virtual double potential_energy(const Vec7& q) const = 0;
  /// Power of the smooth non-conservative forces.
  virtual SmoothPower smooth_power(double t, const Vec7& q, const Vec7& v) const = 0;
  /// Scale of the gap [m] (for scaled witnesses d_N / g0 and tolerances).
  virtual double gap_scale() const = 0;
  /// The contact law.
  virtual const ContactLaw& contact_law() const = 0;
  /// Minimal coordinates of the contact phases, or nullptr when the model has none (the
  /// event-driven integrator then integrates contact phases as a DAE with projection).
  virtual const ContactChart* contact_chart() const { return nullptr; }
  /// The coordinate whose rate is the monitored spin speed omega (the run monitor, omega_max,
  /// the crossing of omega_lim; Carpenter's free-spin column), or -1 when the model has none.
  /// The solvers never name a coordinate themselves.
  virtual int spin_coordinate() const { return -1; }
  /// omega at a state (0 without a spin coordinate).
  double spin(const Vec7& v) const {
    const int i = spin_coordinate();
    return i >= 0 ? v[i] : 0.0;
  }
  /// Number of unilateral contacts. The solvers handle one (the circular clearance); a model
  /// with more is rejected by them, not silently reduced.
  virtual int contact_count() const { return 1; }
};

}  // namespace rubdyn
