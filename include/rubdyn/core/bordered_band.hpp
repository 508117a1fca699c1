#pragma once
// Linear algebra of the Newton systems of wide models (the event-driven engine's BDF phases,
// the fixed-step schemes' iteration matrices): an N x N matrix
// S whose coordinates split into a banded set and a few dense "border" ones (the spin: its row
// and column couple every coordinate through the gyroscopic and unbalance terms). A
// finite-element rotor with 4 coordinates per node has half-bandwidths of 7 whatever its size,
// so that S is factored in O(N w^2) and solved in O(N w) instead of O(N^3) and O(N^2).
//
// The structure is detected from the matrices (detect()), never declared: the half-bandwidths
// kl, ku of the non-border block are the largest |i - j| of a nonzero entry of any matrix given,
// in the non-border coordinates' own order. Where a band is not worth it (a reduced model's dense
// matrices: banded flops N kl (kl + ku) against N^3 / 3), the same calls factor S densely
// (LU with partial pivoting): the choice is the flop count's, the answer the same to round-off.
//
// With A the banded block, B, R its border columns and rows and D the border corner:
//   A = P L U (banded LU with partial pivoting, U of upper bandwidth kl + ku; LAPACK's dgbtf2
//   algorithm), X = A^-1 B, and the border's Schur complement D - R X (dense LU);
//   solve: y = A^-1 b_A, x_D = (D - R X)^-1 (b_D - R y), x_A = y - X x_D.
// Products with any of the detected matrices (product()) touch the band and the border only.
// Workspaces grow when a wider band is detected (the first Jacobian of a session), never in a
// solve.
#include <Eigen/LU>
#include <span>
#include <vector>

#include "rubdyn/core/matrix_entry.hpp"
#include "rubdyn/core/types.hpp"

namespace rubdyn::detail {

class BorderedBand {
 public:
  /// N coordinates; `border`: the dense ones (sorted, distinct, < N; may be empty).
  BorderedBand(int N, std::span<const int> border);
  /// The border of a model's Newton systems: its spin coordinate (-1: none, no border).
  BorderedBand(int N, int spin);

  /// Starts a detection: the band is the union of the patterns given to detect() after it.
  void reset_pattern();
  /// Widens the band to A's nonzeros (A N x N, dense storage); O(N^2).
  void detect(const Mat& A);
  /// Widens the band to the positions of an entry list (their values are not read); O(entries).
  void detect(std::span<const MatrixEntry> A);
  /// Ends a detection: sizes the workspaces and chooses banded or dense factorisation.
  void finish_pattern();

  /// Factors S = A0 + c1 A1 + c2 A2 (each N x N, within the detected pattern: entries outside
  /// are not read). False: S is singular.
  bool factor(const Mat& A0, double c1, const Mat& A1, double c2, const Mat& A2);
  /// The same with the matrices as entry lists (within the detected pattern); O(entries) to
  /// assemble, the factorisation as above.
  bool factor(std::span<const MatrixEntry> A0, double c1, std::span<const MatrixEntry> A1,
              double c2, std::span<const MatrixEntry> A2);
  /// Factors S = A (within the detected pattern).
  bool factor(const Mat& A);
  /// x = S^-1 b (b and x of size N, distinct).
  void solve(const double* b, double* x) const;
  /// y += alpha A x for a matrix within the detected pattern, touching the band and the border
  /// only.
  void product(const Mat& A, double alpha, const double* x, double* y) const;

  /// y += alpha A x for an entry list; O(entries).
  void product(std::span<const MatrixEntry> A, double alpha, const double* x, double* y) const;

  bool banded() const { return banded_; }
  int kl() const { return kl_; }
  int ku() const { return ku_; }

 private:
  double& ab(int i, int j) { return ab_[static_cast<std::size_t>(kv_ + i - j + j * ld_)]; }
  double ab(int i, int j) const { return ab_[static_cast<std::size_t>(kv_ + i - j + j * ld_)]; }
  void band_solve(double* b) const;  // b = A^-1 b in the banded order (m entries)
  /// The banded factorisation of the matrix with entries S(i, j) (banded_).
  template <class Entry>
  bool factor_band(const Entry& S);
  /// Factors the band (ab_) and the border (X_ = B, R_, corner_ = D) filled in.
  bool factor_filled();

  int N_, m_, nb_;
  std::vector<int> inner_;   ///< the banded coordinates, in order (m of them)
  std::vector<int> border_;  ///< the border's (nb)
  std::vector<int> pos_;     ///< coordinate -> its index among inner_ (or -1 - its border index)
  int kl_ = 0, ku_ = 0, kv_ = 0, ld_ = 1;
  bool banded_ = false;
  std::vector<double> ab_;  ///< LAPACK band storage of A's LU, ld_ = 2 kl + ku + 1
  std::vector<int> ipiv_;
  Mat X_;       ///< A^-1 B (m x nb)
  Mat R_;       ///< R (nb x m)
  Mat corner_;  ///< D - R X
  Eigen::PartialPivLU<Mat> small_lu_, dense_lu_;
  Mat dense_;                         ///< S, when factored densely from several matrices
  mutable std::vector<double> work_;  ///< (m + nb) in the banded order
  mutable Vec zb_;                    ///< the border's unknowns (nb)
};

}  // namespace rubdyn::detail
