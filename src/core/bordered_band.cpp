#include "rubdyn/core/bordered_band.hpp"

#include <algorithm>
#include <cmath>

#include "rubdyn/core/demand.hpp"

namespace rubdyn::detail {

namespace {

/// An LU factorisation with partial pivoting is usable: no zero pivot.
bool nonsingular(const Eigen::PartialPivLU<Mat>& lu) {
  const auto& f = lu.matrixLU();
  for (Eigen::Index i = 0; i < f.rows(); ++i)
    if (f(i, i) == 0.0) return false;
  return true;
}

std::vector<int> spin_only(int spin) {
  return spin >= 0 ? std::vector<int>{spin} : std::vector<int>{};
}

}  // namespace

BorderedBand::BorderedBand(int N, int spin) : BorderedBand(N, spin_only(spin)) {}

BorderedBand::BorderedBand(int N, std::span<const int> border)
    : N_(N), border_(border.begin(), border.end()), pos_(static_cast<std::size_t>(N), 0) {
  nb_ = static_cast<int>(border_.size());
  m_ = N_ - nb_;
  for (int b = 0; b < nb_; ++b) {
    const int i = border_[static_cast<std::size_t>(b)];
    RUBDYN_DEMAND(i >= 0 && i < N_ && (b == 0 || i > border_[static_cast<std::size_t>(b - 1)]));
    pos_[static_cast<std::size_t>(i)] = -1 - b;
  }
  for (int i = 0; i < N_; ++i) {
    if (pos_[static_cast<std::size_t>(i)] < 0) continue;
    pos_[static_cast<std::size_t>(i)] = static_cast<int>(inner_.size());
    inner_.push_back(i);
  }
  X_.setZero(m_, nb_);
  R_.setZero(nb_, m_);
  corner_.setZero(nb_, nb_);
  small_lu_.compute(Mat::Identity(nb_, nb_));  // (sized here)
  work_.assign(static_cast<std::size_t>(N_), 0.0);
  zb_.setZero(nb_);
  reset_pattern();
  finish_pattern();
}

void BorderedBand::reset_pattern() {
  kl_ = ku_ = 0;
}

void BorderedBand::detect(const Mat& A) {
  RUBDYN_DEMAND(A.rows() == N_ && A.cols() == N_);
  for (int jj = 0; jj < m_; ++jj) {
    const int j = inner_[static_cast<std::size_t>(jj)];
    for (int ii = 0; ii < m_; ++ii) {
      if (A(inner_[static_cast<std::size_t>(ii)], j) == 0.0) continue;
      if (ii > jj) kl_ = std::max(kl_, ii - jj);
      if (jj > ii) ku_ = std::max(ku_, jj - ii);
    }
  }
}

void BorderedBand::detect(std::span<const MatrixEntry> A) {
  for (const MatrixEntry& e : A) {
    RUBDYN_DEMAND(e.i >= 0 && e.i < N_ && e.j >= 0 && e.j < N_);
    const int pi = pos_[static_cast<std::size_t>(e.i)], pj = pos_[static_cast<std::size_t>(e.j)];
    if (pi < 0 || pj < 0) continue;  // (a border entry)
    if (pi > pj) kl_ = std::max(kl_, pi - pj);
    if (pj > pi) ku_ = std::max(ku_, pj - pi);
  }
}

void BorderedBand::finish_pattern() {
  // banded when its flops (about 2 m kl (kl + ku) for the LU, plus nb band solves) are fewer
  // than a third of the dense LU's 2/3 N^3: below that the dense kernels' speed wins
  const double band_flops = 2.0 * m_ * kl_ * (kl_ + ku_ + 1.0) + 4.0 * nb_ * m_ * (2.0 * kl_ + ku_);
  const double dense_flops = 2.0 / 3.0 * N_ * double(N_) * N_;
  banded_ = m_ > 0 && 3.0 * band_flops < dense_flops;
  kv_ = kl_ + ku_;
  ld_ = 2 * kl_ + ku_ + 1;
  if (banded_) {
    const auto size = static_cast<std::size_t>(ld_) * static_cast<std::size_t>(m_);
    if (ab_.size() < size) ab_.resize(size);
    if (ipiv_.size() < static_cast<std::size_t>(m_)) ipiv_.resize(static_cast<std::size_t>(m_));
  } else if (dense_.rows() != N_) {
    dense_.setZero(N_, N_);
    dense_lu_.compute(Mat::Identity(N_, N_));  // (sized here)
  }
}

bool BorderedBand::factor(const Mat& A) {
  if (!banded_) {
    if (!A.allFinite()) return false;
    dense_lu_.compute(A);
    return nonsingular(dense_lu_);
  }
  return factor_band([&](int i, int j) { return A(i, j); });
}

bool BorderedBand::factor(const Mat& A0, double c1, const Mat& A1, double c2, const Mat& A2) {
  if (!banded_) {
    dense_ = A0;
    dense_.noalias() += c1 * A1;
    dense_.noalias() += c2 * A2;
    return factor(dense_);
  }
  return factor_band([&](int i, int j) { return A0(i, j) + c1 * A1(i, j) + c2 * A2(i, j); });
}

template <class Entry>
bool BorderedBand::factor_band(const Entry& S) {
  // the band of A, with kl rows of room above it for the fill of the row interchanges
  std::fill(ab_.begin(), ab_.begin() + static_cast<std::ptrdiff_t>(ld_) * m_, 0.0);
  for (int jj = 0; jj < m_; ++jj) {
    const int j = inner_[static_cast<std::size_t>(jj)];
    const int lo = std::max(0, jj - ku_), hi = std::min(m_ - 1, jj + kl_);
    for (int ii = lo; ii <= hi; ++ii) ab(ii, jj) = S(inner_[static_cast<std::size_t>(ii)], j);
  }
  // the border: B (into X), R and D (into the corner)
  for (int b = 0; b < nb_; ++b) {
    const int jb = border_[static_cast<std::size_t>(b)];
    for (int ii = 0; ii < m_; ++ii) {
      const int i = inner_[static_cast<std::size_t>(ii)];
      X_(ii, b) = S(i, jb);
      R_(b, ii) = S(jb, i);
    }
    for (int c = 0; c < nb_; ++c) corner_(b, c) = S(jb, border_[static_cast<std::size_t>(c)]);
  }
  return factor_filled();
}

bool BorderedBand::factor(std::span<const MatrixEntry> A0, double c1,
                          std::span<const MatrixEntry> A1, double c2,
                          std::span<const MatrixEntry> A2) {
  const auto lists = {std::pair{A0, 1.0}, std::pair{A1, c1}, std::pair{A2, c2}};
  if (!banded_) {
    dense_.setZero();
    for (const auto& [A, c] : lists)
      for (const MatrixEntry& e : A) dense_(e.i, e.j) += c * e.v;
    return factor(dense_);
  }
  std::fill(ab_.begin(), ab_.begin() + static_cast<std::ptrdiff_t>(ld_) * m_, 0.0);
  X_.setZero();
  R_.setZero();
  corner_.setZero();
  for (const auto& [A, c] : lists) {
    for (const MatrixEntry& e : A) {
      const int pi = pos_[static_cast<std::size_t>(e.i)], pj = pos_[static_cast<std::size_t>(e.j)];
      const double v = c * e.v;
      if (pi >= 0 && pj >= 0) {
        RUBDYN_DEMAND(pi - pj <= kl_ && pj - pi <= ku_);  // within the detected pattern
        ab(pi, pj) += v;
      } else if (pi >= 0) {
        X_(pi, -1 - pj) += v;
      } else if (pj >= 0) {
        R_(-1 - pi, pj) += v;
      } else {
        corner_(-1 - pi, -1 - pj) += v;
      }
    }
  }
  return factor_filled();
}

bool BorderedBand::factor_filled() {
  // LU with partial pivoting (dgbtf2): column j's pivot among its kl subdiagonal rows; ju the
  // last column that row interchanges so far have filled
  int ju = 0;
  for (int j = 0; j < m_; ++j) {
    const int km = std::min(kl_, m_ - 1 - j);
    int p = 0;
    double best = std::abs(ab(j, j));
    for (int i = 1; i <= km; ++i) {
      const double a = std::abs(ab(j + i, j));
      if (a > best) best = a, p = i;
    }
    ipiv_[static_cast<std::size_t>(j)] = j + p;
    if (!(best > 0.0) || !std::isfinite(best)) return false;
    ju = std::max(ju, std::min(j + ku_ + p, m_ - 1));
    if (p != 0)
      for (int c = j; c <= ju; ++c) std::swap(ab(j, c), ab(j + p, c));
    const double inv = 1.0 / ab(j, j);
    for (int i = 1; i <= km; ++i) ab(j + i, j) *= inv;
    for (int c = j + 1; c <= ju; ++c) {
      const double u = ab(j, c);
      if (u == 0.0) continue;
      for (int i = 1; i <= km; ++i) ab(j + i, c) -= ab(j + i, j) * u;
    }
  }
  if (nb_ == 0) return true;
  // the border: X = A^-1 B, and the Schur complement D - R X
  for (int b = 0; b < nb_; ++b) band_solve(X_.col(b).data());
  corner_.noalias() -= R_ * X_;
  if (!corner_.allFinite()) return false;
  small_lu_.compute(corner_);
  return nonsingular(small_lu_);
}

void BorderedBand::band_solve(double* b) const {
  // L: the row interchanges and the unit lower factor, column by column
  for (int j = 0; j < m_; ++j) {
    const int p = ipiv_[static_cast<std::size_t>(j)];
    if (p != j) std::swap(b[j], b[p]);
    const int km = std::min(kl_, m_ - 1 - j);
    const double bj = b[j];
    if (bj != 0.0)
      for (int i = 1; i <= km; ++i) b[j + i] -= ab(j + i, j) * bj;
  }
  // U, upper bandwidth kl + ku
  for (int j = m_ - 1; j >= 0; --j) {
    b[j] /= ab(j, j);
    const double bj = b[j];
    const int lo = std::max(0, j - kv_);
    if (bj != 0.0)
      for (int i = lo; i < j; ++i) b[i] -= ab(i, j) * bj;
  }
}

void BorderedBand::solve(const double* b, double* x) const {
  if (!banded_) {
    Eigen::Map<Vec>(x, N_) = dense_lu_.solve(Eigen::Map<const Vec>(b, N_));
    return;
  }
  double* y = work_.data();
  for (int ii = 0; ii < m_; ++ii) y[ii] = b[inner_[static_cast<std::size_t>(ii)]];
  band_solve(y);
  if (nb_ > 0) {
    double* z = y + m_;  // x_D = (D - R X)^-1 (b_D - R y)
    for (int c = 0; c < nb_; ++c) {
      double s = b[border_[static_cast<std::size_t>(c)]];
      for (int ii = 0; ii < m_; ++ii) s -= R_(c, ii) * y[ii];
      z[c] = s;
    }
    zb_ = small_lu_.solve(Eigen::Map<const Vec>(z, nb_));
    for (int c = 0; c < nb_; ++c) {
      x[border_[static_cast<std::size_t>(c)]] = zb_[c];
      for (int ii = 0; ii < m_; ++ii) y[ii] -= X_(ii, c) * zb_[c];
    }
  }
  for (int ii = 0; ii < m_; ++ii) x[inner_[static_cast<std::size_t>(ii)]] = y[ii];
}

void BorderedBand::product(const Mat& A, double alpha, const double* x, double* y) const {
  if (!banded_) {
    Eigen::Map<Vec>(y, N_).noalias() += alpha * (A * Eigen::Map<const Vec>(x, N_));
    return;
  }
  for (int ii = 0; ii < m_; ++ii) {
    const int i = inner_[static_cast<std::size_t>(ii)];
    double s = 0.0;
    const int lo = std::max(0, ii - kl_), hi = std::min(m_ - 1, ii + ku_);
    for (int jj = lo; jj <= hi; ++jj) {
      const int j = inner_[static_cast<std::size_t>(jj)];
      s += A(i, j) * x[j];
    }
    for (int b : border_) s += A(i, b) * x[b];
    y[i] += alpha * s;
  }
  for (int b : border_) {
    double s = 0.0;
    for (int j = 0; j < N_; ++j) s += A(b, j) * x[j];
    y[b] += alpha * s;
  }
}

void BorderedBand::product(std::span<const MatrixEntry> A, double alpha, const double* x,
                           double* y) const {
  for (const MatrixEntry& e : A) y[e.i] += alpha * (e.v * x[e.j]);
}

}  // namespace rubdyn::detail
