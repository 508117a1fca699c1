// The event solver's multistep method chosen by the model's stiffness (solver.method = "auto",
// hybrid/method_choice.hpp): the time scales against the Jeffcott rotor's closed forms, the
// verdict on each side of the threshold, and the run that follows it; the contact phases'
// formulation chosen by the Newton systems' structure (solver.contact_phases = "auto").
#include <catch2/catch.hpp>
#include <cmath>

#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/hybrid/method_choice.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/model/jeffcott_model.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"

using namespace rubdyn;

namespace {

/// A Jeffcott rotor whose free flight has the closed-form time scales sqrt(k_r / m_r) = 1000 and
/// sqrt(k_s / m_s) rad/s, damping rates c_r / m_r = 60 and c_s / m_s = 50 1/s (no coupling
/// between rotor and ring without contact; the spin is not a vibration).
JeffcottParams scene(double stator_omega) {
  JeffcottParams p;
  p.rotor.mass = 5.0;
  p.rotor.k = 5.0e6;
  p.rotor.c = 300.0;
  p.stator.mass = 2.0;
  p.stator.k = 2.0 * stator_omega * stator_omega;
  p.stator.c = 100.0;
  p.loads.unbalance = 1e-4;  // the spin angle then has a small stiffness under gravity: left out
  p.loads.gravity = 9.81;
  return p;
}

MechanicalState spinning(const LagrangianModel& m) {
  MechanicalState s(m.num_dofs());
  s.v[JeffcottModel::TH] = 800.0;
  return s;
}

}  // namespace

TEST_CASE("Method choice: the Jeffcott rotor's time scales are its closed forms, the spin left out",
          "[events][method]") {
  const JeffcottModel m(scene(2000.0));
  const MechanicalState s = spinning(m);
  const StiffnessAssessment a = assess_stiffness(m, s.t, s.q, s.v);
  // The generalised symmetric eigensolver's error is a few eps of the largest eigenvalue
  // (omega^2 = 4e6): 1e-12 relative on the frequencies is far above it and far below any
  // mistake in what enters the matrices (a missed mass or stiffness changes them by O(1)).
  CHECK(a.omega_max == Approx(2000.0).epsilon(1e-12));
  CHECK(a.omega_min == Approx(1000.0).epsilon(1e-12));
  CHECK(a.decay_max == Approx(60.0).epsilon(1e-12));
  CHECK(a.ratio == Approx(2.0).epsilon(1e-12));
  CHECK_FALSE(a.stiff);
  CHECK(a.reason().find("ratio 2 <= 100") != std::string::npos);
}

TEST_CASE("Method choice: a ring 200 times faster than the rotor is stiff, 50 times is not",
          "[events][method]") {
  for (const double factor : {50.0, 200.0}) {
    const JeffcottModel m(scene(1000.0 * factor));
    const MechanicalState s = spinning(m);
    const StiffnessAssessment a = assess_stiffness(m, s.t, s.q, s.v);
    INFO("factor " << factor << ": " << a.reason());
    CHECK(a.ratio == Approx(factor).epsilon(1e-12));
    CHECK(a.stiff == (factor > kStiffRatio));
  }
}

TEST_CASE("Method choice: auto runs Adams on a soft model bit for bit, BDF on a stiff one",
          "[events][method]") {
  const auto run = [](const JeffcottModel& m, MultistepMethod method) {
    EventDrivenOptions opt;
    opt.rtol = 1e-8;
    opt.atol = 1e-12;
    opt.method = method;
    opt.contact_method = method;
    MemorySink sink;
    run_event_driven(m, spinning(m), 0.01, opt, sink);
    REQUIRE(sink.summary.complete());
    return sink;
  };
  SECTION("soft: the same bits as Adams given") {
    const JeffcottModel m(scene(2000.0));
    const MemorySink a = run(m, MultistepMethod::Auto), b = run(m, MultistepMethod::Adams);
    CHECK(a.summary.options.find("\"free_flight\": \"adams\"") != std::string::npos);
    CHECK(a.summary.options.find("free flight auto, contact phases auto") != std::string::npos);
    CHECK(b.summary.options.find("free flight given, contact phases given") != std::string::npos);
    REQUIRE(a.samples.size() == b.samples.size());
    for (std::size_t i = 0; i < a.samples.size(); ++i) {
      INFO("sample " << i);
      REQUIRE(a.samples[i].t == b.samples[i].t);
      REQUIRE(a.samples[i].q == b.samples[i].q);
      REQUIRE(a.samples[i].v == b.samples[i].v);
    }
  }
  SECTION("stiff: BDF, the same bits as BDF given, and fewer steps than Adams") {
    const JeffcottModel m(scene(1000.0 * 300.0));
    const MemorySink a = run(m, MultistepMethod::Auto), b = run(m, MultistepMethod::BDF),
                     c = run(m, MultistepMethod::Adams);
    CHECK(a.summary.options.find("\"free_flight\": \"bdf\"") != std::string::npos);
    CHECK(a.summary.options.find("ratio 300 > 100") != std::string::npos);
    REQUIRE(a.samples.size() == b.samples.size());
    for (std::size_t i = 0; i < a.samples.size(); ++i) {
      INFO("sample " << i);
      REQUIRE(a.samples[i].q == b.samples[i].q);
      REQUIRE(a.samples[i].v == b.samples[i].v);
    }
    // the reason for the choice: Adams' step is bounded by the ring's 3e5 rad/s
    CHECK(a.summary.steps < c.summary.steps);
  }
}

TEST_CASE("Contact formulation: auto charts every model, a banded stiff FE rotor too",
          "[events][method]") {
  // cases/fe-two-seal.toml: a 12-element shaft (52 coordinates, 4 per node), the spin, two
  // rings: half-bandwidth 7 (a node's 4 coordinates and its neighbour's) besides the spin
  const CaseSpec fe = load_case(std::string(RUBDYN_SOURCE_DIR) + "/cases/fe-two-seal.toml", {});
  const auto fe_model = build_model(fe);
  const MechanicalState fe_init = initial_state(fe);
  const NewtonStructure ns = assess_newton_structure(*fe_model, fe_init.t, fe_init.q, fe_init.v);
  INFO(ns.reason());
  CHECK(ns.n == 57);
  CHECK(ns.kl == 7);
  CHECK(ns.ku == 7);
  CHECK(ns.banded);
  // the paper's rotor: 7 coordinates, dense by the flop count
  const RotorStatorModel rigid(RotorStatorParams{});
  const MechanicalState rs(rigid.num_dofs());
  CHECK_FALSE(assess_newton_structure(rigid, 0.0, rs.q, rs.v).banded);

  const auto options = [](const LagrangianModel& m, const MechanicalState& s,
                          ContactFormulation f) {
    EventDrivenOptions opt;
    opt.rtol = 1e-8;
    opt.atol = 1e-13;
    opt.contact_phases = f;
    MemorySink sink;
    run_event_driven(m, s, 1e-3, opt, sink);
    REQUIRE(sink.summary.complete());
    return sink.summary.options;
  };
  // minimal coordinates, their Newton systems banded (the structured solve: docs/fe-rotors.md
  // section 10); where the ring chart does not apply (a rank-deficient set of closed rings),
  // the projected DAE
  const std::string fe_auto = options(*fe_model, fe_init, ContactFormulation::Auto);
  CHECK(fe_auto.find("\"contact_phases\": \"reduced+bdf") != std::string::npos);
  CHECK(fe_auto.find("\"formulation\": \"auto: reduced (Newton systems of 57 coordinates, "
                     "half-bandwidths 7/7 besides the spin: banded)") != std::string::npos);
  // given, it is used as given
  CHECK(options(*fe_model, fe_init, ContactFormulation::Projection).find("bdf+projection") !=
        std::string::npos);
  // a stiff model with dense Newton systems keeps minimal coordinates (BDF in them)
  const JeffcottModel stiff(scene(1000.0 * 300.0));
  const std::string j = options(stiff, spinning(stiff), ContactFormulation::Auto);
  CHECK(j.find("reduced+bdf") != std::string::npos);
  CHECK(j.find("auto: reduced") != std::string::npos);
  // a soft one (Adams in contact) is not assessed: minimal coordinates, as before
  const JeffcottModel soft(scene(2000.0));
  const std::string k = options(soft, spinning(soft), ContactFormulation::Auto);
  CHECK(k.find("reduced+adams") != std::string::npos);
  CHECK(k.find("formulation") == std::string::npos);
}
