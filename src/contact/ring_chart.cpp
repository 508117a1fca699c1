#include "rubdyn/contact/ring_chart.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "rubdyn/core/demand.hpp"

namespace rubdyn {

namespace {
bool closed_mode(Phase p) {
  return p != Phase::Free;
}
constexpr int kRows = RingAnchor::kMax;
constexpr int kCols = 2 * RingAnchor::kMax;  // each fixed contact's point: at most 2 coordinates
}  // namespace

RingChart::RingChart(int n, int spin, std::vector<RingContact> contacts, std::optional<SpinLaw> law)
    : n_(n),
      spin_(spin),
      c_(std::move(contacts)),
      law_(law),
      ring_owner_(static_cast<std::size_t>(n), -1) {
  RUBDYN_DEMAND(static_cast<int>(c_.size()) <= RingAnchor::kMax);
  RUBDYN_DEMAND(!(law_ && spin_ >= 0));  // a spin is a coordinate or a function of time
  for (int k = 0; k < contact_count(); ++k) {
    const RingContact& c = c_[static_cast<std::size_t>(k)];
    RUBDYN_DEMAND(c.gap > 0.0);
    for (std::size_t j = 0; j < 2; ++j)
      RUBDYN_DEMAND((c.ix[j] < 0) == (c.iy[j] < 0) && c.ix[j] < n && c.iy[j] < n);
    if (c.ring < 0) continue;
    RUBDYN_DEMAND(c.ring + 1 < n);
    for (const int i : {c.ring, c.ring + 1}) {
      // a ring shared by two contacts: owned by the first; applies() refuses the pair
      if (ring_owner_[static_cast<std::size_t>(i)] < 0)
        ring_owner_[static_cast<std::size_t>(i)] = k;
    }
  }
}

bool RingChart::any_stick(std::span<const Phase> modes) {
  return std::any_of(modes.begin(), modes.end(), [](Phase p) { return p == Phase::Stick; });
}

bool RingChart::ring_eliminated(std::span<const Phase> modes, int i) const {
  const int k = ring_owner_[static_cast<std::size_t>(i)];
  return k >= 0 && closed_mode(modes[static_cast<std::size_t>(k)]);
}

double RingChart::point(const std::array<int, 2>& idx, int k, VecIn q) const {
  const RingContact& c = c_[static_cast<std::size_t>(k)];
  double x = 0.0;
  for (std::size_t j = 0; j < 2; ++j)
    if (idx[j] >= 0) x += c.w[j] * q[idx[j]];
  return x;
}
double RingChart::px(int k, VecIn q) const {
  return point(c_[static_cast<std::size_t>(k)].ix, k, q);
}
double RingChart::py(int k, VecIn q) const {
  return point(c_[static_cast<std::size_t>(k)].iy, k, q);
}
double RingChart::sx(int k, VecIn q) const {
  const int d = c_[static_cast<std::size_t>(k)].ring;
  return d >= 0 ? q[d] : 0.0;
}
double RingChart::sy(int k, VecIn q) const {
  const int d = c_[static_cast<std::size_t>(k)].ring;
  return d >= 0 ? q[d + 1] : 0.0;
}

bool RingChart::choose_pivots(const Plan& pl, bool use_y,
                              std::array<int, RingAnchor::kMax>& piv) const {
  // the rows' coefficients over the distinct coordinates they involve (ascending), then
  // Gaussian elimination with full pivoting: each step's largest entry (the first on ties,
  // rows and columns in order) is a pivot
  int col[kCols];
  int m = 0;
  for (int r = 0; r < pl.rows; ++r) {
    const RingContact& c = c_[static_cast<std::size_t>(pl.row_k[static_cast<std::size_t>(r)])];
    for (std::size_t j = 0; j < 2; ++j) {
      const int i = use_y ? c.iy[j] : c.ix[j];
      if (i >= 0 && c.w[j] != 0.0 && std::find(col, col + m, i) == col + m) col[m++] = i;
    }
  }
  std::sort(col, col + m);
  if (m < pl.rows) return false;
  double A[kRows][kCols] = {};
  double scale = 0.0;
  for (int r = 0; r < pl.rows; ++r) {
    const RingContact& c = c_[static_cast<std::size_t>(pl.row_k[static_cast<std::size_t>(r)])];
    for (std::size_t j = 0; j < 2; ++j) {
      const int i = use_y ? c.iy[j] : c.ix[j];
      if (i < 0) continue;
      const int at = static_cast<int>(std::find(col, col + m, i) - col);
      if (at < m) A[r][at] += c.w[j];
    }
    for (int a = 0; a < m; ++a) scale = std::max(scale, std::abs(A[r][a]));
  }
  bool used[kCols] = {};
  int row_done[kRows] = {};
  for (int s = 0; s < pl.rows; ++s) {
    int br = -1, bc = -1;
    double best = 0.0;
    for (int r = 0; r < pl.rows; ++r) {
      if (row_done[r]) continue;
      for (int a = 0; a < m; ++a)
        if (!used[a] && std::abs(A[r][a]) > best) {
          best = std::abs(A[r][a]);
          br = r;
          bc = a;
        }
    }
    if (br < 0 || !(best > kRingChartPivot * scale)) return false;
    row_done[br] = 1;
    used[bc] = true;
    piv[static_cast<std::size_t>(br)] = col[bc];
    for (int r = 0; r < pl.rows; ++r) {
      if (row_done[r] || A[r][bc] == 0.0) continue;
      const double f = A[r][bc] / A[br][bc];
      for (int a = 0; a < m; ++a) A[r][a] -= f * A[br][a];
    }
  }
  return true;
}

void RingChart::plan(std::span<const Phase> modes, Plan& pl) const {
  pl = Plan{};
  if (static_cast<int>(modes.size()) != contact_count()) return;
  std::copy(modes.begin(), modes.end(), pl.modes.begin());
  bool any = false;
  for (int k = 0; k < contact_count(); ++k) {
    const Phase mk = modes[static_cast<std::size_t>(k)];
    if (!closed_mode(mk)) continue;
    any = true;
    const RingContact& c = c_[static_cast<std::size_t>(k)];
    if (mk == Phase::Stick && spin_ < 0 && !law_) return;
    if (c.ring >= 0) {
      if (ring_owner_[static_cast<std::size_t>(c.ring)] != k ||
          ring_owner_[static_cast<std::size_t>(c.ring + 1)] != k)
        return;  // a ring shared with another contact
      if (spin_ == c.ring || spin_ == c.ring + 1) return;
    } else {
      pl.row_k[static_cast<std::size_t>(pl.rows++)] = k;
    }
  }
  if (!any) return;
  for (int k = 0; k < contact_count(); ++k) {
    const RingContact& c = c_[static_cast<std::size_t>(k)];
    if (!closed_mode(modes[static_cast<std::size_t>(k)])) continue;
    for (int j = 0; j < 2; ++j)  // the rotor's point must not move with the spin or a ring
      for (const int i : {c.ix[static_cast<std::size_t>(j)], c.iy[static_cast<std::size_t>(j)]})
        if (i >= 0 && (i == spin_ || ring_eliminated(modes, i))) return;
    if (c.ring < 0) continue;
    for (int l = k + 1; l < contact_count(); ++l)  // two closed contacts on one ring
      if (closed_mode(modes[static_cast<std::size_t>(l)]) &&
          c_[static_cast<std::size_t>(l)].ring >= 0 &&
          std::abs(c_[static_cast<std::size_t>(l)].ring - c.ring) <= 1)
        return;
  }
  if (pl.rows > 0) {
    // the fixed rings' pivots: rotor coordinates of their points (checked above: never the
    // spin or a closed contact's ring)
    if (!choose_pivots(pl, false, pl.piv_x) || !choose_pivots(pl, true, pl.piv_y)) return;
  }
  for (int i = 0; i < n_; ++i)
    if (ring_eliminated(modes, i)) pl.elim[static_cast<std::size_t>(pl.n_elim++)] = i;
  for (int r = 0; r < pl.rows; ++r) {
    pl.elim[static_cast<std::size_t>(pl.n_elim++)] = pl.piv_x[static_cast<std::size_t>(r)];
    pl.elim[static_cast<std::size_t>(pl.n_elim++)] = pl.piv_y[static_cast<std::size_t>(r)];
  }
  std::sort(pl.elim.begin(), pl.elim.begin() + pl.n_elim);
  // a coordinate eliminated twice (a model whose x and y coordinates of the rotor points
  // overlap): not a chart
  if (std::adjacent_find(pl.elim.begin(), pl.elim.begin() + pl.n_elim) !=
      pl.elim.begin() + pl.n_elim)
    return;
  pl.ok = true;
}

void RingChart::solve_rows(const Plan& pl, bool use_y, const double* rhs, VecOut x) const {
  // row r: sum over its point's terms of w x = rhs[r]; the pivots unknown, every other
  // coordinate known. Gaussian elimination with partial pivoting on the rows x rows system.
  const std::array<int, RingAnchor::kMax>& piv = use_y ? pl.piv_y : pl.piv_x;
  const int nr = pl.rows;
  double A[kRows][kRows] = {}, b[kRows];
  for (int r = 0; r < nr; ++r) {
    const RingContact& c = c_[static_cast<std::size_t>(pl.row_k[static_cast<std::size_t>(r)])];
    b[r] = rhs[r];
    for (std::size_t j = 0; j < 2; ++j) {
      const int i = use_y ? c.iy[j] : c.ix[j];
      if (i < 0) continue;
      const int at = static_cast<int>(std::find(piv.begin(), piv.begin() + nr, i) - piv.begin());
      if (at < nr)
        A[r][at] += c.w[j];
      else
        b[r] -= c.w[j] * x[i];
    }
  }
  for (int s = 0; s < nr; ++s) {
    int p = s;
    for (int r = s + 1; r < nr; ++r)
      if (std::abs(A[r][s]) > std::abs(A[p][s])) p = r;
    if (p != s) {
      for (int a = 0; a < nr; ++a) std::swap(A[s][a], A[p][a]);
      std::swap(b[s], b[p]);
    }
    for (int r = s + 1; r < nr; ++r) {
      const double f = A[r][s] / A[s][s];
      for (int a = s; a < nr; ++a) A[r][a] -= f * A[s][a];
      b[r] -= f * b[s];
    }
  }
  for (int s = nr - 1; s >= 0; --s) {
    double v = b[s];
    for (int a = s + 1; a < nr; ++a) v -= A[s][a] * x[piv[static_cast<std::size_t>(a)]];
    x[piv[static_cast<std::size_t>(s)]] = v / A[s][s];
  }
}

bool RingChart::applies(std::span<const Phase> modes) const {
  Plan pl;
  plan(modes, pl);
  return pl.ok;
}

int RingChart::dim(std::span<const Phase> modes) const {
  int d = n_;
  for (const Phase p : modes) d -= closed_mode(p) ? (p == Phase::Stick ? 2 : 1) : 0;
  return d;
}

void RingChart::chart(std::span<const Phase> modes, double t, VecIn q, VecIn v, RingAnchor& anchor,
                      VecOut p, VecOut pd) const {
  Plan pl;
  plan(modes, pl);
  chart(modes, pl, t, q, v, anchor, p, pd);
}

void RingChart::chart(std::span<const Phase> modes, const Plan& pl, double t, VecIn q, VecIn v,
                      RingAnchor& anchor, VecOut p, VecOut pd) const {
  RUBDYN_DEMAND(pl.ok && std::equal(modes.begin(), modes.end(), pl.modes.begin()));
  const bool stick = any_stick(modes);
  anchor.theta0 = stick && spin_ >= 0 ? q[spin_] : 0.0;
  anchor.t0 = t;
  int j = 0;
  for (int i = 0, e = 0; i < n_; ++i) {
    if (e < pl.n_elim && pl.elim[static_cast<std::size_t>(e)] == i) {  // eliminated
      ++e;
      continue;
    }
    p[j] = stick && i == spin_ ? 0.0 : q[i];  // theta - theta0 = 0 at the anchor
    pd[j] = v[i];
    ++j;
  }
  for (int k = 0; k < contact_count(); ++k) {
    const Phase m = modes[static_cast<std::size_t>(k)];
    if (!closed_mode(m)) continue;
    const RingContact& c = c_[static_cast<std::size_t>(k)];
    const double dx = px(k, q) - sx(k, q), dy = py(k, q) - sy(k, q);
    const double phi = std::atan2(dy, dx);
    if (m == Phase::Stick) {
      anchor.phi0[static_cast<std::size_t>(k)] = phi;
      continue;
    }
    const double dvx = px(k, v) - sx(k, v), dvy = py(k, v) - sy(k, v);
    p[j] = phi;
    pd[j] = (-std::sin(phi) * dvx + std::cos(phi) * dvy) / c.gap;
    ++j;
  }
}

void RingChart::embed(std::span<const Phase> modes, const RingAnchor& anchor, double t, VecIn p,
                      VecIn pd, VecOut q, VecOut v) const {
  Plan pl;
  plan(modes, pl);
  embed(modes, pl, anchor, t, p, pd, q, v);
}

void RingChart::embed(std::span<const Phase> modes, const Plan& pl, const RingAnchor& anchor,
                      double t, VecIn p, VecIn pd, VecOut q, VecOut v) const {
  embed_impl(modes, pl, anchor, t, p, pd, q, v, false);
}

void RingChart::embed_tangent(std::span<const Phase> modes, const Plan& pl,
                              const RingAnchor& anchor, double t, VecIn p, VecIn x, VecOut q,
                              VecOut v) const {
  embed_impl(modes, pl, anchor, t, p, x, q, v, true);
}

void RingChart::embed_impl(std::span<const Phase> modes, const Plan& pl, const RingAnchor& anchor,
                           double t, VecIn p, VecIn pd, VecOut q, VecOut v, bool tangent) const {
  RUBDYN_DEMAND(pl.ok && std::equal(modes.begin(), modes.end(), pl.modes.begin()));
  const bool stick = any_stick(modes);
  int j = 0;
  for (int i = 0, e = 0; i < n_; ++i) {
    if (e < pl.n_elim && pl.elim[static_cast<std::size_t>(e)] == i) {  // eliminated
      ++e;
      continue;
    }
    q[i] = stick && i == spin_ ? anchor.theta0 + p[j] : p[j];
    v[i] = pd[j];
    ++j;
  }
  // each closed contact's angle and its rate
  std::array<double, RingAnchor::kMax> phi{}, phid{};
  for (int k = 0; k < contact_count(); ++k) {
    const Phase m = modes[static_cast<std::size_t>(k)];
    if (!closed_mode(m)) continue;
    const RingContact& c = c_[static_cast<std::size_t>(k)];
    const auto ku = static_cast<std::size_t>(k);
    if (m == Phase::Stick) {
      // theta - theta0 and omega: the spin coordinate's, or the prescribed spin's at t
      const double ratio = c.radius / c.gap;
      const double turned = spin_ >= 0 ? q[spin_] - anchor.theta0 : law_->advance(anchor.t0, t);
      phi[ku] = anchor.phi0[ku] - ratio * turned;
      // (the prescribed spin's rate is no function of p': no term of the tangent map)
      phid[ku] = -ratio * (spin_ >= 0 ? v[spin_] : (tangent ? 0.0 : law_->omega(t)));
    } else {
      phi[ku] = p[j];
      phid[ku] = pd[j];
      ++j;
    }
  }
  if (pl.rows > 0) {
    // the fixed rings first: P_k = g_k (cos phi_k, sin phi_k) for the pivots, positions and rates
    double rx[kRows], ry[kRows], rvx[kRows], rvy[kRows];
    for (int r = 0; r < pl.rows; ++r) {
      const int k = pl.row_k[static_cast<std::size_t>(r)];
      const auto ku = static_cast<std::size_t>(k);
      const double g = c_[ku].gap, cs = std::cos(phi[ku]), sn = std::sin(phi[ku]);
      rx[r] = g * cs;
      ry[r] = g * sn;
      rvx[r] = -g * phid[ku] * sn;
      rvy[r] = g * phid[ku] * cs;
    }
    solve_rows(pl, false, rx, q);
    solve_rows(pl, true, ry, q);
    solve_rows(pl, false, rvx, v);
    solve_rows(pl, true, rvy, v);
  }
  // then the sprung rings, from the completed rotor points
  for (int k = 0; k < contact_count(); ++k) {
    const Phase m = modes[static_cast<std::size_t>(k)];
    const RingContact& c = c_[static_cast<std::size_t>(k)];
    if (!closed_mode(m) || c.ring < 0) continue;
    const auto ku = static_cast<std::size_t>(k);
    const double cs = std::cos(phi[ku]), sn = std::sin(phi[ku]);
    q[c.ring] = px(k, q) - c.gap * cs;
    q[c.ring + 1] = py(k, q) - c.gap * sn;
    v[c.ring] = px(k, v) + c.gap * phid[ku] * sn;
    v[c.ring + 1] = py(k, v) - c.gap * phid[ku] * cs;
  }
}

void RingChart::reduce(std::span<const Phase> modes, VecIn q, VecIn a, VecOut pdd) const {
  Plan pl;
  plan(modes, pl);
  reduce(modes, pl, q, a, pdd);
}

void RingChart::reduce(std::span<const Phase> modes, const Plan& pl, VecIn q, VecIn a,
                       VecOut pdd) const {
  RUBDYN_DEMAND(pl.ok && std::equal(modes.begin(), modes.end(), pl.modes.begin()));
  int j = 0;
  for (int i = 0, e = 0; i < n_; ++i) {
    if (e < pl.n_elim && pl.elim[static_cast<std::size_t>(e)] == i) {  // eliminated
      ++e;
      continue;
    }
    pdd[j++] = a[i];
  }
  for (int k = 0; k < contact_count(); ++k) {
    const Phase m = modes[static_cast<std::size_t>(k)];
    if (!closed_mode(m) || m == Phase::Stick) continue;
    const RingContact& c = c_[static_cast<std::size_t>(k)];
    const double dx = px(k, q) - sx(k, q), dy = py(k, q) - sy(k, q);
    const double rho = std::sqrt(dx * dx + dy * dy);
    const double cs = dx / rho, sn = dy / rho;
    const double ax = px(k, a) - sx(k, a), ay = py(k, a) - sy(k, a);
    pdd[j++] = (-sn * ax + cs * ay) / c.gap;
  }
}

void RingChart::lengths(std::span<const Phase> modes, std::span<double> L) const {
  Plan pl;
  plan(modes, pl);
  lengths(modes, pl, L);
}

void RingChart::lengths(std::span<const Phase> modes, const Plan& pl, std::span<double> L,
                        std::span<int> copies) const {
  RUBDYN_DEMAND(pl.ok && std::equal(modes.begin(), modes.end(), pl.modes.begin()));
  const bool stick = any_stick(modes);
  double R = 0.0;
  for (int k = 0; k < contact_count(); ++k)
    if (modes[static_cast<std::size_t>(k)] == Phase::Stick)
      R = std::max(R, c_[static_cast<std::size_t>(k)].radius);
  int j = 0;
  for (int i = 0, e = 0; i < n_; ++i) {
    if (e < pl.n_elim && pl.elim[static_cast<std::size_t>(e)] == i) {  // eliminated
      ++e;
      continue;
    }
    const bool angle = stick && i == spin_;
    if (!copies.empty()) copies[static_cast<std::size_t>(j)] = angle ? -1 : i;
    L[static_cast<std::size_t>(j++)] = angle ? R : 0.0;
  }
  for (int k = 0; k < contact_count(); ++k) {
    const Phase m = modes[static_cast<std::size_t>(k)];
    if (closed_mode(m) && m != Phase::Stick) {
      if (!copies.empty()) copies[static_cast<std::size_t>(j)] = -1;
      L[static_cast<std::size_t>(j++)] = c_[static_cast<std::size_t>(k)].gap;
    }
  }
}

}  // namespace rubdyn
