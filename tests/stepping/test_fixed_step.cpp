// Fixed-step schemes on exact solutions: orders, contact convergence, Signorini at position and
// velocity level, Carpenter variants against each other, round-off at small steps.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <tuple>
#include <vector>

#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"
#include "rubdyn/stepping/fixed_step.hpp"
#include "support/problems.hpp"

using namespace rubdyn;
using rubdyn::testing::BlockOnBelt;
using rubdyn::testing::BouncingBall;
using rubdyn::testing::SpringMass;

namespace {

MemorySink run(const LagrangianModel& m, const MechanicalState& s0, double t_end,
               FixedStepScheme scheme, double h, int every = 1) {
  MemorySink sink;
  FixedStepOptions o;
  o.scheme = scheme;
  o.h = h;
  o.output_every = every;
  const RunSummary s = run_fixed_step(m, s0, t_end, o, sink);
  INFO(s.message);
  REQUIRE(s.complete());
  return sink;
}

/// The sample closest to time t (fixed-step samples fall on the grid).
const Sample& at(const MemorySink& s, double t) {
  const Sample* best = &s.samples.front();
  for (const auto& x : s.samples)
    if (std::abs(x.t - t) < std::abs(best->t - t)) best = &x;
  return *best;
}

double rate(double e_coarse, double e_fine) {
  return std::log2(e_coarse / e_fine);
}

const FixedStepScheme kAll[] = {FixedStepScheme::CarpOneVC, FixedStepScheme::CarpQN,
                                FixedStepScheme::MoreauJean, FixedStepScheme::MoreauJeanProjected};
}  // namespace

TEST_CASE("Contact-free: central differences and MJ(theta = 1/2) converge at order 2",
          "[stepping]") {
  const SpringMass m;  // w = 2 pi, exact x = cos(w t)
  // t = 0.3 (not a multiple of the half period, where the phase error of central differences
  // cancels and the position error superconverges)
  const double T = 0.3;
  for (auto scheme : {FixedStepScheme::CarpOneVC, FixedStepScheme::MoreauJean}) {
    double ex[5], ev[5];
    double h = 1e-2;
    for (int k = 0; k < 5; ++k, h /= 2) {
      const MemorySink s = run(m, m.initial(), T, scheme, h);
      const Sample& x = at(s, T);
      REQUIRE(x.t == Approx(T).margin(1e-12));
      ex[k] = std::abs(x.q[0] - m.exact_x(T));
      ev[k] = std::abs(x.v[0] - m.exact_v(T));
    }
    for (int k = 0; k < 4; ++k) {
      INFO(to_string(scheme) << " h/" << (1 << k) << ": position errors " << ex[k] << " -> "
                             << ex[k + 1] << ", velocity " << ev[k] << " -> " << ev[k + 1]);
      CHECK(std::abs(rate(ex[k], ex[k + 1]) - 2.0) < 0.2);
      CHECK(std::abs(rate(ev[k], ev[k + 1]) - 2.0) < 0.2);
    }
  }
}

TEST_CASE("Bouncing ball: landing within one step - resting on the ground - MJ bounces converge",
          "[stepping]") {
  // e_n = 0 (plastic, Carpenter's implicit law). Free flight under constant gravity is exact for
  // all four schemes (quadratic), so the only error is the landing, resolved to one step.
  const BouncingBall ball(0.0);
  const double t1 = ball.first_impact_time();
  for (auto scheme : kAll) {
    for (double h : {1e-3, 1e-4}) {
      const MemorySink s = run(ball, ball.initial(), 0.6, scheme, h);
      double landing = -1.0;
      for (const auto& e : s.events)
        if (e.kind == EventKind::Impact) {
          landing = e.t;
          break;
        }
      INFO(to_string(scheme) << " h = " << h << ": landing " << landing << " exact " << t1);
      // Carpenter corrects the step that would penetrate: the event is at most one step off.
      // Moreau-Jean activates the contact when d_N + h/2 v_N <= 0 at a step start and logs the
      // impulse at the end of that step: up to two steps after the exact landing.
      const bool mj =
          scheme == FixedStepScheme::MoreauJean || scheme == FixedStepScheme::MoreauJeanProjected;
      CHECK(std::abs(landing - t1) <= (mj ? 2.0 : 1.0) * h * (1 + 1e-9));
      // at rest afterwards: Carpenter and mj-proj on the ground to round-off. Plain MJ keeps the
      // O(h) penetration of velocity-level Signorini: the free step may end below the ground by
      // up to h |v|, and with theta = 1/2 the impulse step still moves q by h/2 v_i: 1.5 h |v|.
      const double y = at(s, 0.6).q[1];
      const double v_land = ball.g() * t1;
      if (scheme == FixedStepScheme::MoreauJean) {
        CHECK(y <= 0.0);
        CHECK(-y <= 1.5 * h * v_land);
      } else {
        CHECK(std::abs(y) <= 1e-12);
      }
    }
  }
  // e_n = 0.5 for Moreau-Jean (Newton's law at velocity level): the second impact time
  const BouncingBall bounce(0.5);
  for (auto scheme : {FixedStepScheme::MoreauJean, FixedStepScheme::MoreauJeanProjected}) {
    double err[3];
    double h = 1e-3;
    for (int k = 0; k < 3; ++k, h /= 2) {
      const MemorySink s = run(bounce, bounce.initial(), 1.0, scheme, h);
      int n = 0;
      double t2 = 0;
      for (const auto& e : s.events)
        if (e.kind == EventKind::Impact && ++n == 2) t2 = e.t;
      err[k] = std::abs(t2 - bounce.impact_time(2));
    }
    std::printf("bouncing ball e=0.5 %-8s second impact time errors %.3e %.3e %.3e\n",
                std::string(to_string(scheme)).c_str(), err[0], err[1], err[2]);
    INFO(to_string(scheme) << ": " << err[0] << " " << err[1] << " " << err[2]);
    // order >= 1 with a one-step jitter of the detected event: over two halvings / 3
    CHECK(err[2] < err[0] / 3.0);
  }
}

TEST_CASE("Block on a belt: every scheme converges to the stick-slip solution", "[stepping]") {
  const BlockOnBelt m(0.5, 100.0, 1.0, 0.2);
  // before the degenerate touch at t2 + 2 pi / w; a whole number of the steps below (1 ms and
  // its halvings), as run_fixed_step requires
  const double T = std::ceil((m.slip_time() + 0.2) / 1e-3) * 1e-3;
  for (auto scheme : kAll) {
    double err[3];
    double h = 1e-3;
    for (int k = 0; k < 3; ++k, h /= 2) {
      const MemorySink s = run(m, m.initial(), T, scheme, h);
      double e = 0;
      for (const auto& x : s.samples)
        e = std::max(e, std::abs(x.q[0] + m.belt_speed() * x.t - m.exact_lab_x(x.t)));
      err[k] = e;
    }
    std::printf("block on belt %-10s errors %.3e %.3e %.3e\n",
                std::string(to_string(scheme)).c_str(), err[0], err[1], err[2]);
    INFO(to_string(scheme) << ": " << err[0] << " " << err[1] << " " << err[2]);
    // order >= 1: two halvings divide the error by at least 3 (rate >= 0.8 each)
    CHECK(err[2] < err[0] / 3.0);
  }
}

TEST_CASE("Position-level schemes keep d_N >= -1e-9 g0 - MJ satisfies velocity Signorini",
          "[stepping]") {
  const RotorStatorModel model(RotorStatorParams{});
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.v[TH] = 2000.0;
  const double g0 = model.params().stator.gap;
  for (auto scheme : {FixedStepScheme::CarpOneVC, FixedStepScheme::CarpQN,
                      FixedStepScheme::MoreauJeanProjected}) {
    const MemorySink s = run(model, s0, 0.03, scheme, 1e-6);
    double min_dN = 1e300;
    for (const auto& x : s.samples) min_dN = std::min(min_dN, x.contacts[0].d_N);
    INFO(to_string(scheme) << " min d_N " << min_dN);
    CHECK(min_dN >= -1e-9 * g0);
    CHECK(s.summary.events[static_cast<int>(EventKind::Impact)] >= 1);
  }
  // MJ on the bouncing ball (constant W_N): at every step with an impulse, the velocity
  // Signorini condition v_N(i+1) + e_n v_N(i) = 0 holds to round-off, and F_N >= 0; without
  // one, the contact was inactive or separating.
  const BouncingBall ball(0.5);
  const MemorySink s = run(ball, ball.initial(), 1.5, FixedStepScheme::MoreauJean, 1e-3);
  int active = 0;
  for (std::size_t i = 1; i < s.samples.size(); ++i) {
    const Sample& a = s.samples[i - 1];
    const Sample& b = s.samples[i];
    CHECK(b.contacts[0].F_N >= 0.0);
    if (b.contacts[0].F_N > 0.0) {
      ++active;
      // velocities ~ 4 m/s: round-off ~1e-15
      CHECK(std::abs(b.contacts[0].v_N + 0.5 * a.contacts[0].v_N) < 1e-12);
    }
  }
  CHECK(active > 5);
}

TEST_CASE("mj-proj moves positions along M^-1 W_N (mass) or along W_N (identity)", "[stepping]") {
  // mj and mj-proj take identical steps until the first step that ends with d_N < 0; there the
  // projected run differs from the plain one by the projection alone, dq = alpha M(q)^-1 W_N
  // (kinetic metric) or dq = alpha W_N (Euclidean metric, Siconos' choice).
  const RotorStatorModel model(RotorStatorParams{});
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.v[TH] = 2000.0;
  for (bool with_mass : {true, false}) {
    FixedStepOptions o;
    o.h = 1e-6;
    o.output_every = 1;
    o.project_with_mass = with_mass;
    MemorySink plain, proj;
    o.scheme = FixedStepScheme::MoreauJean;
    REQUIRE(run_fixed_step(model, s0, 0.0065, o, plain).complete());
    o.scheme = FixedStepScheme::MoreauJeanProjected;
    REQUIRE(run_fixed_step(model, s0, 0.0065, o, proj).complete());
    REQUIRE(plain.samples.size() == proj.samples.size());
    std::size_t k = 0;
    while (k < plain.samples.size() && plain.samples[k].contacts[0].d_N >= 0.0) {
      REQUIRE(plain.samples[k].q == proj.samples[k].q);  // bitwise: the same operations
      ++k;
    }
    REQUIRE(k < plain.samples.size());  // an impact happens before 6.5 ms
    const Vec dq = proj.samples[k].q - plain.samples[k].q;
    const ContactKinematics c = model.contact(0, 0.0, proj.samples[k].q, proj.samples[k].v);
    Mat M(7, 7);
    model.mass_matrix(proj.samples[k].q, M);
    // the direction: dq (identity) or M dq (mass) is parallel to W_N (taken at the projected
    // q; the projection iterates, so the last direction dominates: the first correction's
    // residual is second order in the penetration, ~1e-9 m here, so 1e-6 relative is ample)
    const Vec dir = with_mass ? Vec(M * dq) : dq;
    const double along = dir.dot(c.W_N) / c.W_N.squaredNorm();
    INFO((with_mass ? "mass" : "identity")
         << ": d_N before " << plain.samples[k].contacts[0].d_N << ", dq = " << dq.transpose());
    CHECK(plain.samples[k].contacts[0].d_N < 0.0);
    // projected onto d_N >= 0 (the loop stops when d_N >= 0; d_N's own round-off is
    // ~1e-16 |s| ~ 2e-20 m, far below this bound)
    CHECK(proj.samples[k].contacts[0].d_N >= -1e-15 * model.params().stator.gap);
    CHECK((dir - along * c.W_N).norm() <= 1e-6 * std::abs(along) * c.W_N.norm());
    if (!with_mass) {
      // W_N has no bearing or spin entry: those coordinates are not moved
      CHECK(dq[XB] == 0.0);
      CHECK(dq[YB] == 0.0);
      CHECK(dq[TH] == 0.0);
    } else {
      CHECK(dq[XB] != 0.0);  // the kinetic metric couples B with R (M12 != 0)
    }
  }
}

TEST_CASE("carp-qn and carp-onevc agree to O(h) on the first 30 ms of the reference case",
          "[stepping]") {
  const RotorStatorModel model(RotorStatorParams{});
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.v[TH] = 2000.0;
  double diff[2];
  double h = 2e-6;
  for (int k = 0; k < 2; ++k, h /= 2) {
    const MemorySink a = run(model, s0, 0.03, FixedStepScheme::CarpOneVC, h, 0);
    const MemorySink b = run(model, s0, 0.03, FixedStepScheme::CarpQN, h, 0);
    double d = 0;
    for (std::size_t i = 0; i < std::min(a.samples.size(), b.samples.size()); ++i)
      d = std::max(d, std::abs(a.samples[i].q[XR] - b.samples[i].q[XR]) +
                          std::abs(a.samples[i].q[YR] - b.samples[i].q[YR]));
    diff[k] = d;
  }
  std::printf("carp-qn vs carp-onevc: max orbit difference %.3e (h = 2e-6), %.3e (h = 1e-6)\n",
              diff[0], diff[1]);
  INFO(diff[0] << " " << diff[1]);
  CHECK(diff[1] < 0.75 * diff[0] + 1e-15);  // O(h): halving h roughly halves it
}

TEST_CASE("Carpenter keeps converging at h = 1e-7 (no round-off floor from theta)", "[stepping]") {
  // First 30 ms of the reference case (three impacts), reference: event-driven at rtol 1e-12.
  // Once contacts occur the schemes are first order, so omega(30 ms) must improve ~10x per
  // 10x smaller step. Storing absolute positions, the central-difference spin speed
  // (theta_{i+1} - theta_{i-1}) / 2h with theta ~ 60 rad would carry a round-off of
  // ~1e-14 / h ~ 1e-7 rad/s at h = 1e-7 and stall; increments keep it converging.
  const RotorStatorModel model(RotorStatorParams{});
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.v[TH] = 2000.0;
  const double T = 0.03;
  MemorySink ref;
  EventDrivenOptions eo;
  eo.rtol = 1e-12;
  eo.atol = 1e-14;
  eo.output_dt = 1e-3;
  REQUIRE(run_event_driven(model, s0, T, eo, ref).complete());
  const double omega_ref = ref.samples.back().v[TH];
  double e[3];
  double h = 1e-5;
  for (int k = 0; k < 3; ++k, h /= 10) {
    const MemorySink s = run(model, s0, T, FixedStepScheme::CarpOneVC, h, 0);
    const Sample& last = at(s, T);
    REQUIRE(last.t == Approx(T).margin(1e-12));
    e[k] = std::abs(last.v[TH] - omega_ref);
  }
  std::printf("carp-onevc, 30 ms: omega errors %.3e %.3e %.3e (h = 1e-5, 1e-6, 1e-7)\n", e[0], e[1],
              e[2]);
  // first order: 10x per decade; 3x allows for the one-step jitter of impact detection
  CHECK(e[1] < e[0] / 3.0);
  CHECK(e[2] < e[1] / 3.0);
}

TEST_CASE("Fixed-step runs report progress at every output sample", "[stepping]") {
  // the rotor-stator reference for 10 ms at h = 1e-6 with samples every 1e-4 s: the progress
  // function sees each written sample once, in order, with the sample's spin speed and phase and
  // the events logged so far (the first impact is at about 6 ms)
  const RotorStatorModel model(RotorStatorParams{});
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.v[TH] = 2000.0;
  for (auto scheme : kAll) {
    MemorySink sink;
    FixedStepOptions o;
    o.scheme = scheme;
    o.h = 1e-6;
    std::vector<std::tuple<double, long, double, Phase>> calls;
    o.progress = [&](double t, long events, double omega, Phase ph) {
      calls.emplace_back(t, events, omega, ph);
    };
    const RunSummary s = run_fixed_step(model, s0, 0.01, o, sink);
    INFO(to_string(scheme) << ": " << s.message);
    REQUIRE(s.complete());
    REQUIRE(calls.size() == sink.samples.size());  // the initial one included
    for (size_t i = 0; i < calls.size(); ++i) {
      const Sample& x = sink.samples[i];
      CHECK(std::get<0>(calls[i]) == x.t);
      CHECK(std::get<2>(calls[i]) == x.v[TH]);
      CHECK(std::get<3>(calls[i]) == x.contacts[0].phase);
    }
    const long total = std::accumulate(s.events.begin(), s.events.end(), 0L);
    CHECK(std::get<1>(calls.back()) == total);
    CHECK(total >= 1);
  }
}

TEST_CASE("Every fixed-step scheme writes t_start and the final state, and nothing else changes",
          "[stepping][output]") {
  // Before: mj and mj-proj (whose step i completes t_{i+1}) never wrote the initial state, and
  // no scheme wrote the final state when t_end was off the output grid, or with a huge
  // output.dt or output.every: analyze and compare refused such a folder.
  RotorStatorParams p;
  const RotorStatorModel model(p);
  MechanicalState s0(RotorStatorModel::kDofs);
  s0.v[TH] = 2000.0;
  s0.t = 0.001;                 // a restart time, not 0
  const double t_end = 0.0085;  // 7500 steps of 1e-6 s: off the 1e-3 s output grid
  for (auto scheme : {FixedStepScheme::CarpOneVC, FixedStepScheme::CarpQN,
                      FixedStepScheme::MoreauJean, FixedStepScheme::MoreauJeanProjected}) {
    INFO(to_string(scheme));
    // every step: the reference the sparser outputs are compared with
    const MemorySink all = run(model, s0, t_end, scheme, 1e-6, 1);
    REQUIRE(all.samples.size() == 7501);
    CHECK(all.samples.front().t == s0.t);
    CHECK(all.samples.front().q == s0.q);  // the initial position itself, bit for bit
    // Moreau-Jean's initial row is the initial state; Carpenter's row 0 carries its central
    // velocity (q_1 - q_-1) / 2h, v_0 in exact arithmetic only (as before this change)
    if (scheme == FixedStepScheme::MoreauJean || scheme == FixedStepScheme::MoreauJeanProjected)
      CHECK(all.samples.front().v == s0.v);
    auto sparse = [&](int every, double dt) {
      MemorySink sink;
      FixedStepOptions o;
      o.scheme = scheme;
      o.h = 1e-6;
      o.output_every = every;
      o.output_dt = dt;
      const RunSummary s = run_fixed_step(model, s0, t_end, o, sink);
      REQUIRE(s.complete());
      REQUIRE(sink.samples.size() >= 2);
      CHECK(sink.samples.front().t == s0.t);
      CHECK(sink.samples.back().t == s.t_reached);
      CHECK(std::abs(s.t_reached - t_end) <= 1e-15);  // ends at t_end (to round-off)
      // every row is the every-step run's row of the same time, bit for bit (the initial row of
      // mj carries no contact force: the state before the first step)
      for (const Sample& x : sink.samples) {
        const Sample& y = at(all, x.t);
        CHECK(x.t == y.t);
        CHECK(x.q == y.q);
        CHECK(x.v == y.v);
        CHECK(x.contacts[0].F_N == y.contacts[0].F_N);
      }
      return sink.samples.size();
    };
    CHECK(sparse(0, 1e-3) == 9);              // t_start, 7 grid times, t_end
    CHECK(sparse(0, 1e308) == 2);             // t_start, t_end
    CHECK(sparse(2'000'000'000, 1e-4) == 2);  // index 0 only, then t_end
    CHECK(sparse(1000, 1e-4) == 9);           // indices 0, 1000, ..., 7000, then 7500
  }
}
