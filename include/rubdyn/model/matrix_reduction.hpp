#pragma once
// Modal reduction of a user's linear rotor (kind = "matrices", case section [reduction];
// docs/fe-rotors.md, section 8): the n coordinates q are replaced by m < n coordinates p with
// q = T p, and the model's matrices by their projections
//   M_r = T^T M T, C_r = T^T C T, K_r = T^T K T, G_r = T^T G T (skew-symmetric again), f0_r = T^T
//   f0,
// the same Lagrangian (docs/models.md, section 5) restricted to the motions q = T p: the
// gyroscopic term -1/2 theta' q^T G q' becomes -1/2 theta' p^T G_r p', so the spin coupling
// b = 1/2 G q of the mass matrix is projected with the same basis. Every contact node's (x, y)
// stays a coordinate of p (its row of T is a unit row), so the contact kinematics, the seal
// rings and the unbalance (at the first node) act on p exactly as on q.
//
// Methods (the modes are those of the undamped, non-spinning rotor: K phi = w^2 M phi):
// - CraigBampton: p = (the contact nodes' x, y; eta), T = [[I, 0], [Psi, Phi]] in (boundary,
//   interior) order, with the static constraint modes Psi = -K_ii^-1 K_ib and the fixed-interface
//   modes Phi of (K_ii, M_ii) (the contact coordinates held), mass-normalised.
// - Modal: the free modes Phi of (K, M), in a basis of their span in which the contact
//   coordinates are coordinates: T = Phi A, A = [Phi_b^+, N] (Phi_b: the modes' rows at the
//   contact coordinates, N a basis of its null space), so that Phi_b A = [I, 0]. The same motions
//   as plain modal truncation; a contact node that the kept modes do not move in both x and y
//   (Phi_b of rank < 2K) would be eliminated: refused.
// By number (`modes`) or by frequency (`cutoff`: every mode below it). An isotropic rotor whose
// coordinates pair as (x, y) = (q_2i, q_2i+1) with its nodes so paired (M, C, K equal on the two
// planes and without x-y terms, to 1e-12 of their largest entry) is reduced plane by plane: each
// x-plane mode gives a pair of coordinates (eta<k>x, eta<k>y), so that the reduced rotor is
// isotropic too and its Campbell diagram keeps its whirl labels; `modes` then counts both of a
// pair and must be even.
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "rubdyn/model/matrix_model.hpp"

namespace rubdyn {

enum class ReductionMethod { None, Modal, CraigBampton };
std::string_view to_string(ReductionMethod m);

struct ReductionParams {
  ReductionMethod method = ReductionMethod::None;
  int modes = 0;        ///< modes kept (0: by cutoff)
  double cutoff = 0.0;  ///< [Hz] keep every mode below (0: by modes)
};

/// A reduced model and what it was made of.
struct ReducedMatrices {
  ReductionParams params;
  int full_size = 0;       ///< n
  bool isotropic = false;  ///< reduced plane by plane (coordinates in (x, y) pairs)
  /// The reduced rotor's matrices and coordinates' names (its Jp is the full rotor's: apply()).
  MatrixRotorParams rotor;
  /// The full coordinate (index into q) of each physical coordinate of p: p's first ones.
  std::vector<int> physical;
  /// Each contact node's (x, y) as indices into p (in the full rotor's node order).
  std::vector<std::pair<int, int>> node_xy;
  Mat T;  ///< q = T p, n x m
  /// The kept modes' shapes (n x modes, mass-normalised; CB: zero at the contact coordinates)
  /// and frequencies [Hz], lowest first; isotropic: x-plane then y-plane mode of each pair.
  Mat modes;
  std::vector<double> f_hz;
  std::vector<std::string> mode_planes;  ///< "x", "y" (isotropic) or ""
  /// The next mode's frequency above the kept ones [Hz] (NaN when all were kept).
  double f_next = std::numeric_limits<double>::quiet_NaN();
  /// One line: the method, n -> m, the physical coordinates kept, the modes and their range.
  std::string describe() const;
  /// The reduced model's parameters: `full` (its Jp, nodes' seals, laws and rings, loads) with
  /// the reduced matrices and names and its nodes' coordinates in p.
  MatrixParams apply(const MatrixParams& full) const;
};

/// Bad input, named by its key (reduction.modes, reduction.cutoff, reduction.method) and rule.
class ReductionRefused : public std::invalid_argument {
 public:
  ReductionRefused(std::string key, const std::string& rule)
      : std::invalid_argument(rule), key_(std::move(key)) {}
  const std::string& key() const { return key_; }

 private:
  std::string key_;
};

/// The lowest free modes of a matrices model's rotor (output.modes; docs/fe-rotors.md, section
/// 11): K phi = w^2 M phi of its M and K (the undamped rotor at rest), mass-normalised
/// (phi^T M phi = 1), lowest first, each with its largest entry positive (a deterministic sign).
/// An isotropic rotor (isotropic_rotor) plane by plane, as the modal reduction computes them:
/// each x-plane mode (of the even coordinates) gives the pair (x-plane, y-plane) of one frequency.
struct RotorModes {
  bool isotropic = false;
  Mat shapes;                       ///< n x count
  std::vector<double> f_hz;         ///< [Hz] (NaN of a negative eigenvalue: an indefinite K)
  std::vector<std::string> planes;  ///< "x", "y" (isotropic) or ""
};

/// Whether p's rotor is isotropic as above: n even, M, C, K equal on the x (even) and y (odd)
/// coordinates and without x-y terms (to 1e-12 of each matrix's largest entry), and every
/// contact node's (x, y) = (2i, 2i + 1).
bool isotropic_rotor(const MatrixParams& p);

/// The `count` lowest free modes of p's rotor (0 <= count <= n, even when it is isotropic:
/// RUBDYN_DEMAND; the case validation names output.modes). The modal reduction's free modes are
/// these.
RotorModes rotor_modes(const MatrixParams& p, int count);

/// The reduced model of `full` (its matrices, names, nodes, loads) by `r` (method not None).
/// Throws ReductionRefused for: no modes or cutoff, modes > the modes available (n for modal,
/// n - 2K for Craig-Bampton), an odd number of modes of an isotropic rotor, a cutoff below the
/// first mode, fewer modal modes than contact coordinates or a contact node the kept modes do not
/// move (modal), a rotor not held when the contact nodes are (Craig-Bampton: K_ii not positive
/// definite).
ReducedMatrices reduce_matrix_model(const MatrixParams& full, const ReductionParams& r);

}  // namespace rubdyn
