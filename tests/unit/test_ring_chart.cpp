// The K-contact chart (contact/ring_chart.hpp) of cases/two-plane.toml's rotor (each plane on a
// sprung ring of its own, then plane 2's ring fixed, then both rings fixed), checked against the
// model's own contact kinematics (embedded states lie on every closed contact's constraint, at
// velocity level too, and roll in stick), its own inverse (chart after embed), finite
// differences of the embedding along a motion (reduce), and the rules of when it composes.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "rubdyn/contact/ring_chart.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "support/fixed_rings.hpp"

using namespace rubdyn;

namespace {

using Modes = std::vector<Phase>;

const std::vector<Modes> kModes = {
    {Phase::SlipNeg, Phase::Free},    {Phase::Free, Phase::SlipPos},
    {Phase::SlipNeg, Phase::SlipPos}, {Phase::Stick, Phase::SlipNeg},
    {Phase::SlipPos, Phase::Stick},   {Phase::Stick, Phase::Stick},
    {Phase::Free, Phase::Stick},
};

/// The three variants of the two-plane rotor: each ring sprung (9 coordinates), plane 2's ring
/// fixed (7), both fixed (5).
struct Variant {
  const char* name;
  bool fixed1, fixed2;
};
const Variant kVariants[] = {{"sprung rings", false, false},
                             {"plane 2 on a fixed ring", false, true},
                             {"both planes on fixed rings", true, true}};

struct Fixture {
  explicit Fixture(const Variant& v)
      : spec(parse_case(rubdyn::testing::two_plane_fixed_rings_text(v.fixed1, v.fixed2),
                        "two-plane.toml")),
        model(build_model(spec)),
        chart(*model->ring_chart()) {}
  CaseSpec spec;
  std::unique_ptr<LagrangianModel> model;
  const RingChart& chart;
  static constexpr int kSpin = 4;  // theta in the model's coordinates
  std::mt19937_64 rng{77};
  double u() { return std::uniform_real_distribution<double>(-1.0, 1.0)(rng); }
  /// The reduced coordinate that is the spin (theta - theta0 in stick): found by embedding unit
  /// vectors, so that the test does not restate the chart's layout.
  int spin_index(const Modes& modes) const {
    const int d = chart.dim(modes), n = model->num_dofs();
    Vec q(n), v(n);
    RingAnchor anchor;
    for (int j = 0; j < d; ++j) {
      Vec p = Vec::Zero(d), pd = Vec::Zero(d);
      pd[j] = 1.0;
      chart.embed(modes, anchor, 0.0, p, pd, q, v);
      if (v[kSpin] == 1.0) return j;
    }
    return -1;
  }
  /// Random reduced coordinates and rates of `modes` at the scale of the case: positions of
  /// the gap's order, speeds of 0.1 m/s, the spin near 2000 rad/s, angles anywhere.
  void random_state(const Modes& modes, Vec& p, Vec& pd, RingAnchor& anchor) {
    const int d = chart.dim(modes);
    const int js = spin_index(modes);
    REQUIRE(js >= 0);
    p.resize(d);
    pd.resize(d);
    std::vector<double> L(static_cast<std::size_t>(d));
    chart.lengths(modes, L);
    const bool stick = std::count(modes.begin(), modes.end(), Phase::Stick) > 0;
    for (int j = 0; j < d; ++j) {
      p[j] = 1e-4 * u();
      pd[j] = 0.1 * u();
    }
    p[js] = stick ? 0.3 * u() : 50.0 * u();
    pd[js] = 2000.0 + 100.0 * u();
    for (int j = 0; j < d; ++j)
      if (L[static_cast<std::size_t>(j)] > 0.0 && j != js) {  // phi_k
        p[j] = 3.0 * u();
        pd[j] = 500.0 * u();
      }
    anchor.theta0 = 40.0 * u();
    for (double& a : anchor.phi0) a = 3.0 * u();
  }
};

}  // namespace

TEST_CASE(
    "Ring chart: embedded states lie on the closed contacts' constraints, and chart "
    "inverts embed",
    "[model][chart]") {
  for (const Variant& var : kVariants) {
    Fixture f(var);
    INFO(var.name);
    REQUIRE(f.model->ring_chart() != nullptr);
    const int n = f.model->num_dofs();
    ContactKinematics c(n);
    for (const Modes& modes : kModes) {
      REQUIRE(f.chart.applies(modes));
      int removed = 0;
      for (Phase p : modes) removed += p == Phase::Free ? 0 : (p == Phase::Stick ? 2 : 1);
      CHECK(f.chart.dim(modes) == n - removed);
      for (int trial = 0; trial < 50; ++trial) {
        Vec p, pd, q(n), v(n);
        RingAnchor anchor;
        f.random_state(modes, p, pd, anchor);
        f.chart.embed(modes, anchor, 0.0, p, pd, q, v);
        for (int k = 0; k < 2; ++k) {
          const Phase mk = modes[static_cast<std::size_t>(k)];
          if (mk == Phase::Free) continue;
          f.model->compute_contact(k, 0.0, q, v, c);
          INFO("modes " << to_string(modes[0]) << ", " << to_string(modes[1]) << " contact " << k);
          // d_N = g - |P - S| with |P - S| = g by construction: the round-off of forming P - S
          // from coordinates of 1e-4 m and taking its norm, a few ulps of 1e-4 m (2e-20 m each)
          CHECK(std::abs(c.d_N) < 1e-18);
          // v_N: the same at velocity level, the round-off of the velocities P' - S' is formed
          // from: a few ulps of the fastest of them (0.1 m/s sliding; R omega = 100 m/s where a
          // contact rolls, g phi' = -R theta', which on a fixed ring moves the rotor's
          // coordinates themselves, so that a sliding plane's P' is a difference of them)
          const double rotor_speed = v.head(4).cwiseAbs().maxCoeff();
          const double ring_speed =
              std::max(mk == Phase::Stick ? 0.05 * std::abs(v[Fixture::kSpin]) : 0.2, rotor_speed);
          INFO("v_N " << std::scientific << c.v_N << " v_t " << c.v_t << " speed " << ring_speed);
          CHECK(std::abs(c.v_N) < 1e-14 * ring_speed);
          // rolling: v_t = -g phi' - R theta' = 0, a sum of terms of R omega = 100 m/s
          if (mk == Phase::Stick) CHECK(std::abs(c.v_t) < 1e-14 * ring_speed);
        }
        // chart of the embedded state, embedded again: the same state (the anchor is re-taken)
        Vec p2(p.size()), pd2(pd.size()), q2(n), v2(n);
        RingAnchor a2;
        f.chart.chart(modes, 0.0, q, v, a2, p2, pd2);
        f.chart.embed(modes, a2, 0.0, p2, pd2, q2, v2);
        // positions of 1e-4 m and the spin of up to 60 rad: atan2 and cos/sin of the angles
        // recover the ring to a few ulps of the spin's size times R / g for rolling angles
        CHECK((q2 - q).cwiseAbs().maxCoeff() < 1e-12 * (1.0 + std::abs(q[Fixture::kSpin])));
        CHECK((v2 - v).cwiseAbs().maxCoeff() < 1e-10);
      }
    }
  }
}

TEST_CASE("Ring chart: reduce is the second derivative of the embedding along a motion",
          "[model][chart]") {
  // p(t) = p0 + pd0 t + pdd0 t^2 / 2 embedded at t = +-h: the central difference of the embedded
  // velocities is the full acceleration a, which satisfies the constraints at acceleration level
  // by construction; reduce(q(0), a) must give back pdd0. Error of the difference: O(h^2)
  // relative (h = 1e-7 s against the fastest angle's period, 2 pi / 500 rad/s: 1e-8) plus the
  // round-off of velocities of 100 m/s differenced over 2h (1e-14 * 100 / 2e-7 = 5e-6 of
  // accelerations of 1e4 .. 1e6): 1e-4 relative to the largest pdd bounds both.
  for (const Variant& var : kVariants) {
    Fixture f(var);
    INFO(var.name);
    const int n = f.model->num_dofs();
    const double h = 1e-7;
    for (const Modes& modes : kModes) {
      for (int trial = 0; trial < 20; ++trial) {
        Vec p, pd;
        RingAnchor anchor;
        f.random_state(modes, p, pd, anchor);
        const int d = static_cast<int>(p.size());
        Vec pdd(d);
        for (int j = 0; j < d; ++j) pdd[j] = 1e4 * f.u();
        Vec q0(n), v0(n), qp(n), vp(n), qm(n), vm(n);
        f.chart.embed(modes, anchor, 0.0, p, pd, q0, v0);
        const Vec pp = p + pd * h + 0.5 * h * h * pdd, pm = p - pd * h + 0.5 * h * h * pdd;
        const Vec pdp = pd + h * pdd, pdm = pd - h * pdd;
        f.chart.embed(modes, anchor, 0.0, pp, pdp, qp, vp);
        f.chart.embed(modes, anchor, 0.0, pm, pdm, qm, vm);
        const Vec a = (vp - vm) / (2.0 * h);
        Vec back(d);
        f.chart.reduce(modes, q0, a, back);
        INFO("modes " << to_string(modes[0]) << ", " << to_string(modes[1]));
        CHECK((back - pdd).cwiseAbs().maxCoeff() < 1e-4 * pdd.cwiseAbs().maxCoeff());
      }
    }
  }
}

TEST_CASE(
    "Ring chart: composes where every closed contact has a sprung ring of its own or a fixed "
    "ring whose equations have full rank",
    "[model][chart]") {
  // three contacts of a 9-coordinate model: 0 and 1 on rings at 5 and 7, 2 on a fixed ring;
  // the rotor's points at (2, 3) (and (0, 1) with weights for contact 1); spin at 4
  std::vector<RingContact> rc(3);
  rc[0].ix = {2, -1};
  rc[0].iy = {3, -1};
  rc[0].w = {1.0, 0.0};
  rc[0].ring = 5;
  rc[0].gap = 2e-4;
  rc[0].radius = 0.05;
  rc[1] = rc[0];
  rc[1].ix = {0, 2};
  rc[1].iy = {1, 3};
  rc[1].w = {0.5, 0.5};
  rc[1].ring = 7;
  rc[2] = rc[0];
  rc[2].ring = -1;
  const RingChart chart(9, 4, rc);
  using P = Phase;
  CHECK(chart.applies(Modes{P::SlipPos, P::Stick, P::Free}));
  CHECK_FALSE(chart.applies(Modes{P::Free, P::Free, P::Free}));  // nothing to chart
  // a fixed ring (contact 2) solved for the rotor point's (2, 3), then contact 0's ring at 5
  // from that point: they compose
  CHECK(chart.applies(Modes{P::SlipPos, P::Free, P::Stick}));
  CHECK(chart.dim(Modes{P::SlipPos, P::Free, P::Stick}) == 9 - 1 - 2);
  CHECK(chart.applies(Modes{P::Free, P::SlipPos, P::SlipNeg}));  // rows (0.5, 0.5) and (0, 1)
  // two fixed rings at the same rotor point: two equations for one coordinate (x and y each)
  std::vector<RingContact> twice = {rc[0], rc[2], rc[2]};
  const RingChart over(9, 4, twice);
  CHECK(over.applies(Modes{P::SlipPos, P::SlipPos, P::Free}));
  CHECK_FALSE(over.applies(Modes{P::Free, P::SlipPos, P::SlipPos}));
  // two fixed rings whose points are proportional (weights 0.5, 0.5 and 1, 1 on the same
  // coordinates): rank 1, refused
  std::vector<RingContact> prop = {rc[1], rc[1]};
  prop[0].ring = prop[1].ring = -1;
  prop[1].w = {1.0, 1.0};
  const RingChart dependent(9, 4, prop);
  CHECK(dependent.applies(Modes{P::SlipPos, P::Free}));
  CHECK_FALSE(dependent.applies(Modes{P::SlipPos, P::Stick}));
  // a fixed ring whose point's y is another fixed ring's x coordinate: one coordinate would be
  // eliminated twice
  std::vector<RingContact> crossed = {rc[2], rc[2]};
  crossed[1].ix = {3, -1};
  crossed[1].iy = {2, -1};
  const RingChart cross(9, 4, crossed);
  CHECK(cross.applies(Modes{P::SlipPos, P::Free}));
  CHECK_FALSE(cross.applies(Modes{P::SlipPos, P::SlipPos}));
  // a ring shared by two contacts (a split of one body's constraint): not when both are closed
  std::vector<RingContact> shared = {rc[0], rc[1]};
  shared[1].ring = 5;
  const RingChart one_ring(9, 4, shared);
  CHECK(one_ring.applies(Modes{P::SlipPos, P::Free}));
  CHECK_FALSE(one_ring.applies(Modes{P::SlipPos, P::SlipNeg}));
  CHECK_FALSE(one_ring.applies(Modes{P::Free, P::SlipNeg}));  // its ring is contact 0's
  // no spin coordinate and no prescribed spin: slip composes, stick does not (nothing says how
  // the contact rolls); with a prescribed spin, stick composes too (test_prescribed_planes.cpp)
  const RingChart no_spin(9, -1, {rc[0], rc[1]});
  CHECK(no_spin.applies(Modes{P::SlipPos, P::SlipNeg}));
  CHECK_FALSE(no_spin.applies(Modes{P::Stick, P::Free}));
  const RingChart prescribed(9, -1, {rc[0], rc[1]}, SpinLaw{0.0, 0.0, 300.0, 0.0});
  CHECK(prescribed.applies(Modes{P::Stick, P::Free}));
  CHECK(prescribed.dim(Modes{P::Stick, P::SlipPos}) == 9 - 2 - 1);
  // a rotor point that moves with another closed contact's ring
  std::vector<RingContact> chained = {rc[0], rc[1]};
  chained[1].ix = {5, -1};
  chained[1].iy = {6, -1};
  const RingChart chain(9, 4, chained);
  CHECK(chain.applies(Modes{P::Free, P::SlipPos}));
  CHECK_FALSE(chain.applies(Modes{P::SlipPos, P::SlipPos}));
}
