// The bordered band LU of the BDF Newton systems (core/bordered_band.*): solves and products
// against Eigen's dense LU and products on the same matrices, banded with a border, with row
// interchanges forced, and dense (the fall-back).
#include <algorithm>
#include <catch2/catch.hpp>
#include <random>
#include <vector>

#include "rubdyn/core/bordered_band.hpp"

using namespace rubdyn;
using namespace rubdyn::detail;

namespace {

/// A random N x N matrix banded (kl, ku) in the non-border coordinates, dense in the border's
/// rows and columns; `weak_diagonal`: the diagonal ten times smaller than the rest, so that
/// partial pivoting must interchange rows.
Mat random_bordered(int N, int kl, int ku, const std::vector<int>& border, bool weak_diagonal,
                    unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<int> inner;
  for (int i = 0; i < N; ++i)
    if (std::find(border.begin(), border.end(), i) == border.end()) inner.push_back(i);
  Mat A = Mat::Zero(N, N);
  const int m = static_cast<int>(inner.size());
  for (int ii = 0; ii < m; ++ii)
    for (int jj = std::max(0, ii - kl); jj <= std::min(m - 1, ii + ku); ++jj)
      A(inner[ii], inner[jj]) = u(rng) * (ii == jj ? (weak_diagonal ? 0.1 : 4.0) : 1.0);
  for (int b : border)
    for (int j = 0; j < N; ++j) {
      A(b, j) = u(rng);
      A(j, b) = u(rng);
    }
  for (int b : border) A(b, b) = 3.0 + u(rng);
  return A;
}

/// |x - x_ref| / |x_ref| of the bordered band solve of S = A0 + c1 A1 + c2 A2 against Eigen's
/// dense LU, and the same for the products with A1.
struct Errors {
  double solve = 0.0, product = 0.0;
  bool banded = false;
};

/// A's nonzeros as an entry list, each split into two parts (1/4 and 3/4) and the whole list
/// shuffled: the lists' entries at one position add up, in any order.
std::vector<MatrixEntry> entries(const Mat& A, unsigned seed) {
  std::vector<MatrixEntry> e;
  for (int j = 0; j < A.cols(); ++j)
    for (int i = 0; i < A.rows(); ++i)
      if (A(i, j) != 0.0) {
        e.push_back({i, j, 0.25 * A(i, j)});
        e.push_back({i, j, 0.75 * A(i, j)});
      }
  std::mt19937 rng(seed);
  std::shuffle(e.begin(), e.end(), rng);
  return e;
}

/// `lists`: the matrices given to detect, factor and product as entry lists.
Errors compare(int N, int kl, int ku, const std::vector<int>& border, bool weak, unsigned seed,
               bool lists = false) {
  const Mat A0 = random_bordered(N, kl, ku, border, weak, seed);
  // the other two within the same pattern, narrower
  const Mat A1 = random_bordered(N, kl / 2, ku, border, false, seed + 1);
  const Mat A2 = random_bordered(N, kl, ku / 2, border, false, seed + 2);
  const double c1 = -0.3, c2 = 0.7;
  const std::vector<MatrixEntry> E0 = entries(A0, seed), E1 = entries(A1, seed + 1),
                                 E2 = entries(A2, seed + 2);
  BorderedBand bb(N, border);
  bb.reset_pattern();
  if (lists) {
    bb.detect(E0);
    bb.detect(E1);
    bb.detect(E2);
  } else {
    bb.detect(A0);
    bb.detect(A1);
    bb.detect(A2);
  }
  bb.finish_pattern();
  REQUIRE((lists ? bb.factor(E0, c1, E1, c2, E2) : bb.factor(A0, c1, A1, c2, A2)));
  const Mat S = A0 + c1 * A1 + c2 * A2;
  std::mt19937 rng(seed + 3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec b(N);
  for (int i = 0; i < N; ++i) b[i] = u(rng);
  Vec x(N);
  bb.solve(b.data(), x.data());
  const Vec xr = S.partialPivLu().solve(b);
  Vec y = Vec::Constant(N, 0.5), yr = y;
  if (lists)
    bb.product(E1, -2.0, b.data(), y.data());
  else
    bb.product(A1, -2.0, b.data(), y.data());
  yr += -2.0 * A1 * b;
  Errors e;
  e.solve = (x - xr).norm() / xr.norm();
  e.product = (y - yr).norm() / yr.norm();
  e.banded = bb.banded();
  CHECK(bb.kl() == kl);
  CHECK(bb.ku() == ku);
  return e;
}

}  // namespace

TEST_CASE("Bordered band LU equals the dense LU", "[unit][newton]") {
  // Both are backward stable LU factorisations with partial pivoting of the same well
  // conditioned matrices (condition numbers below 1e4 for these draws), so that their solutions
  // agree to cond * a few n eps: 1e-10 leaves room for cond up to 1e5 at N = 200 (n eps =
  // 4e-14); a wrong entry, pivot or border term gives O(1) (measured with the border's
  // Schur complement left out: 0.3 .. 1). The products sum the same terms in another order:
  // a few eps relative, 1e-13.
  struct Case {
    int N, kl, ku;
    std::vector<int> border;
    bool weak;
  };
  const std::vector<Case> cases = {
      {60, 7, 7, {56}, false},      // an FE rotor's S: the spin, then two ring coordinates
      {60, 7, 7, {56}, true},       // row interchanges in every column
      {200, 3, 5, {0, 100}, true},  // unsymmetric band, two borders inside the order
      {120, 7, 7, {}, true},        // no border (a prescribed spin)
      {12, 7, 7, {11}, false},      // too wide for its size: the dense fall-back
  };
  unsigned seed = 11;
  for (const Case& c : cases) {
    INFO("N " << c.N << ", kl " << c.kl << ", ku " << c.ku << ", border " << c.border.size()
              << (c.weak ? ", weak diagonal" : ""));
    seed += 10;
    // the same matrices as dense blocks and as entry lists (model/newton_entries): the lists'
    // parts (1/4 + 3/4 of each entry, shuffled) add up to the entry within an eps or two, so
    // the same bounds hold; a lost entry, a border entry put in the band or a detection that
    // misses a list's entries gives O(1) or fails kl/ku
    for (const bool lists : {false, true}) {
      INFO((lists ? "entry lists" : "dense blocks"));
      const Errors e = compare(c.N, c.kl, c.ku, c.border, c.weak, seed, lists);
      CHECK(e.solve <= 1e-10);
      CHECK(e.product <= 1e-13);
      // the flop count chooses: the band below a third of the dense LU's flops
      CHECK(e.banded == (c.N >= 60));
    }
  }
}

TEST_CASE("Bordered band LU reports a singular matrix", "[unit][newton]") {
  // a zero column in the band: no pivot (partial pivoting finds only zeros), not a NaN answer
  const int N = 30;
  Mat A = random_bordered(N, 2, 2, {29}, false, 5u);
  A.col(10).setZero();
  BorderedBand bb(N, std::vector<int>{29});
  bb.reset_pattern();
  bb.detect(A);
  bb.finish_pattern();
  REQUIRE(bb.banded());
  const Mat Z = Mat::Zero(N, N);
  CHECK_FALSE(bb.factor(A, 0.0, Z, 0.0, Z));
}
