#pragma once
// Minimal coordinates of the contact phases (optional, provided by a model that can parametrise
// its contact manifold exactly). With them the event-driven integrator integrates a sliding or
// sticking phase as an ODE in which the constraints hold by construction: no drift, no
// projection, nothing removed from the energy.
//
// Slip  (d_N = 0):             the manifold {q : d_N(q) = 0}, one coordinate fewer than q.
// Stick (d_N = 0 and v_t = 0): when the sticking condition is integrable (a holonomic rolling
//                              constraint, as for a disc rolling in a ring), the manifold of
//                              both constraints, anchored at the state where stick began.
// A chart maps reduced coordinates p (size dim) and their rates p' to the full state:
//     q = Q(p),  v = J(p) p',  a = J(p) p'' + c(p, p')
// and back. For the rotor-stator model (see rotor_stator_model.hpp) the coordinates are
//     slip:  p = (x_b, y_b, phi, theta, x_s, y_s),  x_r = x_s + g0 cos phi, y_r = y_s + g0 sin phi
//     stick: p = (x_b, y_b, theta - theta0, x_s, y_s), phi = phi0 - (R_r / g0)(theta - theta0)
// (phi: the angle of the rotor centre seen from the stator centre; v_t = -g0 phi' - R_r omega).
//
// Accelerations: the integrator computes the constrained acceleration a of the full model (the
// acceleration-level contact problem, which also gives F_N and F_T for the witnesses) at
// (Q(p), J p'); `reduce` returns p'' = L (a - c) for a left inverse L of J (L J = I). Since a
// satisfies the constraints at acceleration level, a - c lies in the range of J and p'' is the
// solution of J^T M J p'' = J^T (f - M c): the reduced equations of motion.
#include <array>
#include <vector>

#include "rubdyn/core/types.hpp"

namespace rubdyn {

enum class ChartMode : int { Slip = 0, Stick = 1 };

/// Per reduced coordinate, how its integration error is measured (tolerances of the integrator).
/// A coordinate with length 0 is weighted like the full coordinate it copies (rtol |p_i| + atol).
/// A coordinate with length L > 0 is an angle that moves the contact point by L per radian: its
/// error is weighted as the displacement it causes, absolutely, at the scale of the gap:
/// (rtol g0 + atol) / L; its rate is weighted rtol |p_i'| + atol_v (atol_v taken in rad/s:
/// stricter than the atol_v / L the displacement rate would give).
struct ChartScales {
  std::vector<double> length;  ///< one per reduced coordinate (size dim(mode)); empty: all 0
  /// Per reduced coordinate with length 0, the full coordinate it copies (its error weighted
  /// with that coordinate's Coordinate::length), or -1; empty: none named (weighted as metres).
  std::vector<int> copies;
};

/// What a chart keeps of the state where a phase began (e.g. phi0, theta0 of a stick phase).
using ChartAnchor = std::array<double, 4>;

class ContactChart {
 public:
  virtual ~ContactChart() = default;
  /// Number of reduced coordinates in `mode` (< num_dofs() of the model).
  virtual int dim(ChartMode mode) const = 0;
  /// Reduced coordinates of a state on the manifold (d_N = 0, v_N = 0; and v_t = 0 for Stick):
  /// p, p' (size dim(mode)) and the anchor the chart keeps for this phase.
  virtual void chart(ChartMode mode, VecIn q, VecIn v, ChartAnchor& anchor, VecOut p,
                     VecOut pd) const = 0;
  /// The state on the manifold: q = Q(p), v = J(p) p' (q, v of the model's size).
  virtual void embed(ChartMode mode, const ChartAnchor& anchor, VecIn p, VecIn pd, VecOut q,
                     VecOut v) const = 0;
  /// p'' of a full acceleration a that satisfies the constraints at acceleration level, at the
  /// embedded state q = Q(p).
  virtual void reduce(ChartMode mode, const ChartAnchor& anchor, VecIn p, VecIn pd, VecIn q,
                      VecIn a, VecOut pdd) const = 0;
  /// How the error of each reduced coordinate is weighted.
  virtual ChartScales scales(ChartMode mode) const = 0;
};

}  // namespace rubdyn
