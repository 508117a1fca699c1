// The single-contact problem: mode selection (incl. Painleve situations) and the impact map, on
// constructed states where the answer is known by hand.
#include <catch2/catch.hpp>

#include "rubdyn/hybrid/contact_problem.hpp"
#include "rubdyn/hybrid/event_driven.hpp"
#include "support/problems.hpp"

using namespace rubdyn;

namespace {
// Two coupled dofs (x, y) with mass matrix [[1, c], [c, 1]], the plane y >= 0, tangent x, and a
// normal load P on y. Then A_NN = 1/(1-c^2), A_NT = -c/(1-c^2), b_N = (P - c Fx)/(1-c^2) with no
// tangential load: the slip normal mass A_NN - mu s A_NT = (1 + mu s c)/(1-c^2) is <= 0 when
// mu s c <= -1: the Painleve situation of a sliding contact with inertial coupling.
class CoupledBlock final : public rubdyn::testing::PlaneModel {
 public:
  CoupledBlock(double mu, double c, double P) : PlaneModel({mu, 0.0, 0.0}, 1.0), c_(c), P_(P) {}
  std::string_view name() const override { return "coupled-block"; }
  void mass_matrix(VecIn, MatOut M) const override {
    M.setIdentity();
    M(0, 1) = M(1, 0) = c_;
  }
  // the base class's mass solve, product and kinetic energy are those of m I: the general ones
  void mass_product(VecIn q, VecIn x, VecOut y) const override {
    LagrangianModel::mass_product(q, x, y);
  }
  void solve_mass(VecIn q, MatOut B) const override { LagrangianModel::solve_mass(q, B); }
  double kinetic_energy(double t, VecIn q, VecIn v) const override {
    return LagrangianModel::kinetic_energy(t, q, v);
  }
  void smooth_forces(double, VecIn, VecIn, VecOut f) const override {
    f.setZero();
    f[1] = P_;
  }
  void smooth_force_jacobians(double, VecIn, VecIn, MatOut a, MatOut b) const override {
    a.setZero();
    b.setZero();
  }
  double potential_energy(double, VecIn q) const override { return -P_ * q[1]; }
  SmoothPower smooth_power(double, VecIn, VecIn) const override { return {}; }

 private:
  double c_, P_;
};

ContactOperators ops(const LagrangianModel& m, double vx, double vy = 0.0) {
  Vec q = Vec::Zero(2), v = Vec::Zero(2);
  v[0] = vx;
  v[1] = vy;
  ContactOperators op(2);
  compute_contact_operators(m, 0.0, q, v, op);
  return op;
}
}  // namespace

TEST_CASE("Mode selection: regular sliding - sticking and lift-off", "[contact]") {
  // c = 0: no coupling. Pressed (P = -1): slip in the direction of v_t, F_N = 1, F_T = -mu s.
  const CoupledBlock pressed(0.5, 0.0, -1.0);
  auto d = select_mode(ops(pressed, -2.0), 0.5, 1e-9);
  REQUIRE(d.phase == Phase::SlipNeg);
  REQUIRE_FALSE(d.painleve);
  REQUIRE(d.dyn.F_N == Approx(1.0));
  REQUIRE(d.dyn.F_T == Approx(0.5));
  // at rest: stick with F_T = 0 (no tangential load)
  d = select_mode(ops(pressed, 0.0), 0.5, 1e-9);
  REQUIRE(d.phase == Phase::Stick);
  REQUIRE(d.dyn.F_N == Approx(1.0));
  REQUIRE(d.dyn.F_T == Approx(0.0).margin(1e-15));
  // pulled away (P = +1): free
  const CoupledBlock pulled(0.5, 0.0, 1.0);
  d = select_mode(ops(pulled, -2.0), 0.5, 1e-9);
  REQUIRE(d.phase == Phase::Free);
  REQUIRE_FALSE(d.painleve);
  // mu = 0: one contact mode, no stick
  const CoupledBlock frictionless(0.0, 0.3, -1.0);
  d = select_mode(ops(frictionless, 0.0), 0.0, 1e-9);
  REQUIRE(d.phase != Phase::Stick);
  REQUIRE(d.phase != Phase::Free);
  REQUIRE(d.dyn.F_T == 0.0);
}

TEST_CASE("Painleve situations are detected: inconsistency and non-uniqueness", "[contact]") {
  const double mu = 2.0, c = 0.8;  // s = -1 (v_t < 0): mu s c = -1.6 <= -1
  {
    // pressed into the plane: free is inconsistent (b_N < 0); slip needs F_N = -b_N / mass
    // with mass < 0: F_N < 0, inconsistent too. No solution.
    const CoupledBlock m(mu, c, -1.0);
    const auto op = ops(m, -1.0);
    REQUIRE(op.A_NN - mu * (-1.0) * op.A_NT < 0.0);
    const auto d = select_mode(op, mu, 1e-9);
    REQUIRE(d.painleve);
    REQUIRE(d.n_consistent == 0);
  }
  {
    // pulled away: free is consistent, and slip too (F_N = -b_N / mass > 0): two solutions.
    const CoupledBlock m(mu, c, 1.0);
    const auto d = select_mode(ops(m, -1.0), mu, 1e-9);
    REQUIRE(d.painleve);
    REQUIRE(d.n_consistent == 2);
    REQUIRE(d.phase == Phase::Free);  // the documented rule: least force
  }
  {
    // the same coupling with mu = 0.5 is well posed: unique slip
    const CoupledBlock m(0.5, c, -1.0);
    const auto d = select_mode(ops(m, -1.0), 0.5, 1e-9);
    REQUIRE_FALSE(d.painleve);
    REQUIRE(d.phase == Phase::SlipNeg);
  }
}

TEST_CASE("An inconsistent Painleve contact ends the run with a typed termination", "[contact]") {
  const CoupledBlock m(2.0, 0.8, -1.0);
  MechanicalState s0(2);
  s0.v[0] = -1.0;  // on the plane, sliding
  MemorySink sink;
  EventDrivenOptions opt;
  const RunSummary s = run_event_driven(m, s0, 0.1, opt, sink);
  REQUIRE(s.termination == Termination::Painleve);
  REQUIRE_FALSE(s.message.empty());
  REQUIRE(s.events[static_cast<int>(EventKind::Painleve)] == 1);
  REQUIRE(sink.summary.termination == Termination::Painleve);  // the sink got the summary
}

TEST_CASE("Impact map: Newton restitution and Coulomb impulse", "[contact]") {
  // c = 0, unit masses: A = identity. Incoming v = (vx, -1).
  const CoupledBlock m(0.5, 0.0, 0.0);
  ContactLaw law{0.5, 0.5, 0.0};
  {
    // small tangential speed: sticking impulse, P_T = -vx (v_t+ = 0), P_N = 1.5
    const auto op = ops(m, 0.2, -1.0);
    const auto r = impact_map(op, Vec((Vec(2) << 0.2, -1).finished()), law);
    REQUIRE(r.sticking);
    REQUIRE(r.P_N == Approx(1.5));
    REQUIRE(r.P_T == Approx(-0.2));
    REQUIRE(r.v_plus[1] == Approx(0.5));
    REQUIRE(r.v_plus[0] == Approx(0.0).margin(1e-15));
  }
  {
    // large tangential speed: sliding impulse P_T = -mu P_N
    Vec v = Vec::Zero(2);
    v[0] = 3.0;
    v[1] = -1.0;
    const auto op = ops(m, 3.0, -1.0);
    const auto r = impact_map(op, v, law);
    REQUIRE_FALSE(r.sticking);
    REQUIRE(r.P_N == Approx(1.5));
    REQUIRE(r.P_T == Approx(-0.75));
    REQUIRE(r.v_plus[0] == Approx(2.25));
  }
}
