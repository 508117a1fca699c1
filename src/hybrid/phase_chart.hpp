#pragma once
// Minimal coordinates of contact phases, as the engine sees them: one interface over the
// model's charts. One contact: the model's ContactChart (contact/contact_chart.hpp: slip
// eliminates the rotor's point, stick ties it to the spin); several: the RingChart
// (contact/ring_chart.hpp: each closed contact's ring replaced by one angle, or tied to the spin
// in stick; fixed rings eliminate rotor coordinates). A session of the engine integrates every
// mode tuple whose chart has its dimension; its PhaseChart keeps what the running phase's chart
// needs (the anchor where it began, the plan of its eliminations). Nothing here allocates
// after construction.
#include <memory>
#include <span>

#include "contact_modes.hpp"
#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn::detail {

class PhaseChart {
 public:
  virtual ~PhaseChart() = default;
  /// The closed contacts of `modes` can be charted together.
  virtual bool applies(const Modes& modes) const = 0;
  /// The number of reduced coordinates of `modes` (applies(modes)).
  virtual int dim(const Modes& modes) const = 0;
  /// Begins a phase of `modes` at time t and a state (q, v) on its constraints: its reduced
  /// coordinates p, p' (size dim) and, per reduced coordinate, the length an angle moves a contact
  /// point by per radian (0: a copy of a full coordinate), which weights its error, and the full
  /// coordinate a copy copies (-1 for an angle or when the chart does not say).
  virtual void enter(const Modes& modes, double t, VecIn q, VecIn v, VecOut p, VecOut pd,
                     std::span<double> lengths, std::span<int> copies) = 0;
  /// The full state at time t of reduced coordinates of the phase begun last (t matters where a
  /// constraint depends on time: stick at a prescribed spin, ring_chart.hpp).
  virtual void embed(double t, VecIn p, VecIn pd, VecOut q, VecOut v) const = 0;
  /// p'' of a full acceleration a that satisfies the constraints at acceleration level, at the
  /// embedded state q.
  virtual void reduce(VecIn p, VecIn pd, VecIn q, VecIn a, VecOut pdd) const = 0;
  /// The chart's tangent map at p (time t) of the phase begun last: v = T x with T = dq/dp, the
  /// rates embed gives for p' = x without what a rheonomic constraint adds (a sticking contact
  /// at a prescribed spin: no function of p'); q: the embedded position (written).
  virtual void tangent(double t, VecIn p, VecIn x, VecOut q, VecOut v) const = 0;
  /// The linear part of reduce at the embedded state q: out = L y for a full vector y, L the
  /// left inverse of T that reduce applies (L T = I).
  virtual void reduce_linear(VecIn p, VecIn pd, VecIn q, VecIn y, VecOut out) const = 0;
  /// A chart of its own for another session (each keeps its phase's anchor).
  virtual std::unique_ptr<PhaseChart> clone() const = 0;
};

/// The chart of a model's contact phases: its ContactChart with one contact, its RingChart
/// (covering every contact) otherwise; null when it has none (the projection formulation).
std::unique_ptr<PhaseChart> make_phase_chart(const LagrangianModel& m);

}  // namespace rubdyn::detail
