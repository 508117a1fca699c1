#include "rubdyn/analysis/continuation.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

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

/// The orbit at one point: its chart, monodromy, G_lambda, tangent and books.
struct PointData {
  BranchPoint p;
  std::unique_ptr<SectionChart> chart;
  Mat J;  // d x (d + 1): [Phi - I, G_lambda s_lambda]
  Vec t;  // unit tangent (d + 1), in this chart's coordinates
};

struct Eval {
  bool ok = false;
  std::string why;
  bool penetrates = false;  // the state lies inside a stator (beyond a grazing): not run
  FlowRun run;
  std::string signature;  // the run's events (event_signature)
  Vec G;                  // coords(P(x)) - coords(x)
};

Eval evaluate(const ModelFamily& family, const SectionChart& chart, VecIn xi, double lambda,
              long& runs) {
  Eval e;
  ParameterModel pm;
  try {
    pm = family(lambda);
  } catch (const std::exception& ex) {
    e.why = fmt::format("the model at {:.10g}: {}", lambda, ex.what());
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
  if (const auto pen = penetrates_open_contact(*pm.model, chart, pm.t0, x)) {
    e.penetrates = true;
    e.signature =
        fmt::format("inside contact {}'s stator, d_N = {:.3g} m", pen->contact + 1, pen->d_N);
    e.why = fmt::format("the state at {:.10g} lies {}", lambda, e.signature);
    return e;
  }
  const PeriodMap map(*pm.model, pm.t0, pm.options);
  e.run = map.run(x, pm.period);
  ++runs;
  if (!e.run.complete()) {
    e.why = fmt::format("a run at {:.10g} ended early ({}): {}", lambda,
                        to_string(e.run.summary.termination), e.run.summary.message);
    return e;
  }
  e.signature = event_signature(e.run, pm.t0);
  e.G = chart.coords(stacked_state(e.run.samples.back())) -
        chart.coords(stacked_state(e.run.samples.front()));
  e.ok = true;
  return e;
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
  const double y0 = s[prev].contacts[0].d_N, y2 = s[next].contacts[0].d_N;
  const double curv = y0 - 2.0 * y1 + y2;
  if (!(y0 > y1 && y2 > y1 && curv > 0.0)) return y1;
  return y1 - (y2 - y0) * (y2 - y0) / (8.0 * curv);
}

/// Everything about the orbit through x at lambda (x on its section's constraints).
bool make_point(const ModelFamily& family, double lambda, VecIn x, const ContinuationOptions& opt,
                PointData& out, std::string& why, long& runs, const std::string* expect = nullptr) {
  ParameterModel pm = family(lambda);
  const PeriodMap map(*pm.model, pm.t0, pm.options);
  const FlowRun run = map.run(x, pm.period);
  ++runs;
  if (!run.complete()) {
    why =
        fmt::format("the run on the point at {:.10g} ended early: {}", lambda, run.summary.message);
    return false;
  }
  const Vec xs = stacked_state(run.samples.front());
  if (expect && event_signature(run, pm.t0) != *expect) {
    // the orbit's events changed (a grazing, a lift-off at the section): no chart of the
    // previous phases, no smooth continuation; the point is reported as it is
    out.p.lambda = lambda;
    out.p.period = pm.period;
    out.p.x0 = xs;
    out.p.signature = event_signature(run, pm.t0);
    out.p.floquet.reason = "not computed: the orbit's events changed";
    out.chart.reset();
    return true;
  }
  const Vec D = state_scale(*pm.model, pm.omega);
  out.chart = std::make_unique<SectionChart>(*pm.model, pm.t0, xs, start_phases(run), D);
  const SectionChart& chart = *out.chart;
  const int d = chart.dim();
  const Vec zero = Vec::Zero(d);
  const FiniteDifferenceMonodromy fd(opt.orbit.fd_steps);
  const long runs_before = map.runs();
  Monodromy m = fd.compute(map, pm.period, chart, zero, run);
  const Mat tangent = chart.tangent(zero);
  FloquetAnalysis fl = floquet_analysis(m, tangent, D);
  for (int k = 0; k < opt.orbit.fd_refinements && fl.stability == Stability::Undecided &&
                  fd.refine(map, pm.period, chart, zero, run, m);
       ++k)
    fl = floquet_analysis(m, tangent, D);
  runs += map.runs() - runs_before;
  if (!m.ok) {
    why = "the monodromy at " + fmt::format("{:.10g}", lambda) + ": " + m.failure;
    return false;
  }
  // G_lambda by central differences at the same state
  const double h = kLambdaStep * opt.lambda_scale;
  const Eval ep = evaluate(family, chart, zero, lambda + h, runs);
  const Eval em = evaluate(family, chart, zero, lambda - h, runs);
  if (!ep.ok || !em.ok) {
    why = "G_lambda: " + (ep.ok ? em.why : ep.why);
    return false;
  }
  out.J.resize(d, d + 1);
  out.J.leftCols(d) = m.M - Mat::Identity(d, d);
  out.J.col(d) = (ep.G - em.G) / (2.0 * h) * opt.lambda_scale;
  const Eigen::JacobiSVD<Mat> svd(out.J, Eigen::ComputeFullV);
  out.t = svd.matrixV().col(d);
  // the sampled period: amplitude and forces
  BranchPoint& p = out.p;
  p.lambda = lambda;
  p.period = pm.period;
  p.x0 = xs;
  p.residual = chart.scaled_distance(xs, stacked_state(run.samples.back()));
  p.monodromy = std::move(m);
  p.floquet = std::move(fl);
  p.signature = event_signature(run, pm.t0);
  const int samples = std::max(8, opt.orbit.samples);
  const FlowRun sampled = map.run(xs, pm.period, pm.period / samples);
  ++runs;
  p.F_N_min = std::numeric_limits<double>::infinity();
  p.F_N_max = 0.0;
  for (const Sample& s : sampled.samples) {
    PlaneMotion pl;
    if (pm.model->plane_motion(0, s.t, s.q, s.v, pl))
      p.amplitude = std::max(p.amplitude, pl.rotor.norm());
    p.F_N_max = std::max(p.F_N_max, s.contacts[0].F_N);
    p.F_N_min = std::min(p.F_N_min, s.contacts[0].F_N);
  }
  p.d_N_min = smallest_gap(sampled.samples);
  return true;
}

/// The real multiplier nearest to `target` (+1 or -1), or NaN.
double nearest_real(const FloquetAnalysis& f, double target) {
  double best = std::numeric_limits<double>::quiet_NaN();
  for (const auto& m : f.multipliers) {
    if (std::abs(m.value.imag()) > kRealImag) continue;
    if (std::isnan(best) || std::abs(m.value.real() - target) < std::abs(best - target))
      best = m.value.real();
  }
  return best;
}

int complex_outside(const FloquetAnalysis& f) {
  int n = 0;
  for (const auto& m : f.multipliers)
    if (std::abs(m.value.imag()) > kRealImag && std::abs(m.value) > 1.0) ++n;
  return n;
}

/// The corrector from point `from` at arclength s along its tangent: u with G(u) = 0 and
/// t . (u - u_from) = s. Returns false when it does not converge.
struct Corrected {
  Vec u;
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
  Vec u0 = Vec::Zero(d + 1);
  u0(d) = from.p.lambda / opt.lambda_scale;
  const Vec up = u0 + s * from.t;
  Mat A(d + 1, d + 1);
  A.topRows(d) = from.J;
  A.row(d) = from.t.transpose();
  Vec u = up;
  // Newton with point i's Jacobian (and the arclength row), improved by Broyden's updates
  Vec F_prev, step_prev;
  for (int it = 0; it < opt.max_corrector; ++it) {
    Eval e = evaluate(family, chart, u.head(d), u(d) * opt.lambda_scale, runs);
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
/// free throughout (the gap's minimum over the period, d_N_min, falls towards zero). The secant of
/// that minimum over lambda through the last two points, and the parabola through the last three;
/// the special `s` that ends the branch takes the parabola's root nearest the last point (the
/// secant's with two points) as its value, the two estimates' difference as its spread, and says
/// so in `how`. Where the points allow neither (mixed, or the minimum not falling), `s` is left
/// as it is.
void locate_end(const std::vector<PointData>& pts, BranchSpecial& s) {
  const std::size_t n = std::min<std::size_t>(pts.size(), 3);
  if (n < 2) return;
  // which quantity: every point in contact at every sample, or every point free at every one
  bool contact = true, free = true;
  for (std::size_t k = pts.size() - n; k < pts.size(); ++k) {
    const BranchPoint& p = pts[k].p;
    contact = contact && p.F_N_min > 0.0 && std::isfinite(p.F_N_min);
    free = free && p.F_N_max == 0.0 && p.d_N_min > 0.0 && std::isfinite(p.d_N_min);
  }
  if (!contact && !free) return;
  std::vector<double> l, F;
  for (std::size_t k = pts.size() - n; k < pts.size(); ++k) {
    l.push_back(pts[k].p.lambda);
    F.push_back(contact ? pts[k].p.F_N_min : pts[k].p.d_N_min);
  }
  const std::size_t e = n - 1;
  if (!(F[e] < F[e - 1]) || l[e] == l[e - 1]) return;
  const double secant = l[e] - F[e] * (l[e] - l[e - 1]) / (F[e] - F[e - 1]);
  double lambda = secant, spread = 0.0;
  if (n == 3 && l[0] != l[1] && l[0] != l[2]) {
    // Newton's form of the parabola F(x) through the three, its root nearest l[e]
    const double d1 = (F[1] - F[0]) / (l[1] - l[0]), d2 = (F[2] - F[1]) / (l[2] - l[1]);
    const double c2 = (d2 - d1) / (l[2] - l[0]);
    // F(x) = F[2] + b (x - l[2]) + c2 (x - l[2])^2 with b = d2 + c2 (l[2] - l[1])
    const double b = d2 + c2 * (l[2] - l[1]);
    double root = secant;
    if (c2 != 0.0) {
      const double disc = b * b - 4.0 * c2 * F[2];
      if (disc >= 0.0) {
        const double r1 = (-b + std::sqrt(disc)) / (2.0 * c2),
                     r2 = (-b - std::sqrt(disc)) / (2.0 * c2);
        root = l[2] + (std::abs(r1) < std::abs(r2) ? r1 : r2);
      }
    }
    spread = std::abs(root - secant);
    lambda = root;
  }
  s.lambda = lambda;
  s.spread = spread;
  s.how += fmt::format(
      "; the {}'s minimum over the period, {:.6g} {} at the last point, extrapolated to zero "
      "from the last {} smooth points: {} at {:.10g} (secant {:.10g}, estimates {:.2g} apart)",
      contact ? "contact force" : "gap", F[e], contact ? "N" : "m", n,
      contact ? "lift-off" : "grazing", lambda, secant, spread);
}

}  // namespace

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
  const PeriodMap map0(*pm0.model, pm0.t0, pm0.options);
  OrbitOptions o0 = opt.orbit;
  o0.samples = 0;
  const OrbitResult first = find_forced_orbit(map0, x_guess, pm0.period, pm0.omega, o0);
  runs += first.runs;
  if (!first.converged())
    return done("start_failed", "the orbit at the first value: " + first.message);
  std::vector<PointData> pts;
  {
    PointData p0;
    std::string why;
    if (!make_point(family, lambda0, first.x0, opt, p0, why, runs))
      return done("start_failed", why);
    const int d = p0.chart->dim();
    if (p0.t(d) * opt.direction < 0) p0.t = -p0.t;
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
      if (ds < opt.ds_min)
        return done("step_failed",
                    fmt::format("no step below ds_min = {:.3g} from lambda = {:.10g}: {}",
                                opt.ds_min, cur.p.lambda, why));
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
                    &cur.p.signature))
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
    Vec sec(dn + 1);
    sec.head(dn) = -next.chart->coords(cur.p.x0);
    sec(dn) = (lambda - cur.p.lambda) / opt.lambda_scale;
    if (next.t.dot(sec) < 0) next.t = -next.t;
    BranchPoint& p = next.p;
    p.arclength = cur.p.arclength + (c.u -
                                     [&] {
                                       Vec u0 = Vec::Zero(d + 1);
                                       u0(d) = cur.p.lambda / opt.lambda_scale;
                                       return u0;
                                     }())
                                        .norm();
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
    const double n0 = nearest_real(a.floquet, -1.0), n1 = nearest_real(p.floquet, -1.0);
    if (!std::isnan(n0) && !std::isnan(n1) && (n0 + 1.0) * (n1 + 1.0) < 0) {
      BranchSpecial s;
      s.kind = "period_doubling";
      s.after = i;
      const double w = (n0 + 1.0) / (n0 - n1);  // linear in the arclength
      s.lambda = a.lambda + w * (p.lambda - a.lambda);
      s.how = fmt::format("a real multiplier crosses -1 ({:.6g} -> {:.6g}); linear interpolation",
                          n0, n1);
      b.specials.push_back(s);
    }
    if (complex_outside(a.floquet) != complex_outside(p.floquet)) {
      BranchSpecial s;
      s.kind = "neimark_sacker";
      s.after = i;
      s.lambda = 0.5 * (a.lambda + p.lambda);
      s.how = "a complex pair crosses the unit circle; the midpoint of the two points";
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
