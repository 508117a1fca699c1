#pragma once
// Campbell diagram of the coupled rotor-stator system (paper, section 5.1.2, Fig. 8), of any
// model's linearisation (LagrangianModel::linearize: M x'' + (Omega G + D) x' + K x = 0 with
// (x, y) nodes). The rigid rotor's, written out:
//
// Model. The stator is tied to the rotor at R (x_s = x_r, y_s = y_r): m_s is added to M22 on x_r
// and y_r, k_s and c_s act on x_r and y_r. The spin theta' = Omega is imposed and the mass matrix
// is taken at the centred position (H_x = H_y = 0, eq. 14), so the theta row decouples. With
// q = (x_b, y_b, x_r, y_r) and G4 the top-left 4x4 block of G (eq. 14):
//     M4 q'' + (Omega G4 + D4) q' + K4 q = 0,
//     M4 = [M11 I, M12 I; M12 I, (M22 + m_s) I],  K4 = diag(k_b, k_b, k_s, k_s),
//     D4 = diag(c_b, c_b, c_s, c_s) (damped analysis only, else 0).
// Eigenvalues lambda of the first-order (8x8) form; the four with Im(lambda) > 0 are the modes
// (in general: 2 N_dofs, N_dofs modes):
// frequency f = Im(lambda) / 2 pi [Hz], damping ratio zeta = -Re(lambda) / |lambda|.
//
// Whirl direction (forward / backward). Spin theta' > 0 turns the rotor counterclockwise in the
// (X, Y) plane (a right-handed rotation about +Z). For a mode q(t) = Re(Q e^{i w t}), w > 0, with
// complex amplitudes X, Y at a node, the whirl z = x + i y is
//     z(t) = (X + iY)/2 e^{+i w t} + conj(X - iY)/2 e^{-i w t}:
// a forward circle of radius |X + iY|/2 (counterclockwise, with the spin) plus a backward circle
// of radius |X - iY|/2. A mode is forward when its forward kinetic energy Z_f^H M2 Z_f exceeds the
// backward one Z_b^H M2 Z_b, with Z_f = (X_b + iY_b, X_r + iY_r), Z_b = (X_b - iY_b, X_r - iY_r)
// and M2 = [M11, M12; M12, M22 + m_s]: both nodes together, so a mode with a node (no motion) at R
// or at B is still labelled, and the test does not depend on how the eigenvector is scaled. The
// system is isotropic, so every mode is in fact purely forward or purely backward (in complex
// coordinates it reads M2 z'' + (D2 - i Omega H S) z' + K2 z = 0, S = [1, -1; -1, 1]); a mode
// whose whirl is mixed would reveal a bug and is reported (labels_ok = false).
// Within each direction, index 1 is the lower frequency.
//
// Double modes. At Omega = 0 (and wherever a forward and a backward frequency cross) two modes
// share one eigenvalue; its eigenspace is a plane in which ANY basis is a pair of modes, and the
// eigenvectors an eigen solver returns there are an arbitrary, possibly ill-conditioned basis.
// Such a numerically double eigenvalue (two eigenvalues closer than 1e-10 relative) is taken as
// one forward and one backward mode, the circular basis of the plane, both at the common
// frequency: this is the limit of the labelled modes as Omega -> 0, so the curves are continuous.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "rubdyn/model/lagrangian_model.hpp"
#include "rubdyn/model/rotor_stator_params.hpp"

namespace rubdyn {

struct CaseSpec;

/// The whirl-labelled modes at one spin speed: for a linear model with N nodes, N forward and N
/// backward modes, index 1 the lowest frequency in each direction.
struct CampbellPoint {
  double omega = 0.0;                               ///< spin speed Omega [rad/s]
  std::vector<double> f_backward, f_forward;        ///< [Hz], N each, ascending (NaN: mode missing)
  std::vector<double> zeta_backward, zeta_forward;  ///< damping ratios [-] (0 when undamped)
  /// The first two of each direction (the rigid rotor's four modes; NaN when absent).
  double f1b = 0.0, f1f = 0.0, f2b = 0.0, f2f = 0.0;
  double zeta_1b = 0.0, zeta_1f = 0.0, zeta_2b = 0.0, zeta_2f = 0.0;
  int n_forward = 0, n_backward = 0;  ///< oscillating modes found in each direction
  double min_whirl_purity = 1.0;      ///< min over modes of |E_f - E_b| / (E_f + E_b), 1: circular
  /// Exactly N forward and N backward modes, each with an unambiguous whirl.
  bool labels_ok = false;
};

/// The linear model's first-order form, assembled once; solve() is one real eigenproblem of
/// size 2 N_dofs (the rigid rotor: 8, cheap enough to be called per frame of a spectrogram).
class CampbellSolver {
 public:
  /// damped = false: D = 0 (the paper's Campbell diagram); true: the model's dampers.
  /// Throws std::invalid_argument for a model with no coordinate or no (x, y) node (nothing
  /// whirls: a Jeffcott rotor in a rigid stator tied to it).
  explicit CampbellSolver(const LinearModel& lm, bool damped = false);
  /// The rigid rotor's tied system (RotorStatorModel::linearize(Linearization::Tied)); throws
  /// std::invalid_argument when it has none (a [[plane]] with a fixed ring).
  explicit CampbellSolver(const RotorStatorParams& p, bool damped = false);

  /// The modes at spin speed omega [rad/s] (any sign; omega < 0 swaps the directions).
  CampbellPoint solve(double omega) const;

  bool damped() const { return damped_; }
  int nodes() const { return static_cast<int>(lm_.nodes.size()); }
  const LinearModel& model() const { return lm_; }
  /// The column labels of the modes: f1b, f1f, f2b, f2f, ... (N of each direction).
  std::vector<std::string> labels() const;

 private:
  LinearModel lm_;
  bool damped_;
  double w_ref_;         // time scale of the first-order form [rad/s]
  Mat MiK_, MiG_, MiD_;  // M^-1 K / w_ref^2, M^-1 G / w_ref, M^-1 D / w_ref
  Mat Mx_;               // the mass matrix among the nodes' x coordinates (whirl energies)
};

/// One-shot convenience: CampbellSolver(p, damped).solve(omega).
CampbellPoint solve_campbell_point(const RotorStatorParams& p, double omega, bool damped = false);

/// The diagram on a uniform grid.
struct CampbellDiagram {
  bool damped = false;
  std::vector<double> omega;              ///< grid [rad/s], from 0 to omega_max
  std::vector<std::string> labels;        ///< f1b, f1f, f2b, f2f, ...
  std::vector<std::vector<double>> f;     ///< [label][grid point] [Hz]
  std::vector<std::vector<double>> zeta;  ///< [label][grid point] [-], empty when undamped
  std::vector<double> unlabelled;  ///< grid speeds where labels_ok was false (should be none)

  std::size_t size() const { return omega.size(); }
  bool labels_ok() const { return unlabelled.empty(); }
  /// The frequencies of a label (f1b, ...); throws std::out_of_range for an unknown one.
  const std::vector<double>& column(const std::string& label) const;
};

/// `points` (>= 2) speeds Omega_i = omega_max i / (points - 1), omega_max > 0.
/// Throws std::invalid_argument on points < 2 or omega_max not finite and > 0.
CampbellDiagram compute_campbell_diagram(const LinearModel& lm, double omega_max, int points = 201,
                                         bool damped = false);
CampbellDiagram compute_campbell_diagram(const RotorStatorParams& p, double omega_max,
                                         int points = 201, bool damped = false);

/// The linear model of a case's Campbell diagram (`rubdyn campbell`, Python's
/// rubdyn.campbell): the model's linearisation with the stator tied to the rotor (the paper's
/// coupled system, `tied`), or its free modes (no contact, `tied` false) when the tied system
/// does not exist (a fixed ring tied to the rotor is a constraint) or has nothing left to
/// vibrate (a Jeffcott rotor in a rigid stator).
struct CampbellModel {
  LinearModel lm;
  bool tied = true;
};
/// Of a validated case. Throws CaseError naming the key that leaves the model without a
/// linearisation (a matrices rotor of odd size n: rotor.M).
CampbellModel campbell_model(const CaseSpec& spec);

/// campbell.csv text: header omega_rad_s,omega_rpm,f1b,f1f,f2b,f2f,... (Hz) and, when damped,
/// zeta_1b,zeta_1f,...; one row per grid point, 17 significant digits.
std::string campbell_csv(const CampbellDiagram& d);

}  // namespace rubdyn
