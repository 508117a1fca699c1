#pragma once
// The rigid rotor on one bearing inside a sprung rigid stator ring (paper, section 3, eq. 9-21).
//
// Coordinates q = (x_b, y_b, x_r, y_r, theta, x_s, y_s): bearing B and contact plane R of the
// rotor (translations), spin angle theta, stator centre. Y is vertical (gravity along -Y).
// Let l = L - delta (B to R), nu = d / l (B to G over B to R), u = x_r - x_b, w = y_r - y_b.
//
// Derivation (short). The small-angle kinematics (eq. 5, 9, 10) give
//   x_G = nu x_r + (1 - nu) x_b,  theta_x = -w / l,  theta_y = u / l,
// and the kinetic energy (eq. 8) becomes (eq. 11)
//   2 T = M11 (xb'^2 + yb'^2) + M22 (xr'^2 + yr'^2) + 2 M12 (xb' xr' + yb' yr') + Jp theta'^2
//         + H theta' (u' w - w' u) + m_s (xs'^2 + ys'^2),
//   M11 = (1-nu)^2 m + Jd/l^2,  M12 = nu (1-nu) m - Jd/l^2,  M22 = nu^2 m + Jd/l^2,  H = Jp/l^2.
// T = 1/2 v^T M(q) v with the only q-dependent entries from the term H theta' (u' w - w' u) / 2:
//   M(theta, x_r) = dT/dtheta' dxr' = H w / 2 = -H_y,   M(theta, x_b) = H_y = -H w / 2,
//   M(theta, y_r) = -H u / 2 = -H_x,                     M(theta, y_b) = H_x = H u / 2    (eq. 14)
// Lagrange's equations, row by row:
//   theta:  d/dt(Jp theta' + H (u' w - w' u)/2) - 0 = Jp theta'' + H (w u'' - u w'')/2
//           (the u'w' terms cancel): the theta row is M(q) row 5 times q'', with NO velocity term.
//   x_r:    d/dt(M22 xr' + M12 xb' + H theta' w / 2) - dT/dx_r
//           = M22 xr'' + M12 xb'' + H w theta''/2 + H theta' w'/2 - (-H theta' w'/2)
//           = [M q'']_xr + H theta' (yr' - yb')                      -> row x_r of theta' G v
//   and likewise for x_b, y_b, y_r. Hence (eq. 13, 16) with G skew-symmetric (eq. 14):
//   M(q) q'' + (theta' G + D) q' + K q = f_ext,   f_ext = (0, -(1-nu) m g, 0, -nu m g, tau_a, 0,
//   0).
// The potential is V = k_b/2 (x_b^2 + y_b^2) + m g (nu y_r + (1-nu) y_b) + k_s/2 (x_s^2 + y_s^2)
// (eq. 12, 15: the stator has no gravity term in the paper; its weight is carried by its
// support at q_s = 0). D holds c_b on (x_b, y_b) and c_s on (x_s, y_s). Since G is skew, the
// gyroscopic forces do no work: d(T+V)/dt = tau_a theta' - v^T D v + F_N v_N + F_T v_t.
// Contact kinematics: see contact/contact_kinematics.hpp (eq. 17-19).
//
// Loads beyond the paper (docs/models.md, sections 2-3; model/loads.hpp):
//   - a mass unbalance u_b = m eps (loads.unbalance) in the plane of G at the angle theta + phi_u
//     from X. It adds to T the cross terms u_b theta' (-sin(theta + phi_u) x_G' + cos(theta +
//     phi_u) y_G') with x_G = nu x_r + (1 - nu) x_b: M(q) gains the theta-column entries
//     -u_b s nu, u_b c nu (rows x_r, y_r) and -u_b s (1-nu), u_b c (1-nu) (rows x_b, y_b),
//     s = sin(theta + phi_u), c = cos(theta + phi_u); the lateral rows gain the centrifugal
//     force u_b theta'^2 (c, s) spread by nu and 1 - nu; the theta row gains gravity's torque
//     -u_b g c. Jp is the polar inertia about the shaft axis with the unbalance's m eps^2
//     included. With u_b = 0 every formula above is the paper's, to the same arithmetic.
//   - the drive torque tau(Omega): constant tau_a, or the linear law tau_a (1 - Omega /
//     loads.torque_free_speed) (its derivative -tau_a / Omega_0 enters the velocity Jacobian).
//   - loads.spin = "prescribed": the model is wrapped by PrescribedSpin (prescribed_spin.hpp),
//     which drops the theta row and reports the holding torque.
//
// Structured mass solve. M couples x_b-x_r and y_b-y_r through the constant 2x2 block
// A = [[M11, M12], [M12, M22]] and every rotor lateral dof to theta through the column
// b = (H_y, H_x, -H_y, -H_x) (rows x_b, y_b, x_r, y_r); the stator is diagonal. With u = A^-1 b
// and the Schur complement s = Jp - b.u = Jp - (H_x^2 + H_y^2)(M11 + M22 + 2 M12) / det A:
//   theta'' = (r_th - b.A^-1 r_L) / s,  x_L = A^-1 r_L - u theta'',  x_s = r_s / m_s,
// about 25 flops per right-hand side instead of a 7x7 factorisation.
//
// Minimal coordinates of the contact phases (contact/contact_chart.hpp), with phi the angle of
// (x_r - x_s, y_r - y_s) and n = (cos phi, sin phi), t_phi = (-sin phi, cos phi):
//   slip:  p = (x_b, y_b, phi, theta, x_s, y_s); x_r = x_s + g0 cos phi, y_r = y_s + g0 sin phi;
//          v_r - v_s = g0 phi' t_phi; a_r - a_s = g0 phi'' t_phi - g0 phi'^2 n, so
//          phi'' = t_phi . (a_r - a_s) / g0 (the curvature term is normal to t_phi).
//   stick: v_t = -g0 phi' - R_r theta' = 0 integrates to phi = phi0 - k (theta - theta0),
//          k = R_r / g0; p = (x_b, y_b, theta - theta0, x_s, y_s), anchor (phi0, theta0).
//          Theta is integrated relative to its value at the start of the phase: the orbit
//          position depends on it through k, and an absolute theta of O(1e3) rad would carry
//          its round-off (1e-13 rad) into the orbit.
//   Error weights: phi moves the contact point by g0 per radian, theta - theta0 (stick) by R_r.
//
// Several rub planes (RotorStatorParams::planes, a case's [[plane]] tables; docs/models.md,
// section 6). Plane k sits at the axial distance p_k from B; the rotor's point there is the
// paper's linear interpolation (eq. 9-10) z_k = (1 - s_k) z_b + s_k z_r, s_k = p_k / l. Its ring
// is sprung (m_s,k, k_s,k, c_s,k: coordinates x_s_k, y_s_k after theta, in plane order) or fixed
// at the origin (no coordinates). Contact k: sr = z_k - z_s,k, d_N = g0_k - |sr|, and
//   W_N = -n on (x_b, y_b) times (1 - s_k), on (x_r, y_r) times s_k, +n on the ring's coordinates,
//   W_T = t likewise, -R_k on theta,  v_t = t . d(sr)/dt - R_k theta',
// wdot_N, wdot_T as in contact_kinematics.hpp with |sr|. The mass matrix is the rotor block above
// (unchanged) with one diagonal m_s,k block per sprung ring; the rings' springs and dampers join
// K and D. No planes: the paper's single plane at R (s = 1) on the ring of [stator], the model
// above exactly (the same coordinates, names and arithmetic). The contact chart exists for that
// model, and for one [[plane]] at R on a sprung ring (the same model under other names); with
// other planes the event-driven solver uses its projection formulation.
#include <optional>
#include <string_view>
#include <vector>

#include "rubdyn/model/lagrangian_model.hpp"
#include "rubdyn/model/rotor_stator_params.hpp"

namespace rubdyn {

/// Index of each generalised coordinate of the rigid rotor in q (paper, section 3.2.2, eq. 17).
enum Dof : int { XB = 0, YB = 1, XR = 2, YR = 3, TH = 4, XS = 5, YS = 6 };

class RotorStatorModel final : public LagrangianModel {
 public:
  /// The dofs of the paper's model (one plane at R on a sprung ring); with planes, 5 plus two
  /// per sprung ring.
  static constexpr int kDofs = 7;
  /// Two planes, each on a sprung ring of its own (the steppers' 9-dof fixed-size path).
  static constexpr int kTwoPlaneDofs = 9;
  explicit RotorStatorModel(const RotorStatorParams& p);

  std::string_view name() const override { return "rigid-rotor"; }
  int num_dofs() const override { return n_; }
  const std::vector<Coordinate>& coordinates() const override;
  /// The coordinates of the model these parameters make (only p.planes matters).
  static std::vector<Coordinate> coordinates_of(const RotorStatorParams& p);
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
  int contact_count() const override { return static_cast<int>(planes_.size()); }
  double gap_scale(int k = 0) const override { return planes_[static_cast<std::size_t>(k)].gap; }
  const ContactLaw& contact_law(int k = 0) const override {
    return planes_[static_cast<std::size_t>(k)].law;
  }
  double contact_radius(int k = 0) const override {
    return planes_[static_cast<std::size_t>(k)].radius;
  }
  bool plane_motion(int k, double t, VecIn q, VecIn v, PlaneMotion& out) const override;
  const ContactChart* contact_chart() const override { return chartable_ ? &chart_ : nullptr; }
  const RingChart* ring_chart() const override { return ring_chart_ ? &*ring_chart_ : nullptr; }
  int spin_coordinate() const override { return TH; }
  /// Tied: the 4-dof (x_b, y_b, x_r, y_r) system with every sprung ring tied to the rotor at
  /// its plane (its mass, damper and spring on the rotor's point there, through the
  /// interpolation weights; campbell.hpp); none when a ring is fixed (a constraint, not a
  /// linear model of this form). Free: (x_b, y_b, x_r, y_r) and the rings, without contact.
  std::optional<LinearModel> linearize(Linearization mode) const override;

  /// Power of the bearing dampers -c_b |v_b|^2 and of the rings' dampers -sum c_s |v_s|^2 [W].
  double bearing_damping_power(VecIn v) const;
  double stator_damping_power(VecIn v) const;
  /// The model without planes: the paper's one plane at R on a sprung ring (7 dofs).
  bool single_plane() const { return single_; }
  /// Power of the driving torque tau(theta') theta' [W].
  double torque_power(VecIn v) const { return p_.loads.drive_torque(v[TH]) * v[TH]; }

  const RotorStatorParams& params() const { return p_; }
  double l() const { return l_; }      ///< L - delta [m]
  double nu() const { return nu_; }    ///< d / (L - delta) [-]
  double M11() const { return M11_; }  ///< [kg]
  double M12() const { return M12_; }  ///< [kg]
  double M22() const { return M22_; }  ///< [kg]
  double H() const { return H_; }      ///< Jp / (L - delta)^2 [kg]
  /// Gyroscopic matrix G (eq. 14), constant and skew-symmetric; the force is theta' G v.
  const Mat& G() const { return G_; }
  /// Damping and stiffness matrices D, K.
  const Mat& D() const { return D_; }
  const Mat& K() const { return K_; }
  /// External load vector f_ext (gravity split and driving torque).
  const Vec& f_ext() const { return fext_; }

 private:
  class Chart final : public ContactChart {
   public:
    Chart(double g0, double R_r) : g0_(g0), R_r_(R_r) {}
    int dim(ChartMode mode) const override { return mode == ChartMode::Slip ? 6 : 5; }
    void chart(ChartMode mode, VecIn q, VecIn v, ChartAnchor& anchor, VecOut p,
               VecOut pd) const override;
    void embed(ChartMode mode, const ChartAnchor& anchor, VecIn p, VecIn pd, VecOut q,
               VecOut v) const override;
    void reduce(ChartMode mode, const ChartAnchor& anchor, VecIn p, VecIn pd, VecIn q, VecIn a,
                VecOut pdd) const override;
    ChartScales scales(ChartMode mode) const override;

   private:
    double g0_, R_r_;
  };

  /// A sprung ring: its coordinates (dof, dof + 1) and support.
  struct Ring {
    int dof = 0;
    double mass = 1, k = 0, c = 0, inv_mass = 1;
  };
  /// A rub plane: its interpolation weight, seal, clearance, law and ring (-1: fixed ring).
  struct Plane {
    double s = 1.0;    ///< p_k / l
    bool at_R = true;  ///< s == 1: the rotor's point is (x_r, y_r) itself
    double radius = 0, gap = 0;
    ContactLaw law;
    int ring = -1;     ///< first dof of its ring, or -1
    RingContact geom;  ///< the rotor's point (R, or between B and R) and the ring, for the
                       ///< one ring-contact kinematics (contact_kinematics.hpp)
  };

  /// compute_contact of plane k of a model with [[plane]] tables.
  void plane_contact(int k, VecIn q, VecIn v, ContactKinematics& c) const;
  /// The rings' rows of a column of solve_mass: divided by their masses.
  template <class Col>
  void scale_rings(Col& r) const {
    if (single_) {
      r[XS] *= inv_ms_;
      r[YS] *= inv_ms_;
      return;
    }
    for (const Ring& g : rings_) {
      r[g.dof] *= g.inv_mass;
      r[g.dof + 1] *= g.inv_mass;
    }
  }

  RotorStatorParams p_;
  Chart chart_;
  std::optional<RingChart> ring_chart_;  ///< every plane's point and ring
  double inv_ms_ = 1.0;                  // 1 / m_s of the single plane's ring
  bool single_ = true;                   // no planes: the paper's model
  bool chartable_ = true;                // one plane at R on a sprung ring: the chart applies
  int n_ = kDofs;
  std::vector<Ring> rings_;
  std::vector<Plane> planes_;
  std::vector<Coordinate> coords_;  // with planes (the single-plane model's are static)
  double l_, nu_, M11_, M12_, M22_, H_;
  Mat G_, D_, K_, M0_;  // M0_: the constant part of M(q)
  // the same, fixed-size: the unrolled fast path of mass_matrix and smooth_force_jacobians
  Eigen::Matrix<double, kDofs, kDofs> M0f_, Gf_, Df_, Kf_;
  Vec fext_;
  double detA_ = 1;            // det of the 2x2 rotor block
  double ub_ = 0, phi_u_ = 0;  // the unbalance u_b [kg m] and its phase [rad]
};

}  // namespace rubdyn
