#include "rubdyn/analysis/continuation.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>

namespace rubdyn {

namespace {

// The parameter step of G_lambda's central differences, in units of s_lambda: the same as the
// state's first finite-difference step (1e-3 of its scale), where the differences of the
// return map are truncation- or noise-limited at about 1e-3 .. 1e-5 (docs/orbits.md, 4).
constexpr double kLambdaStep = 1e-3;
// A special point is located by successive parabolic interpolation of lambda (fold) or of the
// crossing multiplier (the others) in the arclength between the two points that bracket it,
// stopping when the arclength moves by less than this fraction of the bracket, or after
// kLocateIterations corrector solves.
constexpr double kLocateRel = 1e-4;
constexpr int kLocateIterations = 8;
// A multiplier is real when its imaginary part is below this (eigenvalues of a real matrix
// come in exact conjugate pairs, and Eigen returns real ones with a zero imaginary part).
constexpr double kRealImag = 0.0;
// A forced orbit's section is a time t0, which the continuation keeps while the parameter moves;
// an event of the orbit that comes this close to it (a fraction of the period, either side)
// would cross it within a few steps, which changes the event signature (and the map's
// smoothness) for a reason that has nothing to do with the orbit, and brings the finite
// differences' perturbations near it: the section is then moved to the middle of the longest
// stretch of free flight between events (move_section). 10 %: on the paper's rotor's branch
// the events move by up to 0.04 T from one point to the next, and a lift-off 0.05 T before the
// section already made the monodromy's error 4 (an undecided point).
constexpr double kSectionClearance = 0.1;

/// The orbit at one point: its chart, monodromy, G_lambda, tangent and books.
struct PointData {
  BranchPoint p;
  std::unique_ptr<SectionChart> chart;
  Mat J;  // d x (d + 1): [Phi - I, G_lambda s_lambda]
  Vec t;  // unit tangent (d + 1), in this chart's coordinates
  /// The orbit's events after the section, as offsets from it in (0, T) (the decision at the
  /// section is its start, not an event), each with whether every contact is free after it
  std::vector<std::pair<double, bool>> event_offsets;
  /// An autonomous orbit's unknowns: the section coordinate fixed by the phase condition (it
  /// is left out of u, whose component d - 1 is the period per T_ref instead); -1: forced
  int phase = -1;
  double T_ref = 0.0;
};

/// The section coordinates, the period and the parameter of the unknowns u of the point `from`
/// (u = (xi, lambda / s) for a forced orbit, (xi without the phase coordinate, T / T_ref,
/// lambda / s) for an autonomous one; the period NaN for a forced orbit: the family's).
void unpack(const PointData& from, VecIn u, double lambda_scale, Vec& xi, double& T,
            double& lambda) {
  const int d = static_cast<int>(u.size()) - 1;
  lambda = u(d) * lambda_scale;
  if (from.phase < 0) {
    xi = u.head(d);
    T = std::numeric_limits<double>::quiet_NaN();
    return;
  }
  xi.resize(d);
  for (int i = 0, k = 0; i < d; ++i) xi(i) = i == from.phase ? 0.0 : u(k++);
  T = u(d - 1) * from.T_ref;
}

/// The unknowns, in the point `at`'s coordinates, of the orbit through x (period T) at lambda.
Vec pack(const PointData& at, VecIn x, double T, double lambda, double lambda_scale) {
  const Vec xi = at.chart->coords(x);
  const int d = static_cast<int>(xi.size());
  Vec u(d + 1);
  if (at.phase < 0) {
    u.head(d) = xi;
  } else {
    for (int i = 0, k = 0; i < d; ++i)
      if (i != at.phase) u(k++) = xi(i);
    u(d - 1) = T / at.T_ref;
  }
  u(d) = lambda / lambda_scale;
  return u;
}

struct Eval {
  bool ok = false;
  std::string why;
  bool penetrates = false;  // the state lies inside a stator (beyond a grazing): not run
  bool refused = false;     // the model refuses the parameter's value (a bound of the key)
  FlowRun run;
  std::string signature;  // the run's events (event_signature)
  Vec G;                  // coords(P(x)) - coords(x)
};

Eval evaluate(const ModelFamily& family, const SectionChart& chart, VecIn xi, double lambda,
              long& runs, double T = std::numeric_limits<double>::quiet_NaN()) {
  Eval e;
  ParameterModel pm;
  try {
    pm = family(lambda);
  } catch (const std::exception& ex) {
    e.why = fmt::format("the model at {:.10g}: {}", lambda, ex.what());
    e.refused = true;
    return e;
  }
  Vec x;
  if (!chart.embed_on(*pm.model, xi, x)) {
    e.why =
        fmt::format("the state could not be put on the section's constraints at {:.10g}", lambda);
    return e;
  }
  // an iterate beyond a grazing of the free orbits it continues lies inside the stator: the
  // switching surface is crossed, as when an iterate's events change
  const double t0 = chart.time();  // the section's time: the point's, not the family's
  if (const auto pen = penetrates_open_contact(*pm.model, chart, t0, x)) {
    e.penetrates = true;
    e.signature =
        fmt::format("inside contact {}'s stator, d_N = {:.3g} m", pen->contact + 1, pen->d_N);
    e.why = fmt::format("the state at {:.10g} lies {}", lambda, e.signature);
    return e;
  }
  const PeriodMap map(*pm.model, t0, pm.options);
  e.run = map.run(x, std::isnan(T) ? pm.period : T);
  ++runs;
  if (!e.run.complete()) {
    e.why = fmt::format("a run at {:.10g} ended early ({}): {}", lambda,
                        to_string(e.run.summary.termination), e.run.summary.message);
    return e;
  }
  e.signature = event_signature(e.run, t0);
  e.G = chart.coords(stacked_state(e.run.samples.back())) -
        chart.coords(stacked_state(e.run.samples.front()));
  e.ok = true;
  return e;
}

/// The minimum of the parabola through three equally spaced values y0, y1, y2 that have a strict
/// minimum at y1 (NaN when they do not): the refinement of a sampled minimum, exact to O(dt^4)
/// where the samples are O(dt^2) off.
double parabola_minimum(double y0, double y1, double y2) {
  const double curv = y0 - 2.0 * y1 + y2;
  if (!(y0 > y1 && y2 > y1 && curv > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return y1 - (y2 - y0) * (y2 - y0) / (8.0 * curv);
}

/// The state scale of a point's orbit: velocities per the spin speed (forced), per the orbit's
/// own frequency 2 pi / T (autonomous, as find_case_orbit does).
Vec point_scale(const ParameterModel& pm, double period) {
  return state_scale(*pm.model, pm.autonomous ? 2.0 * std::numbers::pi / period : pm.omega);
}

/// Contact 1's smallest gap over a sampled period (samples on a uniform grid from t0 to t0 + T,
/// the last the first's state again; both sides of an event where there are events): the
/// smallest sample's gap, refined where it is a strict local minimum between its grid
/// neighbours (the period wrapping around) by the vertex of the parabola through the three. The
/// gap is smooth in free flight, so the vertex is the minimum to O(dt^4) where a sample is off
/// by O(dt^2): what locating a grazing from the branch's last free orbits needs.
double smallest_gap(const std::vector<Sample>& s) {
  const std::size_t n = s.size();
  if (n == 0) return 0.0;
  std::size_t i = 0;
  for (std::size_t k = 1; k < n; ++k)
    if (s[k].contacts[0].d_N < s[i].contacts[0].d_N) i = k;
  const double y1 = s[i].contacts[0].d_N;
  // the neighbours on the grid: the first and the last sample are one state (wrap past them)
  if (n < 4) return y1;
  const std::size_t prev = i == 0 ? n - 2 : i - 1, next = i + 1 < n ? i + 1 : 1;
  const auto grid = [&](std::size_t a, std::size_t b) {  // b one grid step after a
    const double dt = s[1].t - s[0].t;
    double d = s[b].t - s[a].t;
    if (d < 0) d += s[n - 1].t - s[0].t;
    return std::abs(d - dt) <= 1e-9 * std::abs(dt);
  };
  if (!grid(prev, i) || !grid(i, next)) return y1;  // (an event's rows: not a grid)
  const double v = parabola_minimum(s[prev].contacts[0].d_N, y1, s[next].contacts[0].d_N);
  return std::isnan(v) ? y1 : v;
}

/// Contact 1's smallest strict local minimum of the gap at a sample of a free stretch (both
/// grid neighbours free, on the grid, not at an event), refined by the vertex of the parabola
/// through the three: a flight's closest approach away from its contacts; NaN when there is none.
double gap_dip(const std::vector<Sample>& s) {
  double best = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 1; i + 1 < s.size(); ++i) {
    const Sample &a = s[i - 1], &m = s[i], &b = s[i + 1];
    if (a.t == m.t || m.t == b.t) continue;                                  // an event's rows
    if (std::abs((b.t - m.t) - (m.t - a.t)) > 1e-9 * (b.t - a.t)) continue;  // not the grid
    if (a.contacts[0].phase != Phase::Free || m.contacts[0].phase != Phase::Free ||
        b.contacts[0].phase != Phase::Free)
      continue;
    const double v = parabola_minimum(a.contacts[0].d_N, m.contacts[0].d_N, b.contacts[0].d_N);
    if (!std::isnan(v) && !(v >= best)) best = v;
  }
  return best;
}

/// The monodromy at the chart's origin: the options' provider (the flow's sensitivities), or the
/// finite differences at the options' steps.
Monodromy point_monodromy(const ContinuationOptions& opt, const PeriodMap& map, double period,
                          const SectionChart& chart, const FlowRun& run) {
  const Vec zero = Vec::Zero(chart.dim());
  if (opt.orbit.provider) return opt.orbit.provider->compute(map, period, chart, zero, run);
  return FiniteDifferenceMonodromy(opt.orbit.fd_steps).compute(map, period, chart, zero, run);
}

/// Everything about the orbit through x at lambda (x on its section's constraints), its section
/// at the time t0 (NaN: the family's).
bool make_point(const ModelFamily& family, double lambda, VecIn x, const ContinuationOptions& opt,
                PointData& out, std::string& why, long& runs, const std::string* expect = nullptr,
                double t0 = std::numeric_limits<double>::quiet_NaN(),
                double T = std::numeric_limits<double>::quiet_NaN()) {
  ParameterModel pm = family(lambda);
  if (std::isnan(t0)) t0 = pm.t0;
  // the period: the family's (forced), or the orbit's own (autonomous: found with it)
  const double period = std::isnan(T) ? pm.period : T;
  const PeriodMap map(*pm.model, t0, pm.options);
  const FlowRun run = map.run(x, period);
  ++runs;
  if (!run.complete()) {
    why =
        fmt::format("the run on the point at {:.10g} ended early: {}", lambda, run.summary.message);
    return false;
  }
  const Vec xs = stacked_state(run.samples.front());
  out.p.t0 = t0;
  out.event_offsets.clear();
  for (const EventRecord& ev : run.events) {
    if (!(ev.t > t0 && ev.t < t0 + period)) continue;
    if (!out.event_offsets.empty() && out.event_offsets.back().first == ev.t - t0) continue;
    // the phases after the event: the last sample at its time
    bool free = true;
    for (auto it = run.samples.rbegin(); it != run.samples.rend(); ++it)
      if (it->t == ev.t) {
        for (const ContactSample& c : it->contacts) free = free && c.phase == Phase::Free;
        break;
      }
    out.event_offsets.push_back({ev.t - t0, free});
  }
  {
    bool free = true;  // at the section: the phases the run started in
    for (const Phase ph : start_phases(run)) free = free && ph == Phase::Free;
    double t_prev = 0.0;
    out.p.free_time = 0.0;
    for (const auto& [o, f] : out.event_offsets) {
      if (free) out.p.free_time += o - t_prev;
      t_prev = o;
      free = f;
    }
    if (free) out.p.free_time += period - t_prev;
  }
  out.p.impact_speed_min = std::numeric_limits<double>::quiet_NaN();
  for (const EventRecord& ev : run.events)
    if (ev.kind == EventKind::Impact && ev.t > t0 && ev.t < t0 + period &&
        !(std::abs(ev.v_N_minus) >= out.p.impact_speed_min))
      out.p.impact_speed_min = std::abs(ev.v_N_minus);
  if (expect && event_signature(run, t0) != *expect) {
    // the orbit's events changed (a grazing, a lift-off at the section): no chart of the
    // previous phases, no smooth continuation; the point is reported as it is
    out.p.lambda = lambda;
    out.p.period = period;
    out.p.x0 = xs;
    out.p.signature = event_signature(run, t0);
    out.p.floquet.reason = "not computed: the orbit's events changed";
    out.chart.reset();
    return true;
  }
  const Vec D = point_scale(pm, period);
  out.chart = std::make_unique<SectionChart>(*pm.model, t0, xs, start_phases(run), D,
                                             pm.autonomous ? pm.pinned : std::vector<int>{});
  const SectionChart& chart = *out.chart;
  const int d = chart.dim();
  const Vec zero = Vec::Zero(d);
  const int samples = std::max(8, opt.orbit.samples);
  const FlowRun sampled = map.run(xs, period, period / samples);
  ++runs;
  if (!sampled.complete() || sampled.samples.size() < 2) {
    why = fmt::format("the sampled run on the point at {:.10g} ended early", lambda);
    return false;
  }
  out.phase = -1;
  out.T_ref = period;
  if (pm.autonomous) {
    // the phase condition: the section coordinate along which the flow moves fastest
    Eigen::Index j = 0;
    for (const Sample& smp : sampled.samples)
      if (smp.t > t0) {
        chart.coords(stacked_state(smp)).cwiseAbs().maxCoeff(&j);
        break;
      }
    out.phase = static_cast<int>(j);
  }
  const FiniteDifferenceMonodromy fd(opt.orbit.fd_steps);
  const long runs_before = map.runs();
  Monodromy m = point_monodromy(opt, map, period, chart, run);
  const Mat tangent = chart.tangent(zero);
  FloquetAnalysis fl = floquet_analysis(m, tangent, D, pm.autonomous);
  // (the finite differences' refinements: the sensitivities' error is the integration's)
  for (int k = 0;
       !opt.orbit.provider && k < opt.orbit.fd_refinements &&
       fl.stability == Stability::Undecided && fd.refine(map, period, chart, zero, run, m);
       ++k)
    fl = floquet_analysis(m, tangent, D, pm.autonomous);
  runs += map.runs() - runs_before;
  if (!m.ok) {
    why = "the monodromy at " + fmt::format("{:.10g}", lambda) + ": " + m.failure;
    return false;
  }
  // G_lambda by central differences at the same state (and period); next to a value the model
  // refuses (a key's bound, mu >= 0) by the one-sided second-order difference away from it
  const double Tg = pm.autonomous ? period : std::numeric_limits<double>::quiet_NaN();
  const double h = kLambdaStep * opt.lambda_scale;
  const Eval ep = evaluate(family, chart, zero, lambda + h, runs, Tg);
  const Eval em = evaluate(family, chart, zero, lambda - h, runs, Tg);
  Vec G_lambda;
  if (ep.ok && em.ok) {
    G_lambda = (ep.G - em.G) / (2.0 * h);
  } else if (ep.refused != em.refused && (ep.ok || em.ok)) {
    const double side = em.refused ? 1.0 : -1.0;
    const Eval e2 = evaluate(family, chart, zero, lambda + 2.0 * side * h, runs, Tg);
    if (!e2.ok) {
      why = "G_lambda: " + e2.why;
      return false;
    }
    const Vec G0 = chart.coords(stacked_state(run.samples.back()));  // (coords(xs) = 0)
    G_lambda = side * (-3.0 * G0 + 4.0 * (em.refused ? ep.G : em.G) - e2.G) / (2.0 * h);
  } else {
    why = "G_lambda: " + (ep.ok ? em.why : ep.why);
    return false;
  }
  out.J.resize(d, d + 1);
  const Mat A = m.M - Mat::Identity(d, d);
  if (out.phase < 0) {
    out.J.leftCols(d) = A;
  } else {
    // the phase coordinate's column replaced by d G / d(T / T_ref), central differences in T
    for (int i = 0, k = 0; i < d; ++i)
      if (i != out.phase) out.J.col(k++) = A.col(i);
    const double hT = opt.orbit.newton_step;
    const Eval tp = evaluate(family, chart, zero, lambda, runs, period * (1.0 + hT));
    const Eval tm = evaluate(family, chart, zero, lambda, runs, period * (1.0 - hT));
    if (!tp.ok || !tm.ok) {
      why = "G_T: " + (tp.ok ? tm.why : tp.why);
      return false;
    }
    out.J.col(d - 1) = (tp.G - tm.G) / (2.0 * hT);
  }
  out.J.col(d) = G_lambda * opt.lambda_scale;
  const Eigen::JacobiSVD<Mat> svd(out.J, Eigen::ComputeFullV);
  out.t = svd.matrixV().col(d);
  // the sampled period: amplitude and forces
  BranchPoint& p = out.p;
  p.lambda = lambda;
  p.period = period;
  p.x0 = xs;
  p.residual = chart.scaled_distance(xs, stacked_state(run.samples.back()));
  p.monodromy = std::move(m);
  p.floquet = std::move(fl);
  p.signature = event_signature(run, t0);
  p.F_N_min = std::numeric_limits<double>::infinity();
  p.F_N_max = 0.0;
  p.cone_min = std::numeric_limits<double>::quiet_NaN();
  const double mu = pm.model->contact_law(0).mu;
  for (const Sample& s : sampled.samples) {
    if (s.contacts[0].phase == Phase::Stick) {
      const double margin = mu * s.contacts[0].F_N - std::abs(s.contacts[0].F_T);
      if (!(margin >= p.cone_min)) p.cone_min = margin;
    }
    PlaneMotion pl;
    if (pm.model->plane_motion(0, s.t, s.q, s.v, pl))
      p.amplitude = std::max(p.amplitude, pl.rotor.norm());
    p.F_N_max = std::max(p.F_N_max, s.contacts[0].F_N);
    p.F_N_min = std::min(p.F_N_min, s.contacts[0].F_N);
  }
  p.d_N_min = smallest_gap(sampled.samples);
  p.d_N_dip = gap_dip(sampled.samples);
  return true;
}

/// The real multiplier nearest to `target` (+1 or -1), or NaN.
double nearest_real(const FloquetAnalysis& f, double target) {
  double best = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < f.multipliers.size(); ++i) {
    const auto& m = f.multipliers[i];
    if (static_cast<int>(i) == f.trivial) continue;  // an autonomous orbit's flow direction
    if (std::abs(m.value.imag()) > kRealImag) continue;
    if (std::isnan(best) || std::abs(m.value.real() - target) < std::abs(best - target))
      best = m.value.real();
  }
  return best;
}

/// The multipliers outside the unit circle: all, and the complex ones.
std::pair<int, int> outside(const FloquetAnalysis& f) {
  int all = 0, complex = 0;
  for (const auto& m : f.multipliers)
    if (std::abs(m.value) > 1.0) {
      ++all;
      if (std::abs(m.value.imag()) > kRealImag) ++complex;
    }
  return {all, complex};
}

/// A Neimark-Sacker point between two points: the multipliers outside the circle change in
/// number, and by as many complex ones (a complex pair outside that meets on the real axis and
/// splits into two real multipliers outside changes only the complex count: no crossing).
bool neimark_sacker_between(const FloquetAnalysis& a, const FloquetAnalysis& b) {
  const auto [na, ca] = outside(a);
  const auto [nb, cb] = outside(b);
  return na != nb && nb - na == cb - ca;
}

/// The corrector from point `from` at arclength s along its tangent: u with G(u) = 0 and
/// t . (u - u_from) = s. Returns false when it does not converge.
struct Corrected {
  Vec u;
  double T = 0.0;  ///< the period of the corrected orbit
  Eval eval;
  int iterations = 0;
  /// An iterate whose orbit has other events than the point corrected from (a grazing or a
  /// lift-off crossed): its parameter and events, kept when the corrector fails.
  bool events_changed = false;
  double changed_lambda = 0.0;
  std::string changed_signature;
};
bool correct(const ModelFamily& family, const PointData& from, double s,
             const ContinuationOptions& opt, Corrected& out, std::string& why, long& runs) {
  const SectionChart& chart = *from.chart;
  const int d = chart.dim();
  const Vec u0 = pack(from, from.p.x0, from.p.period, from.p.lambda, opt.lambda_scale);
  const Vec up = u0 + s * from.t;
  Mat A(d + 1, d + 1);
  A.topRows(d) = from.J;
  A.row(d) = from.t.transpose();
  Vec u = up;
  // Newton with point i's Jacobian (and the arclength row), improved by Broyden's updates
  Vec F_prev, step_prev, xi;
  double T, lam;
  for (int it = 0; it < opt.max_corrector; ++it) {
    unpack(from, u, opt.lambda_scale, xi, T, lam);
    Eval e = evaluate(family, chart, xi, lam, runs, T);
    if (!e.ok) {
      if (e.penetrates && !out.events_changed) {
        out.events_changed = true;
        out.changed_lambda = u(d) * opt.lambda_scale;
        out.changed_signature = e.signature;
      }
      why = e.why;
      return false;
    }
    if (e.signature != from.p.signature && !out.events_changed) {
      out.events_changed = true;
      out.changed_lambda = u(d) * opt.lambda_scale;
      out.changed_signature = e.signature;
    }
    Vec F(d + 1);
    F.head(d) = e.G;
    F(d) = from.t.dot(u - up);
    if (F_prev.size())
      A += ((F - F_prev) - A * step_prev) * step_prev.transpose() / step_prev.squaredNorm();
    const double res = e.G.size() ? e.G.cwiseAbs().maxCoeff() : 0.0;
    if (res <= opt.orbit.tol) {
      out.u = u;
      out.T = T;
      out.eval = std::move(e);
      out.iterations = it;
      return true;
    }
    const Vec step = A.colPivHouseholderQr().solve(-F);
    if (!all_finite(step)) {
      why = "the corrector's system is singular";
      return false;
    }
    u += step;
    F_prev = F;
    step_prev = step;
  }
  why = fmt::format("the corrector did not converge in {} iterations at ds = {:.3g}",
                    opt.max_corrector, s);
  return false;
}

/// Where a smooth branch meets a switching surface, extrapolated from its last smooth points
/// `pts` (up to three): a lift-off where its orbits are in contact throughout their period (the
/// contact force's minimum over the period, F_N_min, falls towards zero), a grazing where they are
/// free throughout (the gap's minimum over the period, d_N_min, falls towards zero), the
/// vanishing of the free flight where they are partly free (the square of the time free per
/// period falls towards zero: the lift-off meets the impact, full rub beyond). The secant of
/// that minimum over lambda through the last two points, and the parabola through the last three;
/// the special `s` that ends the branch takes the parabola's root nearest the last point (the
/// secant's with two points) as its value, the two estimates' difference as its spread, and says
/// so in `how`. Where the points allow neither (mixed, or the minimum not falling), `s` is left
/// as it is.
/// The root nearest the last of lambda of F (falling towards it) through the last points
/// (l, F): the parabola's through three, else the secant's; `secant` the secant's, `spread` the
/// two's difference (without a parabola's root: the secant's whole reach beyond the last point).
/// False when F does not fall towards the last point.
bool extrapolate_root(const std::vector<double>& l, const std::vector<double>& F, double& root,
                      double& secant, double& spread) {
  const std::size_t n = l.size(), e = n - 1;
  if (n < 2 || !(F[e] < F[e - 1]) || l[e] == l[e - 1]) return false;
  secant = l[e] - F[e] * (l[e] - l[e - 1]) / (F[e] - F[e - 1]);
  root = secant;
  spread = std::abs(secant - l[e]);
  if (n == 3 && l[0] != l[1] && l[0] != l[2]) {
    // Newton's form of the parabola F(x) through the three, its root nearest l[e]
    const double d1 = (F[1] - F[0]) / (l[1] - l[0]), d2 = (F[2] - F[1]) / (l[2] - l[1]);
    const double c2 = (d2 - d1) / (l[2] - l[0]);
    // F(x) = F[2] + b (x - l[2]) + c2 (x - l[2])^2 with b = d2 + c2 (l[2] - l[1])
    const double b = d2 + c2 * (l[2] - l[1]);
    if (c2 != 0.0) {
      const double disc = b * b - 4.0 * c2 * F[2];
      if (disc >= 0.0) {
        const double r1 = (-b + std::sqrt(disc)) / (2.0 * c2),
                     r2 = (-b - std::sqrt(disc)) / (2.0 * c2);
        root = l[2] + (std::abs(r1) < std::abs(r2) ? r1 : r2);
        spread = std::abs(root - secant);
      }
    } else {
      spread = 0.0;  // the three on a line: the parabola is the secant
    }
  }
  return std::isfinite(root);
}

void locate_end(const std::vector<PointData>& pts, BranchSpecial& s) {
  const std::size_t n = std::min<std::size_t>(pts.size(), 3);
  if (n < 2) return;
  // the quantities whose zero is a switching surface, where the last points all have them:
  // contact throughout (the contact force's minimum: lift-off), free throughout (the gap's
  // minimum: grazing), impacts (the slowest impact's speed, squared: a grazing impact, where the
  // impact's speed ~ sqrt(lambda - lambda_c)), partly free (the flight's duration, squared:
  // a flight between a lift-off and an impact has a gap ~ t (tau - t), and tau ~ sqrt(lambda -
  // lambda_c) where the slide's smallest contact force touches 0), a gap minimum in free flight
  // away from the contacts (grazing: a new contact appears), the friction cone's margin mu F_N -
  // |F_T| where the contact sticks (the stick breaks into slip). Of those that fall towards the
  // last point, the one whose zero comes first.
  enum Q { Contact, Free, Impact, Flight, Dip, Cone };
  bool has[6] = {true, true, true, true, true, true};
  for (std::size_t k = pts.size() - n; k < pts.size(); ++k) {
    const BranchPoint& p = pts[k].p;
    has[Contact] = has[Contact] && p.F_N_min > 0.0 && std::isfinite(p.F_N_min);
    has[Free] = has[Free] && p.F_N_max == 0.0 && p.d_N_min > 0.0 && std::isfinite(p.d_N_min) &&
                std::isnan(p.impact_speed_min);
    has[Impact] = has[Impact] && p.impact_speed_min > 0.0 && std::isfinite(p.impact_speed_min);
    has[Flight] = has[Flight] && p.free_time > 0.0 && p.free_time < p.period;
    has[Dip] = has[Dip] && p.d_N_dip > 0.0 && std::isfinite(p.d_N_dip);
    has[Cone] = has[Cone] && p.cone_min > 0.0 && std::isfinite(p.cone_min);
  }
  if (has[Contact] || has[Free]) has[Impact] = has[Flight] = has[Dip] = false;
  int best = -1;
  double best_root = 0.0, best_secant = 0.0, best_spread = 0.0, best_last = 0.0;
  std::vector<double> l;
  for (std::size_t k = pts.size() - n; k < pts.size(); ++k) l.push_back(pts[k].p.lambda);
  std::vector<std::pair<int, double>> roots;  // every quantity's estimate
  for (int q = 0; q < 6; ++q) {
    if (!has[q]) continue;
    std::vector<double> F;
    for (std::size_t k = pts.size() - n; k < pts.size(); ++k) {
      const BranchPoint& p = pts[k].p;
      F.push_back(q == Contact  ? p.F_N_min
                  : q == Free   ? p.d_N_min
                  : q == Impact ? p.impact_speed_min * p.impact_speed_min
                  : q == Flight ? p.free_time * p.free_time
                  : q == Dip    ? p.d_N_dip
                                : p.cone_min);
    }
    double root, secant, spread;
    if (!extrapolate_root(l, F, root, secant, spread)) continue;
    roots.push_back({q, root});
    if (best < 0 || std::abs(root - l.back()) < std::abs(best_root - l.back()))
      best = q, best_root = root, best_secant = secant, best_spread = spread, best_last = F.back();
  }
  if (best < 0) return;
  s.lambda = best_root;
  s.spread = best_spread;
  static const char* what[] = {"the contact force's minimum over the period, {:.6g} N",
                               "the gap's minimum over the period, {:.6g} m",
                               "the slowest impact's closing speed squared, {:.6g} m^2/s^2",
                               "the square of the free flight's duration per period, {:.6g} s^2",
                               "the smallest gap minimum in free flight, {:.6g} m",
                               "the friction cone's smallest margin in stick, {:.6g} N"};
  static const char* end[] = {"lift-off",
                              "grazing",
                              "grazing impact (the impact's speed vanishes)",
                              "the flight vanishes (its lift-off meets its impact)",
                              "grazing (a new contact in the flight)",
                              "slip onset (the stick breaks)"};
  s.how += "; " + fmt::format(fmt::runtime(what[best]), best_last) +
           fmt::format(
               " at the last point, extrapolated to zero from the last {} smooth points: "
               "{} at {:.10g} (secant {:.10g}, estimates {:.2g} apart)",
               n, end[best], best_root, best_secant, s.spread);
  for (const auto& [q, r] : roots)
    if (q != best)
      s.how += fmt::format("; from {} instead: {:.10g}",
                           std::string(what[q]).substr(0, std::string(what[q]).find(',')), r);
}

/// Where to move the section of an orbit with an event within kSectionClearance of a period of
/// it (`off`: the events' offsets from the section, in (0, T), increasing, each with whether the
/// orbit is free after it): the middle of the longest stretch of the period between two events
/// in free flight (when its middle is kSectionClearance from them), else of the longest stretch,
/// as an offset in (0, T) from the section; NaN when no event is that near, or when the move
/// would not double the events' distance from the section. A section in free flight has the
/// identity as its chart; one in a contact phase charts the constraint manifold (a circle in the
/// relative position) linearly, which the corrector's steps along the branch can carry beyond where
/// it is one-to-one.
double new_section_offset(const std::vector<std::pair<double, bool>>& off, double T) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (off.empty()) return nan;
  const double clearance = std::min(off.front().first, T - off.back().first);
  if (clearance >= kSectionClearance * T) return nan;
  // the longest stretch in free flight when its middle clears the events by kSectionClearance,
  // else the longest
  double best_len = -1.0, best_mid = 0.0;
  for (const bool free_only : {true, false}) {
    for (std::size_t k = 0; k < off.size(); ++k) {
      // the stretch after event k, to the next (across the section after the last)
      const double a = off[k].first;
      const double b = k + 1 < off.size() ? off[k + 1].first : off.front().first + T;
      if (free_only && !off[k].second) continue;
      if (b - a > best_len) best_len = b - a, best_mid = a + 0.5 * (b - a);
    }
    if (best_len >= 2.0 * kSectionClearance * T) break;
  }
  // moved only where the events end up clearly farther (a section whose events crowd every
  // stretch stays where it is)
  if (!(0.5 * best_len > 2.0 * clearance)) return nan;
  return best_mid < T ? best_mid : best_mid - T;
}

/// Moves the section of the branch's last point `pts.back()` away from its orbit's events when
/// one comes within kSectionClearance of a period of it (new_section_offset): the same orbit,
/// its state at the new section from a run of the point's, the point made anew there (chart,
/// monodromy, tangent), the tangent oriented along the secant from the previous point's state at
/// the new section (or as the old tangent's parameter component, at the first point). Returns
/// the new section's time (NaN: not moved); false on failure (why).
bool move_section(const ModelFamily& family, const ContinuationOptions& opt,
                  std::vector<PointData>& pts, long& runs, double& moved_to, std::string& why) {
  moved_to = std::numeric_limits<double>::quiet_NaN();
  PointData& cur = pts.back();
  if (cur.phase >= 0) return true;  // autonomous: the section is a hyperplane, not a time
  const double off = new_section_offset(cur.event_offsets, cur.p.period);
  if (std::isnan(off)) return true;
  const double t_new = cur.p.t0 + off;
  const auto state_at = [&](const BranchPoint& p, Vec& x) {
    ParameterModel pm = family(p.lambda);
    const PeriodMap map(*pm.model, p.t0, pm.options);
    const FlowRun r = map.run(p.x0, t_new - p.t0);
    ++runs;
    if (!r.complete()) {
      why = fmt::format("the run moving the section to t = {:.10g} at {:.10g} ended early: {}",
                        t_new, p.lambda, r.summary.message);
      return false;
    }
    x = stacked_state(r.samples.back());
    return true;
  };
  Vec x;
  if (!state_at(cur.p, x)) return false;
  PointData nb;
  if (!make_point(family, cur.p.lambda, x, opt, nb, why, runs, nullptr, t_new)) return false;
  const int d = nb.chart->dim();
  Vec xp;
  if (pts.size() >= 2 && state_at(pts[pts.size() - 2].p, xp)) {
    Vec sec(d + 1);
    sec.head(d) = -nb.chart->coords(xp);
    sec(d) = (cur.p.lambda - pts[pts.size() - 2].p.lambda) / opt.lambda_scale;
    if (nb.t.dot(sec) < 0) nb.t = -nb.t;
  } else if (nb.t(d) * cur.p.tangent_lambda < 0) {
    nb.t = -nb.t;
  }
  why.clear();
  nb.p.arclength = cur.p.arclength;
  nb.p.corrector_iterations = cur.p.corrector_iterations;
  nb.p.tangent_lambda = nb.t(d);
  nb.p.runs = cur.p.runs;
  cur = std::move(nb);
  moved_to = t_new;
  return true;
}

struct Located {
  double lambda = 0.0, spread = 0.0;
  std::string how;
  /// The evaluation nearest the crossing (smallest |g|): its orbit's state at the section and
  /// the direction (full state, unit in the scaled state) of its multiplier nearest `target`
  /// (a period doubling's -1); empty when no evaluation succeeded.
  Vec x, direction;
};

/// Where a function g of the monodromy (chart-invariant: det(Phi + I), a multiplier's modulus)
/// changes sign between point `from` (arclength 0, lambda_a) and the next point (arclength ds,
/// lambda_b): regula falsi (Illinois) on the arclength, each evaluation a corrector solve from
/// `from` and the finite differences' monodromy at the solution, until the bracket in lambda is
/// below kLocateRel of the points' distance or kLocateIterations evaluations. Where an
/// evaluation fails, the bracket so far (the midpoint of the last bracket in lambda, its half
/// width as the spread).
template <class G>
Located locate_crossing(const ModelFamily& family, const PointData& from, double ds,
                        const BranchPoint& a, const BranchPoint& b, const ContinuationOptions& opt,
                        long& runs, G g, double target = -1.0) {
  const double lambda_a = a.lambda, lambda_b = b.lambda;
  const int d = from.chart->dim();
  Located out;
  double best_g = std::numeric_limits<double>::infinity();
  const auto eval = [&](double s, double& lam, double& val) {
    Corrected c;
    std::string why;
    if (!correct(family, from, s, opt, c, why, runs)) return false;
    lam = c.u(d) * opt.lambda_scale;
    ParameterModel pm = family(lam);
    const double period = std::isnan(c.T) ? pm.period : c.T;
    const PeriodMap map(*pm.model, from.p.t0, pm.options);
    const Vec xs = stacked_state(c.eval.run.samples.front());
    const SectionChart chart(*pm.model, from.p.t0, xs, start_phases(c.eval.run),
                             point_scale(pm, period),
                             pm.autonomous ? pm.pinned : std::vector<int>{});
    const long r0 = map.runs();
    const Vec zero = Vec::Zero(chart.dim());
    const Monodromy m = point_monodromy(opt, map, period, chart, c.eval.run);
    runs += map.runs() - r0;
    if (!m.ok || m.sequence_changed) return false;
    val = g(m.M);
    if (std::isfinite(val) && std::abs(val) < best_g) {
      // the multiplier nearest the target and its direction as a full state
      best_g = std::abs(val);
      const Eigen::EigenSolver<Mat> es(m.M);
      Eigen::Index k = 0;
      for (Eigen::Index i = 1; i < es.eigenvalues().size(); ++i)
        if (std::abs(es.eigenvalues()(i) - target) < std::abs(es.eigenvalues()(k) - target)) k = i;
      const Vec D = chart.scale();
      Vec v = chart.tangent(zero) * es.eigenvectors().col(k).real();
      const double scaled = (v.array() / D.array()).matrix().norm();
      out.x = xs;
      out.direction = scaled > 0.0 ? Vec(v / scaled) : v;
    }
    return std::isfinite(val);
  };
  // the two points' own monodromies give the ends
  double s0 = 0.0, s1 = ds, l0 = lambda_a, l1 = lambda_b;
  double g0 = g(a.monodromy.M), g1 = g(b.monodromy.M);
  int evals = 0;
  const double tol = kLocateRel * std::abs(lambda_b - lambda_a);
  if (!(g0 * g1 < 0.0)) {
    out.lambda = 0.5 * (lambda_a + lambda_b);
    out.spread = 0.5 * std::abs(lambda_b - lambda_a);
    out.how = "the midpoint of the two points (g does not change sign between their monodromies)";
    return out;
  }
  while (std::abs(l1 - l0) > tol && evals < kLocateIterations) {
    const double s = (s0 * g1 - s1 * g0) / (g1 - g0);
    double l, v;
    if (!eval(s, l, v)) break;
    ++evals;
    if (v * g1 < 0.0) {
      s0 = s1, l0 = l1, g0 = g1;
    } else {
      g0 *= 0.5;  // Illinois: the end kept twice in a row counts half
    }
    s1 = s, l1 = l, g1 = v;
  }
  out.lambda = l0 + (l1 - l0) * g0 / (g0 - g1);
  out.spread = std::abs(l1 - l0);
  out.how = evals == 0 ? fmt::format(
                             "by linear interpolation of g between the two points (a "
                             "corrector solve between them failed; bracket {:.2g})",
                             out.spread)
                       : fmt::format(
                             "by regula falsi on corrector solves ({} evaluations, "
                             "bracket {:.2g})",
                             evals, out.spread);
  return out;
}

}  // namespace

int real_multipliers_below_minus_one(const FloquetAnalysis& f) {
  int n = 0;
  for (const auto& m : f.multipliers)
    if (std::abs(m.value.imag()) <= kRealImag && m.value.real() < -1.0) ++n;
  return n;
}

Branch continue_forced_orbit(const ModelFamily& family, double lambda0, VecIn x_guess,
                             const ContinuationOptions& opt) {
  const auto clock0 = std::chrono::steady_clock::now();
  Branch b;
  long runs = 0;
  auto done = [&](std::string outcome, std::string msg) {
    b.outcome = std::move(outcome);
    b.message = std::move(msg);
    b.runs = runs;
    b.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
    return b;
  };
  // the first point: Newton at lambda0
  ParameterModel pm0;
  try {
    pm0 = family(lambda0);
  } catch (const std::exception& e) {
    return done("start_failed", e.what());
  }
  const double t0 = std::isnan(opt.t0) ? pm0.t0 : opt.t0;
  const double T0 = pm0.autonomous && !std::isnan(opt.period) ? opt.period : pm0.period;
  const PeriodMap map0(*pm0.model, t0, pm0.options);
  OrbitOptions o0 = opt.orbit;
  o0.samples = 0;
  const OrbitResult first =
      pm0.autonomous
          ? find_autonomous_orbit(map0, x_guess, T0, 2.0 * std::numbers::pi / T0, pm0.pinned, o0)
          : find_forced_orbit(map0, x_guess, T0, pm0.omega, o0);
  runs += first.runs;
  if (!first.converged())
    return done("start_failed", "the orbit at the first value: " + first.message);
  std::vector<PointData> pts;
  {
    PointData p0;
    std::string why;
    if (!make_point(family, lambda0, first.x0, opt, p0, why, runs, nullptr, t0,
                    pm0.autonomous ? first.period : std::numeric_limits<double>::quiet_NaN()))
      return done("start_failed", why);
    const int d = p0.chart->dim();
    if (opt.previous_x.size() == p0.p.x0.size()) {
      // along the secant from the point before (in this point's chart)
      const Vec sec =
          pack(p0, p0.p.x0, p0.p.period, lambda0, opt.lambda_scale) -
          pack(p0, opt.previous_x, opt.previous_period, opt.previous_lambda, opt.lambda_scale);
      if (p0.t.dot(sec) < 0) p0.t = -p0.t;
    } else if (p0.t(d) * opt.direction < 0) {
      p0.t = -p0.t;
    }
    p0.p.tangent_lambda = p0.t(d);
    p0.p.runs = runs;
    b.points.push_back(p0.p);
    pts.push_back(std::move(p0));
  }
  double ds = opt.ds;
  // the failed corrections from the current point whose iterates saw other events
  bool changed = false;
  double changed_lambda = 0.0;
  std::string changed_signature;
  while (static_cast<int>(b.points.size()) < opt.max_points) {
    {
      double moved_to;
      std::string why;
      if (!move_section(family, opt, pts, runs, moved_to, why)) return done("step_failed", why);
      if (!std::isnan(moved_to))
        b.section_moves.push_back({static_cast<int>(b.points.size()) - 1, moved_to});
    }
    const PointData& cur = pts.back();
    const long runs_before = runs;
    Corrected c;
    std::string why;
    if (!correct(family, cur, ds, opt, c, why, runs)) {
      if (c.events_changed) {  // (kept over the halvings: the nearest crossing is the last)
        changed = true;
        changed_lambda = c.changed_lambda;
        changed_signature = c.changed_signature;
      }
      ds *= 0.5;
      if (ds < opt.ds_min && changed) {
        // Newton does not converge across a grazing or a lift-off (the return map is not
        // smooth there), so the branch of smooth orbits ends where its iterates saw other
        // events: between the last point and the nearest such iterate
        BranchSpecial sp;
        sp.kind = "events_change";
        sp.after = static_cast<int>(b.points.size()) - 1;
        sp.lambda = changed_lambda;
        sp.how = fmt::format(
            "the corrector's iterate at {:.10g} has the events [{}] instead of [{}], and no step "
            "down to ds_min = {:.3g} converges from the last point ({:.10g}): the return map is "
            "not smooth there (a grazing or a lift-off near these values), where the branch of "
            "smooth orbits ends",
            changed_lambda, changed_signature, cur.p.signature, opt.ds_min, cur.p.lambda);
        locate_end(pts, sp);
        b.specials.push_back(sp);
        return done("events_change", sp.how);
      }
      if (ds < opt.ds_min) {
        // the last step's predictor beyond a bound of the branch (where the model may refuse the
        // value: mu < 0): the branch ends there as asked, it does not fail
        const int d = cur.chart->dim();
        const double predicted =
            (pack(cur, cur.p.x0, cur.p.period, cur.p.lambda, opt.lambda_scale)(d) +
             2.0 * ds * cur.t(d)) *
            opt.lambda_scale;
        if (predicted < opt.lambda_min || predicted > opt.lambda_max)
          return done("lambda_bound",
                      fmt::format("the last point, at {:.10g}, is within the smallest step of "
                                  "the bound [{:.10g}, {:.10g}] (a step across it: {})",
                                  cur.p.lambda, opt.lambda_min, opt.lambda_max, why));
      }
      if (ds < opt.ds_min) {
        // where the last points head for a switching surface (a grazing impact, whose
        // saltation matrix grows as 1 / v_N and spoils the Jacobian first), its extrapolation
        BranchSpecial sp;
        sp.kind = "end";
        sp.after = static_cast<int>(b.points.size()) - 1;
        sp.lambda = std::numeric_limits<double>::quiet_NaN();
        sp.how = "no step converges from the last point";
        locate_end(pts, sp);
        if (!std::isnan(sp.lambda)) b.specials.push_back(sp);
        return done("step_failed",
                    fmt::format("no step below ds_min = {:.3g} from lambda = {:.10g}: {}",
                                opt.ds_min, cur.p.lambda, why));
      }
      continue;
    }
    changed = false;
    const int d = cur.chart->dim();
    const double lambda = c.u(d) * opt.lambda_scale;
    if (lambda < opt.lambda_min || lambda > opt.lambda_max)
      return done("lambda_bound", fmt::format("the next point, at {:.10g}, is outside [{:.10g}, "
                                              "{:.10g}]",
                                              lambda, opt.lambda_min, opt.lambda_max));
    PointData next;
    if (!make_point(family, lambda, stacked_state(c.eval.run.samples.front()), opt, next, why, runs,
                    &cur.p.signature, cur.p.t0, c.T))
      return done("step_failed", why);
    if (!next.chart) {  // the events changed: the branch of smooth orbits ends here
      BranchSpecial s;
      s.kind = "events_change";
      s.after = static_cast<int>(b.points.size()) - 1;
      s.lambda = lambda;
      s.how = "the orbit's events are [" + next.p.signature + "] instead of [" + cur.p.signature +
              "]: a grazing or lift-off between the two points, where the branch of smooth "
              "orbits ends";
      locate_end(pts, s);
      next.p.arclength = cur.p.arclength + std::abs(ds);
      next.p.runs = runs - runs_before;
      b.points.push_back(next.p);
      b.specials.push_back(s);
      return done("events_change", s.how);
    }
    // orientation: along the secant from the current point, in the new chart's coordinates
    const int dn = next.chart->dim();
    const Vec sec = pack(next, next.p.x0, next.p.period, lambda, opt.lambda_scale) -
                    pack(next, cur.p.x0, cur.p.period, cur.p.lambda, opt.lambda_scale);
    if (next.t.dot(sec) < 0) next.t = -next.t;
    BranchPoint& p = next.p;
    p.arclength = cur.p.arclength +
                  (c.u - pack(cur, cur.p.x0, cur.p.period, cur.p.lambda, opt.lambda_scale)).norm();
    p.corrector_iterations = c.iterations;
    p.tangent_lambda = next.t(dn);
    p.runs = runs - runs_before;
    const int i = static_cast<int>(b.points.size()) - 1;  // the special lies after point i
    b.points.push_back(p);
    // special points between cur and next
    const BranchPoint& a = cur.p;
    if (a.tangent_lambda * p.tangent_lambda < 0) {
      BranchSpecial f;
      f.kind = "fold";
      f.after = i;
      // the extremum of lambda over the arclength by successive parabolic interpolation of
      // corrector solves from point i (the bracket [0, ds])
      std::vector<std::pair<double, double>> pts_s = {{0.0, a.lambda}, {ds, lambda}};
      Corrected mid;
      std::string w;
      int evals = 0;
      if (correct(family, cur, 0.5 * ds, opt, mid, w, runs)) {
        pts_s.push_back({0.5 * ds, mid.u(d) * opt.lambda_scale});
        ++evals;
        for (int k = 0; k < kLocateIterations; ++k) {
          std::sort(pts_s.begin(), pts_s.end());
          // the three around the extreme lambda
          std::size_t m = 0;
          for (std::size_t j = 1; j < pts_s.size(); ++j)
            if ((a.tangent_lambda > 0 ? pts_s[j].second > pts_s[m].second
                                      : pts_s[j].second < pts_s[m].second))
              m = j;
          const std::size_t j0 = m == 0 ? 0 : (m + 1 == pts_s.size() ? m - 2 : m - 1);
          const auto [s0, l0] = pts_s[j0];
          const auto [s1, l1] = pts_s[j0 + 1];
          const auto [s2, l2] = pts_s[j0 + 2];
          const double num = (s1 - s0) * (s1 - s0) * (l1 - l2) - (s1 - s2) * (s1 - s2) * (l1 - l0);
          const double den = (s1 - s0) * (l1 - l2) - (s1 - s2) * (l1 - l0);
          if (den == 0.0) break;
          const double sv = s1 - 0.5 * num / den;
          if (!(sv > 0.0 && sv < ds)) break;
          bool close = false;
          for (const auto& q : pts_s) close |= std::abs(q.first - sv) <= kLocateRel * ds;
          if (close) break;
          Corrected cv;
          if (!correct(family, cur, sv, opt, cv, w, runs)) break;
          pts_s.push_back({sv, cv.u(d) * opt.lambda_scale});
          ++evals;
        }
      }
      double best = pts_s[0].second;
      for (const auto& q : pts_s)
        best = a.tangent_lambda > 0 ? std::max(best, q.second) : std::min(best, q.second);
      f.lambda = best;
      const double m0 = nearest_real(a.floquet, 1.0), m1 = nearest_real(p.floquet, 1.0);
      f.how = fmt::format(
          "d lambda / ds changes sign; lambda's extremum over the arclength from {} corrector "
          "solves (successive parabolic interpolation); the real multiplier nearest +1 goes from "
          "{:.6g} to {:.6g}",
          evals + 2, m0, m1);
      b.specials.push_back(f);
    }
    if (std::abs(real_multipliers_below_minus_one(a.floquet) -
                 real_multipliers_below_minus_one(p.floquet)) %
            2 ==
        1) {
      // a real multiplier through -1: det(Phi + I) changes sign (complex pairs add |mu + 1|^2)
      BranchSpecial s;
      s.kind = "period_doubling";
      s.after = i;
      const Located loc = locate_crossing(family, cur, ds, a, p, opt, runs, [](const Mat& M) {
        return (M + Mat::Identity(M.rows(), M.cols())).determinant();
      });
      s.lambda = loc.lambda;
      s.spread = loc.spread;
      s.x = loc.x;
      s.direction = loc.direction;
      s.t0 = cur.p.t0;
      s.how = fmt::format(
          "a real multiplier crosses -1 (the real multipliers below -1: {} -> {}); located where "
          "det(Phi + I) changes sign, {}",
          real_multipliers_below_minus_one(a.floquet), real_multipliers_below_minus_one(p.floquet),
          loc.how);
      b.specials.push_back(s);
    }
    if (neimark_sacker_between(a.floquet, p.floquet)) {
      // the complex multiplier nearest the unit circle: its modulus minus 1 changes sign
      BranchSpecial s;
      s.kind = "neimark_sacker";
      s.after = i;
      const Located loc = locate_crossing(family, cur, ds, a, p, opt, runs, [](const Mat& M) {
        double best = std::numeric_limits<double>::quiet_NaN();
        const Eigen::EigenSolver<Mat> es(M, false);
        for (const auto& z : es.eigenvalues())
          if (std::abs(z.imag()) > kRealImag && !(std::abs(std::abs(z) - 1.0) >= std::abs(best)))
            best = std::abs(z) - 1.0;
        return best;
      });
      s.lambda = loc.lambda;
      s.spread = loc.spread;
      s.how =
          "a complex pair crosses the unit circle; located where the modulus of the complex "
          "multiplier nearest the circle passes 1, " +
          loc.how;
      b.specials.push_back(s);
    }
    if (p.signature != a.signature) {
      BranchSpecial s;
      s.kind = "events_change";
      s.after = i;
      s.lambda = p.lambda;
      s.how = "the orbit's events are [" + p.signature + "] instead of [" + a.signature +
              "]: a grazing or lift-off between the two points, where the branch of smooth "
              "orbits ends";
      locate_end(pts, s);  // (from the smooth points before it)
      b.specials.push_back(s);
      pts.push_back(std::move(next));
      return done("events_change", s.how);
    }
    pts.push_back(std::move(next));
    if (pts.size() > 3) pts.erase(pts.begin());  // only the last points are needed
    // step control
    if (c.iterations <= 4)
      ds = std::min(1.3 * ds, opt.ds_max);
    else if (c.iterations >= 7)
      ds = std::max(0.7 * ds, opt.ds_min);
  }
  return done("max_points", fmt::format("{} points", b.points.size()));
}

}  // namespace rubdyn
