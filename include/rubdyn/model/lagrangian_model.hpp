#pragma once
// LagrangianModel: what every solver and every layer above the model may know about the
// mechanics. Solvers see a model only through this interface (they never include a model's
// header), so that the rigid rotor, the Jeffcott rotor and test problems with exact solutions
// (bouncing ball, block on a belt, spring-mass) run through the same solvers.
//
// The model owns its size (num_dofs()), the names and roles of its coordinates (coordinates()),
// its contacts (contact_count(), each with its kinematics, law and gap scale) and the services
// the layers above need: the initial-state gap check (initial_penetration), the linearisation of
// the Campbell diagram (linearize).
//
// Equations of motion with K unilateral contacts (paper eq. 21, with C_N, C_T of K columns):
//     M(q) dv/dt = f(t, q, v) + sum_k (W_N,k(q) F_N,k + W_T,k(q) F_T,k),     dq/dt = v
// f collects every smooth force: external loads, gyroscopic, damping, stiffness, gravity.
// Energy audit: d(T + V)/dt = P_ext + P_damp + sum_k (F_N,k v_N,k + F_T,k v_t,k), where
// T = 1/2 v^T M(q) v, V is the potential of the conservative forces inside f, P_ext the power of
// the non-conservative applied loads (driving torque) and P_damp <= 0 the power of the viscous
// dampers.
//
// Sizes: every vector argument has num_dofs() entries, every matrix num_dofs() rows (VecIn binds
// to a Vec without a copy). A model holds no mutable state: one model may serve several runs on
// several threads.
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "rubdyn/contact/contact_chart.hpp"
#include "rubdyn/contact/contact_kinematics.hpp"
#include "rubdyn/contact/contact_law.hpp"
#include "rubdyn/contact/ring_chart.hpp"
#include "rubdyn/core/matrix_entry.hpp"
#include "rubdyn/core/types.hpp"
#include "rubdyn/model/coordinates.hpp"

namespace rubdyn {

/// Power of the smooth non-conservative forces [W].
struct SmoothPower {
  double external = 0.0;  ///< applied loads (driving torque)
  double damping = 0.0;   ///< viscous dampers, <= 0
};

/// Which linearisation of the model a Campbell diagram is made of (LagrangianModel::linearize).
enum class Linearization {
  /// The stator tied to the rotor in every contact plane (the paper's coupled system, section
  /// 5.1.2): the modes a permanent full contact would whirl at.
  Tied,
  /// No contact: the rotor and the stator each on their own supports.
  Free,
};

/// A linear(ised) rotor at spin speed Omega:  M x'' + (Omega G + D) x' + K x = 0, about the
/// centred position, with the spin imposed (its row dropped). `nodes` pairs the (x, y)
/// coordinates whose whirl labels the modes forward or backward; the model is isotropic, so that
/// every mode whirls one way only (analysis/campbell.hpp).
struct LinearModel {
  std::vector<std::string> names;  ///< the coordinates of x
  Mat M, G, D, K;                  ///< M SPD, G skew-symmetric
  std::vector<std::pair<int, int>> nodes;
  int size() const { return static_cast<int>(names.size()); }
};

/// The force of one contact (F_N along -n on the rotor, F_T along t): what a rheonomic drive's
/// work and a model's observables may depend on.
struct ContactForce {
  double F_N = 0.0, F_T = 0.0;
};

/// A quantity a model computes at every output sample besides its coordinates (an output column
/// of timeseries.csv): e.g. the spin angle, speed and holding torque of a prescribed spin.
struct Observable {
  std::string name, unit, meaning;
};

/// The two centres of a contact's plane at one state: the rotor's point and the stator ring's
/// centre, with their velocities (LagrangianModel::plane_motion). What the analysis reads a
/// plane's orbit, precession and whirl from.
struct PlaneMotion {
  Vec2 rotor = Vec2::Zero(), rotor_rate = Vec2::Zero();
  Vec2 stator = Vec2::Zero(), stator_rate = Vec2::Zero();
};

/// A contact that the initial state penetrates (initial_penetration).
struct Penetration {
  int contact = 0;
  double d_N = 0.0;  ///< < 0 [m]
};

class LagrangianModel {
 public:
  virtual ~LagrangianModel() = default;

  virtual std::string_view name() const = 0;
  /// Number of generalised coordinates n.
  virtual int num_dofs() const = 0;
  /// Their names and roles, in q order (size n).
  virtual const std::vector<Coordinate>& coordinates() const = 0;

  /// M(q), symmetric positive definite.
  virtual void mass_matrix(VecIn q, MatOut M) const = 0;
  /// y = M(q) x. The default forms M (allocates); a model used in a fixed-step scheme's hot path
  /// overrides it with a structured product (the built-in models do).
  virtual void mass_product(VecIn q, VecIn x, VecOut y) const;
  /// Solves M(q) X = B in place for every column of B (n rows). The default factors M (LDLT)
  /// into temporaries, i.e. allocates: a model used in a solver's hot path overrides it with a
  /// structured solve (the built-in models do).
  virtual void solve_mass(VecIn q, MatOut B) const;
  /// J = d(M(q) a)/dq for a fixed vector a (needed by implicit schemes and analytic Jacobians).
  virtual void mass_matrix_product_jacobian(VecIn q, VecIn a, MatOut J) const = 0;
  /// Smooth forces f(t, q, v) (no contact).
  virtual void smooth_forces(double t, VecIn q, VecIn v, VecOut f) const = 0;
  /// df/dq and df/dv.
  virtual void smooth_force_jacobians(double t, VecIn q, VecIn v, MatOut dfdq,
                                      MatOut dfdv) const = 0;
  /// The matrices of free flight's Newton systems as entry lists, for wide models whose dense
  /// n x n Jacobians would cost O(n^2) per Jacobian: e.M = M(q), e.dq = df/dq - d(M a)/dq,
  /// e.dv = df/dv (a: the acceleration at (t, q, v)), each the sum of its entries. The lists
  /// are structural: an entry is listed where the matrix can be nonzero, whatever its value
  /// now, so that their positions do not change with the state. The lists are cleared first;
  /// they keep their capacity, so that only the first call of a session allocates. False (the
  /// default): not provided, the solvers use the dense Jacobians above.
  virtual bool newton_entries(double /*t*/, VecIn /*q*/, VecIn /*v*/, VecIn /*a*/,
                              NewtonEntries& /*e*/) const {
    return false;
  }
  /// Solves M'(q) X = B in place, M' the mass matrix without row and column `s` (B: n - 1 rows,
  /// coordinate s left out), for models that solve it cheaper than through the whole M (a
  /// prescribed spin's block). False (the default): not provided.
  virtual bool solve_mass_without(int /*s*/, VecIn /*q*/, MatOut /*B*/) const { return false; }
  /// The spin coordinate's rows alone: (M(q) a)_s and f_s(t, q, v), the same values as
  /// mass_product's and smooth_forces' entries s, in O(n w) instead of all rows (a prescribed
  /// spin's drive torque at every right-hand side). False (the default): not provided.
  virtual bool spin_row(double /*t*/, VecIn /*q*/, VecIn /*v*/, VecIn /*a*/, double& /*Ma*/,
                        double& /*f*/) const {
    return false;
  }

  /// Number of unilateral contacts K >= 1. Every solver takes several (the event-driven
  /// integrator up to 8); none silently reduces them.
  virtual int contact_count() const { return 1; }
  /// Kinematics of contact k at (t, q, v) into `c` (W_N and W_T of size n, every field set).
  virtual void compute_contact(int k, double t, VecIn q, VecIn v, ContactKinematics& c) const = 0;
  /// The same, returned, for any vector expressions (allocates: for tests and tools, not for
  /// hot paths).
  template <class Q, class V>
  ContactKinematics contact(int k, double t, const Eigen::MatrixBase<Q>& q,
                            const Eigen::MatrixBase<V>& v) const {
    const Vec qe = q, ve = v;
    ContactKinematics c(num_dofs());
    compute_contact(k, t, qe, ve, c);
    return c;
  }
  /// The law of contact k.
  virtual const ContactLaw& contact_law(int k = 0) const = 0;
  /// Scale of the gap of contact k [m] (scaled witnesses d_N / g0, tolerances).
  virtual double gap_scale(int k = 0) const = 0;
  /// The lever arm of contact k's friction force about the spin axis: the rotor's seal radius
  /// R (the spin entry of W_T is -R) [m]; 0 for a model without a spin.
  virtual double contact_radius(int /*k*/ = 0) const { return 0.0; }
  /// The centres of contact k's plane at (t, q, v) into `out`; false when the model cannot say
  /// (no rotor coordinates for that plane). The default reads the coordinates' roles
  /// (plane_coordinates(coordinates(), k); a stator without coordinates is fixed at the origin);
  /// a model whose rotor point in a plane is a combination of coordinates overrides it.
  virtual bool plane_motion(int k, double t, VecIn q, VecIn v, PlaneMotion& out) const;
  /// Minimal coordinates of the contact phases, or nullptr when the model has none (the
  /// event-driven integrator then integrates contact phases as a DAE with projection).
  virtual const ContactChart* contact_chart() const { return nullptr; }
  /// Minimal coordinates of contact phases with several closed contacts, each on a sprung ring
  /// of its own (contact/ring_chart.hpp), or nullptr (the projection formulation then).
  virtual const RingChart* ring_chart() const { return nullptr; }

  /// Kinetic energy 1/2 v^T M(q) v (of the whole system, a prescribed motion's included) at
  /// time t. The default forms M (allocates); models override it.
  virtual double kinetic_energy(double t, VecIn q, VecIn v) const;
  /// Potential energy of the conservative forces included in f [J], at time t.
  virtual double potential_energy(double t, VecIn q) const = 0;
  /// Power of the smooth non-conservative forces.
  virtual SmoothPower smooth_power(double t, VecIn q, VecIn v) const = 0;
  /// Whether the applied loads' power depends on the accelerations and the contact forces (a
  /// prescribed motion, held by whatever torque it takes): solvers then pass them to
  /// applied_power. False: applied_power is smooth_power's external part.
  virtual bool rheonomic() const { return false; }
  /// Power of the applied loads [W] at (t, q, v) with the accelerations a and the contact
  /// forces F (one per contact): the drive's power, in the energy balance.
  virtual double applied_power(double t, VecIn q, VecIn v, VecIn /*a*/,
                               const ContactForce* /*F*/) const {
    return smooth_power(t, q, v).external;
  }
  /// What the model computes at each output sample besides its coordinates (default: none).
  virtual const std::vector<Observable>& observables() const;
  /// Their values at (t, q, v) with the accelerations a and contact forces F, into `out`
  /// (size observables().size()).
  virtual void compute_observables(double /*t*/, VecIn /*q*/, VecIn /*v*/, VecIn /*a*/,
                                   const ContactForce* /*F*/, VecOut /*out*/) const {}

  /// The coordinate whose rate is the monitored spin speed omega (the run monitor, omega_max,
  /// the crossing of omega_lim; Carpenter's free-spin column), or -1 when the model has none.
  /// The solvers never name a coordinate themselves.
  virtual int spin_coordinate() const { return -1; }
  /// omega at a state (0 without a spin coordinate).
  virtual double spin(double /*t*/, VecIn /*q*/, VecIn v) const {
    const int i = spin_coordinate();
    return i >= 0 ? v[i] : 0.0;
  }

  // ---- services for the layers above (case validation, Campbell diagram) ----

  /// Kinetic plus potential energy at time t.
  double mechanical_energy(double t, VecIn q, VecIn v) const {
    return kinetic_energy(t, q, v) + potential_energy(t, q);
  }
  /// The first contact that q penetrates by more than `roundoff` times its gap scale, if any
  /// (an initial state must not penetrate; a state written by a run on the constraint has d_N
  /// within round-off of 0, of either sign).
  std::optional<Penetration> initial_penetration(VecIn q, double roundoff) const;
  /// The linearised model of a Campbell diagram, or nullopt when the model has none.
  virtual std::optional<LinearModel> linearize(Linearization /*mode*/) const {
    return std::nullopt;
  }
};

}  // namespace rubdyn
