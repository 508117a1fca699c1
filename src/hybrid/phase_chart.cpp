#include "phase_chart.hpp"

#include <algorithm>

#include "rubdyn/contact/contact_chart.hpp"
#include "rubdyn/contact/ring_chart.hpp"

namespace rubdyn::detail {

namespace {

/// One contact: the model's ContactChart (slip and stick).
class SingleChart final : public PhaseChart {
 public:
  explicit SingleChart(const ContactChart& c) : c_(c) {}
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
  std::unique_ptr<PhaseChart> clone() const override { return std::make_unique<SingleChart>(c_); }

 private:
  static ChartMode mode_of(const Modes& m) {
    return m[0] == Phase::Stick ? ChartMode::Stick : ChartMode::Slip;
  }
  const ContactChart& c_;
  ChartMode mode_ = ChartMode::Slip;
  ChartAnchor anchor_{};
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
    return std::make_unique<SingleChart>(*m.contact_chart());
  const RingChart* rc = m.ring_chart();
  if (rc != nullptr && rc->contact_count() == K) return std::make_unique<MultiChart>(*rc);
  return nullptr;
}

}  // namespace rubdyn::detail
