// The one Coulomb-Signorini local solver (rubdyn/contact/coulomb_signorini.hpp): its solutions
// satisfy the law as written (checked here from the definitions, not from the enumeration),
// it is unique where theory says so, and the tie rule is the documented one.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "rubdyn/contact/coulomb_signorini.hpp"

using namespace rubdyn;

namespace {

/// A problem with data of order 1 and the round-off band.
LocalProblem problem(double A_NN, double A_NT, double A_TT, double u_N, double u_T, double mu) {
  return make_local_problem(A_NN, A_NT, A_TT, u_N, u_T, mu);
}

/// Checks the law from its definition: u = u0 + A r; 0 <= u_N _|_ r_N >= 0; |r_T| <= mu r_N;
/// inside the cone u_T = 0; on its edge r_T opposes u_T. `tol`: relative round-off of the data.
void check_law(const LocalProblem& p, const LocalSolution& s, double tol) {
  const double uN = p.u_N + p.A_NN * s.r_N + p.A_NT * s.r_T;
  const double uT = p.u_T + p.A_NT * s.r_N + p.A_TT * s.r_T;
  const double scale_u = std::abs(p.u_N) + std::abs(p.u_T) + 1e-300;
  const double scale_r = scale_u / p.A_NN;
  CHECK(uN >= -tol * scale_u);
  CHECK(s.r_N >= -tol * scale_r);
  CHECK(std::abs(uN * s.r_N) <= tol * scale_u * scale_r);
  CHECK(std::abs(s.r_T) <= p.mu * s.r_N + tol * scale_r);
  if (s.r_N > tol * scale_r && std::abs(s.r_T) < p.mu * s.r_N * (1.0 - 1e-9)) {
    CHECK(std::abs(uT) <= tol * scale_u);  // strictly inside the cone: sticking
  }
  CHECK(uT * s.r_T <= tol * scale_u * scale_r);  // friction opposes the sliding
}

}  // namespace

TEST_CASE("Coulomb-Signorini: the solutions of random well-posed problems satisfy the law",
          "[contact][unit]") {
  // A = W^T M^{-1} W for random SPD 2x2 matrices, u0 and mu in [0, 2]. Where both slip normal
  // masses A_NN -+ mu A_NT are positive the problem of one contact has exactly one solution
  // (the Painleve-free case): the enumeration must find exactly one strict candidate, except
  // in the measure-zero boundary cases, and that candidate satisfies the law.
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  int checked = 0;
  for (int k = 0; k < 20000; ++k) {
    const double a = U(rng), b = U(rng), c = U(rng), d = U(rng);
    // A = B B^T + 0.05 I, B = [[a b][c d]]: SPD with eigenvalues >= 0.05
    const double A_NN = a * a + b * b + 0.05, A_NT = a * c + b * d, A_TT = c * c + d * d + 0.05;
    const double mu = k % 7 == 0 ? 0.0 : 1.0 + U(rng);
    if (A_NN - mu * std::abs(A_NT) <= 1e-3 * A_NN) continue;  // Painleve-type: see below
    const LocalProblem p = problem(A_NN, A_NT, A_TT, U(rng), U(rng), mu);
    const LocalSolution s = solve_coulomb_signorini(p);
    REQUIRE(s.ok());
    CHECK(s.n_strict <= 1);
    // 1e-11: the 2x2 solves lose a few digits to the conditioning (A_TT >= 0.05, det >= 0.0025)
    check_law(p, s, 1e-11);
    ++checked;
  }
  CHECK(checked > 5000);
}

TEST_CASE("Coulomb-Signorini: each mode on a problem solved by hand", "[contact][unit]") {
  // A = [[2 1][1 3]], mu = 0.5.
  SECTION("separating: free, r = 0") {
    const LocalSolution s = solve_coulomb_signorini(problem(2, 1, 3, 0.4, -1.0, 0.5));
    CHECK(s.phase == Phase::Free);
    CHECK(s.r_N == 0.0);
    CHECK(s.n_consistent == 1);
  }
  SECTION("inside the cone: stick, A r = -u0") {
    // A^{-1} = [[3 -1][-1 2]] / 5; u0 = (-1, -0.1): r = (2.9, -0.8) / 5, |r_T| < mu r_N.
    const LocalSolution s = solve_coulomb_signorini(problem(2, 1, 3, -1.0, -0.1, 0.5));
    CHECK(s.phase == Phase::Stick);
    CHECK(s.r_N == Approx(0.58).epsilon(1e-14));
    CHECK(s.r_T == Approx(-0.16).epsilon(1e-14));
  }
  SECTION("outside the cone: slip in the direction of u_T") {
    // u0 = (-1, 2): stick would need r = -(3(-1) - 2, -(-1) + 4) / 5 = (1, -1), |r_T| > mu r_N.
    // slip+: r_T = -0.5 r_N, u_N = -1 + (2 - 0.5) r_N = 0: r_N = 2/3, u_T = 2 + 2/3 - 1 > 0.
    const LocalSolution s = solve_coulomb_signorini(problem(2, 1, 3, -1.0, 2.0, 0.5));
    CHECK(s.phase == Phase::SlipPos);
    CHECK(s.r_N == Approx(2.0 / 3.0).epsilon(1e-14));
    CHECK(s.r_T == Approx(-1.0 / 3.0).epsilon(1e-14));
  }
  SECTION("frictionless: contact labelled SlipPos with r_T = 0") {
    const LocalSolution s = solve_coulomb_signorini(problem(2, 1, 3, -1.0, 2.0, 0.0));
    CHECK(s.phase == Phase::SlipPos);
    CHECK(s.r_N == Approx(0.5).epsilon(1e-14));
    CHECK(s.r_T == 0.0);
  }
  SECTION("already sliding (acceleration level): only that direction, no stick") {
    LocalProblem p = problem(2, 1, 3, -1.0, -0.1, 0.5);  // would stick if v_t were 0
    p.sliding = -1;
    const LocalSolution s = solve_coulomb_signorini(p);
    CHECK(s.phase == Phase::SlipNeg);
    // slip-: r_T = 0.5 r_N, u_N = -1 + (2 + 0.5) r_N = 0
    CHECK(s.r_N == Approx(0.4).epsilon(1e-14));
    CHECK(s.r_T == Approx(0.2).epsilon(1e-14));
  }
}

TEST_CASE("Coulomb-Signorini: the tie rule", "[contact][unit]") {
  // A = [[2 1][1 3]], mu = 0.5, u0 = (-1, x): the stick impulse is r = ((3 + x), (-1 - 2x)) / 5,
  // on the cone's edge r_T = -mu r_N for x = 1/3, where slip+ (r_N = 2/3, r_T = -1/3) has
  // u_T = 0: both candidates are on their boundaries, with the same r.
  SECTION("at the cone edge stick and slip coincide; stick is named (order free, stick, slip)") {
    LocalProblem p = problem(2, 1, 3, -1.0, 1.0 / 3.0, 0.5);
    p.tol_u = 1e-9;  // 1/3 is not representable: a band far above its rounding holds both
    p.tol_r = 1e-9;
    const LocalSolution s = solve_coulomb_signorini(p);
    CHECK(s.n_strict == 0);
    CHECK(s.n_consistent == 2);
    CHECK(s.phase == Phase::Stick);
    CHECK(s.r_N == Approx(2.0 / 3.0).epsilon(1e-14));
  }
  SECTION("the excluded mode is dropped while another is consistent") {
    LocalProblem p = problem(2, 1, 3, -1.0, 1.0 / 3.0, 0.5);
    p.tol_u = 1e-9;
    p.tol_r = 1e-9;
    p.excluded = Phase::Stick;
    CHECK(solve_coulomb_signorini(p).phase == Phase::SlipPos);
    // ... and kept when it is the only one (u0 = (-1, -0.1): strictly inside the cone, both
    // slip directions contradict the sign of their u_T)
    LocalProblem q = problem(2, 1, 3, -1.0, -0.1, 0.5);
    q.excluded = Phase::Stick;
    CHECK(solve_coulomb_signorini(q).phase == Phase::Stick);
  }
  // A Painleve-type Delassus matrix: A = [[1 2][2 5]] (SPD, det 1), mu = 1, so the slip+ normal
  // mass A_NN - mu A_NT = -1.
  SECTION("Painleve: several strict solutions are flagged, least contact effort kept") {
    // u0 = (0.5, 3): free (u_N > 0); slip+ r_N = 0.5, r_T = -0.5, u_T = 3 + 1 - 2.5 > 0; stick
    // r = -A^{-1} u0 = (3.5, -2), inside the cone. Three strict candidates.
    const LocalSolution s = solve_coulomb_signorini(problem(1, 2, 5, 0.5, 3.0, 1.0));
    CHECK(s.n_strict == 3);
    CHECK(s.nonunique());
    CHECK(s.phase == Phase::Free);
    CHECK(s.r_N == 0.0);
  }
  SECTION("Painleve: no solution is flagged, phase Free and r = 0") {
    // The classical inconsistency at acceleration level: sliding in direction +1 with the gap
    // closing (u_N = -1) and a negative slip normal mass: free is violated, and slip+ needs
    // r_N = -1 < 0.
    LocalProblem p = problem(1, 2, 5, -1.0, 0.0, 1.0);
    p.sliding = 1;
    const LocalSolution s = solve_coulomb_signorini(p);
    CHECK_FALSE(s.ok());
    CHECK(s.phase == Phase::Free);
    CHECK(s.r_N == 0.0);
  }
}
