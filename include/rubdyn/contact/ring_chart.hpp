#pragma once
// Minimal coordinates of contact phases with several closed contacts, where each closed contact
// has a sprung ring of its own (the rigid rotor's [[plane]]s, a matrices model's
// [[contact_node]]s): the K-contact counterpart of contact_chart.hpp.
//
// Contact k touches when the rotor's point P_k (a fixed linear combination of coordinates: the
// interpolation between B and R, or a node's x, y) is at distance g_k from its ring's centre S_k.
// The ring's two coordinates then follow from P_k and one angle phi_k:
//     S_k = P_k - g_k (cos phi_k, sin phi_k),   S_k' = P_k' + g_k phi_k' (sin phi_k, -cos phi_k),
// and, with the model's tangent (sin phi, -cos phi) and v_t = t . (P - S)' - R_k theta',
//     v_t,k = -g_k phi_k' - R_k theta'.
// So a sliding contact replaces its ring's (x_s, y_s) by phi_k (one coordinate fewer), and a
// sticking one ties phi_k to the spin, phi_k = phi_k0 - (R_k / g_k)(theta - theta0) (rolling:
// two fewer). Each contact's elimination touches only its own ring's coordinates, so the charts
// of the contacts compose: any set of closed contacts whose rings are sprung, distinct, and
// none of them a coordinate of another closed contact's rotor point. A set that shares a ring
// (a split ring, two contacts on one ring) or touches a fixed ring does not: the integrator then
// uses the projection formulation for that phase.
//
// Reduced coordinates p of a mode tuple: the model's coordinates in their order without the
// closed contacts' ring coordinates (the spin stored as theta - theta0 when a contact sticks, for
// precision, as contact_chart.hpp does), then phi_k of each sliding contact in contact order.
// Accelerations: `reduce` takes the constrained acceleration a of the full model (which
// satisfies every closed contact's constraint at acceleration level) and returns p'' (the
// copied coordinates' a, and phi_k'' = (-sin phi, cos phi) . (P'' - S'') / g_k).
// Nothing here allocates.
#include <array>
#include <span>
#include <vector>

#include "rubdyn/core/run_types.hpp"
#include "rubdyn/core/types.hpp"

namespace rubdyn {

/// One contact's geometry for the chart.
struct RingContact {
  /// The rotor's point: x = sum_j w[j] q[ix[j]], y = sum_j w[j] q[iy[j]] (unused terms: -1).
  std::array<int, 2> ix{-1, -1}, iy{-1, -1};
  std::array<double, 2> w{0.0, 0.0};
  int ring = -1;        ///< the ring's x coordinate (y: ring + 1); -1: a fixed ring
  double gap = 0.0;     ///< g_k [m]
  double radius = 0.0;  ///< R_k, the seal radius (the spin's entry of W_T is -R_k) [m]
};

/// What the chart keeps of the state where a phase began (the sticking contacts' angles).
struct RingAnchor {
  static constexpr int kMax = 8;
  double theta0 = 0.0;
  std::array<double, kMax> phi0{};
};

class RingChart {
 public:
  /// n: the model's coordinates; spin: the spin's index (-1: none, so no sticking contact is
  /// charted); contacts: every contact of the model (at most RingAnchor::kMax).
  RingChart(int n, int spin, std::vector<RingContact> contacts);

  int contact_count() const { return static_cast<int>(c_.size()); }
  /// The closed contacts of `modes` can be charted together (see above).
  bool applies(std::span<const Phase> modes) const;
  /// The number of reduced coordinates for `modes`: n - (closed contacts) - (sticking ones).
  int dim(std::span<const Phase> modes) const;
  /// Reduced coordinates of a state on the constraints of `modes`, and the anchor.
  void chart(std::span<const Phase> modes, VecIn q, VecIn v, RingAnchor& anchor, VecOut p,
             VecOut pd) const;
  /// The full state of reduced coordinates.
  void embed(std::span<const Phase> modes, const RingAnchor& anchor, VecIn p, VecIn pd, VecOut q,
             VecOut v) const;
  /// p'' of a full acceleration a that satisfies the closed contacts' constraints at
  /// acceleration level, at the embedded state q.
  void reduce(std::span<const Phase> modes, VecIn q, VecIn a, VecOut pdd) const;
  /// Per reduced coordinate, the length an angle moves a contact point by per radian (0: a copy
  /// of a full coordinate; phi_k: g_k; theta - theta0 when a contact sticks: the largest R_k of
  /// the sticking contacts), as ChartScales::length in contact_chart.hpp.
  void lengths(std::span<const Phase> modes, std::span<double> L) const;

 private:
  /// sum_j w[j] q[idx[j]]: one coordinate of contact k's rotor point (idx: its ix or iy)
  double point(const std::array<int, 2>& idx, int k, VecIn q) const;
  double px(int k, VecIn q) const;
  double py(int k, VecIn q) const;
  /// Coordinate i is a closed contact's ring coordinate (eliminated).
  bool eliminated(std::span<const Phase> modes, int i) const;
  static bool any_stick(std::span<const Phase> modes);

  int n_, spin_;
  std::vector<RingContact> c_;
  std::vector<int> ring_owner_;  ///< per coordinate: the contact whose ring it is, or -1
};

}  // namespace rubdyn
