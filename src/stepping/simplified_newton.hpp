#pragma once
// The simplified Newton iteration shared by the implicit fixed-step schemes (Carpenter's
// prediction, Moreau-Jean's step). The iteration matrix is kept as an explicit inverse across
// steps (a 7x7 product is cheaper than two triangular solves) and refreshed every 32 steps, or
// when the iteration contracts slowly (ratio > 0.1): the converged solution solves the step's
// equations whatever the iteration matrix. Converged when the scaled change is within tolerance
// (norm <= 1), when the estimated remaining error r / (1 - r) times the last change is (r the
// contraction ratio), or when round-off is reached (r >= 0.5 after 4 iterations).
#include <Eigen/LU>
#include <cmath>
#include <memory>

#include "rubdyn/core/bordered_band.hpp"
#include "rubdyn/core/types.hpp"

namespace rubdyn::detail {

/// Vectors and matrices of a stepper for a model of N dofs: fixed-size for the sizes that have
/// a fast path (the rigid rotor's 7), Eigen::Dynamic otherwise. Fixed sizes are unrolled by the
/// compiler; measured on the reference case, a dynamic mj step costs 1.6x a fixed one (vector
/// operations of runtime size 7 are loops with their overhead).
template <int N>
using SVec = Eigen::Matrix<double, N, 1>;
template <int N>
using SMat = Eigen::Matrix<double, N, N>;

/// y = A x. Fixed sizes up to 8: Eigen's unrolled product. Dynamic sizes and larger fixed ones
/// (the two-plane rotor's 9, which Eigen no longer unrolls but sends to its general kernel): a
/// plain loop, column by column (each y_i summed in column order): for n = 7 as fast as the
/// fixed product and twice as fast as Eigen's dynamic one (measured: 8.6, 9.2, 15.9 ns).
template <int N>
inline void mat_vec(const SMat<N>& A, const SVec<N>& x, SVec<N>& y) {
  if constexpr (N != Eigen::Dynamic && N <= 8) {
    y.noalias() = A * x;
  } else if constexpr (N != Eigen::Dynamic) {
    // the same sums as the loop below, y held in registers across the columns (the loop stores
    // and reloads y for each column)
    const double* a = A.data();
    double acc[N];
    for (int i = 0; i < N; ++i) acc[i] = a[i] * x[0];
    for (int j = 1; j < N; ++j)
      for (int i = 0; i < N; ++i) acc[i] += a[j * N + i] * x[j];
    for (int i = 0; i < N; ++i) y[i] = acc[i];
  } else {
    const Eigen::Index n = A.rows(), m = A.cols();
    const double* a = A.data();
    const double* xd = x.data();
    double* yd = y.data();
    for (Eigen::Index i = 0; i < n; ++i) yd[i] = a[i] * xd[0];
    for (Eigen::Index j = 1; j < m; ++j) {
      const double* col = a + j * n;
      const double xj = xd[j];
      for (Eigen::Index i = 0; i < n; ++i) yd[i] += col[i] * xj;
    }
  }
}

/// inv = J^{-1} by Gauss-Jordan elimination with partial pivoting, in place in the workspace
/// `a` (a copy of J; both sized n x n): Eigen's dynamic-size LU and inverse allocate
/// temporaries, this allocates nothing. Returns false for a singular J.
inline bool invert_in_place(Mat& a, Mat& inv) {
  const Eigen::Index n = a.rows();
  inv.setIdentity();
  for (Eigen::Index k = 0; k < n; ++k) {
    Eigen::Index p = k;
    for (Eigen::Index i = k + 1; i < n; ++i)
      if (std::abs(a(i, k)) > std::abs(a(p, k))) p = i;
    if (a(p, k) == 0.0) return false;
    if (p != k) {
      a.row(p).swap(a.row(k));
      inv.row(p).swap(inv.row(k));
    }
    const double d = 1.0 / a(k, k);
    a.row(k) *= d;
    inv.row(k) *= d;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (i == k || a(i, k) == 0.0) continue;
      const double f = a(i, k);
      a.row(i) -= f * a.row(k);
      inv.row(i) -= f * inv.row(k);
    }
  }
  return true;
}

/// The largest system solve_small takes (the contacts of one step: K <= 16).
constexpr int kMaxSmall = 16;
/// Solves G x = b in place (m x m, partial pivoting) for the small systems of the K-contact
/// corrections of the fixed-step schemes (m <= kMaxSmall): false when G is singular.
using SmallMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxSmall, kMaxSmall>;
using SmallVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxSmall, 1>;
inline bool solve_small(SmallMat& G, SmallVec& b) {
  const Eigen::Index m = G.rows();
  for (Eigen::Index k = 0; k < m; ++k) {
    Eigen::Index p = k;
    for (Eigen::Index i = k + 1; i < m; ++i)
      if (std::abs(G(i, k)) > std::abs(G(p, k))) p = i;
    if (G(p, k) == 0.0) return false;
    if (p != k) {
      G.row(p).swap(G.row(k));
      std::swap(b[p], b[k]);
    }
    for (Eigen::Index i = k + 1; i < m; ++i) {
      const double f = G(i, k) / G(k, k);
      for (Eigen::Index j = k; j < m; ++j) G(i, j) -= f * G(k, j);
      b[i] -= f * b[k];
    }
  }
  for (Eigen::Index k = m - 1; k >= 0; --k) {
    double x = b[k];
    for (Eigen::Index j = k + 1; j < m; ++j) x -= G(k, j) * b[j];
    b[k] = x / G(k, k);
  }
  return true;
}

/// Dynamic sizes (the matrices models, finite-element rotors among them): where the iteration
/// matrix is banded apart from the spin's row and column (detected from the matrix at each
/// refresh, core/bordered_band.hpp), it is factored as such, O(n w^2), and applied by band
/// solves, O(n w), instead of inverted (n^3) and multiplied (n^2); the same solution to
/// round-off. Fixed sizes and dense matrices keep the explicit inverse.
template <int N>
class SimplifiedNewton {
 public:
  /// For n unknowns (n = N for a fixed size; the workspace is sized here); `border`: the spin's
  /// coordinate (-1: none), the dense row and column of a banded matrix.
  SimplifiedNewton(int n, int max_iterations, int border = -1)
      : max_(max_iterations), inv_(SMat<N>::Zero(n, n)), lu_(n), work_(n, n) {
    if constexpr (N == Eigen::Dynamic) band_ = std::make_unique<BorderedBand>(n, border);
  }

  /// Before the first iteration of a step.
  void begin_step() {
    fresh_ = valid_ && ++age_ < 32;
    it_ = 0;
    prev_ = 0.0;
  }
  /// True when the iteration matrix must be set before the next iteration.
  bool needs_matrix() const { return !fresh_; }
  void set_matrix(const SMat<N>& J) {
    if constexpr (N != Eigen::Dynamic) {
      lu_.compute(J);
      inv_ = lu_.inverse();
    } else {
      band_->reset_pattern();
      band_->detect(J);
      band_->finish_pattern();
      banded_ = band_->banded();
      if (banded_) {
        // a singular J: NaN, so that the next iterate is non-finite and the step says so
        singular_ = !band_->factor(J);
      } else {
        work_ = J;
        if (!invert_in_place(work_, inv_)) inv_.setConstant(std::nan(""));
      }
    }
    valid_ = fresh_ = true;
    age_ = 0;
  }
  /// y = J^{-1} x with the kept inverse or band factors (x and y distinct).
  void apply_inverse(const SVec<N>& x, SVec<N>& y) const {
    if constexpr (N == Eigen::Dynamic) {
      if (banded_) {
        if (singular_)
          y.setConstant(std::nan(""));
        else
          band_->solve(x.data(), y.data());
        return;
      }
    }
    mat_vec<N>(inv_, x, y);
  }
  /// The same for a sparse x (a contact's W_N or W_T: 6 or 7 of the two-plane rotor's 9
  /// entries are not zero): the columns of its zero entries skipped. Above 8 dofs and for
  /// dynamic sizes the sums of apply_inverse less their zero terms, so the same numbers (up to
  /// the sign of a zero); fixed sizes up to 8 use apply_inverse itself.
  void apply_inverse_sparse(const SVec<N>& x, SVec<N>& y) const {
    if constexpr (N != Eigen::Dynamic && N <= 8) {
      mat_vec<N>(inv_, x, y);
    } else {
      if constexpr (N == Eigen::Dynamic) {
        if (banded_) {
          apply_inverse(x, y);
          return;
        }
      }
      const Eigen::Index n = inv_.rows();
      const double* a = inv_.data();
      y.setZero();
      for (Eigen::Index j = 0; j < n; ++j) {
        const double xj = x[j];
        if (xj == 0.0) continue;
        const double* col = a + j * n;
        for (Eigen::Index i = 0; i < n; ++i) y[i] += col[i] * xj;
      }
    }
  }

  enum class Next { Iterate, Converged, Failed };
  /// After an iteration whose change has the scaled norm `norm` (1 = the tolerance).
  Next after(double norm) {
    ++it_;
    if (norm <= 1.0) return Next::Converged;
    if (it_ >= 2) {
      const double r = norm / prev_;
      if (r < 1.0 && r / (1.0 - r) * norm <= 1.0) return Next::Converged;
      if (r > 0.1) fresh_ = false;                       // slow contraction: refresh the matrix
      if (it_ >= 4 && r >= 0.5) return Next::Converged;  // round-off reached
    }
    prev_ = norm;
    return it_ >= max_ ? Next::Failed : Next::Iterate;
  }
  int iterations() const { return it_; }
  int max_iterations() const { return max_; }

 private:
  int max_;
  SMat<N> inv_;
  Eigen::PartialPivLU<SMat<N>> lu_;     // fixed sizes
  Mat work_;                            // dynamic sizes: the elimination's workspace
  std::unique_ptr<BorderedBand> band_;  // dynamic sizes: the banded factorisation
  bool banded_ = false, singular_ = false;
  bool valid_ = false, fresh_ = false;
  int age_ = 0, it_ = 0;
  double prev_ = 0.0;
};

}  // namespace rubdyn::detail
