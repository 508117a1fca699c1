#pragma once
// The minimum-norm solution of a small consistent linear system A x = b whose matrix is singular:
// the equations of redundant contacts (two contacts whose rows of H are dependent: a rod lying
// flat on two supports, a ring split into two halves at one plane). Their motion is determinate,
// their forces are not; among all the forces that produce the motion this picks the one of least
// Euclidean norm, which shares a load equally between identical contacts.
//
// Used by the K-contact solver (contact_set.cpp: a combination of modes whose system is
// rank-deficient but consistent is a candidate, with its minimum-norm forces) and by the
// event-driven integrator's contact phases (the constrained accelerations, the projections).
//
// Method: Gaussian elimination with full pivoting to the numerical rank r (pivots above
// rel_threshold times the largest entry of A); the basic solution y (free unknowns 0); the null
// space N of the echelon form (one column per free unknown); then x = y - N (N^T N)^{-1} N^T y,
// the component of y orthogonal to the null space. Moving along N leaves A x unchanged: where
// the dependence is exact in floating point (equal rows of H give equal columns of A), A x is
// the basic solution's to the bit, so the constraints are met as exactly as by a regular solve.
// Storage bounded at compile time: nothing is allocated.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace rubdyn {

/// Square systems of at most Cap unknowns.
template <int Cap>
using CapMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, Cap, Cap>;
template <int Cap>
using CapVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, Cap, 1>;

/// What min_norm_solve found.
struct MinNormResult {
  bool consistent = false;  ///< b lies in the range of A (to the bound of min_norm_solve)
  int rank = 0;             ///< numerical rank
  double kappa = 1.0;       ///< largest over smallest retained pivot (>= 1)
};

/// x = the minimum-norm solution of A x = b (m x m, m <= Cap), the rank decided at
/// rel_threshold times the largest entry of A. Consistent when every equation the elimination
/// leaves (the rows beyond the rank) is 0 to 1e3 m kappa eps (|A|_max |y|_inf + |b|_inf): the
/// round-off of the elimination, with a margin of a thousand. A regular A gives the ordinary
/// solution (rank m).
template <int Cap>
MinNormResult min_norm_solve(CapMat<Cap> a, CapVec<Cap> b, CapVec<Cap>& x, double rel_threshold) {
  MinNormResult res;
  const int m = static_cast<int>(a.rows());
  x.setZero(m);
  if (m == 0) {
    res.consistent = true;
    return res;
  }
  int col[Cap];
  double scale = 0.0, b_max = 0.0;
  for (int i = 0; i < m; ++i) {
    col[i] = i;
    b_max = std::max(b_max, std::abs(b[i]));
    for (int j = 0; j < m; ++j) scale = std::max(scale, std::abs(a(i, j)));
  }
  int r = 0;
  for (; r < m; ++r) {
    int pr = r, pc = r;
    double best = -1.0;
    for (int i = r; i < m; ++i)
      for (int j = r; j < m; ++j)
        if (std::abs(a(i, j)) > best) {
          best = std::abs(a(i, j));
          pr = i;
          pc = j;
        }
    if (!(best > rel_threshold * scale)) break;
    if (pr != r) {
      a.row(pr).swap(a.row(r));
      std::swap(b[pr], b[r]);
    }
    if (pc != r) {
      a.col(pc).swap(a.col(r));
      std::swap(col[pc], col[r]);
    }
    for (int i = r + 1; i < m; ++i) {
      const double f = a(i, r) / a(r, r);
      if (f == 0.0) continue;
      for (int j = r + 1; j < m; ++j) a(i, j) -= f * a(r, j);
      a(i, r) = 0.0;
      b[i] -= f * b[r];
    }
  }
  res.rank = r;
  for (int k = 0; k < r; ++k) res.kappa = std::max(res.kappa, std::abs(a(0, 0) / a(k, k)));
  // the basic solution y (free unknowns 0), in the permuted order
  CapVec<Cap> y = CapVec<Cap>::Zero(m);
  for (int k = r - 1; k >= 0; --k) {
    double s = b[k];
    for (int j = k + 1; j < r; ++j) s -= a(k, j) * y[j];
    y[k] = s / a(k, k);
  }
  double left = 0.0;  // what the elimination leaves of the dependent equations
  for (int i = r; i < m; ++i) left = std::max(left, std::abs(b[i]));
  const double bound = 1e3 * m * res.kappa * std::numeric_limits<double>::epsilon() *
                       (scale * y.cwiseAbs().maxCoeff() + b_max);
  res.consistent = std::isfinite(left) && left <= bound && y.allFinite();
  const int nf = m - r;
  if (nf > 0 && r > 0) {
    // null space: column f of N has 1 at free unknown r + f, 0 at the other free ones
    CapMat<Cap> N = CapMat<Cap>::Zero(m, nf);
    for (int f = 0; f < nf; ++f) {
      N(r + f, f) = 1.0;
      for (int k = r - 1; k >= 0; --k) {
        double s = -a(k, r + f);
        for (int j = k + 1; j < r; ++j) s -= a(k, j) * N(j, f);
        N(k, f) = s / a(k, k);
      }
    }
    CapMat<Cap> G = N.transpose() * N;  // SPD (N has an identity block)
    CapVec<Cap> c = N.transpose() * y;
    Eigen::LLT<CapMat<Cap>> llt(G);
    c = llt.solve(c);
    y.noalias() -= N * c;
  }
  for (int i = 0; i < m; ++i) x[col[i]] = y[i];
  return res;
}

}  // namespace rubdyn
