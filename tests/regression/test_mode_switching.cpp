// Mode switching on ordinary scenes: each of these once ended early (solver failure at t = 0,
// chattering between a mode and itself). They must complete with valid invariants.
#include <catch2/catch.hpp>
#include <cmath>
#include <sstream>

#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"

using namespace rubdyn;

namespace {

struct Scene {
  const char* name;
  RotorStatorParams p;
  MechanicalState s0 = MechanicalState(RotorStatorModel::kDofs);
  double t_end;
};

RunSummary run_scene(const Scene& sc, MemorySink& sink) {
  const RotorStatorModel model(sc.p);
  EventDrivenOptions opt;
  opt.omega_lim = 2110.0;
  return run_event_driven(model, sc.s0, sc.t_end, opt, sink);
}

void check_invariants(const Scene& sc, const RunSummary& s) {
  const double g0 = sc.p.stator.gap;
  INFO(sc.name << ": " << s.message);
  REQUIRE(s.complete());
  // positions resolved to atol = 1e-12 m; contact phases hold d_N = 0 to round-off
  CHECK(s.max_penetration <= 1e-9 * g0);
  if (!std::isnan(s.min_F_N_in_contact)) CHECK(s.min_F_N_in_contact >= 0.0);
  CHECK(s.max_cone_violation <= 1e-9);
  // The works are integrated with the state to rtol 1e-10 and atol 1e-9 J; these scenes have
  // flows from 1e-2 J (a rotor at rest settling) to 1e3 J (the driven rotor).
  const double flow = std::max({std::abs(s.work_torque), std::abs(s.work_damping),
                                std::abs(s.work_friction), std::abs(s.work_impacts)});
  INFO("energy residual " << s.energy_residual << " J, largest flow " << flow << " J");
  CHECK(std::abs(s.energy_residual) <= 1e-8 * flow + 1e-7);
  // no event loops at one instant
  CHECK(s.events[static_cast<int>(EventKind::Painleve)] == 0);
}

}  // namespace

TEST_CASE("Starting on the stator with a velocity into it: an impact at t = 0, then the run",
          "[events][rotor][regression]") {
  // Today's failure: the impact at t = 0 read the works from an integrator that had not stepped
  // yet (NaN), and CVODE refused the next phase.
  std::vector<Scene> scenes;
  auto touching = [](const char* name, double vy, double mu, double e_n, bool along_x) {
    Scene sc{name, {}, MechanicalState(RotorStatorModel::kDofs), 0.02};
    sc.p.contact.mu = mu;
    sc.p.contact.e_n = e_n;
    sc.s0.v[TH] = 2000.0;
    const int pos = along_x ? XR : YR;
    sc.s0.q[pos] = -sc.p.stator.gap;
    sc.s0.v[pos] = vy;
    return sc;
  };
  scenes.push_back(touching("y_r = -g0, vy_r = -1", -1.0, 0.1, 0.0, false));
  scenes.push_back(touching("y_r = -g0, vy_r = -0.01", -0.01, 0.1, 0.0, false));
  scenes.push_back(touching("y_r = -g0, vy_r = -1, mu = 0", -1.0, 0.0, 0.0, false));
  scenes.push_back(touching("y_r = -g0, vy_r = -1, e_n = 0.5", -1.0, 0.1, 0.5, false));
  scenes.push_back(touching("x_r = -g0, vx_r = -1", -1.0, 0.1, 0.0, true));
  for (const Scene& sc : scenes) {
    MemorySink sink;
    const RunSummary s = run_scene(sc, sink);
    check_invariants(sc, s);
    REQUIRE(!sink.events.empty());
    CHECK(sink.events.front().t == 0.0);
    CHECK((sink.events.front().kind == EventKind::Impact ||
           sink.events.front().kind == EventKind::Zeno));
  }
}

TEST_CASE("A rotor at rest falls onto the stator and settles: no loop at the lift-off",
          "[events][rotor][regression]") {
  // Today's failure: at 0.012 s the stator pushes the rotor back; F_N and the cone margin
  // vanish together and the mode selection restarted the ending phase (stick -> stick, slip ->
  // slip) 20 times at one instant.
  std::vector<Scene> scenes;
  auto at_rest = [](const char* name, double mu, double e_n, bool damping) {
    Scene sc{name, {}, MechanicalState(RotorStatorModel::kDofs), 0.1};
    sc.p.contact.mu = mu;
    sc.p.contact.e_n = e_n;
    sc.p.loads.torque = 0.0;
    if (!damping) sc.p.bearing.c = sc.p.stator.c = 0.0;
    return sc;
  };
  scenes.push_back(at_rest("mu = 0.1", 0.1, 0.0, true));
  scenes.push_back(at_rest("mu = 0", 0.0, 0.0, true));
  scenes.push_back(at_rest("e_n = 0.5", 0.1, 0.5, true));
  scenes.push_back(at_rest("no damping", 0.1, 0.0, false));
  for (const Scene& sc : scenes) {
    MemorySink sink;
    const RunSummary s = run_scene(sc, sink);
    check_invariants(sc, s);
    // the contact does open again after the first landing (the stator's spring returns)
    CHECK(s.events[static_cast<int>(EventKind::Liftoff)] >= 1);
    for (size_t k = 1; k < sink.events.size(); ++k) {
      INFO(sc.name << ": events " << k - 1 << " and " << k);
      CHECK(sink.events[k].t > sink.events[k - 1].t);
    }
  }
}

TEST_CASE("A very stiff stator (k_s = 1e10 N/m): lift-offs end the slide, no slip -> slip loop",
          "[events][rotor][regression]") {
  Scene sc{"k_s = 1e10", {}, MechanicalState(RotorStatorModel::kDofs), 0.03};
  sc.p.stator.k = 1e10;
  sc.s0.v[TH] = 2000.0;
  MemorySink sink;
  const RunSummary s = run_scene(sc, sink);
  check_invariants(sc, s);
  CHECK(s.events[static_cast<int>(EventKind::Liftoff)] >= 2);
  for (const auto& e : sink.events)
    if (e.kind == EventKind::Liftoff) CHECK(e.phase_after == Phase::Free);
}
