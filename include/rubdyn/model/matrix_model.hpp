#pragma once
// A user's own linear rotor (case file: [model] kind = "matrices"; derivation in
// docs/models.md, section 5): n lateral coordinates q with the constant matrices M (symmetric
// positive definite), C and K (symmetric), G (skew-symmetric: the gyroscopic matrix per unit
// spin speed) and a constant load f0, plus the spin angle theta (an unknown) with the polar
// inertia Jp, and one contact node: two of the q, (x, y), are the centre of a seal circle of
// radius R inside a stator ring across the clearance g0.
//
// Coordinates (q_1..q_n, theta, x_s, y_s); with a rigid stator (stator.rigid) no x_s, y_s.
// With psi = theta + phi_u and u_b the unbalance at the node (its mass centre at
// (x, y) + eps e^{i psi}):
//   T = 1/2 q'^T M q' + 1/2 Jp theta'^2 - 1/2 theta' q^T G q'
//       + u_b theta' (y' cos psi - x' sin psi) + 1/2 m_s |z_s'|^2,
//   V = 1/2 q^T K q - f0^T q + g u_b sin psi + 1/2 k_s |z_s|^2 + g m_s y_s,
//   M_full(q) = [[M, b], [b^T, Jp]] (+ m_s I),  b = 1/2 G q + u_b (-sin psi e_x + cos psi e_y),
//   f_q = f0 - C q' - K q - theta' G q' + u_b theta'^2 (cos psi e_x + sin psi e_y),
//   f_theta = tau(theta') - u_b g cos psi,  f_s = -c_s z_s' - k_s z_s - m_s g e_y.
// The paper's rigid rotor is the case q = (x_b, y_b, x_r, y_r), node (x_r, y_r), G = H (...)
// (rotor_stator_model.hpp), f0 its weight, no stator weight (loads.gravity = 0).
//
// Structured mass solve: M is factored once (LLT); per solve u = M^-1 b by the factor, the Schur
// complement s = Jp - b.u on theta, then for each right-hand side
//   theta'' = (r_theta - b.M^-1 r_q) / s,  q'' = M^-1 r_q - u theta''.
//
// Banded matrices (finite-element rotors: 4 coordinates per node, half-bandwidth 7): every
// per-evaluation service costs O(n w), w the bandwidth, instead of O(n^2). Each of M, C, K, G
// and the factor L is kept by its rows, each row over the columns from its first to its last
// nonzero (Envelope, detected from the matrices: a dense matrix has full rows), and every
// product is restricted to them. The Cholesky factor keeps M's envelope (no fill outside it:
// row i of L starts where row i of M does), so the triangular solves with L and L^T cost
// O(n w) too; b (a row of G per entry) and u (two envelope solves) are computed per call,
// in thread-local scratch vectors (a model holds no mutable state and may serve several
// threads; nothing is allocated after a thread's first call of its largest model).
// s > 0 is required of an initial state (case validation); a state where it is not (M_full
// not positive definite: |q| far beyond the linear model's range) makes the solve return NaN,
// which the solvers end as a non-finite state (Termination::NonFinite).
//
// Minimal coordinates of the contact phases, as the Jeffcott rotor's with the other rotor
// coordinates passing through: slip p = (q without the node's (x, y), phi in their place,
// theta, x_s, y_s); stick p = (the same with theta - theta0 in phi's place and no theta).
#include <optional>
#include <string>
#include <vector>

#include "rubdyn/model/lagrangian_model.hpp"
#include "rubdyn/model/loads.hpp"

namespace rubdyn {

struct MatrixRotorParams {
  Mat M, C, K, G;  ///< n x n (n >= 2)
  Vec f0;          ///< n, the constant load (e.g. the rotor's weight)
  double Jp = 0.06;
  /// The names of q (n); empty: q0, q1, ...
  std::vector<std::string> names;
  /// Which coordinates of q are rotations in rad (an FE shaft's slopes, a disc's tilt): n flags,
  /// or empty (all deflections in m). Their unit is "rad" and their error weight the length of
  /// equal kinetic energy (Coordinate::length).
  std::vector<bool> rotation;
  int size() const { return static_cast<int>(M.rows()); }
};

/// A contact node: where a seal circle sits among the coordinates, and its clearance.
struct MatrixContactNode {
  int x = 0, y = 1;      ///< 0-based indices into q of the seal circle's centre
  double radius = 0.05;  ///< R [m]
  double gap = 2.0e-4;   ///< g0 [m]
};

struct MatrixStatorParams {
  bool rigid = false;  ///< a fixed ring at the origin
  double mass = 2.0, k = 2.0e6, c = 100.0;
};

/// One of several contact nodes: its seal circle, its contact law and its stator ring.
struct MatrixNode {
  MatrixContactNode at;
  ContactLaw law{0.1, 0.0, 0.0};
  MatrixStatorParams stator;
};

/// At most this many contact nodes (the event-driven integrator's K-contact limit).
inline constexpr int kMaxContactNodes = kMaxContacts;  // the largest K (core/run_types.hpp)

struct MatrixParams {
  MatrixRotorParams rotor;
  /// The one contact node, its ring and law (used when `nodes` is empty: a case with one
  /// [contact_node] section).
  MatrixContactNode node;
  MatrixStatorParams stator;
  ContactLaw contact{0.1, 0.0, 0.0};
  /// Several contact nodes ([[contact_node]] tables), each with its ring and law; non-empty
  /// replaces node, stator and contact. The unbalance sits at the first node.
  std::vector<MatrixNode> nodes;
  LoadParams loads;
  /// output.modes: the number N of the rotor's lowest free modes whose amplitudes are the
  /// model's observables (0: none; model/matrix_reduction.hpp's rotor_modes, of these matrices)
  int output_modes = 0;
  /// The nodes the model has: `nodes`, or the one of node, stator, contact.
  std::vector<MatrixNode> node_list() const {
    if (!nodes.empty()) return nodes;
    return {MatrixNode{node, contact, stator}};
  }
};

/// The coordinates of a matrices model of size n with these names (empty: q0..q{n-1}) and
/// these contact nodes: q, theta, then each sprung node's ring (x_s, y_s for one node; x_s_k,
/// y_s_k, k = 1..K, for several). `rotation` (n flags or empty) marks q's rotations (unit rad).
std::vector<Coordinate> matrix_model_coordinates(int n, const std::vector<std::string>& names,
                                                 const std::vector<MatrixNode>& nodes,
                                                 const std::vector<bool>& rotation = {});

/// The error lengths of q's rotations (Coordinate::length): sqrt(M_ii / m) with m the median
/// of M's diagonal over the deflections (not rotations), the length at which a rotation rate
/// carries the kinetic energy of a deflection rate (the shaft's consistent mass: about 0.16 of
/// the element's length, the lever arm of the slope in the element's deflection); 1 for
/// deflections. All 1 when q has no rotations or no deflections.
std::vector<double> rotation_lengths(const Mat& M, const std::vector<bool>& rotation);

class MatrixModel final : public LagrangianModel {
 public:
  /// Requires M symmetric positive definite (RUBDYN_DEMAND; the case validation checks it).
  explicit MatrixModel(MatrixParams p);  ///< (by value: a temporary's matrices are moved in)

  std::string_view name() const override { return "matrices"; }
  int num_dofs() const override { return N_; }
  const std::vector<Coordinate>& coordinates() const override { return coords_; }
  void mass_matrix(VecIn q, MatOut M) const override;
  void mass_product(VecIn q, VecIn x, VecOut y) const override;
  void solve_mass(VecIn q, MatOut B) const override;
  void mass_matrix_product_jacobian(VecIn q, VecIn a, MatOut J) const override;
  void smooth_forces(double t, VecIn q, VecIn v, VecOut f) const override;
  void smooth_force_jacobians(double t, VecIn q, VecIn v, MatOut dfdq, MatOut dfdv) const override;
  /// The envelopes of M, C, K, G and the spin's row and column: O(n w) entries.
  bool newton_entries(double t, VecIn q, VecIn v, VecIn a, NewtonEntries& e) const override;
  /// s = the spin: the rotor's envelope solves and the rings' masses, no spin border.
  bool solve_mass_without(int s, VecIn q, MatOut B) const override;
  /// (M a)_theta and f_theta as mass_product and smooth_forces compute them (the same bits).
  bool spin_row(double t, VecIn q, VecIn v, VecIn a, double& Ma, double& f) const override;
  int contact_count() const override { return K_; }
  void compute_contact(int k, double t, VecIn q, VecIn v, ContactKinematics& c) const override;
  double kinetic_energy(double t, VecIn q, VecIn v) const override;
  double potential_energy(double t, VecIn q) const override;
  SmoothPower smooth_power(double t, VecIn q, VecIn v) const override;
  double gap_scale(int k = 0) const override { return nd(k).gap; }
  const ContactLaw& contact_law(int k = 0) const override { return nd(k).law; }
  double contact_radius(int k = 0) const override { return nd(k).radius; }
  /// Minimal coordinates for one node; none with several (the event-driven integrator then
  /// integrates contact phases as the DAE with projection).
  const ContactChart* contact_chart() const override { return K_ == 1 ? &chart_ : nullptr; }
  const RingChart* ring_chart() const override { return ring_chart_ ? &*ring_chart_ : nullptr; }
  int spin_coordinate() const override { return th_; }
  /// Free: (q, each ring's x_s, y_s) with M, G, C, K and the rings'; Tied: q with each ring's
  /// mass, damper and spring added on its node's (x, y) (none when a ring is rigid: it pins
  /// its node). `nodes`: the pairs (0, 1), (2, 3), ... of q, then the rings.
  std::optional<LinearModel> linearize(Linearization mode) const override;
  /// With params().output_modes = N > 0: mode1..modeN, vmode1..vmodeN, the amplitudes
  /// eta_k = phi_k^T M q of the rotor's N lowest free modes (rotor_modes) and their rates
  /// phi_k^T M v, O(n N) per sample by the columns of M Phi computed once; else none.
  const std::vector<Observable>& observables() const override { return observables_; }
  void compute_observables(double t, VecIn q, VecIn v, VecIn a, const ContactForce* F,
                           VecOut out) const override;

  /// The Schur complement Jp - b^T M^-1 b of theta at q (> 0 where M_full is positive definite).
  double schur(VecIn q) const;
  const MatrixParams& params() const { return p_; }

 private:
  class Chart final : public ContactChart {
   public:
    explicit Chart(const MatrixModel& m) : m_(m) {}
    int dim(ChartMode mode) const override;
    void chart(ChartMode mode, VecIn q, VecIn v, ChartAnchor& anchor, VecOut p,
               VecOut pd) const override;
    void embed(ChartMode mode, const ChartAnchor& anchor, VecIn p, VecIn pd, VecOut q,
               VecOut v) const override;
    void reduce(ChartMode mode, const ChartAnchor& anchor, VecIn p, VecIn pd, VecIn q, VecIn a,
                VecOut pdd) const override;
    ChartScales scales(ChartMode mode) const override;

   private:
    /// The coordinate of q that reduced coordinate k < n - 1, k != slot_, copies.
    int copied(int k) const {
      return m_.others_[static_cast<std::size_t>(k < m_.slot_ ? k : k - 1)];
    }
    const MatrixModel& m_;
  };

  /// A matrix kept by its rows, row i over the columns lo[i] .. lo[i] + len[i] - 1, from its
  /// first to its last nonzero (none: len 0); the entries outside are zeros and skipped.
  struct Envelope {
    std::vector<Eigen::Index> lo, len, off;  ///< off: where row i starts in val
    Vec val;
    /// The matrix itself where it has kDenseKernelSize rows or more and its envelope holds at
    /// least half of its entries (a reduced model's), and `dense_products` asks for it: its
    /// products by a dense kernel; else empty.
    Mat dense;
    explicit Envelope(const Mat& A = Mat(), bool dense_products = true);
    /// (row i) . x, x of the matrix's width (contiguous)
    double dot(int i, const double* x) const;
    /// y += alpha A x (x of the matrix's width, y of its height; contiguous, distinct); row by
    /// row, each y_i + alpha dot(i, x), unless dense.
    void multiply_add(double alpha, const double* x, double* y) const;
  };

  /// b_i(q), the theta column of M_full (row i < n).
  double b(int i, VecIn q, double ubs, double ubc) const;
  /// bq[0..n) = b(q), each entry as b(i, q, ubs, ubc) (or by a dense product: Ge_.dense).
  void spin_b(VecIn q, double ubs, double ubc, double* bq) const;
  /// b(q) and u = M^-1 b into bq[0..n), u[0..n); returns the Schur complement Jp - b.u.
  double spin_column(VecIn q, double ubs, double ubc, double* bq, double* u) const;
  /// x <- M^-1 x by the envelope solves with L and L^T.
  void solve_rotor_mass(double* x) const;
  /// (u_b sin psi, u_b cos psi), zeros without an unbalance.
  void unbalance_terms(VecIn q, double& ubs, double& ubc) const;

  /// A contact node as the model uses it: its coordinates, ring coordinates (-1: rigid), law.
  /// x = M_rotor^-1 x for a right-hand side x (n) from the contact nodes' unit solves when its
  /// nonzeros are all on them, else by the envelope solve; `tmp`: n of scratch.
  void solve_rotor_rhs(double* x, double* tmp) const;
  /// x's rotor part (its first n entries) is all zeros: a product with M's rows adds nothing.
  bool rotor_part_zero(const double* x) const;

  struct Node {
    int ix = 0, iy = 1, xs = -1, ys = -1;
    double radius = 0.05, gap = 2e-4;
    ContactLaw law;
    MatrixStatorParams stator;
    bool sprung() const { return xs >= 0; }
  };
  const Node& nd(int k) const { return nodes_[static_cast<std::size_t>(k)]; }

  MatrixParams p_;
  std::vector<Node> nodes_;
  int K_;
  int n_, N_, th_, xs_ = -1, ys_ = -1, ix_, iy_;  ///< (x_s, y_s, ix, iy: the first node's)
  bool sprung_;                                   ///< the first node's ring is sprung
  std::vector<Coordinate> coords_;
  /// M, C, K, G by rows (M's rows as its columns: M is symmetric) and the factor L of
  /// M = L L^T (row i: lo[i] .. i, the diagonal last)
  Envelope Me_, Ce_, Ke_, Ge_, Le_;
  /// M^-1 where M is dense (Me_.dense; a reduced model's): its solves one dense product (3x faster
  /// at n = 22 than the two triangular solves; forward error of order cond(M) u either way)
  Mat Minv_;
  /// M^-1 e_i of the contact nodes' (x, y) coordinates (column unit_pos_[i]; -1: none): a right
  /// -hand side whose rotor part lies on them (a contact's W_N, W_T) is solved as their
  /// combination, O(n) per entry, instead of by two envelope solves
  Mat unit_solves_;
  std::vector<int> unit_pos_;
  /// slot of phi among the reduced rotor coordinates; the other rotor coordinates, in order
  int slot_;
  std::vector<int> others_;
  Chart chart_;
  std::optional<RingChart> ring_chart_;  ///< every node's (x, y) and ring
  /// M Phi of the output modes (n x N; empty without), and their observables
  Mat Mphi_;
  std::vector<Observable> observables_;
};

}  // namespace rubdyn
