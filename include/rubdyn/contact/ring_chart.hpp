#pragma once
// Minimal coordinates of contact phases with several closed contacts, each on a sprung ring of
// its own or on a fixed ring (the rigid rotor's [[plane]]s, a matrices model's
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
// of such contacts compose.
//
// A FIXED RING (centre at the origin, no coordinates) constrains the rotor itself:
//     P_k(q) = g_k (cos phi_k, sin phi_k),
// two linear equations (x and y) in the rotor coordinates of P_k, with the same v_t,k and the
// same stick rule. The closed contacts on fixed rings together eliminate two rotor coordinates
// each: their x equations (and, separately, their y equations) are solved for as many of the
// coordinates they involve, the pivots chosen by Gaussian elimination with full pivoting over
// those coordinates (deterministic: the largest entry, the lowest index on ties). The rest of
// the state fixes the pivots, then the sprung rings follow from the completed rotor points. It
// composes when that system has full rank (a pivot above kRingChartPivot of the largest entry):
// two fixed planes of the rigid rotor at different positions eliminate x_b, x_r (and y_b, y_r);
// a third fixed plane, or two at one position, do not (redundant or over-determined).
//
// A PRESCRIBED SPIN (no spin coordinate; theta(t) a given function of time, model/
// prescribed_spin.hpp) makes the stick constraint rheonomic:
//     phi_k(t) = phi_k0 - (R_k / g_k)(theta(t) - theta(t_a)),   phi_k' = -(R_k / g_k) omega(t),
// t_a the time the phase began. The chart then takes the time (chart and embed), sticking
// contacts remove two coordinates each as with a spin coordinate, and theta(t) - theta(t_a) is
// computed as (t - t_a)(omega0 + alpha ((t - t0) + (t_a - t0)) / 2), not as a difference of two
// large angles.
//
// The chart does not apply (the integrator uses the projection formulation for that phase): to a
// ring shared by two closed contacts, to stick with neither a spin coordinate nor a prescribed
// spin, to a rotor point that moves with the spin or with a closed contact's sprung ring, and to
// fixed rings whose equations are rank-deficient.
//
// Reduced coordinates p of a mode tuple: the model's coordinates in their order without the
// closed contacts' ring coordinates and the fixed rings' pivots (the spin stored as theta - theta0
// when a contact sticks, for precision, as contact_chart.hpp does), then phi_k of each sliding
// contact in contact order. Accelerations: `reduce` takes the constrained acceleration a of the
// full model (which satisfies every closed contact's constraint at acceleration level) and returns
// p'' (the copied coordinates' a, and phi_k'' = (-sin phi, cos phi) . (P'' - S'') / g_k, S'' = 0
// for a fixed ring). Nothing here allocates.
#include <array>
#include <optional>
#include <span>
#include <vector>

#include "rubdyn/contact/contact_kinematics.hpp"
#include "rubdyn/core/run_types.hpp"
#include "rubdyn/core/types.hpp"

namespace rubdyn {

/// The fixed rings' equations are rank-deficient below this pivot (relative to their largest
/// coefficient): their contacts are redundant or over-determine the rotor.
inline constexpr double kRingChartPivot = 1e-9;

/// What the chart keeps of the state where a phase began (the sticking contacts' angles).
struct RingAnchor {
  static constexpr int kMax = kMaxContacts;
  double theta0 = 0.0;  ///< the spin angle where the phase began (a spin coordinate's)
  double t0 = 0.0;      ///< the time the phase began (a prescribed spin's theta(t_a))
  std::array<double, kMax> phi0{};
};

/// A spin that is a given function of time: theta(t) = theta0 + omega0 (t - t0) + alpha (t -
/// t0)^2 / 2 (model/prescribed_spin.hpp).
struct SpinLaw {
  double t0 = 0.0, theta0 = 0.0, omega0 = 0.0, alpha = 0.0;
  double theta(double t) const {
    const double dt = t - t0;
    return theta0 + omega0 * dt + 0.5 * alpha * dt * dt;
  }
  double omega(double t) const { return omega0 + alpha * (t - t0); }
  /// theta(t) - theta(ta), without cancellation.
  double advance(double ta, double t) const {
    return (t - ta) * (omega0 + 0.5 * alpha * ((t - t0) + (ta - t0)));
  }
};

class RingChart {
 public:
  /// n: the model's coordinates; spin: the spin's index (-1: none); contacts: every contact of
  /// the model (at most RingAnchor::kMax); law: the spin as a function of time when it is
  /// prescribed (spin = -1). Without either, no sticking contact is charted.
  RingChart(int n, int spin, std::vector<RingContact> contacts,
            std::optional<SpinLaw> law = std::nullopt);

  int contact_count() const { return static_cast<int>(c_.size()); }
  /// The prescribed spin, if any (the spin then no coordinate).
  const std::optional<SpinLaw>& spin_law() const { return law_; }
  /// Every contact's geometry, as given (a wrapper of the model builds its own chart from them).
  const std::vector<RingContact>& contacts() const { return c_; }
  /// Which coordinates the closed contacts of a mode tuple eliminate (built on the stack by
  /// plan(): no allocation).
  struct Plan {
    bool ok = false;
    std::array<Phase, RingAnchor::kMax> modes{};  ///< the modes planned for
    int rows = 0;                                 ///< closed contacts on fixed rings
    std::array<int, RingAnchor::kMax> row_k{};    ///< their contacts, in contact order
    /// the rotor coordinates their x and y equations are solved for (row r's pivot: piv_x[r])
    std::array<int, RingAnchor::kMax> piv_x{}, piv_y{};
    /// every eliminated coordinate (closed contacts' sprung rings, the pivots), ascending
    int n_elim = 0;
    std::array<int, 2 * RingAnchor::kMax> elim{};
  };
  /// The plan of `modes` (ok = false where the chart does not apply). A caller that embeds
  /// and reduces many states of one mode tuple (an integrator's right-hand side) computes it
  /// once and passes it to embed and reduce.
  void plan(std::span<const Phase> modes, Plan& pl) const;

  /// The closed contacts of `modes` can be charted together (see above).
  bool applies(std::span<const Phase> modes) const;
  /// The number of reduced coordinates for `modes`: n - (closed contacts) - (sticking ones).
  int dim(std::span<const Phase> modes) const;
  /// Reduced coordinates of a state at time t on the constraints of `modes`, and the anchor.
  void chart(std::span<const Phase> modes, double t, VecIn q, VecIn v, RingAnchor& anchor, VecOut p,
             VecOut pd) const;
  /// The full state at time t of reduced coordinates (t matters with a prescribed spin only).
  void embed(std::span<const Phase> modes, const RingAnchor& anchor, double t, VecIn p, VecIn pd,
             VecOut q, VecOut v) const;
  /// p'' of a full acceleration a that satisfies the closed contacts' constraints at
  /// acceleration level, at the embedded state q.
  void reduce(std::span<const Phase> modes, VecIn q, VecIn a, VecOut pdd) const;

  /// Per reduced coordinate, the length an angle moves a contact point by per radian (0: a copy
  /// of a full coordinate; phi_k: g_k; theta - theta0 when a contact sticks: the largest R_k of
  /// the sticking contacts), as ChartScales::length in contact_chart.hpp.
  void lengths(std::span<const Phase> modes, std::span<double> L) const;
  /// The same four with the plan of these very modes (plan(); checked against them).
  void chart(std::span<const Phase> modes, const Plan& pl, double t, VecIn q, VecIn v,
             RingAnchor& anchor, VecOut p, VecOut pd) const;
  void embed(std::span<const Phase> modes, const Plan& pl, const RingAnchor& anchor, double t,
             VecIn p, VecIn pd, VecOut q, VecOut v) const;
  void reduce(std::span<const Phase> modes, const Plan& pl, VecIn q, VecIn a, VecOut pdd) const;
  /// The chart's tangent map at p: v = T x with T = dq/dp (the rates embed gives for p' = x
  /// without the prescribed spin's term of a sticking contact, which does not depend on p');
  /// q = the embedded position. reduce is its left inverse on the constraints' tangent space.
  void embed_tangent(std::span<const Phase> modes, const Plan& pl, const RingAnchor& anchor,
                     double t, VecIn p, VecIn x, VecOut q, VecOut v) const;
  /// `copies` (empty, or one per reduced coordinate): the full coordinate each copy copies, -1
  /// for the angles (ChartScales::copies).
  void lengths(std::span<const Phase> modes, const Plan& pl, std::span<double> L,
               std::span<int> copies = {}) const;

 private:
  /// embed (tangent false) or embed_tangent (true).
  void embed_impl(std::span<const Phase> modes, const Plan& pl, const RingAnchor& anchor, double t,
                  VecIn p, VecIn pd, VecOut q, VecOut v, bool tangent) const;
  /// The pivots of the fixed rings' x (or y: use_y) equations; false if rank-deficient.
  bool choose_pivots(const Plan& pl, bool use_y, std::array<int, RingAnchor::kMax>& piv) const;
  /// Solves the fixed rings' equations for their pivots: q (positions: rhs_k = g_k cos phi_k or
  /// g_k sin phi_k) or v (rates: their time derivatives), the other coordinates already set.
  void solve_rows(const Plan& pl, bool use_y, const double* rhs, VecOut x) const;
  /// sum_j w[j] q[idx[j]]: one coordinate of contact k's rotor point (idx: its ix or iy)
  double point(const std::array<int, 2>& idx, int k, VecIn q) const;
  double px(int k, VecIn q) const;
  double py(int k, VecIn q) const;
  /// The ring centre of contact k (the origin for a fixed ring), from q (or v, or a).
  double sx(int k, VecIn q) const;
  double sy(int k, VecIn q) const;
  /// Coordinate i is a closed contact's sprung-ring coordinate.
  bool ring_eliminated(std::span<const Phase> modes, int i) const;
  static bool any_stick(std::span<const Phase> modes);

  int n_, spin_;
  std::vector<RingContact> c_;
  std::optional<SpinLaw> law_;
  std::vector<int> ring_owner_;  ///< per coordinate: the contact whose ring it is, or -1
};

}  // namespace rubdyn
