// Hot paths allocate nothing on the matrices model (model/matrix_model.hpp): its structured
// mass solve (the Schur complement on theta, M factored once) and its forces use no workspace
// but thread-local scratch sized at a thread's first call. The paper's rotor written as matrices in
// code, resting at the bottom of the clearance (a contact phase for the whole run, both
// formulations) and spinning freely with an unbalance (free flight), through every solver: a run
// twice as long, with no event in the extra time, must allocate the same number of times
// (test_no_allocation.cpp's method).
#include <catch2/catch.hpp>

#include "alloc/run_allocations.hpp"
#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/solver_options.hpp"
#include "rubdyn/model/matrix_model.hpp"
#include "rubdyn/stepping/fixed_step.hpp"

using namespace rubdyn;
using namespace rubdyn::testing;

namespace {

/// The paper's rotor (rotor_stator_model.hpp's formulas, the reference parameters) as matrices.
MatrixParams paper_matrices(double g) {
  const double m = 5.0, Jd = 0.035, l = 0.4, nu = 0.3 / l, jl = Jd / (l * l), H = 0.06 / (l * l);
  const double M11 = (1 - nu) * (1 - nu) * m + jl, M12 = nu * (1 - nu) * m - jl,
               M22 = nu * nu * m + jl;
  MatrixParams p;
  auto& r = p.rotor;
  r.M.setZero(4, 4);
  r.M(0, 0) = r.M(1, 1) = M11;
  r.M(2, 2) = r.M(3, 3) = M22;
  r.M(0, 2) = r.M(2, 0) = r.M(1, 3) = r.M(3, 1) = M12;
  r.G.setZero(4, 4);
  r.G(0, 1) = H, r.G(0, 3) = -H, r.G(1, 2) = H, r.G(2, 3) = H;
  r.G = Mat(r.G - r.G.transpose());
  r.C = Vec(Eigen::Vector4d(300, 300, 0, 0)).asDiagonal();
  r.K = Vec(Eigen::Vector4d(5e6, 5e6, 0, 0)).asDiagonal();
  r.f0 = Vec(Eigen::Vector4d(0, -(1 - nu) * m * g, 0, -nu * m * g));
  r.Jp = 0.06;
  p.node = {2, 3, 0.05, 2e-4};
  p.loads.gravity = 0.0;
  return p;
}

}  // namespace

TEST_CASE("No allocation per step: the matrices model at rest on the stator and spinning free",
          "[alloc]") {
  // (1) resting at the bottom of the clearance, frictionless, no spin: a contact phase
  MatrixParams p = paper_matrices(9.81);
  p.contact.mu = 0.0;
  p.loads.torque = 0.0;
  const MatrixModel rest(p);
  const double nu = 0.75, mg = 5.0 * 9.81;
  MechanicalState s0(rest.num_dofs());
  s0.q[1] = -(1 - nu) * mg / 5e6;
  s0.q[6] = -nu * mg / 2e6;
  s0.q[3] = s0.q[6] - 2e-4;
  for (auto formulation : {ContactFormulation::Reduced, ContactFormulation::Projection})
    event_allocations(rest, s0, event_options(1e-4, formulation), 0.01, 0.02);
  // (mj-proj leaves and re-enters this resting contact at round-off, 553 events in 10 ms, with
  // as many allocations either way; it is counted in free flight below)
  fixed_step_allocations(
      rest, s0, {FixedStepScheme::CarpOneVC, FixedStepScheme::CarpQN, FixedStepScheme::MoreauJean},
      step_options(1e-5), 0.01, 0.02);
  // (2) no weight, spinning at 2000 rad/s with a small unbalance at the node: free flight
  MatrixParams q = paper_matrices(0.0);
  q.loads.unbalance = 1e-6;
  const MatrixModel spin(q);
  MechanicalState s1(spin.num_dofs());
  s1.v[4] = 2000.0;
  event_allocations(spin, s1, event_options(), 0.01, 0.02);
  // and by BDF: the structured Newton systems (phase_session.cpp, lsys_free) factor in place
  EventDrivenOptions bdf = event_options();
  bdf.method = MultistepMethod::BDF;
  event_allocations(spin, s1, bdf, 0.01, 0.02);
  fixed_step_allocations(spin, s1, kEveryScheme, step_options(1e-5), 0.01, 0.02);
}

TEST_CASE("No allocation per step: the FE run-up's slip phase in minimal coordinates by BDF",
          "[alloc]") {
  // cases/fe-runup.toml's seal slides from 0.1535 s to the end: its Reduced session's
  // structured Newton systems (phase_session.cpp, lsys_reduced, lsolve_reduced) lift through
  // the ring chart, solve and reduce in place at every Newton iteration from 0.17 to 0.19 s
  const CaseSpec c = load_case(RUBDYN_SOURCE_DIR "/cases/fe-runup.toml");
  const auto m = build_model(c);
  EventDrivenOptions o = event_driven_options(c);
  o.contact_phases = ContactFormulation::Reduced;
  event_allocations(*m, initial_state(c), o, 0.17, 0.19);
}

TEST_CASE("No allocation per sample: the FE run-up's modal amplitudes (output.modes)", "[alloc]") {
  // cases/fe-runup.toml with output.modes = 4 (the prescribed spin forwards its matrices model's
  // mode1..4, vmode1..4): every output sample of the free flight before the first impact
  // (0.107 s) computes them by the columns of M Phi made once, nothing allocated per sample
  CaseSpec c = load_case(RUBDYN_SOURCE_DIR "/cases/fe-runup.toml");
  c.matrices.output_modes = 4;
  const auto m = build_model(c);
  REQUIRE(m->observables().size() == 3 + 8);
  event_allocations(*m, initial_state(c), event_driven_options(c), 0.03, 0.05);
}
