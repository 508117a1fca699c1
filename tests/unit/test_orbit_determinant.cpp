// The determinant of the monodromy of a forced periodic orbit with frictionless Newton impacts
// (issue 33): a check of the finite-difference monodromy (analysis/orbit.hpp) against a theory
// that does not use the model's code.
//
// Over one period T the return map is the composition of smooth flights and impacts, so
//   det(Phi) = prod(det of the flights' flows) * prod(det of the impacts' saltation matrices).
// Flight: x' = A(t, x) with A = [[0, I], [-M^-1 K, -M^-1 C]] for the Jeffcott rotor at a
// prescribed constant spin (docs/models.md, section 1: M = diag(m_r, m_r[, m_s, m_s]) constant,
// no gyroscopic term on the lateral coordinates; even with one, tr(M^-1 Omega G) = 0 for a skew G
// and a symmetric M), and Liouville's formula gives exp(integral of tr A) = exp(-tr(M^-1 C) t)
// over a flight of duration t: gravity and the unbalance are forces that do not depend on the
// state and leave A alone. Impact: a frictionless Newton impact maps the relative normal velocity
// v_N to -e_N v_N and keeps the positions; its saltation matrix
//   S = DR + (f+ - DR f-) dd_N^T / (dd_N . f-)
// has det S = det(DR) (dd_N . f+) / (dd_N . f-). DR is block lower triangular with the identity
// on the positions and the mass-weighted reflection (eigenvalues -e_N once, 1 otherwise) on the
// velocities: det DR = -e_N; and dd_N . f = -v_N, whose ratio across the impact is -e_N. So
// det S = e_N^2 (a 1-D bounce: S = [[-e, 0], [(1 + e) a / v, -e]]). With k impacts per period:
//   det(Phi) = e_N^(2k) exp(-tr(M^-1 C) T),  tr(M^-1 C) = 2 c_r / m_r (+ 2 c_s / m_s, a sprung
// ring).
// The section lies in free flight, where SectionChart has no constraint: its coordinates are
// xi = B^T D^-1 (x - x_b) with B an orthonormal basis of the whole scaled state space (square,
// so B^T = B^-1) and D the diagonal state scale. The monodromy in them, B^T D^-1 DP D B, is
// similar to the full-state derivative DP and has the same determinant: the formula holds in the
// section's coordinates as it stands (the test checks that the chart spans all 2n directions).
//
// The scene: the Jeffcott rotor on a soft shaft (omega_n = sqrt(k_r / m_r) = 316 rad/s) at
// Omega = 250 rad/s, where the unbalance's response (1.2e-4 m) plus the sag under gravity
// (9.8e-5 m) exceeds the gap (2e-4 m): a period-1 partial rub near the bottom of the ring, free
// flight from one impact to the next (not the full annular rub of test_orbit.cpp). The sprung
// ring is a 5 kg ring on 5e6 N/m and 1000 N s/m (1000 rad/s, damping ratio 0.1): the light stiff
// ring of test_orbit.cpp (2 kg, 2e7 N/m, 400 N s/m) rattles against the rotor after each impact,
// and at e_N = 0.5 its orbit ends its bounces in a Zeno accumulation and a contact phase
// (measured at rtol 1e-10: 9 impacts, a Zeno truncation and a lift-off per period), outside the
// formula's assumptions.
#include <Eigen/Dense>
#include <Eigen/SVD>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <numbers>
#include <string>
#include <vector>

#include "rubdyn/analysis/continuation.hpp"
#include "rubdyn/analysis/orbit.hpp"
#include "rubdyn/analysis/orbit_case.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/solver_options.hpp"

using namespace rubdyn;

namespace {

struct Scene {
  double m_r = 5.0, k_r = 5e5, c_r = 300.0;
  double g0 = 2e-4, e_n = 0.5;
  double u_b = 4e-4, Omega = 250.0, gravity = 9.81;
  bool rigid = true;
  double m_s = 5.0, k_s = 5e6, c_s = 1000.0;
  double rtol = 1e-12, atol = 1e-15;
};

std::string fmt_g(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}

std::string case_text(const Scene& p) {
  std::string s =
      "name = \"partial-rub\"\n[model]\nkind = \"jeffcott\"\n[rotor]\nmass = " + fmt_g(p.m_r) +
      "\nk = " + fmt_g(p.k_r) + "\nc = " + fmt_g(p.c_r) +
      "\nradius = 0.05\nJp = 0.06\n[contact]\nmu = 0.0\ne_n = " + fmt_g(p.e_n) +
      "\ne_t = 0.0\n[loads]\ngravity = " + fmt_g(p.gravity) +
      "\nspin = \"prescribed\"\nspin_accel = 0.0\nunbalance = " + fmt_g(p.u_b) +
      "\nunbalance_phase = 0.3\n[initial]\nomega0 = " + fmt_g(p.Omega) +
      "\n[run]\nt_end = 1.0\nomega_lim = 2000.0\n[output]\ndt = 1e-4\n";
  s += p.rigid ? "[stator]\nrigid = true\ngap = " + fmt_g(p.g0) + "\n"
               : "[stator]\nmass = " + fmt_g(p.m_s) + "\nk = " + fmt_g(p.k_s) +
                     "\nc = " + fmt_g(p.c_s) + "\ngap = " + fmt_g(p.g0) + "\n";
  s += "[solver]\nkind = \"event\"\nrtol = " + fmt_g(p.rtol) + "\natol = " + fmt_g(p.atol) + "\n";
  return s;
}

}  // namespace

TEST_CASE(
    "orbit: the monodromy of a partial rub with frictionless impacts has det = e_N^(2k) "
    "exp(-tr(M^-1 C) T)",
    "[orbit]") {
  struct Setting {
    bool rigid;
    double e_n;
  };
  for (const Setting st :
       {Setting{true, 0.5}, Setting{true, 0.8}, Setting{false, 0.5}, Setting{false, 0.8}}) {
    Scene p;
    p.rigid = st.rigid;
    p.e_n = st.e_n;
    const CaseSpec spec = parse_case(case_text(p), "partial-rub.toml");
    CaseOrbitOptions o;
    // The transient from rest decays at c_r / (2 m_r) = 30 1/s (and faster with the impacts'
    // losses): 40 periods (1 s) leave Newton a start within its basin.
    o.settle = 40;
    o.orbit.samples = 1;
    const CaseOrbit co = find_case_orbit(spec, o);
    const OrbitResult& res = co.result;
    INFO((st.rigid ? "rigid" : "sprung") << " ring, e_N = " << st.e_n << ": " << res.message);
    REQUIRE(res.converged());
    const int n = co.model->num_dofs();
    // the lateral coordinates only (the prescribed spin has no coordinate)
    REQUIRE(n == (st.rigid ? 2 : 4));
    // the section in free flight, its chart spanning the whole state space
    for (const Phase ph : res.section_phases) REQUIRE(ph == Phase::Free);
    REQUIRE(res.chart_dim == 2 * n);
    REQUIRE(res.monodromy.ok);
    CHECK_FALSE(res.monodromy.sequence_changed);
    // every event of the orbit an impact: no contact phase, whose flow would have another
    // trace, and no Zeno truncation (a plastic impact, det 0)
    int k = 0;
    for (const auto& ev : res.events) {
      INFO("event at " << ev.t << " of kind " << static_cast<int>(ev.kind));
      CHECK(ev.kind == EventKind::Impact);
      if (ev.kind == EventKind::Impact) ++k;
    }
    REQUIRE(k >= 1);
    const double T = res.period;
    const double trace = 2 * p.c_r / p.m_r + (st.rigid ? 0.0 : 2 * p.c_s / p.m_s);
    const double expected = std::pow(p.e_n, 2 * k) * std::exp(-trace * T);
    const Mat& Phi = res.monodromy.M;
    const double det = Phi.determinant();
    // The tolerance from the monodromy's own error estimate E (|dPhi|_2 <= E): to first order
    // d det = tr(adj(Phi) dPhi) = det tr(Phi^-1 dPhi), and |tr(X Y)| <= |X|_* |Y|_2 (the
    // nuclear norm, sum of singular values, is the dual of the 2-norm), so
    // |d det| / |det| <= |Phi^-1|_* E.
    const Mat Phi_inv = Phi.inverse();
    const double nuclear = Eigen::JacobiSVD<Mat>(Phi_inv).singularValues().sum();
    const double bound = nuclear * res.monodromy.error;
    const double rel = std::abs(det - expected) / expected;
    INFO("k = " << k << ", T = " << T << ", det = " << det << ", formula = " << expected
                << ", relative difference = " << rel
                << ", monodromy error = " << res.monodromy.error << ", relative bound = " << bound);
    // The first-order bound means something only while it is small. At the case default rtol
    // 1e-10 the sprung ring's differences are noise-dominated (E = 2.1e-3 and 5.8e-3, so
    // bounds 0.19 and 0.45 with |Phi^-1|_* = 93 and 78: the orbit contracts strongly,
    // det ~ 1e-6), hence rtol 1e-12 here, where E falls 40- to 70-fold.
    REQUIRE(bound < 0.1);
    // E is the finite differences' calibrated error estimate (docs/orbits.md, section 4), not a
    // strict bound, and is taken as it is: no margin on top of it.
    CHECK(rel <= bound);
  }
}

// The same orbits with the monodromy from the flow's sensitivities: free flight's variational
// equations and, at every impact, the saltation matrix with the Jacobian of the engine's impact
// decision. Its determinant obeys the same formula, to its own (much smaller) bound, and its
// multipliers are the finite differences' within the latter's bounds.
TEST_CASE(
    "orbit: the sensitivities' monodromy of the frictionless partial rub: its determinant and "
    "the finite differences' multipliers",
    "[orbit]") {
  const SensitivityMonodromy sens;
  for (const bool rigid : {true, false}) {
    Scene p;
    p.rigid = rigid;
    p.e_n = 0.5;
    const CaseSpec spec = parse_case(case_text(p), "partial-rub.toml");
    CaseOrbitOptions o;
    o.settle = 40;  // as above
    o.orbit.samples = 1;
    const CaseOrbit fd = find_case_orbit(spec, o);
    o.orbit.provider = &sens;
    const CaseOrbit co = find_case_orbit(spec, o);
    const OrbitResult& res = co.result;
    INFO((rigid ? "rigid" : "sprung") << " ring: " << res.message << "; " << res.monodromy.method);
    REQUIRE(fd.result.converged());
    REQUIRE(res.converged());
    REQUIRE(res.monodromy.ok);
    REQUIRE(res.monodromy.method.rfind("sensitivities", 0) == 0);
    int k = 0;
    for (const auto& ev : res.events) k += ev.kind == EventKind::Impact ? 1 : 0;
    REQUIRE(k >= 1);
    const double trace = 2 * p.c_r / p.m_r + (rigid ? 0.0 : 2 * p.c_s / p.m_s);
    const double expected = std::pow(p.e_n, 2 * k) * std::exp(-trace * res.period);
    const Mat& Phi = res.monodromy.M;
    const double nuclear = Eigen::JacobiSVD<Mat>(Mat(Phi.inverse())).singularValues().sum();
    const double bound = nuclear * res.monodromy.error;
    const double rel = std::abs(Phi.determinant() - expected) / expected;
    INFO("det " << Phi.determinant() << ", formula " << expected << ", relative difference " << rel
                << ", bound " << bound);
    // the first-order bound of the test above, from this monodromy's error estimate (the
    // difference of the solves at rtol and rtol / 100); it must be informative: the finite
    // differences' is 1.9e-4 (rigid) and 4.6e-3 (sprung) here; measured 9.7e-7 and 1.7e-5, the
    // differences 8.2e-9 and 4.6e-8. A bound of 1e-4 is 2x and 46x below the former.
    REQUIRE(bound < 1e-4);
    CHECK(rel <= bound);
    // the finite differences' multipliers within the sum of both bounds (measured: 1.7e-8 ..
    // 5.7e-8 apart, the finite differences' bounds ~1e-4)
    for (const auto& f : res.floquet.multipliers) {
      double best = 1e300, err = 0.0;
      for (const auto& g : fd.result.floquet.multipliers)
        if (std::abs(g.value - f.value) < best) best = std::abs(g.value - f.value), err = g.error;
      INFO("multiplier " << f.value << " +- " << f.error << ", finite differences' nearest at "
                         << best << " +- " << err);
      CHECK(best <= f.error + err);
    }
  }
}

namespace {

/// The scene's family in the spin speed, its section at the time t_s, where the spin angle is
/// theta_s at every speed (as `--from` sets it: run.t_start = t_s, initial.theta = theta_s), so
/// that the forcing's phase at the section does not turn with the speed.
ModelFamily speed_family_at(const std::string& text, double t_s, double theta_s) {
  return [text, t_s, theta_s](double omega) {
    const CaseSpec spec =
        parse_case(text, "partial-rub.toml",
                   {"initial.omega0=" + fmt_g(omega), "run.t_start=" + fmt_g(t_s),
                    "run.t_end=" + fmt_g(t_s + 1.0), "initial.theta=" + fmt_g(theta_s)});
    ParameterModel pm;
    pm.model = build_model(spec);
    pm.t0 = t_s;
    pm.omega = omega;
    pm.period = 2 * std::numbers::pi / omega;
    pm.options = event_driven_options(spec);
    return pm;
  };
}

/// The orbit of `periods` forcing periods at omega from a guess at the section t_s, with its
/// monodromy (and Newton's Jacobians) from sensitivities, `samples` samples a period.
OrbitResult orbit_at(const ModelFamily& family, double omega, VecIn guess, int periods = 1,
                     int samples = 2000) {
  static const SensitivityMonodromy sens;
  const ParameterModel pm = family(omega);
  const PeriodMap map(*pm.model, pm.t0, pm.options);
  OrbitOptions o;
  o.provider = &sens;
  o.samples = samples;
  return find_forced_orbit(map, guess, periods * pm.period, pm.omega, o);
}

}  // namespace

// The continuation's section is a time t0, kept while the parameter moves; an event of the orbit
// near it would cross it within a few steps. Started with the section 3 % of a period before the
// impact, the branch (in the spin speed) moves it at once to the middle of the flight, and every
// point after it is the same kind of orbit with its events well away from its section.
TEST_CASE("orbit: a continuation moves its section away from the orbit's events", "[orbit]") {
  Scene p;
  p.rtol = 1e-10;
  p.atol = 1e-13;
  const std::string text = case_text(p);
  CaseOrbitOptions o;
  o.settle = 40;  // as above
  o.orbit.samples = 1;
  const CaseOrbit co = find_case_orbit(parse_case(text, "partial-rub.toml"), o);
  const OrbitResult& res = co.result;
  REQUIRE(res.converged());
  REQUIRE(res.events.size() == 1);  // one impact a period, free flight between
  const double T = res.period;
  const double t_impact = res.events[0].t;  // from t0
  // the section 0.03 T before the impact: the orbit's state there
  const double lead = t_impact > 0.03 * T ? t_impact - 0.03 * T : t_impact + 0.97 * T;
  const PeriodMap map0(*co.model, res.t0, event_driven_options(parse_case(text, "x.toml")));
  const FlowRun to_s = map0.run(res.x0, lead);
  REQUIRE(to_s.complete());
  const double t_s = res.t0 + lead;
  const ModelFamily family = speed_family_at(text, t_s, p.Omega * t_s);
  ContinuationOptions opt;
  opt.lambda_scale = 2.5;  // 1 % of the speed
  opt.ds = 0.2;
  opt.ds_max = 0.5;
  opt.max_points = 4;
  const Branch b = continue_forced_orbit(family, p.Omega, stacked_state(to_s.samples.back()), opt);
  INFO(b.outcome << ": " << b.message);
  REQUIRE(b.points.size() == 4);
  REQUIRE(!b.section_moves.empty());
  CHECK(b.section_moves.front().after == 0);  // before the first step
  CHECK(b.points[0].t0 == t_s);
  for (std::size_t i = 1; i < b.points.size(); ++i) {
    const BranchPoint& q = b.points[i];
    INFO("point " << i << " at " << q.lambda << ", section t0 = " << q.t0);
    CHECK(q.lambda > b.points[i - 1].lambda);  // the tangent kept its orientation
    CHECK(q.t0 == b.section_moves.back().t0);
    CHECK(q.signature == "free | impact | free");
    // its orbit from its section: periodic (the corrector's tolerance, scaled) and the impact
    // at least 0.1 T away from both ends: the middle of a flight that fills the period but for
    // the impact instant, 0.5 T, moved by the few steps since
    const ParameterModel pm = family(q.lambda);
    const PeriodMap m(*pm.model, q.t0, pm.options);
    const FlowRun r = m.run(q.x0, pm.period);
    REQUIRE(r.complete());
    const Vec D = state_scale(*pm.model, pm.omega);
    CHECK(((stacked_state(r.samples.back()) - q.x0).array() / D.array()).abs().maxCoeff() <=
          opt.orbit.tol);
    for (const EventRecord& ev : r.events) {
      CHECK(ev.t - q.t0 >= 0.1 * pm.period);
      CHECK(ev.t - q.t0 <= 0.9 * pm.period);
    }
  }
}

// The frictionless impact oscillator of the scenes above at e_N = 0.8 (one impact a period at
// 250 rad/s): down in the speed a real multiplier leaves through -1 (a period doubling), up a
// second contact appears in the flight (a grazing). Each is located by the continuation and
// checked here on orbits found independently on both sides, with the monodromy from
// sensitivities; from the period doubling's orbit and its multiplier -1's direction, the
// period-2 orbits are found below it.
TEST_CASE(
    "orbit: the continuation locates the impact oscillator's period doubling and grazing, and "
    "switches to the period-2 branch",
    "[orbit]") {
  Scene p;
  p.e_n = 0.8;
  p.rtol = 1e-10;
  p.atol = 1e-13;
  const std::string text = case_text(p);
  CaseOrbitOptions o;
  o.settle = 40;
  o.orbit.samples = 1;
  const CaseOrbit co = find_case_orbit(parse_case(text, "partial-rub.toml"), o);
  REQUIRE(co.result.converged());
  const ModelFamily family = speed_family_at(text, co.result.t0, p.Omega * co.result.t0);
  ContinuationOptions opt;
  opt.lambda_scale = 2.5;
  opt.ds = 0.5;
  opt.ds_max = 2.0;
  opt.max_points = 40;
  opt.direction = -1;
  const Branch down = continue_forced_orbit(family, p.Omega, co.result.x0, opt);
  INFO("down: " << down.outcome << ": " << down.message);
  const BranchSpecial* pd = nullptr;
  for (const auto& s : down.specials)
    if (s.kind == "period_doubling") pd = &s;
  REQUIRE(pd != nullptr);
  INFO("period doubling at " << pd->lambda << " +- " << pd->spread << ": " << pd->how);
  // det(Phi + I) on orbits 1e-4 rad/s on either side (Newton from the point before the
  // crossing, the monodromy from sensitivities): opposite signs, and its zero by linear
  // interpolation
  const BranchPoint& before = down.points[static_cast<std::size_t>(pd->after)];
  const double off = 1e-4;
  double g[2];
  for (int side = 0; side < 2; ++side) {
    const double w = pd->lambda + (side == 0 ? -off : off);
    const OrbitResult r = orbit_at(family, w, before.x0);
    REQUIRE(r.converged());
    REQUIRE(r.monodromy.method.rfind("sensitivities", 0) == 0);
    const Mat& M = r.monodromy.M;
    g[side] = (M + Mat::Identity(M.rows(), M.cols())).determinant();
  }
  INFO("det(Phi + I) = " << g[0] << " and " << g[1] << " at -+ " << off);
  REQUIRE(g[0] * g[1] < 0.0);
  const double zero = pd->lambda - off + 2 * off * g[0] / (g[0] - g[1]);
  INFO("the sensitivities' zero " << std::setprecision(12) << zero << ", the located "
                                  << pd->lambda);
  {
    // the same branch with every point's monodromy from the sensitivities: its period doubling
    // is located on their det(Phi + I), whose error (the monodromy's, ~1e-6) over the slope 0.39
    // per rad/s is ~3e-6 rad/s, as is the zero's above: bound 2e-5 rad/s (measured 1e-8)
    static const SensitivityMonodromy sensitivities;
    ContinuationOptions so = opt;
    so.orbit.provider = &sensitivities;
    const Branch ds = continue_forced_orbit(family, p.Omega, co.result.x0, so);
    INFO("down, sensitivities: " << ds.outcome << ": " << ds.message);
    const BranchSpecial* pds = nullptr;
    for (const auto& s : ds.specials)
      if (s.kind == "period_doubling") pds = &s;
    REQUIRE(pds != nullptr);
    INFO("located there at " << std::setprecision(12) << pds->lambda << " +- " << pds->spread);
    CHECK(std::abs(pds->lambda - zero) <= 2e-5);
    CHECK(ds.points[1].monodromy.method.rfind("sensitivities", 0) == 0);
  }
  // The continuation's regula falsi evaluates det(Phi + I) with finite-difference monodromies
  // (error ~1e-4 near there) on a slope of 0.39 per rad/s: a bound of 3e-4 rad/s; measured
  // 3.8e-7 from the sensitivities' zero (whose own error, ~1e-6 / 0.39, is below that)
  CHECK(std::abs(zero - pd->lambda) <= 3e-4);

  // branch switching: the period-2 orbit from the period doubling's orbit moved along the
  // direction of its multiplier -1, with the period doubled, on the side where the period-1
  // orbit is unstable (below: its real multiplier < -1 there)
  REQUIRE(pd->x.size() == 4);
  REQUIRE(pd->direction.size() == 4);
  double split[2], mu2[2];
  const double below[2] = {0.2, 0.05};
  for (int k = 0; k < 2; ++k) {
    const double w = pd->lambda - below[k];
    const ParameterModel pm = family(w);
    const PeriodMap map(*pm.model, pm.t0, pm.options);
    const Vec D = state_scale(*pm.model, pm.omega);
    const OrbitResult r2 = orbit_at(family, w, Vec(pd->x + 0.05 * pd->direction), 2, 0);
    INFO("period 2 at " << w << ": " << r2.message << "; " << r2.floquet.reason);
    REQUIRE(r2.converged());
    const FlowRun one = map.run(r2.x0, pm.period);
    REQUIRE(one.complete());
    // a period-2 orbit, not the period-1 orbit counted twice: one period moves it by far more
    // than Newton's tolerance; two impacts in its period; stable (a supercritical doubling)
    split[k] = ((stacked_state(one.samples.back()) - r2.x0).array() / D.array()).abs().maxCoeff();
    mu2[k] = std::abs(r2.floquet.multipliers.front().value);
    INFO("split " << split[k] << ", largest multiplier " << mu2[k]);
    CHECK(split[k] > 1e4 * OrbitOptions{}.tol);
    CHECK(r2.events.size() == 2);
    CHECK(r2.floquet.stability == Stability::Stable);
  }
  // The period-2 orbits branch off as sqrt(lambda_PD - lambda): the splits 0.2 and 0.05 rad/s
  // below are in the ratio 2 (measured 0.0848 and 0.0428: 1.98; the next term is O(lambda_PD -
  // lambda) relative, a few %: bound 10 %), and their largest multiplier goes to +1 linearly
  // (the square of the period-1 orbit's -1): 1 - mu in the ratio 4 (measured 0.523 and 0.887:
  // 4.2; bound 20 %)
  CHECK(std::abs(split[0] / split[1] / 2.0 - 1.0) <= 0.1);
  CHECK(std::abs((1.0 - mu2[0]) / (1.0 - mu2[1]) / 4.0 - 1.0) <= 0.2);

  // up: the grazing of the flight (a second contact appears)
  opt.direction = +1;
  const Branch up = continue_forced_orbit(family, p.Omega, co.result.x0, opt);
  INFO("up: " << up.outcome << ": " << up.message);
  REQUIRE(up.outcome == "events_change");
  const BranchSpecial& gr = up.specials.back();
  REQUIRE(gr.kind == "events_change");
  REQUIRE(gr.how.find("grazing (a new contact in the flight) at") != std::string::npos);
  INFO("grazing at " << std::setprecision(12) << gr.lambda << " +- " << gr.spread);
  // orbits 1e-3 and 2e-3 rad/s before it: one impact, a flight whose closest approach (the
  // smallest interior minimum of the gap over 2000 samples, refined by a parabola) is above 0,
  // and its linear extrapolation to 0
  const BranchPoint& last = up.points[static_cast<std::size_t>(gr.after)];
  double dip[2];
  const double deltas[2] = {2e-3, 1e-3};
  for (int k = 0; k < 2; ++k) {
    const double w = gr.lambda - deltas[k];
    const OrbitResult r = orbit_at(family, w, last.x0);
    INFO("the orbit at " << w << ": " << r.message);
    REQUIRE(r.converged());
    REQUIRE(r.events.size() == 1);
    const auto& sm = r.orbit.samples;
    dip[k] = 1e300;
    for (std::size_t i = 1; i + 1 < sm.size(); ++i) {
      const double y0 = sm[i - 1].contacts[0].d_N, y1 = sm[i].contacts[0].d_N,
                   y2 = sm[i + 1].contacts[0].d_N;
      if (sm[i - 1].t == sm[i].t || sm[i].t == sm[i + 1].t || !(y0 > y1 && y2 > y1)) continue;
      dip[k] = std::min(dip[k], y1 - (y2 - y0) * (y2 - y0) / (8.0 * (y0 - 2.0 * y1 + y2)));
    }
    INFO("at " << w << " the flight's closest approach " << dip[k]);
    CHECK(dip[k] > 0.0);
  }
  const double at_zero =
      gr.lambda - deltas[1] + (deltas[0] - deltas[1]) * dip[1] / (dip[0] - dip[1]);
  INFO("the closest approach extrapolated to 0 at " << std::setprecision(12) << at_zero);
  // The located grazing is the continuation's extrapolation from its last three points of the
  // closest approach on 50 samples a period (each refined by a parabola, exact to O(dt^4));
  // these orbits sample 2000 a period, their closest approaches 7.05e-9 and 3.53e-9 m (linear:
  // ratio 2.0). Bound: the spread of the located value's two estimates (2.9e-6 rad/s) plus
  // 1e-5 rad/s for this extrapolation's own curvature; measured 2.4e-6 rad/s apart.
  CHECK(std::abs(at_zero - gr.lambda) <= gr.spread + 1e-5);
}
