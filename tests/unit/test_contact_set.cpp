// The K-contact Coulomb-Signorini solver (rubdyn/contact/contact_set.hpp), checked against
//   - the law's definition (check_law below, written from the law, not from the solver),
//   - an independent brute force over the mode combinations written here from the definition
//     (full 2K x 2K systems, Eigen's LU), for its typed outcome on coupled problems,
//   - the one-contact kernel (coulomb_signorini.hpp): K = 1 reproduces it, and a set of
//     decoupled contacts is the product of K one-contact problems,
// on tens of thousands of random problems with fixed seeds: symmetric positive definite W,
// singular W (redundant contacts), and Painleve-prone W (strong normal-tangential coupling, not
// symmetric, sliding directions fixed) where there are no or several solutions.
#include <Eigen/LU>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include "rubdyn/contact/contact_set.hpp"
#include "rubdyn/contact/coulomb_signorini.hpp"

using namespace rubdyn;

namespace {

using Rng = std::mt19937_64;

double uniform(Rng& rng, double a, double b) {
  return std::uniform_real_distribution<double>(a, b)(rng);
}

/// The scales of a solution: of u (|u0| + |W| |r|, the size of the terms that cancel in u) and of
/// r (|r| + |u0| / min W_NN, the band's own scale).
struct Scales {
  double u = 0, r = 0;
};
Scales scales_of(const Mat& W, const Vec& u0, const Vec& r) {
  double w_min = 1e300;
  for (int i = 0; 2 * i < W.rows(); ++i) w_min = std::min(w_min, std::abs(W(2 * i, 2 * i)));
  const double u0n = u0.size() ? u0.cwiseAbs().maxCoeff() : 0.0;
  const double rn = r.size() ? r.cwiseAbs().maxCoeff() : 0.0;
  const double Wn = W.size() ? W.cwiseAbs().rowwise().sum().maxCoeff() : 0.0;
  return {u0n + Wn * rn + 1e-300, rn + u0n * W.rows() / std::max(w_min, 1e-300) + 1e-300};
}

/// The law from its definition, for the forces r and the modes the solver reports: u = u0 + W r;
/// 0 <= u_N _|_ r_N >= 0; |r_T| <= mu r_N; strictly inside the cone u_T = 0; sliding (u_T != 0
/// or a fixed direction) r_T = -mu s r_N against the sliding; u_T r_T <= 0 (friction never
/// injects power); and each mode's own equations. `tol`: relative to the scales above.
void check_law(const Mat& W, const Vec& u0, const std::vector<SetContact>& c, const Vec& r,
               const std::vector<Phase>& mode, double tol) {
  const Vec u = u0 + W * r;
  const Scales s = scales_of(W, u0, r);
  for (std::size_t i = 0; i < c.size(); ++i) {
    const double rN = r(2 * i), rT = r(2 * i + 1), uN = u(2 * i), uT = u(2 * i + 1);
    const double mu = c[i].mu;
    INFO("contact " << i << " mode " << to_string(mode[i]) << " r = (" << rN << ", " << rT
                    << ") u = (" << uN << ", " << uT << ") mu " << mu << " sliding "
                    << c[i].sliding);
    CHECK(rN >= -tol * s.r);
    CHECK(uN >= -tol * s.u);
    CHECK(std::min(std::abs(uN) / s.u, std::abs(rN) / s.r) <= tol);
    CHECK(std::abs(rT) <= mu * rN + tol * s.r);
    if (c[i].sliding != 0 && mu > 0) {
      CHECK(std::abs(rT + mu * c[i].sliding * rN) <= tol * s.r);
    } else {
      CHECK(uT * rT <= tol * s.u * s.r);
      if (rN > tol * s.r && std::abs(rT) < mu * rN - 1e-6 * s.r)
        CHECK(std::abs(uT) <= tol * s.u);  // strictly inside the cone: no sliding
      if (rN > tol * s.r && std::abs(uT) > tol * s.u)
        CHECK(std::abs(rT + mu * (uT > 0 ? 1.0 : -1.0) * rN) <= tol * s.r);  // on the edge
    }
    switch (mode[i]) {
      case Phase::Free:
        CHECK(rN == 0.0);
        CHECK(rT == 0.0);
        break;
      case Phase::Stick:
        CHECK(std::abs(uN) <= tol * s.u);
        CHECK(std::abs(uT) <= tol * s.u);
        break;
      case Phase::SlipPos:
      case Phase::SlipNeg: {
        const double sg = mode[i] == Phase::SlipPos ? 1.0 : -1.0;
        CHECK(std::abs(uN) <= tol * s.u);
        CHECK(std::abs(rT + mu * sg * rN) <= tol * s.r);
        if (c[i].sliding == 0 && mu > 0) CHECK(sg * uT >= -tol * s.u);
        if (c[i].sliding != 0 && mu > 0) CHECK(sg == c[i].sliding);
        break;
      }
    }
  }
}

std::vector<Phase> modes_of(const ContactSetSolver& s) {
  std::vector<Phase> m(s.size());
  for (int i = 0; i < s.size(); ++i) m[i] = s.mode(i);
  return m;
}

/// Random friction coefficients: 0 (frictionless) one time in 8, else in [0, mu_max].
std::vector<SetContact> random_contacts(Rng& rng, int K, double mu_max, bool sliding) {
  std::vector<SetContact> c(K);
  for (auto& ci : c) {
    ci.mu = rng() % 8 == 0 ? 0.0 : uniform(rng, 0.0, mu_max);
    if (sliding && rng() % 2 == 0) ci.sliding = rng() % 2 == 0 ? 1 : -1;
  }
  return c;
}

/// W = H H^T with H = [B, sqrt(0.05) I] (SPD, eigenvalues >= 0.05), u0 = H f: the structure
/// H M^{-1} H^T of a Delassus operator with M = I.
void random_spd(Rng& rng, int K, Mat& W, Vec& u0) {
  Mat B(2 * K, 2 * K);
  for (int i = 0; i < B.size(); ++i) B.data()[i] = uniform(rng, -1, 1);
  W = B * B.transpose() + 0.05 * Mat::Identity(2 * K, 2 * K);
  u0 = Vec(2 * K);
  for (int i = 0; i < 2 * K; ++i) u0(i) = uniform(rng, -1, 1);
}

/// Redundant contacts: H has fewer columns (dofs) than rows, or two equal normal rows, so
/// W = H H^T is singular; u0 = H f lies in the range of H, as it does for a mechanism.
void random_singular(Rng& rng, int K, Mat& W, Vec& u0) {
  const int n = std::max(1, 2 * K - 1 - static_cast<int>(rng() % 2));
  Mat H(2 * K, n);
  for (int i = 0; i < H.size(); ++i) H.data()[i] = uniform(rng, -1, 1);
  if (K >= 2 && rng() % 2 == 0) H.row(2) = H.row(0);  // contacts 0 and 1: the same normal
  Vec f(n);
  for (int i = 0; i < n; ++i) f(i) = uniform(rng, -1, 1);
  W = H * H.transpose();
  u0 = H * f;
}

/// Painleve-prone: W = SPD + a strong normal-tangential coupling, not symmetric (the slip normal
/// masses W_NN - mu s W_NT of contact and pair may be negative), any u0.
void random_painleve(Rng& rng, int K, Mat& W, Vec& u0) {
  random_spd(rng, K, W, u0);
  for (int i = 0; i < 2 * K; i += 2)
    for (int j = 1; j < 2 * K; j += 2) W(i, j) += uniform(rng, -1.5, 1.5);
}

// --- the independent brute force -------------------------------------------------------------

/// Every combination of modes solved from its full 2K x 2K system (free: r = 0; stick: u = 0;
/// slip s: u_N = 0, r_T + mu s r_N = 0) and judged by the law's inequalities, each scaled by
/// its scale. `robust`: the combinations whose every inequality holds with margin > amb;
/// `loose`: those that hold to -amb; `ambiguous` when a combination's margins or its
/// conditioning fall in between (the problem is then not judged).
struct BruteForce {
  int robust = 0, loose = 0;
  bool ambiguous = false;
  /// the robust combination first in the order of the tie rule, written out here: fewest closed
  /// contacts, fewest slipping ones with friction, then contact by contact free < stick < slip+
  /// < slip- (contact 0 first)
  std::vector<Phase> first;
};
BruteForce brute_force(const Mat& W, const Vec& u0, const std::vector<SetContact>& c) {
  const int K = static_cast<int>(c.size());
  const double amb = 1e-9;
  BruteForce out;
  std::vector<int> m(K, 0), best_key;
  const Phase all[4] = {Phase::Free, Phase::Stick, Phase::SlipPos, Phase::SlipNeg};
  using M8 = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 8, 8>;
  using V8 = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 8, 1>;
  M8 A(2 * K, 2 * K);
  V8 b(2 * K);
  for (int code = 0; code < (1 << (2 * K)); ++code) {
    bool allowed = true;
    for (int i = 0; i < K; ++i) {
      m[i] = (code >> (2 * i)) & 3;
      const Phase p = all[m[i]];
      if (c[i].mu == 0.0) allowed &= p == Phase::Free || p == Phase::SlipPos;
      if (c[i].mu > 0.0 && c[i].sliding != 0)
        allowed &= p == Phase::Free || p == (c[i].sliding > 0 ? Phase::SlipPos : Phase::SlipNeg);
    }
    if (!allowed) continue;
    A.setZero();
    b.setZero();
    for (int i = 0; i < K; ++i) {
      const Phase p = all[m[i]];
      const int N = 2 * i, T = 2 * i + 1;
      if (p == Phase::Free) {
        A(N, N) = 1;
        A(T, T) = 1;
      } else {
        A.row(N) = W.row(N);
        b(N) = -u0(N);
        if (p == Phase::Stick) {
          A.row(T) = W.row(T);
          b(T) = -u0(T);
        } else {
          A(T, T) = 1;
          A(T, N) = c[i].mu * (p == Phase::SlipPos ? 1.0 : -1.0);
        }
      }
    }
    Eigen::FullPivLU<M8> lu(A);
    // singular to the solver's threshold (1e-12, pivots against the largest entry) is not a
    // candidate; the brute force does not judge problems near it (pivot ratios in [1e-14, 1e-10])
    lu.setThreshold(1e-10);
    const bool clear = lu.isInvertible();
    lu.setThreshold(1e-14);
    if (!lu.isInvertible()) continue;
    if (!clear) {
      out.ambiguous = true;
      continue;
    }
    const Vec r = lu.solve(b);
    const Vec u = u0 + W * r;
    const Scales s = scales_of(W, u0, r);
    double worst = 1e300;
    for (int i = 0; i < K; ++i) {
      const Phase p = all[m[i]];
      const double rN = r(2 * i), rT = r(2 * i + 1), uN = u(2 * i), uT = u(2 * i + 1);
      if (p == Phase::Free) {
        worst = std::min(worst, uN / s.u);
      } else {
        worst = std::min(worst, rN / s.r);
        if (p == Phase::Stick) worst = std::min(worst, (c[i].mu * rN - std::abs(rT)) / s.r);
        if ((p == Phase::SlipPos || p == Phase::SlipNeg) && c[i].sliding == 0 && c[i].mu > 0)
          worst = std::min(worst, (p == Phase::SlipPos ? uT : -uT) / s.u);
      }
    }
    // the solver's band grows with the conditioning of a mode's solve (m kappa eps, m <= 8): so
    // does the band in which the brute force does not judge, 100 times wider
    const auto piv = lu.matrixLU().diagonal().cwiseAbs();
    const double band = std::max(amb, 1e3 * piv.maxCoeff() / piv.minCoeff() * 2.2e-16);
    if (worst > band) {
      ++out.robust;
      ++out.loose;
      std::vector<int> key = {0, 0};
      for (int i = 0; i < K; ++i) {
        key[0] += m[i] != 0;
        key[1] += m[i] >= 2 && c[i].mu > 0;
      }
      for (int i = 0; i < K; ++i) key.push_back(m[i]);
      if (best_key.empty() || key < best_key) {
        best_key = key;
        out.first.resize(K);
        for (int i = 0; i < K; ++i) out.first[i] = all[m[i]];
      }
    } else if (worst >= -band) {
      ++out.loose;
      out.ambiguous = true;
    }
  }
  return out;
}

}  // namespace

TEST_CASE("Contact set: K = 1 reproduces the one-contact kernel on random problems",
          "[contact][unit]") {
  // Symmetric 2x2 Delassus matrices, SPD and Painleve-type (mu |A_NT| > A_NN), with and without
  // a fixed sliding direction and an excluded mode: the same mode, the same flags, and the same
  // forces (a slip bit for bit: the same operations; a stick to 1e-13 relative: Cramer's rule
  // against elimination on 2x2 systems with condition number below 1e3, i.e. a few ulps times 1e3).
  Rng rng(20261123);
  ContactSetSolver solver(1);
  int n_nonunique = 0, n_none = 0, n_stick = 0;
  for (int k = 0; k < 20000; ++k) {
    const double a = uniform(rng, -1, 1), b = uniform(rng, -1, 1), cc = uniform(rng, -1, 1),
                 d = uniform(rng, -1, 1);
    const double A_NN = a * a + b * b + 0.05, A_NT = a * cc + b * d, A_TT = cc * cc + d * d + 0.05;
    const double mu = k % 7 == 0 ? 0.0 : uniform(rng, 0.0, 4.0);
    LocalProblem p =
        make_local_problem(A_NN, A_NT, A_TT, uniform(rng, -1, 1), uniform(rng, -1, 1), mu);
    if (k % 3 == 0) p.sliding = rng() % 2 ? 1 : -1;
    if (k % 5 == 0) p.excluded = static_cast<Phase>(rng() % 4);
    const LocalSolution ref = solve_coulomb_signorini(p);

    Mat W(2, 2);
    W << A_NN, A_NT, A_NT, A_TT;
    Vec u0(2);
    u0 << p.u_N, p.u_T;
    std::vector<SetContact> c(1);
    c[0] = {p.mu, p.sliding, p.excluded};
    const SetBand band = contact_set_band(W, u0);
    REQUIRE(band.tol_u == p.tol_u);  // the same band
    REQUIRE(band.tol_r == p.tol_r);
    const SetOutcome o = solver.solve(W, u0, c, band);
    INFO("k " << k << " A " << A_NN << " " << A_NT << " " << A_TT << " u0 " << p.u_N << " " << p.u_T
              << " mu " << mu << " sliding " << p.sliding);
    REQUIRE(solver.mode(0) == ref.phase);
    CHECK(has_solution(o) == ref.ok());
    CHECK((o == SetOutcome::NonUnique) == ref.nonunique());
    CHECK((o == SetOutcome::Boundary) == ref.boundary());
    CHECK(solver.n_strict() == ref.n_strict);
    CHECK(solver.n_consistent() == ref.n_consistent);
    if (ref.phase == Phase::Stick) {
      ++n_stick;
      CHECK(solver.r_N(0) == Approx(ref.r_N).epsilon(1e-13).margin(1e-13));
      CHECK(solver.r_T(0) == Approx(ref.r_T).epsilon(1e-13).margin(1e-13));
    } else {
      CHECK(solver.r_N(0) == ref.r_N);
      CHECK(solver.r_T(0) == ref.r_T);
    }
    n_nonunique += ref.nonunique();
    n_none += !ref.ok();
    if (ref.ok()) check_law(W, u0, c, solver.r(), modes_of(solver), 1e-11);
  }
  // the sample reaches every branch
  CHECK(n_nonunique > 500);
  CHECK(n_none > 500);
  CHECK(n_stick > 500);
}

TEST_CASE("Contact set: decoupled contacts are K one-contact problems", "[contact][unit]") {
  // W block-diagonal with Painleve-prone 2x2 blocks: the set's solutions are the products of the
  // contacts' own, so the outcome, the contacts involved and (rule 2 of the tie rule reduces to
  // the one-contact order contact by contact) each contact's mode and forces follow from K calls
  // of the one-contact kernel with the set's band. Forces: a stick's 2x2 solve within 1e-13 as
  // above; blocks are decoupled exactly (zeros), so nothing else differs.
  Rng rng(7);
  ContactSetSolver solver(kMaxEnumContacts);
  int seen[4] = {};
  for (int k = 0; k < 8000; ++k) {
    const int K = 2 + k % 3;
    Mat W = Mat::Zero(2 * K, 2 * K);
    Vec u0(2 * K);
    std::vector<SetContact> c(K);
    for (int i = 0; i < K; ++i) {
      const double a = uniform(rng, -1, 1), b = uniform(rng, -1, 1), cc = uniform(rng, -1, 1),
                   d = uniform(rng, -1, 1);
      W(2 * i, 2 * i) = a * a + b * b + 0.05;
      W(2 * i, 2 * i + 1) = W(2 * i + 1, 2 * i) = a * cc + b * d;
      W(2 * i + 1, 2 * i + 1) = cc * cc + d * d + 0.05;
      u0(2 * i) = uniform(rng, -1, 0.3);
      u0(2 * i + 1) = uniform(rng, -1, 1);
      c[i].mu = rng() % 8 == 0 ? 0.0 : uniform(rng, 0.0, 3.0);
      if (rng() % 3 == 0) c[i].sliding = rng() % 2 ? 1 : -1;
      if (rng() % 4 == 0) c[i].excluded = static_cast<Phase>(rng() % 4);
    }
    const SetBand band = contact_set_band(W, u0);
    const SetOutcome o = solver.solve(W, u0, c, band);
    bool any_none = false, any_nonunique = false, any_boundary = false;
    std::vector<LocalSolution> ref(K);
    for (int i = 0; i < K; ++i) {
      LocalProblem p;
      p.A_NN = W(2 * i, 2 * i);
      p.A_NT = W(2 * i, 2 * i + 1);
      p.A_TT = W(2 * i + 1, 2 * i + 1);
      p.u_N = u0(2 * i);
      p.u_T = u0(2 * i + 1);
      p.mu = c[i].mu;
      p.sliding = c[i].sliding;
      p.excluded = c[i].excluded;
      p.tol_u = band.tol_u;
      p.tol_r = band.tol_r;
      ref[i] = solve_coulomb_signorini(p);
      any_none |= !ref[i].ok();
      any_nonunique |= ref[i].nonunique();
      any_boundary |= ref[i].boundary();
    }
    if (any_boundary) continue;  // measure zero; not reached with these seeds
    INFO("k " << k << " K " << K << " outcome " << to_string(o));
    if (any_none) {
      ++seen[0];
      REQUIRE(o == SetOutcome::NoSolution);
      for (int i = 0; i < K; ++i) CHECK(solver.involved(i) == !ref[i].ok());
      continue;
    }
    if (any_nonunique) {
      ++seen[1];
      REQUIRE(o == SetOutcome::NonUnique);
      for (int i = 0; i < K; ++i) CHECK(solver.involved(i) == ref[i].nonunique());
    } else {
      ++seen[2];
      REQUIRE(o == SetOutcome::Unique);
      CHECK(solver.n_involved() == 0);
    }
    for (int i = 0; i < K; ++i) {
      REQUIRE(solver.mode(i) == ref[i].phase);
      CHECK(solver.r_N(i) == Approx(ref[i].r_N).epsilon(1e-13).margin(1e-13));
      CHECK(solver.r_T(i) == Approx(ref[i].r_T).epsilon(1e-13).margin(1e-13));
    }
    check_law(W, u0, c, solver.r(), modes_of(solver), 1e-11);
  }
  CHECK(seen[0] > 500);
  CHECK(seen[1] > 300);
  CHECK(seen[2] > 500);
}

namespace {

/// Solves random problems of one family and checks every solution against the law, the typed
/// outcome against the brute force, and the certificate of non-uniqueness. Returns the counts of
/// each outcome.
struct FamilyCounts {
  int unique = 0, boundary = 0, nonunique = 0, none = 0, skipped = 0;
};
template <class Gen>
FamilyCounts run_family(Rng& rng, int n, int K, double mu_max, bool sliding, Gen&& gen) {
  ContactSetSolver solver(K);
  FamilyCounts fc;
  Mat W;
  Vec u0;
  for (int k = 0; k < n; ++k) {
    gen(rng, K, W, u0);
    const std::vector<SetContact> c = random_contacts(rng, K, mu_max, sliding);
    const SetOutcome o = solver.solve(W, u0, c, contact_set_band(W, u0));
    INFO("K " << K << " problem " << k << " outcome " << to_string(o) << "\nW =\n"
              << W << "\nu0 = " << u0.transpose());
    switch (o) {
      case SetOutcome::Unique: ++fc.unique; break;
      case SetOutcome::Boundary: ++fc.boundary; break;
      case SetOutcome::NonUnique: ++fc.nonunique; break;
      case SetOutcome::NoSolution: ++fc.none; break;
      default: FAIL("enumeration gave " << to_string(o));
    }
    // 1e-11: the solver's band (1e-13 of sum |u0|, i.e. at most 8e-13 of the scale) plus the
    // backward error of Gaussian elimination with full pivoting on <= 8 x 8 systems (a few ulps
    // of |W| |r|): 10x above both
    if (has_solution(o)) check_law(W, u0, c, solver.r(), modes_of(solver), 1e-11);
    if (o == SetOutcome::NonUnique) {
      // the certificate: another solution, different modes, also obeying the law
      std::vector<Phase> other(K);
      bool differs = false;
      for (int i = 0; i < K; ++i) {
        other[i] = solver.other_mode(i);
        differs |= other[i] != solver.mode(i);
        if (other[i] != solver.mode(i)) CHECK(solver.involved(i));
      }
      CHECK(differs);
      CHECK(solver.n_involved() > 0);
      check_law(W, u0, c, solver.other_r(), other, 1e-11);
    }
    if (o == SetOutcome::NoSolution) {
      CHECK(solver.n_involved() > 0);
      CHECK(solver.r().cwiseAbs().maxCoeff() == 0.0);
    }
    // the typed outcome against the brute force, where it can judge
    const BruteForce bf = brute_force(W, u0, c);
    if (bf.ambiguous) {
      ++fc.skipped;
      continue;
    }
    CHECK((o == SetOutcome::NoSolution) == (bf.loose == 0));
    CHECK((o == SetOutcome::NonUnique) == (bf.robust > 1));
    CHECK((o == SetOutcome::Unique) == (bf.robust == 1));
    if (bf.robust > 0) CHECK(modes_of(solver) == bf.first);  // tie rule 2
  }
  return fc;
}

}  // namespace

namespace {

/// The random families of the tests (and of the report below): generator, seed, sizes, mu.
struct Family {
  const char* name;
  void (*gen)(Rng&, int, Mat&, Vec&);
  std::uint64_t seed;
  int n[5];  // problems for K = 0..4
  double mu_max;
  bool sliding;
};
const Family kSpd = {"SPD", random_spd, 11, {0, 6000, 6000, 4000, 1500}, 2.0, false};
const Family kSingular = {"singular", random_singular, 13, {0, 0, 4000, 3000, 1200}, 1.0, false};
const Family kPainleve = {
    "Painleve-prone", random_painleve, 17, {0, 6000, 5000, 3000, 1200}, 2.0, true};

}  // namespace

TEST_CASE("Contact set: random SPD problems, K = 1..4: a solution always, unique without friction",
          "[contact][unit]") {
  // W = H M^{-1} H^T with M SPD and no fixed sliding direction (impulse and velocity levels):
  // the frictional problem always has a solution (the 2D friction cone is polyhedral, and the
  // LCP of Anitescu and Potra, Nonlinear Dynamics 14, 1997, is solvable for every mu), so
  // NoSolution would be a missed candidate. Without friction it is an LCP with a P-matrix:
  // exactly one solution.
  const Family& fam = kSpd;
  Rng rng(fam.seed);
  for (int K = 1; K <= 4; ++K) {
    const FamilyCounts f = run_family(rng, fam.n[K], K, fam.mu_max, fam.sliding, fam.gen);
    INFO("K " << K << ": unique " << f.unique << " boundary " << f.boundary << " non-unique "
              << f.nonunique << " none " << f.none << " not judged " << f.skipped);
    CHECK(f.none == 0);
    CHECK(f.skipped <= fam.n[K] / 100);
    if (K >= 2) CHECK(f.nonunique > 0);  // mu up to 2 reaches Painleve-type non-uniqueness
  }
  const FamilyCounts f0 = run_family(rng, 2000, 3, 0.0, false, random_spd);
  CHECK(f0.unique == 2000);
}

TEST_CASE("Contact set: random singular W (redundant contacts): a solution, the motion unique",
          "[contact][unit]") {
  // W = H H^T with fewer dofs than constraints or two equal normals: the forces may be
  // indeterminate, never the existence (as above). The brute force does not judge the many
  // boundaries (every loaded redundant pair makes one). Without friction, u = u0 + W r is the
  // gradient of a convex quadratic at its minimisers and is the same for every solution: the
  // spread of u over the consistent combinations stays at the band (1e-11 of its scale, as in
  // check_law), whatever the spread of r.
  const Family& fam = kSingular;
  Rng rng(fam.seed);
  for (int K = 2; K <= 4; ++K) {
    const FamilyCounts f = run_family(rng, fam.n[K], K, fam.mu_max, fam.sliding, fam.gen);
    INFO("K " << K << ": unique " << f.unique << " boundary " << f.boundary << " non-unique "
              << f.nonunique << " none " << f.none);
    CHECK(f.none == 0);
  }
  ContactSetSolver solver(4);
  int indeterminate = 0;
  for (int k = 0; k < 2000; ++k) {
    const int K = 2 + k % 3;
    Mat W;
    Vec u0;
    random_singular(rng, K, W, u0);
    std::vector<SetContact> c(K);  // frictionless
    const SetOutcome o = solver.solve(W, u0, c, contact_set_band(W, u0));
    REQUIRE(has_solution(o));
    check_law(W, u0, c, solver.r(), modes_of(solver), 1e-11);
    const Scales s = scales_of(W, u0, solver.r());
    CHECK(solver.u_spread() <= 1e-11 * s.u);
    indeterminate += solver.r_spread() > 1e-6 * s.r;
  }
  CHECK(indeterminate > 100);  // the sample has redundant contacts that carry load
}

TEST_CASE("Contact set: random Painleve-prone problems: none, one or several solutions, typed",
          "[contact][unit]") {
  // Non-symmetric W with strong normal-tangential coupling and, half of the time, fixed sliding
  // directions (the acceleration level): every outcome occurs, and each is the brute force's.
  const Family& fam = kPainleve;
  Rng rng(fam.seed);
  for (int K = 1; K <= 4; ++K) {
    const FamilyCounts f = run_family(rng, fam.n[K], K, fam.mu_max, fam.sliding, fam.gen);
    INFO("K " << K << ": unique " << f.unique << " boundary " << f.boundary << " non-unique "
              << f.nonunique << " none " << f.none << " not judged " << f.skipped);
    CHECK(f.none > fam.n[K] / 50);
    CHECK(f.nonunique > fam.n[K] / 50);
    CHECK(f.unique > fam.n[K] / 50);
    CHECK(f.skipped <= fam.n[K] / 100);
  }
}

TEST_CASE("Contact set: cases solved by hand", "[contact][unit]") {
  ContactSetSolver solver(4);
  SECTION("two equal contacts without friction: forces indeterminate, shared equally") {
    // both normals the same row of H = [1 0]: W = [[1 0 1 0][0 0 0 0][1 0 1 0][0 0 0 0]] + a
    // tangential compliance; u0_N = -2 on both. Any r_N0 + r_N1 = 2 works. The combination with
    // both closed is singular but consistent (r_N0 + r_N1 = 2 twice): a candidate with the
    // minimum-norm forces r_N = (1, 1), both strictly positive, so it is the one strict
    // combination; the two ends (one contact carrying it all, the other's u_N = 0 on the band)
    // are boundary ones, 1 away in r.
    Mat W(4, 4);
    W << 1, 0, 1, 0, 0, 1, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1;
    Vec u0(4);
    u0 << -2, 0.5, -2, -0.5;
    std::vector<SetContact> c(2);
    CHECK(solver.solve(W, u0, c, contact_set_band(W, u0)) == SetOutcome::Unique);
    CHECK(solver.n_strict() == 1);
    CHECK(solver.n_consistent() == 3);
    CHECK(solver.mode(0) == Phase::SlipPos);  // frictionless contact
    CHECK(solver.mode(1) == Phase::SlipPos);
    // the decomposition's round-off on O(1) numbers
    CHECK(solver.r_N(0) == Approx(1.0).epsilon(1e-14));
    CHECK(solver.r_N(1) == Approx(1.0).epsilon(1e-14));
    CHECK(solver.r_spread() == Approx(1.0).epsilon(1e-14));  // the forces are indeterminate
    CHECK(solver.u_spread() < 1e-14);                        // the motion is not
  }
  SECTION("a Painleve contact beside an ordinary one: non-unique, that contact involved") {
    // contact 0: A = [[2 0.5][0.5 1]], u0 = (-1, 0.2), mu = 0.3: stick r = -A^{-1} u0 =
    // (0.5714.., -0.4857..) is outside the cone; slip+ (r_T = -0.3 r_N): r_N = 1 / 1.85.
    // contact 1: the kernel's Painleve example A = [[1 2][2 5]], mu = 1, u0 = (0.5, 3): free,
    // slip+ and stick all strict. Coupled through W_{N0,N1} = 0.1 (symmetric): contact 1 free
    // leaves contact 0 alone; the others shift the numbers but not the count (checked by the law).
    Mat W(4, 4);
    W << 2, 0.5, 0.1, 0, 0.5, 1, 0, 0, 0.1, 0, 1, 2, 0, 0, 2, 5;
    Vec u0(4);
    u0 << -1, 0.2, 0.5, 3;
    std::vector<SetContact> c = {{0.3, 0, {}}, {1.0, 0, {}}};
    CHECK(solver.solve(W, u0, c, contact_set_band(W, u0)) == SetOutcome::NonUnique);
    CHECK_FALSE(solver.involved(0));
    CHECK(solver.involved(1));
    CHECK(solver.mode(0) == Phase::SlipPos);
    CHECK(solver.mode(1) == Phase::Free);  // least effort: contact 1 free
    CHECK(solver.r_N(0) == Approx(1.0 / 1.85).epsilon(1e-15));
    CHECK(solver.r_T(0) == Approx(-0.3 / 1.85).epsilon(1e-15));
  }
  SECTION("a sliding contact with a negative slip mass, closing: no solution, that one involved") {
    // contact 1 slides +1 with A = [[1 2][2 5]], mu = 1 (slip normal mass 1 - 2 = -1) and
    // u0_N = -1: free is violated, slip+ needs r_N = -1. Contact 0 is ordinary (u0_N = -1,
    // W_NN = 1: r_N = 1 whatever contact 1 does, the two being decoupled).
    Mat W = Mat::Zero(4, 4);
    W(0, 0) = 1;
    W(1, 1) = 1;
    W.bottomRightCorner(2, 2) << 1, 2, 2, 5;
    Vec u0(4);
    u0 << -1, 0, -1, 0;
    std::vector<SetContact> c = {{0.5, 0, {}}, {1.0, 1, {}}};
    CHECK(solver.solve(W, u0, c, contact_set_band(W, u0)) == SetOutcome::NoSolution);
    CHECK_FALSE(solver.involved(0));
    CHECK(solver.involved(1));
    CHECK(solver.r().cwiseAbs().maxCoeff() == 0.0);
    CHECK(solver.mode(0) == Phase::Free);
  }
  SECTION("a strict combination before an earlier boundary one (tie rule 2)") {
    // contact 0: the kernel's Painleve matrix A = [[1 2][2 5]], mu = 1, u0 = (0, 3): free is on
    // its boundary (u_N = 0), slip+ too (r_N = 0), stick strict: r = -A^{-1} u0 = (6, -3).
    // Contact 1 (decoupled, W = I, u0 = (-1, 0), mu = 0.5) sticks with r = (1, 0).
    Mat W = Mat::Identity(4, 4);
    W.topLeftCorner(2, 2) << 1, 2, 2, 5;
    Vec u0(4);
    u0 << 0, 3, -1, 0;
    std::vector<SetContact> c = {{1.0, 0, {}}, {0.5, 0, {}}};
    CHECK(solver.solve(W, u0, c, contact_set_band(W, u0)) == SetOutcome::Unique);
    CHECK(solver.n_strict() == 1);
    CHECK(solver.n_consistent() == 3);
    CHECK(solver.mode(0) == Phase::Stick);
    CHECK(solver.mode(1) == Phase::Stick);
    CHECK(solver.r_N(0) == Approx(6.0).epsilon(1e-14));
    CHECK(solver.r_T(0) == Approx(-3.0).epsilon(1e-14));
    CHECK(solver.r_N(1) == 1.0);
    CHECK(solver.r_spread() == Approx(6.0).epsilon(1e-14));  // the boundary ones: contact 0 free
  }
  SECTION("rule 1 contact by contact: an excluded mode goes only where another remains") {
    // two decoupled contacts at the cone edge (the kernel's tie-rule case, A = [[2 1][1 3]],
    // mu = 0.5, u0 = (-1, 1/3), bands 1e-9): stick and slip+ both on their boundary, stick named.
    // Excluding stick at contact 1 leaves contact 0's choice alone.
    Mat W = Mat::Zero(4, 4);
    W.topLeftCorner(2, 2) << 2, 1, 1, 3;
    W.bottomRightCorner(2, 2) << 2, 1, 1, 3;
    Vec u0(4);
    u0 << -1, 1.0 / 3.0, -1, 1.0 / 3.0;
    std::vector<SetContact> c = {{0.5, 0, {}}, {0.5, 0, Phase::Stick}};
    CHECK(solver.solve(W, u0, c, {1e-9, 1e-9}) == SetOutcome::Boundary);
    CHECK(solver.mode(0) == Phase::Stick);
    CHECK(solver.mode(1) == Phase::SlipPos);
    CHECK(solver.n_consistent() == 2);  // contact 1's stick dropped: 2 x 1
    CHECK(solver.r_N(1) == Approx(2.0 / 3.0).epsilon(1e-14));
  }
  SECTION("impulse level: u0 = ((1 + e_n) v_N-, (1 + e_t) v_t-)") {
    std::vector<ContactLaw> laws = {{0.3, 0.5, 0.0}, {0.0, 1.0, 0.2}};
    Vec vm(4), u0(4);
    vm << -2, 1, -1, 3;
    impulse_free_velocity(vm, laws, u0);
    CHECK(u0(0) == -3.0);
    CHECK(u0(1) == 1.0);
    CHECK(u0(2) == -2.0);
    CHECK(u0(3) == Approx(3.6).epsilon(1e-15));
  }
  SECTION("non-finite data: typed, nothing solved") {
    Mat W = Mat::Identity(2, 2);
    Vec u0(2);
    u0 << std::nan(""), 0;
    std::vector<SetContact> c(1);
    CHECK(solver.solve(W, u0, c, {1e-13, 1e-13}) == SetOutcome::NonFinite);
    CHECK(solver.mode(0) == Phase::Free);
    CHECK(solver.r_N(0) == 0.0);
  }
  SECTION("no contact") {
    const Mat W(0, 0);
    const Vec u0(0);
    CHECK(solver.solve(W, u0, {}, contact_set_band(W, u0)) == SetOutcome::Unique);
    CHECK(solver.size() == 0);
  }
}

namespace {

struct PgsStats {
  int solved = 0, converged = 0;
  double sweeps_mean = 0.0;
  int sweeps_max = 0;
  double deviation_max = 0.0;  // Gauss-Seidel against enumeration, relative to |r|
};

/// SPD W with friction mu <= 0.3 and no fixed direction: where the enumeration finds exactly
/// one solution, Gauss-Seidel (from r = 0) must converge to it. It stops when a sweep changes r
/// by <= 1e-12 |r|; with a sweep contraction q the remaining error is <= q / (1 - q) times that
/// change, so 1e-8 |r| holds for q up to 0.9999.
PgsStats pgs_against_enumeration() {
  Rng rng(19);
  ContactSetSolver enumerated(4), pgs(4);
  PgsStats st;
  for (int k = 0; k < 3000; ++k) {
    const int K = 2 + k % 3;
    Mat W;
    Vec u0;
    random_spd(rng, K, W, u0);
    const std::vector<SetContact> c = random_contacts(rng, K, 0.3, false);
    const SetBand band = contact_set_band(W, u0);
    if (enumerated.solve(W, u0, c, band) != SetOutcome::Unique) continue;
    ++st.solved;
    if (pgs.solve(W, u0, c, band, SetMethod::Pgs) != SetOutcome::Converged) continue;
    ++st.converged;
    st.sweeps_mean += pgs.sweeps();
    st.sweeps_max = std::max(st.sweeps_max, pgs.sweeps());
    const double scale = enumerated.r().cwiseAbs().maxCoeff() + band.tol_r;
    const double dev = (pgs.r() - enumerated.r()).cwiseAbs().maxCoeff() / scale;
    st.deviation_max = std::max(st.deviation_max, dev);
    INFO("K " << K << " problem " << k << " sweeps " << pgs.sweeps());
    CHECK(dev <= 1e-8);
  }
  st.sweeps_mean /= std::max(st.converged, 1);
  return st;
}

/// K = 6..16, beyond the enumeration: Auto takes Gauss-Seidel; a converged r obeys the law to
/// 1e-8 (as above: the contacts visited early see the later ones' last change through W).
PgsStats pgs_beyond_enumeration() {
  Rng rng(29);
  ContactSetSolver pgs(16);
  PgsStats st;
  for (int k = 0; k < 300; ++k) {
    const int K = 6 + k % 11;
    Mat W;
    Vec u0;
    random_spd(rng, K, W, u0);
    const std::vector<SetContact> c = random_contacts(rng, K, 0.3, false);
    ++st.solved;
    const SetOutcome o = pgs.solve(W, u0, c, contact_set_band(W, u0));
    CHECK(pgs.method_used() == SetMethod::Pgs);
    if (o != SetOutcome::Converged) continue;
    ++st.converged;
    st.sweeps_mean += pgs.sweeps();
    st.sweeps_max = std::max(st.sweeps_max, pgs.sweeps());
    check_law(W, u0, c, pgs.r(), modes_of(pgs), 1e-8);
  }
  st.sweeps_mean /= std::max(st.converged, 1);
  return st;
}

}  // namespace

TEST_CASE("Contact set: Gauss-Seidel agrees with the enumeration and obeys the law beyond it",
          "[contact][unit]") {
  const PgsStats a = pgs_against_enumeration();
  INFO("unique " << a.solved << " converged " << a.converged);
  CHECK(a.solved > 2500);
  CHECK(a.converged >= a.solved - a.solved / 100);
  const PgsStats b = pgs_beyond_enumeration();
  CHECK(b.converged >= 290);
}

TEST_CASE("Contact set: Gauss-Seidel's failures are typed", "[contact][unit]") {
  SECTION("the iteration cap: NotConverged, the moving contacts involved, the iterate kept") {
    ContactSetSolver pgs(2, PgsOptions{1e-12, 1});
    Mat W(4, 4);
    W << 2, 0, 1, 0, 0, 2, 0, 0, 1, 0, 2, 0, 0, 0, 0, 2;  // coupled normals
    Vec u0(4);
    u0 << -1, 0, -1, 0;
    std::vector<SetContact> c(2);
    CHECK(pgs.solve(W, u0, c, contact_set_band(W, u0), SetMethod::Pgs) == SetOutcome::NotConverged);
    CHECK(pgs.sweeps() == 1);
    CHECK(pgs.n_involved() > 0);
    // one sweep from 0: r_N0 = 1/2, then r_N1 = (1 - 1/2) / 2 = 1/4 (exact in binary)
    CHECK(pgs.r_N(0) == 0.5);
    CHECK(pgs.r_N(1) == 0.25);
  }
  SECTION("a contact without a local solution: NotConverged, that contact involved") {
    ContactSetSolver pgs(2);
    Mat W = Mat::Zero(4, 4);
    W(0, 0) = 1;
    W(1, 1) = 1;
    W.bottomRightCorner(2, 2) << 1, 2, 2, 5;
    Vec u0(4);
    u0 << -1, 0, -1, 0;
    std::vector<SetContact> c = {{0.5, 0, {}}, {1.0, 1, {}}};
    CHECK(pgs.solve(W, u0, c, contact_set_band(W, u0), SetMethod::Pgs) == SetOutcome::NotConverged);
    CHECK_FALSE(pgs.involved(0));
    CHECK(pgs.involved(1));
  }
}

TEST_CASE("Contact set: report of the random families, the cost and Gauss-Seidel", "[.report]") {
  // Not a test of its own (the same checks run): prints the numbers docs/contact-set.md quotes.
  // Run: build/tests/rubdyn_tests "[.report]"
  for (const Family* fam : {&kSpd, &kSingular, &kPainleve}) {
    Rng rng(fam->seed);
    for (int K = 1; K <= 4; ++K) {
      if (fam->n[K] == 0) continue;
      const FamilyCounts f = run_family(rng, fam->n[K], K, fam->mu_max, fam->sliding, fam->gen);
      std::printf(
          "%-14s K = %d: %4d problems: unique %4d, boundary %4d, non-unique %3d, no solution "
          "%3d; not judged by the brute force %4d\n",
          fam->name, K, fam->n[K], f.unique, f.boundary, f.nonunique, f.none, f.skipped);
    }
  }
  Rng rng(23);
  for (int K = 1; K <= 4; ++K) {
    ContactSetSolver solver(K);
    const int n = 2000;
    std::vector<Mat> Ws(n);
    std::vector<Vec> us(n);
    for (int k = 0; k < n; ++k) random_spd(rng, K, Ws[k], us[k]);
    const std::vector<SetContact> c = random_contacts(rng, K, 0.5, false);
    int sum = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (int k = 0; k < n; ++k)
      sum += static_cast<int>(solver.solve(Ws[k], us[k], c, contact_set_band(Ws[k], us[k])));
    const double us_per =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() /
        n;
    std::printf("enumeration K = %d: %.1f us per solve (mean over %d SPD problems, mu <= 0.5)%s\n",
                K, us_per, n, sum < 0 ? "!" : "");
  }
  const PgsStats a = pgs_against_enumeration(), b = pgs_beyond_enumeration();
  std::printf(
      "Gauss-Seidel K = 2..4: %d of %d unique problems converged, sweeps mean %.1f max %d, "
      "largest deviation from the enumeration %.2g |r|\n",
      a.converged, a.solved, a.sweeps_mean, a.sweeps_max, a.deviation_max);
  std::printf("Gauss-Seidel K = 6..16: %d of %d converged, sweeps mean %.1f max %d\n", b.converged,
              b.solved, b.sweeps_mean, b.sweeps_max);
  SUCCEED();
}

TEST_CASE("Contact set: the uniqueness certificate never meets two solutions", "[contact][unit]") {
  // unique_by_monotonicity(W) claims at most one solution for every u0. Tested against the
  // independent brute force on the random families (SPD, and the non-symmetric Painleve-prone
  // W without fixed sliding), with mu up to 2 so that the certificate both holds and fails: a
  // certified problem must never have two robust solutions (bf.robust > 1), and the
  // enumeration must never call it NonUnique. Not vacuous: the certificate holds on a good share
  // and fails on every problem with two solutions (counted below).
  Rng rng(29);
  ContactSetSolver solver(4);
  int certified = 0, uncertified = 0, nonunique_seen = 0;
  for (int family = 0; family < 2; ++family)
    for (int K = 2; K <= 4; ++K)
      for (int k = 0; k < 2500; ++k) {
        Mat W;
        Vec u0;
        if (family == 0)
          random_spd(rng, K, W, u0);
        else
          random_painleve(rng, K, W, u0);
        const double mu_max = k % 2 == 0 ? 0.5 : 2.0;
        const std::vector<SetContact> c = random_contacts(rng, K, mu_max, false);
        const bool cert = unique_by_monotonicity(W, c);
        const SetOutcome o = solver.solve(W, u0, c, contact_set_band(W, u0));
        const BruteForce bf = brute_force(W, u0, c);
        INFO("family " << family << " K " << K << " problem " << k << " outcome " << to_string(o)
                       << " robust " << bf.robust << "\nW =\n"
                       << W << "\nu0 = " << u0.transpose());
        nonunique_seen += o == SetOutcome::NonUnique;
        if (cert) {
          ++certified;
          CHECK(o != SetOutcome::NonUnique);
          CHECK(bf.robust <= 1);
        } else {
          ++uncertified;
        }
      }
  INFO("certified " << certified << ", uncertified " << uncertified << ", non-unique "
                    << nonunique_seen);
  CHECK(certified > 3000);
  CHECK(uncertified > 1000);
  CHECK(nonunique_seen > 50);
  // without friction an SPD W is certified (the bracket is sym(W) itself)
  for (int k = 0; k < 200; ++k) {
    Mat W;
    Vec u0;
    random_spd(rng, 3, W, u0);
    CHECK(unique_by_monotonicity(W, std::vector<SetContact>(3)));
  }
  // a fixed sliding direction is another law: never certified
  Mat W;
  Vec u0;
  random_spd(rng, 2, W, u0);
  CHECK_FALSE(unique_by_monotonicity(W, std::vector<SetContact>{{0.1, 1, {}}, {0.1, 0, {}}}));
}

TEST_CASE("Contact set: a first guess taken is the enumeration's answer to the bit",
          "[contact][unit]") {
  // solve_guess on random SPD problems (mu <= 0.5) with three guesses: the enumeration's own
  // modes (taken when certified and Unique), every contact free (taken only when r = 0 is the
  // strict solution) and the modes of another problem (mostly refused). Whatever it does, its
  // outcome, modes, r and u must be the enumeration's, bit for bit; when it refuses, its counts
  // are the enumeration's too.
  Rng rng(31);
  ContactSetSolver full(4), guessed(4);
  int taken = 0, refused = 0;
  std::vector<Phase> previous(4, Phase::Stick);
  for (int k = 0; k < 6000; ++k) {
    const int K = 2 + k % 3;
    Mat W;
    Vec u0;
    random_spd(rng, K, W, u0);
    const std::vector<SetContact> c = random_contacts(rng, K, 0.5, false);
    const SetBand band = contact_set_band(W, u0);
    const SetOutcome o = full.solve(W, u0, c, band);
    const std::vector<Phase> own = modes_of(full);
    std::vector<Phase> guess = own;
    if (k % 3 == 1) guess.assign(K, Phase::Free);
    if (k % 3 == 2) guess.assign(previous.begin(), previous.begin() + K);
    for (int i = 0; i < K; ++i)  // a frictionless contact's candidates are free and SlipPos
      if (c[i].mu == 0.0 && guess[i] != Phase::Free) guess[i] = Phase::SlipPos;
    const SetOutcome g = guessed.solve_guess(W, u0, c, band, guess);
    INFO("K " << K << " problem " << k << " outcome " << to_string(o) << " guess taken "
              << guessed.guess_taken());
    REQUIRE(g == o);
    CHECK(modes_of(guessed) == own);
    for (int e = 0; e < 2 * K; ++e) {
      CHECK(guessed.r()(e) == full.r()(e));
      CHECK(guessed.u()(e) == full.u()(e));
    }
    if (guessed.guess_taken()) {
      ++taken;
      CHECK(o == SetOutcome::Unique);
      CHECK(guess == own);
      CHECK(unique_by_monotonicity(W, c));
    } else {
      ++refused;
      CHECK(guessed.n_candidates() == full.n_candidates());
      CHECK(guessed.n_strict() == full.n_strict());
    }
    // the caller's certificate, when given, is used as given
    const SetOutcome g2 = guessed.solve_guess(W, u0, c, band, own, false);
    CHECK(g2 == o);
    CHECK_FALSE(guessed.guess_taken());
    previous = own;
    previous.resize(4, Phase::Stick);
  }
  INFO("taken " << taken << ", refused " << refused);
  CHECK(taken > 1000);
  CHECK(refused > 1000);
}
