#include "rubdyn/analysis/orbit.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "rubdyn/hybrid/flow_sensitivity.hpp"

namespace rubdyn {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The projection onto the section's constraints stops at this scaled defect: d_N to 1e-13 of the
// gap scale, v_N and v_t to 1e-13 of L Omega. Round-off of d_N = g0 - |r| is eps |r| ~ 2e-16 L,
// of v_N = W_N^T v about eps |v| / (L Omega) ~ 1e-15 (the Jeffcott full rub: |v| <= 0.7 m/s,
// L Omega = 0.3 m/s); the integrator takes a state within 10 (atol + rtol g0) ~ 5e-8 L and
// 1e4 atol ~ 3e-8 L Omega of the constraint for one on it (decision_tolerances.hpp), so the
// projection's state is on the constraint for it by five orders of magnitude.
constexpr double kProjectionTol = 1e-13;
// ... or stops when its correction stalls below this (round-off) with the defect below
// kProjectionLoose.
constexpr double kProjectionStall = 1e-15;
constexpr double kProjectionLoose = 1e-11;
constexpr int kProjectionIterations = 30;
// Relative step of the central differences of v_N and v_t in q (the chart's Jacobian): v_N is a
// smooth function at the scale of the gap, so 1e-6 L gives a truncation error ~1e-12 and a
// round-off error ~eps |v| / (1e-6 L) ~ 1e-9 relative. Only the tangent basis depends on it
// (not the exactness of embed / coords, which is the projection's).
constexpr double kJacobianStep = 1e-6;
// The finite differences' error estimate is this times the difference of the two estimates of
// the pair used. In the truncation regime the difference is the coarser estimate's error (the
// extrapolation's is far smaller); in the noise regime (error ~ eps / h) the extrapolation
// (r^2 Phi_fine - Phi_coarse) / (r^2 - 1) carries about (16/15) of the finer estimate's noise,
// and the difference of two independent noises is about the larger of them: the estimate is
// then the error itself, up to chance. This factor is our calibration, not a bound: on the full
// annular rub's four orbits (tests/unit/test_orbit.cpp) the multipliers' distance to
// exp(lambda T), in units of condition x difference, was at most 0.5 with the event engine of
// b7381b8 and is at most 1.51 with the one-engine event solver (rigid ring, stable root, rtol
// 1e-10: the two estimates' noises nearly agree); 0.63 elsewhere. 4 leaves 2.6x over the
// largest. A monodromy from sensitivities (orbits.md) would replace the estimate.
constexpr double kErrorSafety = 4.0;
// Newton's linear system is singular (a multiplier at +1) below this reciprocal condition.
constexpr double kSingularRcond = 1e-12;
// The chart is re-based at the iterate when |xi|_inf exceeds this (scaled units): the manifold
// of a gap-sized circle stays a graph over its tangent plane to a fraction of L.
constexpr double kRebase = 0.5;
// Newton's last finite-difference Jacobian seeds the final monodromy when the orbit lies within
// this (scaled) distance of the iterate where it was taken. Moving the base point by delta moves
// the derivative by |P''| delta, with |P''| = O(10) in scaled units on the full rub: 1e-4 at
// most, below the differences' own error (1e-3 at rtol 1e-10). And the error bound is set by the
// difference between the seed and the other step's estimate, which includes the shift whatever
// it is.
constexpr double kReuseDistance = 1e-5;
// Fixed-point steps x <- P(x) at most while a guess's phases at t0 and t0 + T differ.
constexpr int kMaxFixedPointSteps = 10;
// Halvings of a Newton step whose residual does not fall.
constexpr int kMaxHalvings = 8;

double norm2(const Mat& A) {
  if (A.size() == 0) return 0.0;
  Eigen::JacobiSVD<Mat> svd(A);
  return svd.singularValues()(0);
}

std::vector<std::complex<double>> eigenvalues(const Mat& M) {
  std::vector<std::complex<double>> out;
  if (M.size() == 0) return out;
  Eigen::EigenSolver<Mat> es(M, false);
  for (Eigen::Index i = 0; i < es.eigenvalues().size(); ++i) out.push_back(es.eigenvalues()(i));
  return out;
}

double nearest(std::complex<double> z, const std::vector<std::complex<double>>& set) {
  double d = std::numeric_limits<double>::infinity();
  for (const auto& w : set) d = std::min(d, std::abs(z - w));
  return d;
}

}  // namespace

// ---- the return map ----------------------------------------------------------------------------

PeriodMap::PeriodMap(const LagrangianModel& model, double t0, EventDrivenOptions opt)
    : model_(model), t0_(t0), opt_(std::move(opt)) {
  opt_.progress = {};
}

FlowRun PeriodMap::run(VecIn x, double T, double output_dt) const {
  const int n = model_.num_dofs();
  MechanicalState s(n, t0_);
  s.q = x.head(n);
  s.v = x.tail(n);
  EventDrivenOptions o = opt_;
  o.output_dt = output_dt > 0.0 ? output_dt : T;
  MemorySink sink;
  FlowRun r;
  r.summary = run_event_driven(model_, s, t0_ + T, o, sink);
  r.samples = std::move(sink.samples);
  r.events = std::move(sink.events);
  ++runs_;
  return r;
}

std::vector<Phase> start_phases(const FlowRun& r) {
  std::vector<Phase> p;
  if (r.samples.empty()) return p;
  for (const auto& c : r.samples.front().contacts) p.push_back(c.phase);
  return p;
}

std::vector<Phase> end_phases(const FlowRun& r) {
  std::vector<Phase> p;
  if (r.samples.empty()) return p;
  for (const auto& c : r.samples.back().contacts) p.push_back(c.phase);
  return p;
}

namespace {
std::string phase_list(const std::vector<Phase>& p) {
  std::string s;
  for (std::size_t k = 0; k < p.size(); ++k) {
    if (k) s += ',';
    s += to_string(p[k]);
  }
  return s;
}
}  // namespace

std::string event_signature(const FlowRun& r, double t0) {
  std::string s = phase_list(start_phases(r)) + " |";
  for (const auto& e : r.events) {
    if (e.t <= t0) continue;  // the start's own decision (the initial state on the constraint)
    s += ' ';
    s += to_string(e.kind);
    if (r.samples.empty() || r.samples.front().contacts.size() > 1) {
      s += '#';
      s += std::to_string(e.contact + 1);
    }
  }
  s += " | ";
  s += phase_list(end_phases(r));
  return s;
}

Vec state_scale(const LagrangianModel& model, double omega_ref) {
  const int n = model.num_dofs();
  const double L = model.gap_scale(0);
  const double R = std::max(model.contact_radius(0), L);
  Vec D(2 * n);
  const auto& coords = model.coordinates();
  for (int i = 0; i < n; ++i) {
    // an angle is measured by the displacement it causes at the contact radius
    const double unit = coords[static_cast<std::size_t>(i)].unit == "rad" ? L / R : L;
    D(i) = unit;
    D(n + i) = unit * omega_ref;
  }
  return D;
}

// ---- the section's chart -----------------------------------------------------------------------

SectionChart::SectionChart(const LagrangianModel& model, double t, VecIn x_b,
                           const std::vector<Phase>& phases, VecIn scale,
                           const std::vector<int>& pinned)
    : m_(model), t_(t), xb_(x_b), D_(scale), pinned_(pinned), phases_(phases) {
  const int n = m_.num_dofs();
  len_ = m_.gap_scale(0);
  speed_ = len_ * (D_(n) / D_(0));
  for (int k = 0; k < static_cast<int>(phases.size()); ++k) {
    const Phase p = phases[static_cast<std::size_t>(k)];
    if (p == Phase::Free) continue;
    rows_.push_back({k, 0, 0});
    rows_.push_back({k, 1, 0});
    if (p == Phase::Stick) rows_.push_back({k, 2, 0});
  }
  for (int i : pinned_) rows_.push_back({-1, 3, i});
  const int N = 2 * n;
  if (rows_.empty()) {
    B_ = Mat::Identity(N, N);
    N_.resize(N, 0);
    return;
  }
  const Mat J = jacobian(m_, xb_);
  Eigen::ColPivHouseholderQR<Mat> qr(J.transpose());
  const int r = static_cast<int>(qr.rank());
  const Mat Q = qr.householderQ() * Mat::Identity(N, N);
  N_ = Q.leftCols(r);
  B_ = Q.rightCols(N - r);
}

Vec SectionChart::values(const LagrangianModel& m, VecIn x) const {
  const int n = m.num_dofs();
  Vec g(static_cast<Eigen::Index>(rows_.size()));
  ContactKinematics c(n);
  int last = -1;
  const Vec q = x.head(n), v = x.tail(n);
  for (std::size_t r = 0; r < rows_.size(); ++r) {
    const Row& row = rows_[r];
    if (row.kind == 3) {
      g(static_cast<Eigen::Index>(r)) = (x(row.index) - xb_(row.index)) / D_(row.index);
      continue;
    }
    if (row.contact != last) {
      m.compute_contact(row.contact, t_, q, v, c);
      last = row.contact;
    }
    const double L = m.gap_scale(row.contact);
    const double w = speed_ / len_;
    g(static_cast<Eigen::Index>(r)) = row.kind == 0   ? c.d_N / L
                                      : row.kind == 1 ? c.v_N / (L * w)
                                                      : c.v_t / (L * w);
  }
  return g;
}

Mat SectionChart::jacobian(const LagrangianModel& mdl, VecIn x) const {
  const int n = mdl.num_dofs();
  const int m = static_cast<int>(rows_.size());
  Mat J = Mat::Zero(m, 2 * n);
  const Vec q = x.head(n), v = x.tail(n);
  ContactKinematics c(n), cp(n), cm(n);
  const double w = speed_ / len_;
  for (int r = 0; r < m; ++r) {
    const Row& row = rows_[static_cast<std::size_t>(r)];
    if (row.kind == 3) {
      J(r, row.index) = 1.0;
      continue;
    }
    const double L = mdl.gap_scale(row.contact);
    mdl.compute_contact(row.contact, t_, q, v, c);
    if (row.kind == 0) {
      for (int j = 0; j < n; ++j) J(r, j) = c.W_N(j) * D_(j) / L;
      continue;
    }
    const Vec& W = row.kind == 1 ? c.W_N : c.W_T;
    for (int j = 0; j < n; ++j) J(r, n + j) = W(j) * D_(n + j) / (L * w);
    // d(v_N)/dq, d(v_t)/dq: W(q)^T v depends on q through the contact direction
    for (int j = 0; j < n; ++j) {
      const double h = kJacobianStep * D_(j);
      Vec qp = q, qm = q;
      qp(j) += h;
      qm(j) -= h;
      mdl.compute_contact(row.contact, t_, qp, v, cp);
      mdl.compute_contact(row.contact, t_, qm, v, cm);
      const double dp = row.kind == 1 ? cp.v_N - cm.v_N : cp.v_t - cm.v_t;
      J(r, j) = dp / (2.0 * h) * D_(j) / (L * w);
    }
  }
  return J;
}

bool SectionChart::embed(VecIn xi, Vec& x) const {
  return embed_on(m_, xi, x);
}

bool SectionChart::embed_on(const LagrangianModel& model, VecIn xi, Vec& x) const {
  const Vec s0 = B_ * xi;
  x = xb_ + D_.cwiseProduct(s0);
  if (rows_.empty()) return all_finite(x);
  Vec eta = Vec::Zero(N_.cols());
  for (int it = 0; it < kProjectionIterations; ++it) {
    x = xb_ + D_.cwiseProduct(s0 + N_ * eta);
    const Vec g = values(model, x);
    if (!all_finite(g)) return false;
    const double defect = g.cwiseAbs().maxCoeff();
    if (defect <= kProjectionTol) return true;
    const Mat A = jacobian(model, x) * N_;
    const Vec d = A.colPivHouseholderQr().solve(-g);
    if (!all_finite(d)) return false;
    eta += d;
    if (d.cwiseAbs().maxCoeff() <= kProjectionStall * (1.0 + eta.cwiseAbs().maxCoeff())) {
      x = xb_ + D_.cwiseProduct(s0 + N_ * eta);
      return values(model, x).cwiseAbs().maxCoeff() <= kProjectionLoose;
    }
  }
  return false;
}

Vec SectionChart::coords(VecIn x) const {
  return B_.transpose() * (x - xb_).cwiseQuotient(D_);
}

double SectionChart::constraint_defect(VecIn x) const {
  if (rows_.empty()) return 0.0;
  return values(m_, x).cwiseAbs().maxCoeff();
}

Mat SectionChart::coords_jacobian() const {
  return B_.transpose() * D_.cwiseInverse().asDiagonal();
}

Mat SectionChart::tangent(VecIn xi) const {
  if (xi.size() == 0 || xi.cwiseAbs().maxCoeff() == 0.0) return D_.asDiagonal() * B_;
  const int d = dim();
  Mat T(state_size(), d);
  const double h = 1e-6;
  Vec xp, xm;
  for (int j = 0; j < d; ++j) {
    Vec a = xi, b = xi;
    a(j) += h;
    b(j) -= h;
    if (!embed(a, xp) || !embed(b, xm)) {
      T.col(j).setConstant(kNaN);
      continue;
    }
    T.col(j) = (xp - xm) / (2.0 * h);
  }
  return T;
}

double SectionChart::scaled_distance(VecIn x, VecIn y) const {
  Vec d = (y - x).cwiseQuotient(D_).cwiseAbs();
  for (int i : pinned_) d(i) = 0.0;
  return d.size() ? d.maxCoeff() : 0.0;
}

std::optional<Penetration> penetrates_open_contact(const LagrangianModel& model,
                                                   const SectionChart& chart, double t, VecIn x) {
  const int n = model.num_dofs();
  ContactKinematics c(n);
  const Vec q = x.head(n), v = x.tail(n);
  for (int k = 0; k < model.contact_count(); ++k) {
    if (static_cast<std::size_t>(k) < chart.phases().size() &&
        chart.phases()[static_cast<std::size_t>(k)] != Phase::Free)
      continue;
    model.compute_contact(k, t, q, v, c);
    if (c.d_N < -64.0 * std::numeric_limits<double>::epsilon() * model.gap_scale(k))
      return Penetration{k, c.d_N};
  }
  return std::nullopt;
}

// ---- the monodromy by finite differences -------------------------------------------------------

bool FiniteDifferenceMonodromy::estimate(const PeriodMap& map, double T, const SectionChart& chart,
                                         VecIn xi, const std::string& sig0, double h, Monodromy& m,
                                         Mat& Phi) const {
  const int d = chart.dim();
  Phi.resize(d, d);
  Vec x;
  for (int j = 0; j < d; ++j) {
    Vec c[2];
    for (int side = 0; side < 2; ++side) {
      const double hs = side == 0 ? h : -h;
      Vec p = xi;
      p(j) += hs;
      if (!chart.embed(p, x)) {
        m.failure = fmt::format(
            "the perturbation {:+.3g} of section coordinate {} could not be put on the "
            "constraints of the section",
            hs, j + 1);
        return false;
      }
      // a perturbation into the stator crosses the contact surface: the orbit grazes within
      // the step (a free orbit near its grazing), the derivative is meaningless there
      if (const auto pen = penetrates_open_contact(map.model(), chart, map.t0(), x)) {
        if (!m.sequence_changed) {
          m.sequence_changed = true;
          m.sequence_note = fmt::format(
              "perturbed by {:+.3g} along section coordinate {}, the state penetrates contact "
              "{}'s stator (d_N = {:.3g} m): the orbit grazes within the step",
              hs, j + 1, pen->contact + 1, pen->d_N);
        }
        c[side] = p;  // (no run: the estimate is marked meaningless)
        continue;
      }
      const FlowRun r = map.run(x, T);
      if (!r.complete()) {
        m.failure = fmt::format(
            "the run perturbed by {:+.3g} along section coordinate {} ended early ({}): {}", hs,
            j + 1, to_string(r.summary.termination), r.summary.message);
        return false;
      }
      const std::string sig = event_signature(r, map.t0());
      if (sig != sig0 && !m.sequence_changed) {
        m.sequence_changed = true;
        m.sequence_note = fmt::format(
            "perturbed by {:+.3g} along section coordinate {}, the run's events are [{}] instead "
            "of [{}]",
            hs, j + 1, sig, sig0);
      }
      c[side] = chart.coords(stacked_state(r.samples.back()));
    }
    Phi.col(j) = (c[0] - c[1]) / (2.0 * h);
  }
  return true;
}

void FiniteDifferenceMonodromy::combine(Monodromy& m) {
  m.differences.clear();
  m.ok = !m.estimates.empty();
  if (!m.ok) return;
  if (m.estimates.size() == 1) {
    m.M = m.estimates[0];
    m.error = kNaN;
    m.chosen = 0;
    m.method =
        fmt::format("finite differences (central, h = {:.3g}; no error estimate)", m.steps[0]);
    return;
  }
  for (std::size_t k = 0; k + 1 < m.estimates.size(); ++k)
    m.differences.push_back(norm2(m.estimates[k] - m.estimates[k + 1]));
  const auto best = std::min_element(m.differences.begin(), m.differences.end());
  const std::size_t k = static_cast<std::size_t>(best - m.differences.begin());
  const double r2 = (m.steps[k] / m.steps[k + 1]) * (m.steps[k] / m.steps[k + 1]);
  m.M = (r2 * m.estimates[k + 1] - m.estimates[k]) / (r2 - 1.0);
  m.error = kErrorSafety * *best;
  m.chosen = static_cast<int>(k);
  m.method = fmt::format(
      "finite differences (central, Richardson on h = {:.3g} and {:.3g}; error = 4 times "
      "their difference)",
      m.steps[k], m.steps[k + 1]);
}

Monodromy FiniteDifferenceMonodromy::compute(const PeriodMap& map, double T,
                                             const SectionChart& chart, VecIn xi,
                                             const FlowRun& at) const {
  return compute_impl(map, T, chart, xi, at, 0.0, nullptr);
}

Monodromy FiniteDifferenceMonodromy::compute_seeded(const PeriodMap& map, double T,
                                                    const SectionChart& chart, VecIn xi,
                                                    const FlowRun& at, double h_known,
                                                    const Mat& Phi_known) const {
  return compute_impl(map, T, chart, xi, at, h_known, &Phi_known);
}

Monodromy FiniteDifferenceMonodromy::compute_impl(const PeriodMap& map, double T,
                                                  const SectionChart& chart, VecIn xi,
                                                  const FlowRun& at, double h_known,
                                                  const Mat* Phi_known) const {
  Monodromy m;
  const long runs0 = map.runs();
  const std::string sig0 = event_signature(at, map.t0());
  std::vector<double> steps = steps_;
  std::sort(steps.rbegin(), steps.rend());
  for (const double h : steps) {
    Mat Phi;
    if (Phi_known && std::abs(h - h_known) <= 1e-12 * h) {
      Phi = *Phi_known;
    } else if (!estimate(map, T, chart, xi, sig0, h, m, Phi)) {
      m.runs = map.runs() - runs0;
      m.ok = false;
      return m;
    }
    m.steps.push_back(h);
    m.estimates.push_back(Phi);
    m.step_multipliers.push_back(eigenvalues(Phi));
  }
  m.runs = map.runs() - runs0;
  if (m.estimates.empty()) {
    m.failure = "no finite-difference step given";
    return m;
  }
  combine(m);
  if (Phi_known)
    m.method += fmt::format(" [h = {:.3g}: Newton's last Jacobian, taken within 1e-5 of the orbit]",
                            h_known);
  return m;
}

bool FiniteDifferenceMonodromy::refine(const PeriodMap& map, double T, const SectionChart& chart,
                                       VecIn xi, const FlowRun& at, Monodromy& m) const {
  if (!m.ok || m.estimates.empty() || m.sequence_changed) return false;
  double h;
  bool finer;
  if (m.estimates.size() == 1) {
    h = m.steps.back() / 4.0;
    finer = true;
  } else if (m.chosen == static_cast<int>(m.differences.size()) - 1) {
    h = m.steps.back() / 4.0;  // the finest pair is the best: truncation dominates
    finer = true;
  } else if (m.chosen == 0) {
    h = m.steps.front() * 4.0;  // the coarsest is the best: noise dominates
    finer = false;
  } else {
    return false;
  }
  // Steps beyond these bounds are no use: below 1e-7 L the differences are round-off of the
  // states (1e-16 / 1e-7 = 1e-9 relative at best, far below the integrator's noise); above
  // 0.1 L the perturbation is no longer small against the gap.
  if (h < 1e-7 || h > 0.1) return false;
  const long runs0 = map.runs();
  Mat Phi;
  const bool ok = estimate(map, T, chart, xi, event_signature(at, map.t0()), h, m, Phi);
  m.runs += map.runs() - runs0;
  if (!ok) {
    m.ok = false;
    return false;
  }
  if (finer) {
    m.steps.push_back(h);
    m.estimates.push_back(Phi);
    m.step_multipliers.push_back(eigenvalues(Phi));
  } else {
    m.steps.insert(m.steps.begin(), h);
    m.estimates.insert(m.estimates.begin(), Phi);
    m.step_multipliers.insert(m.step_multipliers.begin(), eigenvalues(Phi));
  }
  combine(m);
  return true;
}

// ---- multipliers -------------------------------------------------------------------------------

std::string_view to_string(Stability s) {
  switch (s) {
    case Stability::Stable: return "stable";
    case Stability::Unstable: return "unstable";
    default: return "undecided";
  }
}

FloquetAnalysis floquet_analysis(const Monodromy& m, MatIn tangent, VecIn scale, bool autonomous) {
  FloquetAnalysis out;
  if (!m.ok) {
    out.reason = "no monodromy: " + m.failure;
    return out;
  }
  const int d = static_cast<int>(m.M.rows());
  if (d == 0) {
    out.stability = Stability::Stable;
    out.reason = "the section has no coordinates";
    return out;
  }
  Eigen::EigenSolver<Mat> es(m.M, true);
  const Eigen::VectorXcd lam = es.eigenvalues();
  const Eigen::MatrixXcd V = es.eigenvectors();
  const Eigen::MatrixXcd W = V.inverse();  // rows: left eigenvectors with W V = I
  // the spread between the estimates of the pair used (finite differences)
  std::vector<const std::vector<std::complex<double>>*> pair;
  if (m.chosen >= 0 && static_cast<std::size_t>(m.chosen + 1) < m.step_multipliers.size()) {
    pair.push_back(&m.step_multipliers[static_cast<std::size_t>(m.chosen)]);
    pair.push_back(&m.step_multipliers[static_cast<std::size_t>(m.chosen + 1)]);
  }
  for (int i = 0; i < d; ++i) {
    FloquetMultiplier f;
    f.value = lam(i);
    f.condition = V.col(i).norm() * W.row(i).norm();
    if (!std::isfinite(f.condition)) f.condition = std::numeric_limits<double>::infinity();
    double spread = 0.0;
    for (const auto* s : pair) spread = std::max(spread, nearest(f.value, *s));
    f.error = std::max(f.condition * m.error, spread);
    const Eigen::VectorXcd dir = tangent.cast<std::complex<double>>() * V.col(i);
    const double nrm = dir.cwiseQuotient(scale.cast<std::complex<double>>()).norm();
    f.direction = nrm > 0.0 ? Eigen::VectorXcd(dir / nrm) : dir;
    out.multipliers.push_back(std::move(f));
  }
  std::stable_sort(
      out.multipliers.begin(), out.multipliers.end(),
      [](const auto& a, const auto& b) { return std::abs(a.value) > std::abs(b.value); });
  if (autonomous) {
    for (std::size_t i = 0; i < out.multipliers.size(); ++i) {
      const auto& f = out.multipliers[i];
      if (f.value.imag() != 0.0) continue;
      if (out.trivial < 0 ||
          std::abs(f.value.real() - 1.0) <
              std::abs(out.multipliers[static_cast<std::size_t>(out.trivial)].value.real() - 1.0))
        out.trivial = static_cast<int>(i);
    }
    if (out.trivial >= 0) {
      const auto& f = out.multipliers[static_cast<std::size_t>(out.trivial)];
      out.trivial_ok = std::abs(f.value - 1.0) <= f.error;
    }
  }
  auto skip = [&](std::size_t i) { return static_cast<int>(i) == out.trivial; };
  const std::string others = out.trivial >= 0 ? " (the trivial multiplier set apart)" : "";
  if (m.sequence_changed) {
    out.reason = "the events change within the differences' steps: " + m.sequence_note;
    return out;
  }
  for (std::size_t i = 0; i < out.multipliers.size(); ++i) {
    const auto& f = out.multipliers[i];
    if (skip(i)) continue;
    if (std::abs(f.value) - f.error > 1.0) {
      out.stability = Stability::Unstable;
      out.reason = fmt::format(
          "multiplier {} = {:.6g}{:+.6g}i, |.| = {:.6g} > 1 by more than its error {:.2g}", i + 1,
          f.value.real(), f.value.imag(), std::abs(f.value), f.error);
      return out;
    }
  }
  for (std::size_t i = 0; i < out.multipliers.size(); ++i) {
    const auto& f = out.multipliers[i];
    if (skip(i)) continue;
    if (!(std::abs(f.value) + f.error < 1.0)) {
      out.reason = fmt::format(
          "multiplier {} = {:.6g}{:+.6g}i, |.| = {:.6g}, is within its error {:.2g} of the unit "
          "circle",
          i + 1, f.value.real(), f.value.imag(), std::abs(f.value), f.error);
      return out;
    }
  }
  std::size_t first = 0;
  while (first < out.multipliers.size() && skip(first)) ++first;
  if (first == out.multipliers.size()) {
    out.stability = Stability::Stable;
    out.reason = "no multiplier but the trivial one";
    return out;
  }
  const auto& f = out.multipliers[first];
  out.stability = Stability::Stable;
  out.reason =
      fmt::format("every |multiplier| + its error < 1{} (largest |.| = {:.6g}, error {:.2g})",
                  others, std::abs(f.value), f.error);
  return out;
}

// ---- Newton ------------------------------------------------------------------------------------

std::string_view to_string(OrbitOutcome o) {
  switch (o) {
    case OrbitOutcome::Converged: return "converged";
    case OrbitOutcome::NoConvergence: return "no_convergence";
    case OrbitOutcome::RunFailed: return "run_failed";
    case OrbitOutcome::ChartFailed: return "chart_failed";
    case OrbitOutcome::SequenceChanged: return "sequence_changed";
    case OrbitOutcome::NotIsolated: return "not_isolated";
  }
  return "?";
}

namespace {

/// The orbit's run over one period, its events after t0 and its phase times.
void set_orbit(OrbitResult& res, FlowRun r, double t0) {
  res.orbit = std::move(r);
  res.events.clear();
  res.event_counts = {};
  for (const auto& e : res.orbit.events) {
    if (e.t <= t0) continue;
    res.events.push_back({e.t - t0, e.kind, e.contact, e.phase_before, e.phase_after});
    ++res.event_counts[static_cast<std::size_t>(e.kind)];
  }
  res.phase_time = res.orbit.summary.phase_time;
}

/// The final run over one period, sampled.
void describe_orbit(const PeriodMap& map, double T, int samples, OrbitResult& res) {
  set_orbit(res, map.run(res.x0, T, T / std::max(1, samples)), map.t0());
}

}  // namespace

OrbitResult find_forced_orbit(const PeriodMap& map, VecIn guess, double T, double omega_ref,
                              const OrbitOptions& opt) {
  const auto clock0 = std::chrono::steady_clock::now();
  const long runs0 = map.runs();
  OrbitResult res;
  res.t0 = map.t0();
  res.period = T;
  const LagrangianModel& model = map.model();
  const Vec D = state_scale(model, omega_ref);
  auto finish = [&](OrbitOutcome o, std::string msg) {
    res.outcome = o;
    res.message = std::move(msg);
    // the last iterate's period, sampled (also when the search failed: orbit.csv shows it)
    if (res.orbit.samples.empty() && res.x0.size() == map.state_size() && opt.samples > 0)
      describe_orbit(map, T, opt.samples, res);
    if (res.floquet.reason.empty())
      res.floquet.reason =
          "no multipliers: the search ended without an orbit (" + std::string(to_string(o)) + ")";
    res.runs = map.runs() - runs0;
    res.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
    return res;
  };
  auto failed_run = [&](const FlowRun& r, const std::string& what) {
    res.run_termination = r.summary.termination;
    return finish(OrbitOutcome::RunFailed,
                  fmt::format("{} ended early ({}): {}", what, to_string(r.summary.termination),
                              r.summary.message));
  };

  FlowRun run = map.run(guess, T);
  res.x0 = guess;
  if (!run.complete()) return failed_run(run, "the run from the initial guess");
  // A point of the orbit is in the same phases at t0 and t0 + T. A guess that is not (e.g. in
  // free flight near a contact orbit) is replaced by its image first: fixed-point steps, which
  // bring a stable orbit's neighbourhood onto its phases.
  for (int k = 0; k < kMaxFixedPointSteps && start_phases(run) != end_phases(run); ++k) {
    NewtonRecord rec;
    rec.iteration = static_cast<int>(res.history.size());
    rec.signature = event_signature(run, res.t0);
    rec.jacobian = "fixed point (the phases at t0 and t0 + T differ)";
    const Vec x0 = stacked_state(run.samples.front());
    const Vec x1 = stacked_state(run.samples.back());
    rec.residual = (x1 - x0).cwiseQuotient(D).cwiseAbs().maxCoeff();
    rec.step = rec.residual;
    run = map.run(x1, T);
    rec.runs = map.runs() - runs0;
    res.history.push_back(rec);
    res.x0 = x1;
    if (!run.complete()) return failed_run(run, "the run from a fixed-point step");
  }
  Vec x = stacked_state(run.samples.front());  // the integrator's start (on the constraint)
  res.x0 = x;
  auto chart = std::make_unique<SectionChart>(model, res.t0, x, start_phases(run), D);
  Vec xi = Vec::Zero(chart->dim());
  auto residual_of = [&](const FlowRun& r, const Vec& xs) {
    return chart->scaled_distance(xs, stacked_state(r.samples.back()));
  };
  Vec r = chart->coords(stacked_state(run.samples.back())) - xi;
  double res_norm = residual_of(run, x);
  Mat J;
  bool have_J = false;
  const FiniteDifferenceMonodromy newton_fd({opt.newton_step});
  // Newton's last finite-difference Jacobian, where it was taken (a seed of the final monodromy)
  struct Seed {
    Monodromy m;
    std::unique_ptr<SectionChart> chart;
    Vec xi, x;
  };
  std::unique_ptr<Seed> seed;
  const int it0 = static_cast<int>(res.history.size());
  for (int it = it0;; ++it) {
    NewtonRecord rec;
    rec.iteration = it;
    rec.residual = res_norm;
    rec.signature = event_signature(run, res.t0);
    res.residual = res_norm;
    if (res_norm <= opt.tol) {
      rec.runs = map.runs() - runs0;
      res.history.push_back(rec);
      break;
    }
    if (it - it0 >= opt.max_iterations) {
      rec.runs = map.runs() - runs0;
      res.history.push_back(rec);
      return finish(OrbitOutcome::NoConvergence,
                    fmt::format("no convergence in {} Newton iterations: residual {:.3g} > tol "
                                "{:.3g}",
                                opt.max_iterations, res_norm, opt.tol));
    }
    if (!have_J) {
      // the provider's derivative where one is given (sensitivities: no perturbed runs, so
      // also next to a grazing, where the finite differences' perturbations cross it)
      const Monodromy mj = opt.provider ? opt.provider->compute(map, T, *chart, xi, run)
                                        : newton_fd.compute(map, T, *chart, xi, run);
      if (!mj.ok) {
        rec.runs = map.runs() - runs0;
        res.history.push_back(rec);
        return finish(OrbitOutcome::RunFailed, "Newton's Jacobian: " + mj.failure);
      }
      J = mj.M - Mat::Identity(chart->dim(), chart->dim());
      have_J = true;
      if (!opt.provider)
        seed = std::make_unique<Seed>(Seed{mj, std::make_unique<SectionChart>(*chart), xi, x});
      rec.jacobian = opt.provider ? std::string(opt.provider->name()) : "finite differences";
    } else {
      rec.jacobian = "broyden";
    }
    const Eigen::ColPivHouseholderQR<Mat> qr(J);
    const Eigen::JacobiSVD<Mat> svd(J);
    const auto& sv = svd.singularValues();
    const double rcond = sv.size() ? sv(sv.size() - 1) / sv(0) : 1.0;
    if (!(rcond > kSingularRcond)) {
      rec.runs = map.runs() - runs0;
      res.history.push_back(rec);
      return finish(OrbitOutcome::NotIsolated,
                    fmt::format("Phi - I is singular (reciprocal condition {:.2g}): a multiplier "
                                "at +1, the orbit is not isolated (a fold, or a family)",
                                rcond));
    }
    const Vec step = qr.solve(-r);
    // a halved step while the residual does not fall
    double lambda = 1.0;
    bool accepted = false, got = false, slow = false;
    FlowRun run_new;
    Vec x_new, xi_new;
    OrbitOutcome why_outcome = OrbitOutcome::ChartFailed;
    Termination why_termination = Termination::Completed;
    std::string why;
    for (int h = 0; h <= kMaxHalvings; ++h, lambda *= 0.5) {
      xi_new = xi + lambda * step;
      if (!chart->embed(xi_new, x_new)) {
        why = "the Newton step could not be put on the constraints of the section";
        why_outcome = OrbitOutcome::ChartFailed;
        continue;
      }
      run_new = map.run(x_new, T);
      if (!run_new.complete()) {
        why = fmt::format("the run from the Newton iterate ended early ({}): {}",
                          to_string(run_new.summary.termination), run_new.summary.message);
        why_outcome = OrbitOutcome::RunFailed;
        why_termination = run_new.summary.termination;
        continue;
      }
      const Vec xs = stacked_state(run_new.samples.front());
      const double rn = residual_of(run_new, xs);
      if (rn < res_norm || h == kMaxHalvings) {
        accepted = rn < res_norm;
        // a step that took off less than half the residual: a fresh Jacobian next time
        if (rn > 0.5 * res_norm) slow = true;
        got = true;
        x_new = xs;
        break;
      }
    }
    rec.damping = lambda;
    rec.runs = map.runs() - runs0;
    if (!got) {
      res.history.push_back(rec);
      res.run_termination = why_termination;
      return finish(why_outcome, why);
    }
    rec.step = chart->scaled_distance(x, x_new);
    res.history.push_back(rec);
    // Broyden's update of J from the step taken (in the chart's coordinates)
    const Vec r_new = chart->coords(stacked_state(run_new.samples.back())) - chart->coords(x_new);
    const Vec s = chart->coords(x_new) - xi;
    if (accepted && s.squaredNorm() > 0.0) {
      J += ((r_new - r) - J * s) * s.transpose() / s.squaredNorm();
    } else {
      have_J = false;  // a step that did not help: a fresh Jacobian at the new iterate
    }
    if (lambda < 1.0 || slow) have_J = false;
    x = x_new;
    res.x0 = x;
    run = std::move(run_new);
    xi = chart->coords(x);
    r = r_new;
    res_norm = residual_of(run, x);
    if (xi.size() && xi.cwiseAbs().maxCoeff() > kRebase) {
      chart = std::make_unique<SectionChart>(model, res.t0, x, start_phases(run), D);
      xi = Vec::Zero(chart->dim());
      r = chart->coords(stacked_state(run.samples.back()));
      have_J = false;
    }
  }

  // the orbit: the monodromy in the chart based on it, the multipliers, the sampled period
  res.x0 = x;
  res.section_phases = start_phases(run);
  const SectionChart at(model, res.t0, x, res.section_phases, D);
  res.chart_dim = at.dim();
  res.constraints = at.constraint_count();
  const FiniteDifferenceMonodromy fd(opt.fd_steps);
  const MonodromyProvider& provider = opt.provider ? *opt.provider : fd;
  const Vec zero = Vec::Zero(at.dim());
  const Mat tangent = at.tangent(zero);
  bool seeded = false;
  if (!opt.provider && seed && !seed->m.sequence_changed &&
      at.scaled_distance(seed->x, x) <= kReuseDistance &&
      std::find(opt.fd_steps.begin(), opt.fd_steps.end(), opt.newton_step) != opt.fd_steps.end()) {
    // the seed in this chart's coordinates: C = d(coords here) / d(coords there)
    const Mat C = at.coords_jacobian() * seed->chart->tangent(seed->xi);
    const Eigen::ColPivHouseholderQR<Mat> qc(C);
    if (qc.rank() == at.dim()) {
      const Mat Phi = C * seed->m.M * qc.inverse();
      res.monodromy = fd.compute_seeded(map, T, at, zero, run, opt.newton_step, Phi);
      seeded = true;
    }
  }
  if (!seeded) res.monodromy = provider.compute(map, T, at, zero, run);
  res.floquet = floquet_analysis(res.monodromy, tangent, D);
  // step-size control: more steps while the error leaves the verdict open
  for (int k = 0;
       k < opt.fd_refinements && !opt.provider && res.floquet.stability == Stability::Undecided &&
       fd.refine(map, T, at, zero, run, res.monodromy);
       ++k)
    res.floquet = floquet_analysis(res.monodromy, tangent, D);
  if (opt.samples > 0) {
    describe_orbit(map, T, opt.samples, res);
    if (!res.orbit.complete()) return failed_run(res.orbit, "the sampled run on the orbit");
  } else {
    set_orbit(res, run, res.t0);  // the run from the orbit's state: its ends and events
  }
  if (!res.monodromy.ok)
    return finish(OrbitOutcome::RunFailed, "monodromy: " + res.monodromy.failure);
  if (res.monodromy.sequence_changed)
    return finish(OrbitOutcome::SequenceChanged,
                  "the orbit converged, but its events change within the finite differences' "
                  "steps (grazing, or an event at the section): " +
                      res.monodromy.sequence_note);
  return finish(OrbitOutcome::Converged,
                fmt::format("converged in {} Newton iterations, residual {:.3g}",
                            res.history.size() - 1 - static_cast<std::size_t>(it0), res.residual));
}

// ---- autonomous orbits ------------------------------------------------------------------------

OrbitResult find_autonomous_orbit(const PeriodMap& map, VecIn guess, double T0, double omega_ref,
                                  const std::vector<int>& pinned, const OrbitOptions& opt) {
  const auto clock0 = std::chrono::steady_clock::now();
  const long runs0 = map.runs();
  OrbitResult res;
  res.t0 = map.t0();
  res.period = T0;
  res.x0 = guess;
  const LagrangianModel& model = map.model();
  const Vec D = state_scale(model, omega_ref);
  auto finish = [&](OrbitOutcome o, std::string msg) {
    res.outcome = o;
    res.message = std::move(msg);
    if (res.orbit.samples.empty() && res.x0.size() == map.state_size() && opt.samples > 0)
      describe_orbit(map, res.period, opt.samples, res);
    if (res.floquet.reason.empty())
      res.floquet.reason =
          "no multipliers: the search ended without an orbit (" + std::string(to_string(o)) + ")";
    res.runs = map.runs() - runs0;
    res.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
    return res;
  };
  // the guess's run, sampled a hundred times: the flow's direction at the start
  FlowRun run = map.run(guess, T0, T0 / 100.0);
  if (!run.complete() || run.samples.size() < 2) {
    res.run_termination = run.summary.termination;
    return finish(OrbitOutcome::RunFailed,
                  "the run from the initial guess ended early: " + run.summary.message);
  }
  const Vec xb = stacked_state(run.samples.front());
  res.x0 = xb;
  const SectionChart chart(model, res.t0, xb, start_phases(run), D, pinned);
  const int d = chart.dim();
  // the phase condition: the coordinate along which the flow moves fastest at the base
  const Sample* next = nullptr;  // the first sample after the start
  for (const Sample& s : run.samples)
    if (s.t > res.t0) {
      next = &s;
      break;
    }
  if (!next) return finish(OrbitOutcome::RunFailed, "no sample after the start");
  const Vec flow = chart.coords(stacked_state(*next)) / (next->t - res.t0);
  Eigen::Index j_fixed = 0;
  flow.cwiseAbs().maxCoeff(&j_fixed);
  const int j = static_cast<int>(j_fixed);
  // unknowns v = (xi without j, T / T0); residual r = coords(P_T(embed(xi))) - xi
  auto expand = [&](const Vec& v) {
    Vec xi(d);
    for (int i = 0, k = 0; i < d; ++i) xi(i) = i == j ? 0.0 : v(k++);
    return xi;
  };
  struct Eval {
    bool ok = false;
    FlowRun run;
    Vec r;
    double res = 0.0;
    std::string why;
  };
  auto evaluate = [&](const Vec& v) {
    Eval e;
    const Vec xi = expand(v);
    Vec x;
    if (!chart.embed(xi, x)) {
      e.why = "an iterate could not be put on the constraints of the section";
      return e;
    }
    e.run = map.run(x, v(d - 1) * T0);
    if (!e.run.complete()) {
      e.why = fmt::format("a run ended early ({}): {}", to_string(e.run.summary.termination),
                          e.run.summary.message);
      return e;
    }
    e.r = chart.coords(stacked_state(e.run.samples.back())) - xi;
    e.res = chart.scaled_distance(stacked_state(e.run.samples.front()),
                                  stacked_state(e.run.samples.back()));
    e.ok = true;
    return e;
  };
  Vec v = Vec::Zero(d);
  v(d - 1) = 1.0;
  Eval cur = evaluate(v);
  if (!cur.ok) return finish(OrbitOutcome::RunFailed, cur.why);
  Mat J;
  bool have_J = false;
  const FiniteDifferenceMonodromy newton_fd({opt.newton_step});
  for (int it = 0;; ++it) {
    NewtonRecord rec;
    rec.iteration = it;
    rec.residual = cur.res;
    rec.signature = event_signature(cur.run, res.t0);
    res.residual = cur.res;
    res.period = v(d - 1) * T0;
    res.x0 = stacked_state(cur.run.samples.front());
    if (cur.res <= opt.tol) {
      rec.runs = map.runs() - runs0;
      res.history.push_back(rec);
      break;
    }
    if (it >= opt.max_iterations) {
      rec.runs = map.runs() - runs0;
      res.history.push_back(rec);
      return finish(OrbitOutcome::NoConvergence,
                    fmt::format("no convergence in {} Newton iterations: residual {:.3g} > tol "
                                "{:.3g}",
                                opt.max_iterations, cur.res, opt.tol));
    }
    if (!have_J) {
      // d(coords P)/d xi by the finite differences, d/dT by central differences in T
      const Monodromy mj = newton_fd.compute(map, res.period, chart, expand(v), cur.run);
      if (!mj.ok) return finish(OrbitOutcome::RunFailed, "Newton's Jacobian: " + mj.failure);
      const double h = opt.newton_step;
      Vec vp = v, vm = v;
      vp(d - 1) += h;
      vm(d - 1) -= h;
      const Eval ep = evaluate(vp), em = evaluate(vm);
      if (!ep.ok || !em.ok)
        return finish(OrbitOutcome::RunFailed, "Newton's Jacobian: " + (ep.ok ? em.why : ep.why));
      J.resize(d, d);
      const Mat A = mj.M - Mat::Identity(d, d);
      for (int i = 0, k = 0; i < d; ++i)
        if (i != j) J.col(k++) = A.col(i);
      J.col(d - 1) = (ep.r - em.r) / (2.0 * h);
      have_J = true;
      rec.jacobian = "finite differences";
    } else {
      rec.jacobian = "broyden";
    }
    const Eigen::JacobiSVD<Mat> svd(J);
    const auto& sv = svd.singularValues();
    if (!(sv(sv.size() - 1) > kSingularRcond * sv(0))) {
      rec.runs = map.runs() - runs0;
      res.history.push_back(rec);
      return finish(OrbitOutcome::NotIsolated,
                    "the Newton system is singular: the phase condition does not fix the orbit, "
                    "or a second multiplier is at +1");
    }
    const Vec step = J.colPivHouseholderQr().solve(-cur.r);
    double lambda = 1.0;
    Eval nxt;
    for (int h = 0; h <= kMaxHalvings; ++h, lambda *= 0.5) {
      nxt = evaluate(v + lambda * step);
      if (nxt.ok && (nxt.res < cur.res || h == kMaxHalvings)) break;
    }
    rec.damping = lambda;
    rec.runs = map.runs() - runs0;
    if (!nxt.ok) {
      res.history.push_back(rec);
      return finish(OrbitOutcome::RunFailed, nxt.why);
    }
    const Vec s = lambda * step;
    rec.step = s.cwiseAbs().maxCoeff();
    res.history.push_back(rec);
    if (nxt.res < cur.res && lambda == 1.0 && nxt.res <= 0.5 * cur.res)
      J += ((nxt.r - cur.r) - J * s) * s.transpose() / s.squaredNorm();
    else
      have_J = false;
    v += s;
    cur = std::move(nxt);
  }
  // the orbit: the monodromy at T in the chart based on it
  const Vec x = stacked_state(cur.run.samples.front());
  res.x0 = x;
  res.section_phases = start_phases(cur.run);
  const SectionChart at(model, res.t0, x, res.section_phases, D, pinned);
  res.chart_dim = at.dim();
  res.constraints = at.constraint_count();
  const FiniteDifferenceMonodromy fd(opt.fd_steps);
  const Vec zero = Vec::Zero(at.dim());
  const Mat tangent = at.tangent(zero);
  res.monodromy = opt.provider ? opt.provider->compute(map, res.period, at, zero, cur.run)
                               : fd.compute(map, res.period, at, zero, cur.run);
  res.floquet = floquet_analysis(res.monodromy, tangent, D, true);
  for (int k = 0;
       k < opt.fd_refinements && !opt.provider && res.floquet.stability == Stability::Undecided &&
       fd.refine(map, res.period, at, zero, cur.run, res.monodromy);
       ++k)
    res.floquet = floquet_analysis(res.monodromy, tangent, D, true);
  if (opt.samples > 0) {
    describe_orbit(map, res.period, opt.samples, res);
    if (!res.orbit.complete()) {
      res.run_termination = res.orbit.summary.termination;
      return finish(OrbitOutcome::RunFailed, "the sampled run on the orbit ended early");
    }
  } else {
    set_orbit(res, cur.run, res.t0);
  }
  if (!res.monodromy.ok)
    return finish(OrbitOutcome::RunFailed, "monodromy: " + res.monodromy.failure);
  if (res.monodromy.sequence_changed)
    return finish(OrbitOutcome::SequenceChanged,
                  "the orbit converged, but its events change within the finite differences' "
                  "steps: " +
                      res.monodromy.sequence_note);
  return finish(OrbitOutcome::Converged,
                fmt::format("converged in {} Newton iterations, residual {:.3g}, period {:.10g} "
                            "s (phase condition on section coordinate {})",
                            res.history.size() - 1, res.residual, res.period, j + 1));
}

// ---- the monodromy from the flow's sensitivities ----------------------------------------------

namespace {
// The second solve's tolerance factor: the error estimate is the difference of the monodromies
// at rtol and rtol / 100 (the coarser's error). Below kFinestRtol CVODE is asked for more
// accuracy than double precision gives over a period; the pair is then rtol x 100 and rtol.
constexpr double kSensitivityRtolFactor = 1e-2;
constexpr double kSensitivityFinestRtol = 1e-13;
}  // namespace

Monodromy SensitivityMonodromy::compute(const PeriodMap& map, double T, const SectionChart& chart,
                                        VecIn xi, const FlowRun& at) const {
  Monodromy res;
  if (!at.complete()) {
    res.failure = "the orbit's run did not complete";
    return res;
  }
  const Mat V0 = chart.tangent(xi);
  const double rtol = map.options().rtol;
  const double rtol_b = rtol * kSensitivityRtolFactor >= kSensitivityFinestRtol
                            ? rtol * kSensitivityRtolFactor
                            : rtol / kSensitivityRtolFactor;
  const double fine = std::min(rtol, rtol_b), coarse = std::max(rtol, rtol_b);
  const double t_end = map.t0() + T;
  const FlowSensitivity a = flow_sensitivity(map.model(), map.options(), at.samples, at.events,
                                             t_end, V0, chart.scale(), fine);
  const FlowSensitivity b = a.ok ? flow_sensitivity(map.model(), map.options(), at.samples,
                                                    at.events, t_end, V0, chart.scale(), coarse)
                                 : a;
  if (!a.ok || !b.ok) {
    const FlowSensitivity& bad = a.ok ? b : a;
    res.failure = "sensitivities: " + bad.why;
    if (bad.not_smooth) {
      res.sequence_changed = true;
      res.sequence_note = bad.why;
    }
    return res;
  }
  const Mat C = chart.coords_jacobian();
  res.M = C * a.V;
  res.error = Eigen::JacobiSVD<Mat>(Mat(res.M - C * b.V)).singularValues()(0);
  res.ok = true;
  res.method = fmt::format(
      "sensitivities: variational equations with saltation matrices at {} events, CVODE-BDF at "
      "rtol {:.3g}; error: the difference from rtol {:.3g} ({} steps in all)",
      a.events, fine, coarse, a.steps + b.steps);
  return res;
}

}  // namespace rubdyn
