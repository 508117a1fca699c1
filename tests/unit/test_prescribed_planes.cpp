// A prescribed spin on a model with several rub planes (issue 34): the prescribed-spin wrapper
// (model/prescribed_spin.hpp) passes every service of the model it wraps through, in its own
// coordinates. Before, it answered with LagrangianModel's defaults: plane_motion read the
// coordinates' roles, which a [[plane]] between B and R has none of, so that every such run
// exited 0 and then `rubdyn analyze` and the Python plots failed ("plane 2: the model
// 'rigid-rotor' does not locate its centres"); and ring_chart was null, so that the event solver
// integrated every sliding phase with projection.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "rubdyn/analysis/postprocess.hpp"
#include "rubdyn/driver/simulate.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/output_folder.hpp"
#include "rubdyn/io/output_reader.hpp"
#include "rubdyn/model/prescribed_spin.hpp"
#include "support/cli.hpp"

using namespace rubdyn;
using namespace rubdyn::testing;
namespace fs = std::filesystem;

namespace {

/// cases/two-plane.toml with its spin prescribed (the file's torque line replaced).
std::string prescribed_two_plane() {
  std::string s = slurp(RUBDYN_SOURCE_DIR "/cases/two-plane.toml");
  const auto i = s.find("torque  = 20.0");
  REQUIRE(i != std::string::npos);
  s.replace(i, s.find('\n', i) - i, "spin = \"prescribed\"");
  return s;
}

}  // namespace

TEST_CASE("Prescribed spin: the planes' centres and the ring chart of the wrapped model",
          "[unit][planes][prescribed]") {
  const CaseSpec spec = parse_case(prescribed_two_plane(), "two-plane.toml",
                                   {"loads.spin_accel=-3e4", "initial.theta=0.3"});
  const auto model = build_model(spec);
  const auto* ps = dynamic_cast<const PrescribedSpin*>(model.get());
  REQUIRE(ps != nullptr);
  const LagrangianModel& inner = ps->inner();
  const int n = model->num_dofs(), s = inner.spin_coordinate();
  REQUIRE(n + 1 == inner.num_dofs());
  // a state off centre, moving; the wrapped model's centres are the inner model's at the state
  // with theta(t), omega(t) inserted: the same numbers, bit for bit
  const double t = 0.004;
  Vec q(n), v(n);
  for (int i = 0; i < n; ++i) {
    q[i] = 1e-5 * (i + 1) * (i % 2 ? -1.0 : 1.0);
    v[i] = 0.01 * (n - i);
  }
  Vec qf(n + 1), vf(n + 1);
  for (int i = 0, j = 0; j <= n; ++j) {
    qf[j] = j == s ? ps->theta(t) : q[i];
    vf[j] = j == s ? ps->omega(t) : v[i++];
  }
  for (int k = 0; k < model->contact_count(); ++k) {
    INFO("plane " << k + 1);
    PlaneMotion a, b;
    REQUIRE(model->plane_motion(k, t, q, v, a));  // false before: plane 2 lies between B and R
    REQUIRE(inner.plane_motion(k, t, qf, vf, b));
    CHECK(a.rotor == b.rotor);
    CHECK(a.rotor_rate == b.rotor_rate);
    CHECK(a.stator == b.stator);
    CHECK(a.stator_rate == b.stator_rate);
  }
  // the K-contact chart, the spin's index dropped: sliding contacts are charted (the rotor's
  // points and rings do not involve theta), sticking ones not (without a spin coordinate the
  // rolling constraint would depend on time)
  const RingChart* chart = model->ring_chart();
  REQUIRE(chart != nullptr);
  REQUIRE(inner.ring_chart() != nullptr);
  CHECK(chart->contact_count() == 2);
  for (std::size_t k = 0; k < 2; ++k) {
    const RingContact& a = chart->contacts()[k];
    const RingContact& b = inner.ring_chart()->contacts()[k];
    for (std::size_t j = 0; j < 2; ++j) {
      CHECK(a.ix[j] == (b.ix[j] > s ? b.ix[j] - 1 : b.ix[j]));
      CHECK(a.iy[j] == (b.iy[j] > s ? b.iy[j] - 1 : b.iy[j]));
    }
    CHECK(a.ring == (b.ring > s ? b.ring - 1 : b.ring));
  }
  // sliding and sticking contacts are charted: the rolling constraint depends on time through
  // theta(t) (rheonomic, checked below)
  const Phase slip[] = {Phase::SlipNeg, Phase::SlipPos};
  const Phase stick[] = {Phase::Stick, Phase::SlipPos};
  CHECK(chart->applies(slip));
  CHECK(chart->applies(stick));
  REQUIRE(chart->spin_law().has_value());
  CHECK(chart->spin_law()->omega(t) == ps->omega(t));
}

TEST_CASE(
    "Prescribed spin: the rheonomic ring chart is a motion on every closed contact's "
    "constraint",
    "[unit][planes][prescribed][chart]") {
  // The chart's sticking contacts at a prescribed spin (contact/ring_chart.hpp): phi_k(t) =
  // phi_k0 - (R_k / g_k)(theta(t) - theta(t_a)). A reduced motion p(t) = p0 + pd0 s + pdd0 s^2 / 2
  // (s = t - tc) embedded at tc and tc +- h must be a motion of the full model on the closed
  // contacts' constraints: d_N = v_N = 0, and v_t = 0 in stick, at each time (the model's own
  // kinematics, with the prescribed share -R omega(t) of v_t); the central differences of the
  // embedded positions are the embedded velocities, and those of the velocities satisfy the
  // constraints at acceleration level, W a + wdot = 0 (wdot with the spin's acceleration alpha).
  // The spin ramps (alpha = -3e4 rad/s^2 from 300 rad/s, through 0 at 10 ms), so that a chart
  // without the time (theta frozen at theta(t_a), or omega(t_a), or alpha left out of wdot)
  // fails one of them.
  const CaseSpec spec =
      parse_case(prescribed_two_plane(), "two-plane.toml",
                 {"loads.spin_accel=-3e4", "initial.theta=0.3", "initial.omega0=300"});
  const auto model = build_model(spec);
  const auto* ps = dynamic_cast<const PrescribedSpin*>(model.get());
  REQUIRE(ps != nullptr);
  const RingChart& chart = *model->ring_chart();
  const int n = model->num_dofs();
  ContactKinematics c(n);
  std::mt19937_64 rng(11);
  const auto u = [&] { return std::uniform_real_distribution<double>(-1.0, 1.0)(rng); };
  using P = Phase;
  const std::vector<std::vector<Phase>> all = {{P::Stick, P::Free},
                                               {P::Free, P::Stick},
                                               {P::Stick, P::SlipPos},
                                               {P::SlipNeg, P::Stick},
                                               {P::Stick, P::Stick}};
  // a rolling contact's angle turns at (R / g) |omega| = 500 x 300 = 1.5e5 rad/s: over h = 1e-9 s
  // by 1.5e-4 rad, so that the differences' O(h^2) error, (phi' h)^2 / 6 relative, is 4e-9
  const double h = 1e-9;
  for (const auto& modes : all) {
    REQUIRE(chart.applies(modes));
    const int d = chart.dim(modes);
    int removed = 0;
    for (Phase m : modes) removed += m == P::Free ? 0 : (m == P::Stick ? 2 : 1);
    CHECK(d == n - removed);
    std::vector<double> L(static_cast<std::size_t>(d));
    chart.lengths(modes, L);
    for (int trial = 0; trial < 20; ++trial) {
      INFO(to_string(modes[0]) << ", " << to_string(modes[1]) << " trial " << trial);
      Vec p(d), pd(d), pdd(d);
      for (int j = 0; j < d; ++j) {
        const bool angle = L[static_cast<std::size_t>(j)] > 0.0;  // a sliding contact's phi
        p[j] = angle ? 3.0 * u() : 1e-4 * u();
        pd[j] = angle ? 500.0 * u() : 0.1 * u();
        pdd[j] = angle ? 1e6 * u() : 1e4 * u();
      }
      RingAnchor anchor;
      anchor.t0 = 0.005 + 0.005 * u();
      for (double& a : anchor.phi0) a = 3.0 * u();
      const double tc = anchor.t0 + 0.01 * std::abs(u());  // up to 3 rad of spin since t_a
      Vec q0(n), v0(n), qp(n), vp(n), qm(n), vm(n);
      chart.embed(modes, anchor, tc, p, pd, q0, v0);
      const Vec pp = p + pd * h + 0.5 * h * h * pdd, pm = p - pd * h + 0.5 * h * h * pdd;
      const Vec pdp = pd + h * pdd, pdm = pd - h * pdd;
      chart.embed(modes, anchor, tc + h, pp, pdp, qp, vp);
      chart.embed(modes, anchor, tc - h, pm, pdm, qm, vm);
      const Vec a = (vp - vm) / (2.0 * h);
      // the velocity of the embedded motion: O(h^2), 4e-9 relative, plus the round-off of
      // positions of 1e-4 m differenced over 2h (1e-20 / 2e-9 = 5e-12 m/s) against speeds of up
      // to R omega = 0.05 x 300 = 15 m/s: 1e-7 of the largest speed bounds both
      const double vmax = v0.cwiseAbs().maxCoeff();
      CHECK(((qp - qm) / (2.0 * h) - v0).cwiseAbs().maxCoeff() < 1e-7 * vmax);
      for (int k = 0; k < 2; ++k) {
        const Phase mk = modes[static_cast<std::size_t>(k)];
        if (mk == P::Free) continue;
        INFO("contact " << k);
        model->compute_contact(k, tc, q0, v0, c);
        // as in test_ring_chart.cpp: a few ulps of the 1e-4 m positions, and of the fastest
        // speed (15 m/s rolling) at velocity level
        CHECK(std::abs(c.d_N) < 1e-18);
        CHECK(std::abs(c.v_N) < 1e-14 * vmax);
        if (mk == P::Stick) CHECK(std::abs(c.v_t) < 1e-14 * vmax);
        // acceleration level: the rolling ring's g phi'^2 up to 1e-4 x 1.5e5^2 = 2e6 m/s^2
        // from velocities of 15 m/s differenced over 2h: round-off 1e-15 x 15 / 2e-9 = 8e-6
        // m/s^2, O(h^2) 4e-9 relative; 1e-6 of the largest acceleration bounds both (a W . a
        // sums terms of that size)
        const double amax = a.cwiseAbs().maxCoeff();
        CHECK(std::abs(c.W_N.dot(a) + c.wdot_N) < 1e-6 * amax);
        if (mk == P::Stick) CHECK(std::abs(c.W_T.dot(a) + c.wdot_T) < 1e-6 * amax);
      }
      // chart of the embedded state at tc, embedded again at tc: the same state
      Vec p2(d), pd2(d), q2(n), v2(n);
      RingAnchor a2;
      chart.chart(modes, tc, q0, v0, a2, p2, pd2);
      CHECK(a2.t0 == tc);
      chart.embed(modes, a2, tc, p2, pd2, q2, v2);
      CHECK((q2 - q0).cwiseAbs().maxCoeff() < 1e-18);
      CHECK((v2 - v0).cwiseAbs().maxCoeff() < 1e-14 * vmax);
    }
  }
}

TEST_CASE("Prescribed spin: the event solver's sliding phases in minimal coordinates",
          "[planes][prescribed][events]") {
  // The chart passed through is used, and used right: the run with it (reduced) and the run
  // with projection agree to the tolerance, and the reduced run closes its energy balance to
  // round-off where projection takes out what it projects. Measured over 30 ms (9 impacts,
  // 74 % sliding) at rtol 1e-10: the two runs 1.1e-11 m apart, the reduced one 1.9e-13 m from
  // an rtol 1e-12 run and the projected one 1.1e-11 m; residuals 6.4e-11 J against 3.0e-9 J of
  // 11 J of flows. The bounds: 1e-10 m is 10 rtol x the 1e-4 m clearance (the solver's position
  // tolerance); 1e-9 J is 1e-10 of the flows (rtol), which the projected run's 3e-9 J exceeds.
  const std::string text = prescribed_two_plane();
  const auto run = [&](const char* phases) {
    const CaseSpec spec =
        parse_case(text, "two-plane.toml",
                   {"solver.kind=\"event\"", "solver.rtol=1e-10", "run.t_end=0.03",
                    std::string("solver.contact_phases=\"") + phases + "\""});
    MemorySink sink;
    const RunSummary s = simulate(spec, sink);
    REQUIRE(s.complete());
    return std::make_pair(s, sink.samples.back());
  };
  const auto [reduced, end_r] = run("reduced");
  const auto [projected, end_p] = run("projection");
  CHECK(reduced.options.find("reduced+adams") != std::string::npos);
  CHECK((end_r.q - end_p.q).cwiseAbs().maxCoeff() < 1e-10);
  CHECK(std::abs(reduced.energy_residual) < 1e-9);
  CHECK(reduced.events == projected.events);
}

TEST_CASE("Prescribed spin on two planes: every solver's run is analysed", "[planes][prescribed]") {
  // The runs: every solver, spins held at 0, ramped up and down (through 0). Each must
  // complete and its folder be analysed with each plane's files (plane 2 in analysis/plane_2).
  const fs::path dir = fresh_dir("prescribed-planes");
  const std::string text = prescribed_two_plane();
  const std::vector<std::vector<std::string>> spins = {
      {"initial.omega0=0", "loads.spin_accel=0"},
      {"initial.omega0=0", "loads.spin_accel=1e5"},
      {"initial.omega0=1000", "loads.spin_accel=-1e5"}};
  for (const char* solver : {"event", "mj", "mj-proj", "carp-onevc", "carp-qn"}) {
    for (const auto& spin : spins) {
      std::vector<std::string> sets = spin;
      sets.push_back(std::string("solver.kind=\"") + solver + "\"");
      sets.push_back("run.t_end=0.02");
      if (std::string(solver) != "event") sets.push_back("solver.h=2e-6");
      INFO(solver << " " << spin[0] << " " << spin[1]);
      const CaseSpec spec = parse_case(text, "two-plane.toml", sets);
      fs::remove_all(dir);
      RunSummary s;
      {
        OutputFolder sink(dir.string(), spec);
        s = simulate(spec, sink);
      }
      CHECK(s.complete());
      const RunRecord r = read_run(dir.string());
      RunVerdicts v;
      REQUIRE_NOTHROW(v = write_analysis(r, AnalysisOptions{}, ""));
      CHECK(fs::exists(dir / "analysis" / "plane_2" / "derived.csv"));
    }
  }
  fs::remove_all(dir);
}

TEST_CASE("Prescribed spin: the event solver's sticking phases in minimal coordinates",
          "[planes][prescribed][events]") {
  // Both planes at mu = 0.5 on their sprung rings, the spin prescribed from 2000 rad/s down at
  // -3e4 rad/s^2: the rotor whips, slides and, at 21.2 ms, one plane sticks (rolls at the ramping
  // spin) until an impact at the other opens it; over 22 ms 15 events (7 impacts, 5 lift-offs,
  // 3 sticks). The two formulations, independent in their contact phases (minimal coordinates
  // with the rheonomic chart, the projected index-reduced DAE), at rtol 1e-12, measured: the
  // same events, at times 7.2e-12 s apart at most (at rtol 1e-10 the two are 1.1e-9 s apart,
  // the reduced run 3.8e-10 s from the rtol 1e-12 runs, the projected one 1.1e-9 s); the stick
  // phases in 5 779 steps against 21 471 (the projected DAE resolves the rolling ring's whirl
  // at (R / g) omega ~ 1e6 rad/s in full coordinates); the reduced run's energy residual 1.7e-7 J
  // of 6.3e4 J of flows (2.7e-12).
  const std::string text = [] {
    std::string s = prescribed_two_plane();
    for (std::size_t at = s.find("\nmu "); at != std::string::npos; at = s.find("\nmu ", at + 1))
      s.replace(s.find('=', at) + 1, s.find('\n', at + 1) - s.find('=', at) - 1, " 0.5");
    return s;
  }();
  const auto run = [&](const char* phases) {
    const CaseSpec spec =
        parse_case(text, "two-plane.toml",
                   {"solver.kind=\"event\"", "solver.rtol=1e-12", "solver.atol=1e-15",
                    "run.t_end=0.022", "initial.omega0=2000", "loads.spin_accel=-3e4",
                    std::string("solver.contact_phases=\"") + phases + "\""});
    MemorySink sink;
    const RunSummary s = simulate(spec, sink);
    REQUIRE(s.complete());
    return std::make_pair(s, sink.events);
  };
  const auto [reduced, ev_r] = run("reduced");
  const auto [projected, ev_p] = run("projection");
  const auto stick = static_cast<std::size_t>(Phase::Stick);
  const double flows = std::abs(reduced.work_damping) + std::abs(reduced.work_friction) +
                       std::abs(reduced.work_torque) + std::abs(reduced.work_impacts);
  INFO("stick " << reduced.phase_time[stick] << " s, steps " << reduced.phase_steps[stick]
                << " reduced, " << projected.phase_steps[stick] << " projected; residual "
                << reduced.energy_residual << " J of " << flows << " J; events " << ev_r.size()
                << " and " << ev_p.size());
  double dt = 0.0;
  int sticks = 0;
  REQUIRE(ev_r.size() == ev_p.size());
  for (std::size_t i = 0; i < ev_r.size(); ++i) {
    CHECK(ev_r[i].kind == ev_p[i].kind);
    CHECK(ev_r[i].contact == ev_p[i].contact);
    dt = std::max(dt, std::abs(ev_r[i].t - ev_p[i].t));
    sticks += ev_r[i].kind == EventKind::Stick;
  }
  INFO("event times apart by " << dt << " s");
  CHECK(sticks >= 1);
  // the bound 5e-11 s: 7x the measured, 20x below what the runs at rtol 1e-10 differ by
  CHECK(dt < 5e-11);
  // the chart is used: a stick phase that fell back to projection would take the projected
  // run's steps (measured 3.7x more; asked 2x)
  CHECK(2 * reduced.phase_steps[stick] < projected.phase_steps[stick]);
  // the balance closes to the integrator's tolerance: 1e-11 of the flows, 3.7x the measured
  CHECK(std::abs(reduced.energy_residual) < 1e-11 * flows);
  CHECK(reduced.max_drift_position < 1e-18);
}
