// The K-contact test problems (tests/support/multi_problems.hpp) are themselves checked before
// the solvers are tested on them: contact Jacobians and rates against finite differences, the
// product model against its parts.
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <random>

#include "support/multi_problems.hpp"
#include "support/problems.hpp"

using namespace rubdyn;
using namespace rubdyn::testing;

namespace {

/// Checks W_N, W_T, v_N, v_t and wdot of every contact of m at (q, v) against central finite
/// differences of d_N along the coordinates and of v_N, v_t along the motion.
void check_contact_derivatives(const LagrangianModel& m, const Vec& q, const Vec& v) {
  const int n = m.num_dofs();
  const double h = 1e-6;
  for (int k = 0; k < m.contact_count(); ++k) {
    const ContactKinematics c = m.contact(k, 0.0, q, v);
    for (int i = 0; i < n; ++i) {
      Vec qp = q, qm = q;
      qp[i] += h;
      qm[i] -= h;
      const double dd = (m.contact(k, 0.0, qp, v).d_N - m.contact(k, 0.0, qm, v).d_N) / (2 * h);
      // central difference of smooth trigonometric functions of O(1) arguments: error
      // O(h^2) = 1e-12, round-off eps / h = 2e-10; 1e-8 is 50x above both
      CHECK(dd == Approx(c.W_N[i]).margin(1e-8));
    }
    CHECK(c.v_N == Approx(c.W_N.dot(v) + c.b_N).margin(1e-14));
    CHECK(c.v_t == Approx(c.W_T.dot(v) + c.b_T).margin(1e-14));
    // wdot = (dW/dt)^T v: the rate of W^T v along q' = v at fixed v
    const Vec qp = q + h * v, qm = q - h * v;
    const ContactKinematics cp = m.contact(k, 0.0, qp, v), cm = m.contact(k, 0.0, qm, v);
    // same argument as above, with |v| = O(1)
    CHECK((cp.W_N.dot(v) - cm.W_N.dot(v)) / (2 * h) == Approx(c.wdot_N).margin(1e-8));
    CHECK((cp.W_T.dot(v) - cm.W_T.dot(v)) / (2 * h) == Approx(c.wdot_T).margin(1e-8));
  }
}

}  // namespace

TEST_CASE("Falling rod: contact Jacobians and rates equal finite differences",
          "[unit][problems][multi]") {
  const FallingRod rod({0.3, 0.0, 0.0});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Vec q(3), v(3);
    q << u(rng), 1.0 + u(rng), 1.5 * u(rng);
    v << u(rng), u(rng), 3.0 * u(rng);
    check_contact_derivatives(rod, q, v);
  }
}

TEST_CASE("Falling rod dropped flat: both ends touch the ground at the same instant",
          "[unit][problems][multi]") {
  const FallingRod rod({0.0, 0.0, 0.0});
  const MechanicalState s = rod.initial(0.2);
  // flat: d_N of both ends is the height exactly, with opposite moment arms
  const ContactKinematics a = rod.contact(0, 0.0, s.q, s.v), b = rod.contact(1, 0.0, s.q, s.v);
  CHECK(a.d_N == 0.2);
  CHECK(b.d_N == 0.2);
  CHECK(a.W_N[2] == -rod.half_length());
  CHECK(b.W_N[2] == rod.half_length());
}

TEST_CASE("Product model: each contact and each block is its part's", "[unit][problems][multi]") {
  auto ball = std::make_shared<BouncingBall>(0.5);
  auto rod = std::make_shared<FallingRod>(ContactLaw{0.2, 0.0, 0.0});
  const ProductModel p(ball, rod);
  REQUIRE(p.num_dofs() == 5);
  REQUIRE(p.contact_count() == 3);
  CHECK(p.coordinates()[0].name == "x_a");
  CHECK(p.coordinates()[4].name == "phi_b");
  CHECK(p.contact_law(1).mu == 0.2);
  CHECK(p.gap_scale(0) == ball->gap_scale(0));

  Vec q(5), v(5);
  q << 0.3, 0.7, 0.1, 0.4, 0.2;
  v << 0.5, -1.0, 0.3, -0.2, 1.1;
  check_contact_derivatives(p, q, v);
  // the rod's contact 1 (model contact 2) sees only the rod's dofs, exactly as the rod does
  const ContactKinematics cp = p.contact(2, 0.0, q, v);
  const ContactKinematics cr = rod->contact(1, 0.0, q.tail(3), v.tail(3));
  CHECK(cp.d_N == cr.d_N);
  CHECK(cp.W_N.head(2).isZero(0.0));
  CHECK(cp.W_N.tail(3) == cr.W_N);
  // block-diagonal mass: solve_mass of the product equals the parts' solves
  Mat B = Mat::Identity(5, 5), M(5, 5);
  p.solve_mass(q, B);
  p.mass_matrix(q, M);
  // M is diagonal with entries of O(1): M B = I to round-off
  CHECK((M * B - Mat::Identity(5, 5)).cwiseAbs().maxCoeff() < 1e-15);
  CHECK(p.mechanical_energy(0.0, q, v) ==
        Approx(ball->mechanical_energy(0.0, q.head(2), v.head(2)) +
               rod->mechanical_energy(0.0, q.tail(3), v.tail(3)))
            .epsilon(1e-15));
}
