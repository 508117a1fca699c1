#pragma once
// The Jeffcott-Black rotor (case file: [model] kind = "jeffcott"; derivation in
// docs/models.md, section 1): a disc on a massless shaft inside a stator ring across a radial
// clearance. Jeffcott's rotor (1919) with Black's sprung point-mass stator (1968); planar.
//
// Coordinates q = (x_r, y_r, theta, x_s, y_s): the disc's geometric centre (the centre of the
// seal circle of radius R), the spin angle, the stator centre; with a rigid stator
// (stator.rigid = true) the stator is fixed at the origin and q = (x_r, y_r, theta).
// Y is vertical (gravity along -Y, on the rotor and the sprung stator). With psi = theta + phi_u
// and u_b = m_r eps the unbalance (mass centre at z_r + eps e^{i psi}), J the polar inertia about
// the geometric centre (m_r eps^2 included; J > u_b^2 / m_r):
//   T = 1/2 m_r |z_r'|^2 + 1/2 J Omega^2 + u_b Omega (y_r' cos psi - x_r' sin psi)
//       + 1/2 m_s |z_s'|^2,
//   V = 1/2 k_r |z_r|^2 + 1/2 k_s |z_s|^2 + g (m_r y_r + u_b sin psi + m_s y_s),
//   M(q) = [m_r, 0, -u_b sin psi; 0, m_r, u_b cos psi; -u_b sin psi, u_b cos psi, J] (+ m_s I),
//   f = (-c_r x_r' - k_r x_r + u_b Omega^2 cos psi, -c_r y_r' - k_r y_r - m_r g
//        + u_b Omega^2 sin psi, tau(Omega) - u_b g cos psi, -c_s x_s' - k_s x_s,
//        -c_s y_s' - k_s y_s - m_s g).
// The contact is the paper's (contact/contact_kinematics.hpp) between the seal circle and the
// stator ring: d_N = g0 - |z_r - z_s|, W_T with -R on theta.
// Structured mass solve: the rotor block by its Schur complement on theta,
//   s = J - u_b^2 / m_r,  theta'' = (r_th - (a r_x + b r_y) / m_r) / s,
//   x'' = (r_x - a theta'') / m_r,  y'' = (r_y - b theta'') / m_r   (a = -u_b sin psi,
//   b = u_b cos psi), the stator diagonal.
// Minimal coordinates of the contact phases, as for the rigid rotor (phi: the angle of
// z_r - z_s): slip p = (phi, theta, x_s, y_s), stick p = (theta - theta0, x_s, y_s) with
// phi = phi0 - (R / g0)(theta - theta0) (without the stator's two for a rigid stator).
#include <vector>

#include "rubdyn/contact/ring_chart.hpp"
#include "rubdyn/model/lagrangian_model.hpp"
#include "rubdyn/model/loads.hpp"

namespace rubdyn {

struct JeffcottRotorParams {
  double mass = 5.0;     ///< m_r [kg], the disc's total mass (the unbalance included)
  double k = 5.0e6;      ///< k_r [N/m], the shaft's stiffness at the disc
  double c = 300.0;      ///< c_r [N s/m]
  double radius = 0.05;  ///< R [m], the seal circle
  double Jp = 0.06;      ///< J [kg m^2], polar inertia about the geometric centre
};

struct JeffcottStatorParams {
  bool rigid = false;   ///< a fixed ring at the origin: no coordinates, no mass, k, c
  double mass = 2.0;    ///< m_s [kg]
  double k = 2.0e6;     ///< k_s [N/m]
  double c = 100.0;     ///< c_s [N s/m]
  double gap = 2.0e-4;  ///< g0 [m], the radial clearance
};

struct JeffcottParams {
  JeffcottRotorParams rotor;
  JeffcottStatorParams stator;
  ContactLaw contact{0.1, 0.0, 0.0};
  LoadParams loads;
};

class JeffcottModel final : public LagrangianModel {
 public:
  enum Index : int { XR = 0, YR = 1, TH = 2, XS = 3, YS = 4 };
  explicit JeffcottModel(const JeffcottParams& p);

  std::string_view name() const override { return "jeffcott"; }
  int num_dofs() const override { return n_; }
  const std::vector<Coordinate>& coordinates() const override { return coords_; }
  void mass_matrix(VecIn q, MatOut M) const override;
  void mass_product(VecIn q, VecIn x, VecOut y) const override;
  void solve_mass(VecIn q, MatOut B) const override;
  void mass_matrix_product_jacobian(VecIn q, VecIn a, MatOut J) const override;
  void smooth_forces(double t, VecIn q, VecIn v, VecOut f) const override;
  void smooth_force_jacobians(double t, VecIn q, VecIn v, MatOut dfdq, MatOut dfdv) const override;
  void compute_contact(int k, double t, VecIn q, VecIn v, ContactKinematics& c) const override;
  double kinetic_energy(double t, VecIn q, VecIn v) const override;
  double potential_energy(double t, VecIn q) const override;
  SmoothPower smooth_power(double t, VecIn q, VecIn v) const override;
  double gap_scale(int /*k*/ = 0) const override { return p_.stator.gap; }
  const ContactLaw& contact_law(int /*k*/ = 0) const override { return p_.contact; }
  double contact_radius(int /*k*/ = 0) const override { return p_.rotor.radius; }
  const ContactChart* contact_chart() const override { return &chart_; }
  /// The same contact as a ring chart's (the event solver uses contact_chart; a prescribed spin
  /// wraps this one, contact/ring_chart.hpp).
  const RingChart* ring_chart() const override { return &ring_chart_; }
  int spin_coordinate() const override { return TH; }
  /// Tied: (x_r, y_r) with the stator's mass, spring and damper added (no coordinates for a
  /// rigid stator: the rotor is pinned); Free: the rotor and the stator on their own supports.
  /// No gyroscopic coupling: forward and backward whirl share every frequency.
  std::optional<LinearModel> linearize(Linearization mode) const override;

  const JeffcottParams& params() const { return p_; }
  bool rigid_stator() const { return p_.stator.rigid; }

 private:
  class Chart final : public ContactChart {
   public:
    Chart(double g0, double R, bool rigid) : g0_(g0), R_(R), rigid_(rigid) {}
    int dim(ChartMode mode) const override {
      return (mode == ChartMode::Slip ? 2 : 1) + (rigid_ ? 0 : 2);
    }
    void chart(ChartMode mode, VecIn q, VecIn v, ChartAnchor& anchor, VecOut p,
               VecOut pd) const override;
    void embed(ChartMode mode, const ChartAnchor& anchor, VecIn p, VecIn pd, VecOut q,
               VecOut v) const override;
    void reduce(ChartMode mode, const ChartAnchor& anchor, VecIn p, VecIn pd, VecIn q, VecIn a,
                VecOut pdd) const override;
    ChartScales scales(ChartMode mode) const override;

   private:
    double g0_, R_;
    bool rigid_;
  };

  JeffcottParams p_;
  int n_;
  std::vector<Coordinate> coords_;
  Chart chart_;
  RingContact geom_;  ///< the disc centre inside the ring (x_s, y_s), or the fixed ring
  RingChart ring_chart_;
  double ms_ = 0, ks_ = 0, cs_ = 0;  // 0 for a rigid stator
};

}  // namespace rubdyn
