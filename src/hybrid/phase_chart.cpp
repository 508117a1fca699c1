#include "phase_chart.hpp"

#include <algorithm>

#include "rubdyn/contact/contact_chart.hpp"
#include "rubdyn/contact/ring_chart.hpp"

namespace rubdyn::detail {

namespace {

/// One contact: the model's ContactChart (slip and stick).
class SingleChart final : public PhaseChart {
 public:
  SingleChart(const ContactChart& c, int n)
      : c_(c),
        zero_(Vec::Zero(n)),
        offset_(Vec::Zero(std::max(c.dim(ChartMode::Slip), c.dim(ChartMode::Stick)))) {}
  bool applies(const Modes& modes) const override { return modes.K == 1 && closed(modes[0]); }
  int dim(const Modes& modes) const override { return c_.dim(mode_of(modes)); }
  void enter(const Modes& modes, double, VecIn q, VecIn v, VecOut p, VecOut pd,
             std::span<double> lengths, std::span<int> copies) override {
    mode_ = mode_of(modes);
    c_.chart(mode_, q, v, anchor_, p, pd);
    const ChartScales s = c_.scales(mode_);
    for (std::size_t i = 0; i < lengths.size(); ++i)
      lengths[i] = i < s.length.size() ? s.length[i] : 0.0;
    for (std::size_t i = 0; i < copies.size(); ++i)
      copies[i] = i < s.copies.size() ? s.copies[i] : -1;
  }
  void embed(double, VecIn p, VecIn pd, VecOut q, VecOut v) const override {
    c_.embed(mode_, anchor_, p, pd, q, v);
  }
  void reduce(VecIn p, VecIn pd, VecIn q, VecIn a, VecOut pdd) const override {
    c_.reduce(mode_, anchor_, p, pd, q, a, pdd);
  }
  // a ContactChart's v = J(p) p' has no other term (contact_chart.hpp)
  void tangent(double, VecIn p, VecIn x, VecOut q, VecOut v) const override {
    c_.embed(mode_, anchor_, p, x, q, v);
  }
  // p'' = L (a - c(p, p')): L y = reduce(y) - reduce(0) (exact where c = 0, the matrices
  // model's chart; else to round-off of c, which a Newton matrix tolerates)
  void reduce_linear(VecIn p, VecIn pd, VecIn q, VecIn y, VecOut out) const override {
    const int d = c_.dim(mode_);
    auto off = offset_.head(d);
    c_.reduce(mode_, anchor_, p, pd, q, zero_, off);
    c_.reduce(mode_, anchor_, p, pd, q, y, out);
    out -= off;
  }
  std::unique_ptr<PhaseChart> clone() const override {
    return std::make_unique<SingleChart>(c_, static_cast<int>(zero_.size()));
  }

 private:
  static ChartMode mode_of(const Modes& m) {
    return m[0] == Phase::Stick ? ChartMode::Stick : ChartMode::Slip;
  }
  const ContactChart& c_;
  ChartMode mode_ = ChartMode::Slip;
  ChartAnchor anchor_{};
  Vec zero_;            ///< a full acceleration of zeros (reduce_linear)
  mutable Vec offset_;  ///< reduce of it
};

/// K contacts: the model's RingChart.
class MultiChart final : public PhaseChart {
 public:
  explicit MultiChart(const RingChart& c) : c_(c) {}
  bool applies(const Modes& modes) const override { return c_.applies(modes.span()); }
  int dim(const Modes& modes) const override { return c_.dim(modes.span()); }
  void enter(const Modes& modes, double t, VecIn q, VecIn v, VecOut p, VecOut pd,
             std::span<double> lengths, std::span<int> copies) override {
    modes_ = modes;
    c_.plan(modes_.span(), plan_);  // the modes' eliminations, for every rhs of the phase
    c_.chart(modes_.span(), plan_, t, q, v, anchor_, p, pd);
    c_.lengths(modes_.span(), plan_, lengths, copies);
  }
  void embed(double t, VecIn p, VecIn pd, VecOut q, VecOut v) const override {
    c_.embed(modes_.span(), plan_, anchor_, t, p, pd, q, v);
  }
  void reduce(VecIn, VecIn, VecIn q, VecIn a, VecOut pdd) const override {
    c_.reduce(modes_.span(), plan_, q, a, pdd);
  }
  void tangent(double t, VecIn p, VecIn x, VecOut q, VecOut v) const override {
    c_.embed_tangent(modes_.span(), plan_, anchor_, t, p, x, q, v);
  }
  void reduce_linear(VecIn, VecIn, VecIn q, VecIn y, VecOut out) const override {
    c_.reduce(modes_.span(), plan_, q, y, out);  // linear in the acceleration
  }
  std::unique_ptr<PhaseChart> clone() const override { return std::make_unique<MultiChart>(c_); }

 private:
  const RingChart& c_;
  Modes modes_;
  RingChart::Plan plan_;
  RingAnchor anchor_;
};

}  // namespace

std::unique_ptr<PhaseChart> make_phase_chart(const LagrangianModel& m) {
  const int K = m.contact_count();
  if (K == 1 && m.contact_chart() != nullptr)
    return std::make_unique<SingleChart>(*m.contact_chart(), m.num_dofs());
  const RingChart* rc = m.ring_chart();
  if (rc != nullptr && rc->contact_count() == K) return std::make_unique<MultiChart>(*rc);
  return nullptr;
}

}  // namespace rubdyn::detail
