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
}  // namespace

RingChart::RingChart(int n, int spin, std::vector<RingContact> contacts)
    : n_(n), spin_(spin), c_(std::move(contacts)), ring_owner_(static_cast<std::size_t>(n), -1) {
  RUBDYN_DEMAND(static_cast<int>(c_.size()) <= RingAnchor::kMax);
  for (int k = 0; k < contact_count(); ++k) {
    const RingContact& c = c_[static_cast<std::size_t>(k)];
    RUBDYN_DEMAND(c.gap > 0.0);
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

bool RingChart::eliminated(std::span<const Phase> modes, int i) const {
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

bool RingChart::applies(std::span<const Phase> modes) const {
  if (static_cast<int>(modes.size()) != contact_count()) return false;
  bool any = false;
  for (int k = 0; k < contact_count(); ++k) {
    if (!closed_mode(modes[static_cast<std::size_t>(k)])) continue;
    any = true;
    const RingContact& c = c_[static_cast<std::size_t>(k)];
    if (c.ring < 0) return false;  // a fixed ring: the rotor's point itself is constrained
    if (ring_owner_[static_cast<std::size_t>(c.ring)] != k ||
        ring_owner_[static_cast<std::size_t>(c.ring + 1)] != k)
      return false;  // a ring shared with another contact
    if (modes[static_cast<std::size_t>(k)] == Phase::Stick && spin_ < 0) return false;
    for (int j = 0; j < 2; ++j)  // the rotor's point must not move with a charted ring
      for (const int i : {c.ix[static_cast<std::size_t>(j)], c.iy[static_cast<std::size_t>(j)]})
        if (i >= 0 && (i == spin_ || eliminated(modes, i))) return false;
    if (spin_ == c.ring || spin_ == c.ring + 1) return false;
  }
  for (int k = 0; k < contact_count(); ++k) {  // two closed contacts on one ring
    const RingContact& c = c_[static_cast<std::size_t>(k)];
    if (!closed_mode(modes[static_cast<std::size_t>(k)]) || c.ring < 0) continue;
    for (int l = k + 1; l < contact_count(); ++l)
      if (closed_mode(modes[static_cast<std::size_t>(l)]) &&
          c_[static_cast<std::size_t>(l)].ring >= 0 &&
          std::abs(c_[static_cast<std::size_t>(l)].ring - c.ring) <= 1)
        return false;
  }
  return any;
}

int RingChart::dim(std::span<const Phase> modes) const {
  int d = n_;
  for (const Phase p : modes) d -= closed_mode(p) ? (p == Phase::Stick ? 2 : 1) : 0;
  return d;
}

void RingChart::chart(std::span<const Phase> modes, VecIn q, VecIn v, RingAnchor& anchor, VecOut p,
                      VecOut pd) const {
  const bool stick = any_stick(modes);
  anchor.theta0 = stick ? q[spin_] : 0.0;
  int j = 0;
  for (int i = 0; i < n_; ++i) {
    if (eliminated(modes, i)) continue;
    p[j] = stick && i == spin_ ? 0.0 : q[i];  // theta - theta0 = 0 at the anchor
    pd[j] = v[i];
    ++j;
  }
  for (int k = 0; k < contact_count(); ++k) {
    const Phase m = modes[static_cast<std::size_t>(k)];
    if (!closed_mode(m)) continue;
    const RingContact& c = c_[static_cast<std::size_t>(k)];
    const double dx = px(k, q) - q[c.ring], dy = py(k, q) - q[c.ring + 1];
    const double phi = std::atan2(dy, dx);
    if (m == Phase::Stick) {
      anchor.phi0[static_cast<std::size_t>(k)] = phi;
      continue;
    }
    const double dvx = px(k, v) - v[c.ring], dvy = py(k, v) - v[c.ring + 1];
    p[j] = phi;
    pd[j] = (-std::sin(phi) * dvx + std::cos(phi) * dvy) / c.gap;
    ++j;
  }
}

void RingChart::embed(std::span<const Phase> modes, const RingAnchor& anchor, VecIn p, VecIn pd,
                      VecOut q, VecOut v) const {
  const bool stick = any_stick(modes);
  int j = 0;
  for (int i = 0; i < n_; ++i) {
    if (eliminated(modes, i)) continue;
    q[i] = stick && i == spin_ ? anchor.theta0 + p[j] : p[j];
    v[i] = pd[j];
    ++j;
  }
  for (int k = 0; k < contact_count(); ++k) {
    const Phase m = modes[static_cast<std::size_t>(k)];
    if (!closed_mode(m)) continue;
    const RingContact& c = c_[static_cast<std::size_t>(k)];
    double phi = 0.0, phid = 0.0;
    if (m == Phase::Stick) {
      const double ratio = c.radius / c.gap;
      phi = anchor.phi0[static_cast<std::size_t>(k)] - ratio * (q[spin_] - anchor.theta0);
      phid = -ratio * v[spin_];
    } else {
      phi = p[j];
      phid = pd[j];
      ++j;
    }
    const double cs = std::cos(phi), sn = std::sin(phi);
    q[c.ring] = px(k, q) - c.gap * cs;
    q[c.ring + 1] = py(k, q) - c.gap * sn;
    v[c.ring] = px(k, v) + c.gap * phid * sn;
    v[c.ring + 1] = py(k, v) - c.gap * phid * cs;
  }
}

void RingChart::reduce(std::span<const Phase> modes, VecIn q, VecIn a, VecOut pdd) const {
  int j = 0;
  for (int i = 0; i < n_; ++i) {
    if (eliminated(modes, i)) continue;
    pdd[j++] = a[i];
  }
  for (int k = 0; k < contact_count(); ++k) {
    const Phase m = modes[static_cast<std::size_t>(k)];
    if (!closed_mode(m) || m == Phase::Stick) continue;
    const RingContact& c = c_[static_cast<std::size_t>(k)];
    const double dx = px(k, q) - q[c.ring], dy = py(k, q) - q[c.ring + 1];
    const double rho = std::sqrt(dx * dx + dy * dy);
    const double cs = dx / rho, sn = dy / rho;
    const double ax = px(k, a) - a[c.ring], ay = py(k, a) - a[c.ring + 1];
    pdd[j++] = (-sn * ax + cs * ay) / c.gap;
  }
}

void RingChart::lengths(std::span<const Phase> modes, std::span<double> L) const {
  const bool stick = any_stick(modes);
  double R = 0.0;
  for (int k = 0; k < contact_count(); ++k)
    if (modes[static_cast<std::size_t>(k)] == Phase::Stick)
      R = std::max(R, c_[static_cast<std::size_t>(k)].radius);
  int j = 0;
  for (int i = 0; i < n_; ++i) {
    if (eliminated(modes, i)) continue;
    L[static_cast<std::size_t>(j++)] = stick && i == spin_ ? R : 0.0;
  }
  for (int k = 0; k < contact_count(); ++k) {
    const Phase m = modes[static_cast<std::size_t>(k)];
    if (closed_mode(m) && m != Phase::Stick)
      L[static_cast<std::size_t>(j++)] = c_[static_cast<std::size_t>(k)].gap;
  }
}

}  // namespace rubdyn
