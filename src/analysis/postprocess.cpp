#include "rubdyn/analysis/postprocess.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>
#include <unsupported/Eigen/FFT>

#include "rubdyn/analysis/campbell.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/text_files.hpp"

namespace rubdyn {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Time-weighted fraction of [t0, t1] where pred(i) holds; sample i holds over [t_i, t_{i+1}).
template <class Pred>
double fraction(const std::vector<DerivedSample>& d, double t0, double t1, Pred pred) {
  double acc = 0.0;
  for (size_t i = 0; i + 1 < d.size(); ++i) {
    const double a = std::max(d[i].t, t0), b = std::min(d[i + 1].t, t1);
    if (b > a && pred(i)) acc += b - a;
  }
  return t1 > t0 ? acc / (t1 - t0) : 0.0;
}

// Marks the samples of sustained runs of `dir` whirl: in contact, or in any regime when
// `in_contact` is false (the precession-sign whirl; see the header).
std::vector<char> sustained_runs(const std::vector<DerivedSample>& d, double t0, double t1,
                                 Whirl dir, double min_turns, bool in_contact = true) {
  std::vector<char> mark(d.size(), 0);
  auto in_run = [&](const DerivedSample& x) {
    return (!in_contact || x.regime != Regime::Free) && x.whirl == dir && x.t >= t0 && x.t <= t1;
  };
  const double need = 2.0 * M_PI * min_turns;
  size_t i = 0;
  while (i < d.size()) {
    if (!in_run(d[i])) {
      ++i;
      continue;
    }
    size_t j = i;
    double angle = 0.0;
    // extend while the next sample is in the run, or is a zero-length row before one that is
    while (j + 1 < d.size()) {
      size_t k = j + 1;
      while (k + 1 < d.size() && !in_run(d[k]) && d[k + 1].t == d[k].t) ++k;
      if (!in_run(d[k])) break;
      angle += 0.5 * (std::abs(d[j].precession) + std::abs(d[k].precession)) * (d[k].t - d[j].t);
      j = k;
    }
    if (angle >= need)
      for (size_t k = i; k <= j; ++k)
        if (in_run(d[k])) mark[k] = 1;
    i = j + 1;
  }
  return mark;
}

// The window [t0, t1] of the options, clipped to the run.
std::pair<double, double> window_of(const RunRecord& r, const AnalysisOptions& o) {
  if (r.samples.empty()) throw std::invalid_argument(r.dir + ": timeseries.csv has no rows");
  // the samples may come from memory (Python's analyze) rather than the reader, which checks
  // the same: a NaN time would drop out of every comparison below and of the window's clipping
  for (std::size_t i = 0; i < r.samples.size(); ++i) {
    const double t = r.samples[i].t;
    if (!std::isfinite(t))
      throw std::invalid_argument(fmt::format("{}: sample {}: t = {} is not finite", r.dir, i, t));
    if (i > 0 && t < r.samples[i - 1].t) {
      throw std::invalid_argument(
          fmt::format("{}: sample {}: t = {} < {} (the sample before): "
                      "times must not decrease",
                      r.dir, i, t, r.samples[i - 1].t));
    }
  }
  const double a = r.samples.front().t, b = r.samples.back().t;
  if (!std::isfinite(o.t0.value_or(a)) || !std::isfinite(o.t1.value_or(b))) {
    throw std::invalid_argument(fmt::format("analysis window [{}, {}]: times must be finite",
                                            o.t0.value_or(a), o.t1.value_or(b)));
  }
  const double t0 = std::max(a, o.t0.value_or(a)), t1 = std::min(b, o.t1.value_or(b));
  if (!(t1 > t0)) {
    throw std::invalid_argument(
        fmt::format("analysis window [{}, {}] does not overlap the run [{}, {}]", o.t0.value_or(a),
                    o.t1.value_or(b), a, b));
  }
  return {t0, t1};
}

// The plane must be one of the model's contacts, and the model must locate its centres.
void check_plane(const LagrangianModel& m, int plane) {
  if (plane < 0 || plane >= m.contact_count())
    throw std::invalid_argument(fmt::format("plane {}: the model '{}' has {} contact plane(s)",
                                            plane + 1, m.name(), m.contact_count()));
  PlaneMotion pm;
  const Vec z = Vec::Zero(m.num_dofs());
  if (!m.plane_motion(plane, 0.0, z, z, pm))
    throw std::invalid_argument(
        fmt::format("plane {}: the model '{}' does not locate its centres", plane + 1, m.name()));
}

// z = x_r + i y_r (the rotor's point in the plane) and omega on a uniform grid of spacing dt over
// [t0, t1].
struct Uniform {
  double t0 = 0, dt = 0;
  std::vector<std::complex<double>> z;
  std::vector<std::complex<double>> vz;  ///< dz/dt: a state, exact at the samples (no aliasing)
  std::vector<double> omega;
};
/// The uniform grid of the spectrum is never longer than this (1e8 points: 4 GB in its three
/// arrays); the output rows are at most kMaxOutputRows (1e8) too.
constexpr double kMaxResampled = 1e8;

Uniform resample(const RunRecord& r, double t0, double t1, int plane) {
  const std::unique_ptr<LagrangianModel> model = build_model(r.spec);
  check_plane(*model, plane);
  const auto& s = r.samples;
  std::map<long long, long> count;  // spacing histogram in units of 1e-12 s
  for (size_t i = 0; i + 1 < s.size(); ++i) {
    const double h = s[i + 1].t - s[i].t;
    // (a spacing below the histogram's unit cannot be a grid's: a run that ended within
    // 1e-12 s of its start, say, has no uniform grid to resample)
    if (h > 0 && std::llround(h * 1e12) >= 1) ++count[std::llround(h * 1e12)];
  }
  if (count.empty())
    throw std::invalid_argument(r.dir + ": no two sample times 1e-12 s apart or more");
  const auto mode = std::max_element(count.begin(), count.end(),
                                     [](auto& a, auto& b) { return a.second < b.second; });
  Uniform u;
  u.t0 = t0;
  u.dt = static_cast<double>(mode->first) * 1e-12;
  const double span = std::floor((t1 - t0) / u.dt * (1 + 1e-12)) + 1;
  if (!(span <= kMaxResampled))
    throw std::invalid_argument(fmt::format(
        "{}: {:.3g} points of spacing {:.3g} s in [{}, {}] s, above the {:.0e} resampled at most",
        r.dir, span, u.dt, t0, t1, kMaxResampled));
  const long n = static_cast<long>(span);
  u.z.resize(n);
  u.vz.resize(n);
  u.omega.resize(n);
  size_t j = 0;
  PlaneMotion pa, pb;
  for (long k = 0; k < n; ++k) {
    const double t = t0 + static_cast<double>(k) * u.dt;
    while (j + 2 < s.size() && s[j + 1].t <= t) ++j;
    const Sample& a = s[j];
    const Sample& b = s[std::min(j + 1, s.size() - 1)];
    const double w = b.t > a.t ? std::clamp((t - a.t) / (b.t - a.t), 0.0, 1.0) : 0.0;
    model->plane_motion(plane, a.t, a.q, a.v, pa);
    model->plane_motion(plane, b.t, b.q, b.v, pb);
    u.z[k] = {pa.rotor.x() + w * (pb.rotor.x() - pa.rotor.x()),
              pa.rotor.y() + w * (pb.rotor.y() - pa.rotor.y())};
    u.vz[k] = {pa.rotor_rate.x() + w * (pb.rotor_rate.x() - pa.rotor_rate.x()),
               pa.rotor_rate.y() + w * (pb.rotor_rate.y() - pa.rotor_rate.y())};
    const double wa = model->spin(a.t, a.q, a.v), wb = model->spin(b.t, b.q, b.v);
    u.omega[k] = wa + w * (wb - wa);
  }
  return u;
}

// The frame's whirl frequency scale max |z'| / (2 pi max |z - mean z|), from the velocities (states
// the solver computed, not differences of samples, so it sees a whirl however fast): exactly f0
// for a circular whirl a e^{i 2 pi f0 t}, and by Bernstein's inequality a signal band-limited
// to B has max |z'| <= 2 pi B max |z - c| for its centre c, so a scale above the Nyquist
// frequency proves content that the samples alias. 0 for a frame at rest, infinite for one that
// moves without leaving its mean (nothing to measure the whirl against).
double whirl_frequency_scale(const Uniform& u, long first, long len) {
  std::complex<double> mean = 0.0;
  for (long k = first; k < first + len; ++k) mean += u.z[k];
  mean /= static_cast<double>(len);
  double rmax = 0.0, vmax = 0.0;
  for (long k = first; k < first + len; ++k) {
    rmax = std::max(rmax, std::abs(u.z[k] - mean));
    vmax = std::max(vmax, std::abs(u.vz[k]));
  }
  if (vmax == 0.0) return 0.0;  // at rest: nothing to alias
  return rmax > 0.0 ? vmax / (2.0 * M_PI * rmax) : std::numeric_limits<double>::infinity();
}

// Hann-windowed, zero-padded FFT of z[first, first + len): amplitudes on ascending frequencies
// (fftshift), |f| <= f_max.
void windowed_fft(const std::vector<std::complex<double>>& z, long first, long len, int pad,
                  double dt, double f_max, std::vector<double>& f, std::vector<double>& amp) {
  long nfft = 1;
  while (nfft < len * std::max(pad, 1)) nfft *= 2;
  std::vector<std::complex<double>> in(nfft, {0.0, 0.0}), out;
  double wsum = 0.0;
  for (long k = 0; k < len; ++k) {
    const double w =
        len > 1 ? 0.5 - 0.5 * std::cos(2.0 * M_PI * static_cast<double>(k) / (len - 1)) : 1.0;
    in[k] = w * z[first + k];
    wsum += w;
  }
  Eigen::FFT<double> fft;
  fft.fwd(out, in);
  f.clear();
  amp.clear();
  const double df = 1.0 / (static_cast<double>(nfft) * dt);
  for (long m = -nfft / 2; m < nfft / 2; ++m) {
    const double fm = static_cast<double>(m) * df;
    if (std::abs(fm) > f_max) continue;
    const long idx = m < 0 ? m + nfft : m;
    f.push_back(fm);
    amp.push_back(std::abs(out[idx]) / wsum);
  }
}

std::string opt_json(const std::optional<double>& x) {
  return x ? fmt::format("{}", *x) : "null";
}
std::string num_json(double x) {
  return std::isfinite(x) ? fmt::format("{}", x) : "null";
}

}  // namespace

std::string_view to_string(Whirl w) {
  switch (w) {
    case Whirl::None: return "none";
    case Whirl::Forward: return "forward";
    case Whirl::Backward: return "backward";
  }
  return "?";
}

std::string_view to_string(Regime r) {
  switch (r) {
    case Regime::Free: return "free";
    case Regime::Sliding: return "sliding";
    case Regime::Rolling: return "rolling";
  }
  return "?";
}

std::vector<DerivedSample> derive(const RunRecord& r, int plane) {
  // the model says where the contact plane's centres are and which coordinate spins
  const std::unique_ptr<LagrangianModel> model = build_model(r.spec);
  check_plane(*model, plane);
  const double g0 = model->gap_scale(plane), R = model->contact_radius(plane),
               tau = nominal_torque(r.spec);
  std::vector<DerivedSample> out;
  out.reserve(r.samples.size());
  PlaneMotion pm;
  for (const Sample& s : r.samples) {
    DerivedSample d;
    d.t = s.t;
    d.omega = model->spin(s.t, s.q, s.v);
    model->plane_motion(plane, s.t, s.q, s.v, pm);
    const double sx = pm.rotor.x() - pm.stator.x(), sy = pm.rotor.y() - pm.stator.y();
    const double vx = pm.rotor_rate.x() - pm.stator_rate.x(),
                 vy = pm.rotor_rate.y() - pm.stator_rate.y();
    const double rho2 = sx * sx + sy * sy;
    if (rho2 > 1e-6 * g0 * g0) {
      d.precession = (sx * vy - sy * vx) / rho2;
      d.precession_ratio = d.omega != 0.0 ? d.precession / d.omega : kNaN;
      const double sgn = d.precession * (d.omega != 0.0 ? d.omega : 1.0);
      d.whirl = sgn > 0 ? Whirl::Forward : sgn < 0 ? Whirl::Backward : Whirl::None;
    } else {
      d.precession = d.precession_ratio = kNaN;
    }
    const ContactSample& c = s.contacts[static_cast<std::size_t>(plane)];
    d.regime = c.phase == Phase::Free    ? Regime::Free
               : c.phase == Phase::Stick ? Regime::Rolling
                                         : Regime::Sliding;
    d.dN_over_g0 = c.d_N / g0;
    d.friction_torque_ratio = tau != 0.0 ? R * c.F_T / tau : kNaN;
    out.push_back(d);
  }
  return out;
}

RunVerdicts verdicts(const RunRecord& r, std::vector<DerivedSample>& d, const AnalysisOptions& o) {
  if (!(o.min_turns > 0.0))
    throw std::invalid_argument(fmt::format("min_turns {} must be > 0", o.min_turns));
  const auto [t0, t1] = window_of(r, o);
  RunVerdicts v;
  v.t0 = t0;
  v.t1 = t1;
  v.events = r.events;
  const double lim = r.spec.run.omega_lim;
  v.omega_max = -std::numeric_limits<double>::infinity();
  v.min_dN_over_g0 = std::numeric_limits<double>::infinity();
  double torque_integral = 0.0;
  for (size_t i = 0; i < d.size(); ++i) {
    if (d[i].t < t0 || d[i].t > t1) continue;
    v.omega_max = std::max(v.omega_max, d[i].omega);
    v.omega_final = d[i].omega;
    v.min_dN_over_g0 = std::min(v.min_dN_over_g0, d[i].dN_over_g0);
    if (std::isfinite(d[i].friction_torque_ratio))
      v.max_friction_torque_ratio =
          std::max(v.max_friction_torque_ratio, d[i].friction_torque_ratio);
    if (i + 1 < d.size()) {
      const double a = d[i].t, b = std::min(d[i + 1].t, t1);
      if (b > a && std::isfinite(d[i].friction_torque_ratio))
        torque_integral += d[i].friction_torque_ratio * (b - a);
    }
    if (!v.t_omega_lim && d[i].omega >= lim) {
      if (i > 0 && d[i - 1].omega < lim && d[i].t > d[i - 1].t && d[i - 1].t >= t0) {
        const double w = (lim - d[i - 1].omega) / (d[i].omega - d[i - 1].omega);
        v.t_omega_lim = d[i - 1].t + w * (d[i].t - d[i - 1].t);
      } else {
        v.t_omega_lim = d[i].t;
      }
    }
  }
  v.limited = !v.t_omega_lim.has_value();
  v.mean_friction_torque_ratio = torque_integral / (t1 - t0);
  v.contact_fraction = fraction(d, t0, t1, [&](size_t i) { return d[i].regime != Regime::Free; });
  v.stick_fraction = fraction(d, t0, t1, [&](size_t i) { return d[i].regime == Regime::Rolling; });
  const auto bwd = sustained_runs(d, t0, t1, Whirl::Backward, o.min_turns);
  const auto fwd = sustained_runs(d, t0, t1, Whirl::Forward, o.min_turns);
  for (size_t i = 0; i < d.size(); ++i) {
    d[i].sustained = bwd[i] || fwd[i];
    if (!bwd[i]) continue;
    if (!v.backward_onset) v.backward_onset = d[i].t;
    if (!v.whip_onset && d[i].regime == Regime::Sliding) v.whip_onset = d[i].t;
    if (!v.whirl_onset && d[i].regime == Regime::Rolling) v.whirl_onset = d[i].t;
  }
  const auto sign_bwd = sustained_runs(d, t0, t1, Whirl::Backward, o.min_turns, false);
  const auto sign_fwd = sustained_runs(d, t0, t1, Whirl::Forward, o.min_turns, false);
  for (size_t i = 0; i < d.size(); ++i) {
    d[i].sign_run = sign_bwd[i] || sign_fwd[i];
    if (sign_bwd[i] && !v.sign_backward_onset) v.sign_backward_onset = d[i].t;
  }
  // the last free sample of the window: contact is permanent from the next row on
  std::optional<size_t> last_free;
  for (size_t i = 0; i < d.size(); ++i)
    if (d[i].t >= t0 && d[i].t <= t1 && d[i].regime == Regime::Free) last_free = i;
  if (!last_free) {
    v.permanent_contact_onset = t0;
  } else if (*last_free + 1 < d.size() && d[*last_free + 1].t <= t1) {
    v.permanent_contact_onset = d[*last_free + 1].t;
  }
  auto marked = [](const std::vector<char>& m) { return [&m](size_t i) { return m[i] != 0; }; };
  v.backward_fraction = fraction(d, t0, t1, marked(bwd));
  v.whip_fraction =
      fraction(d, t0, t1, [&](size_t i) { return bwd[i] && d[i].regime == Regime::Sliding; });
  v.whirl_fraction =
      fraction(d, t0, t1, [&](size_t i) { return bwd[i] && d[i].regime == Regime::Rolling; });
  v.forward_fraction = fraction(d, t0, t1, marked(fwd));
  v.sign_backward_fraction = fraction(d, t0, t1, marked(sign_bwd));
  return v;
}

Spectrum full_spectrum(const RunRecord& r, const AnalysisOptions& o) {
  const auto [t0, t1] = window_of(r, o);
  const Uniform u = resample(r, t0, t1, o.plane);
  if (u.z.size() < 8) throw std::invalid_argument("fewer than 8 samples for the spectrum");
  Spectrum s;
  windowed_fft(u.z, 0, static_cast<long>(u.z.size()), 1, u.dt, o.f_max, s.f, s.amplitude);
  return s;
}

Spectrogram spectrogram(const RunRecord& r, const AnalysisOptions& o) {
  if (!(o.overlap >= 0.0 && o.overlap < 1.0))
    throw std::invalid_argument(fmt::format("overlap {} is outside [0, 1)", o.overlap));
  if (o.pad < 1) throw std::invalid_argument(fmt::format("pad {} is below 1", o.pad));
  const auto [t0, t1] = window_of(r, o);
  const Uniform u = resample(r, t0, t1, o.plane);
  const long n = static_cast<long>(u.z.size());
  const long len = std::lround(o.window / u.dt);
  if (len < 8 || len > n) {
    throw std::invalid_argument(
        fmt::format("spectrogram window {} s is {} samples of {} s: needs 8 to {} (the run)",
                    o.window, len, u.dt, n));
  }
  const long hop = std::max(1L, std::lround(static_cast<double>(len) * (1.0 - o.overlap)));
  const std::unique_ptr<LagrangianModel> model = build_model(r.spec);
  const std::optional<LinearModel> lm = model->linearize(Linearization::Tied);
  const std::optional<CampbellSolver> campbell =
      lm && lm->size() > 0 ? std::optional<CampbellSolver>(CampbellSolver(*lm)) : std::nullopt;
  Spectrogram g;
  if (campbell) {
    for (int k = 1; k <= campbell->nodes(); ++k)
      g.campbell_labels.push_back(fmt::format("f{}f", k));
    for (int k = 1; k <= campbell->nodes(); ++k)
      g.campbell_labels.push_back(fmt::format("f{}b", k));
    g.campbell.assign(g.campbell_labels.size(), {});
  }
  g.f_nyquist = 0.5 / u.dt;
  std::vector<double> amp;
  for (long first = 0; first + len <= n; first += hop) {
    windowed_fft(u.z, first, len, o.pad, u.dt, o.f_max, g.f, amp);
    double om = 0.0;
    for (long k = first; k < first + len; ++k) om += u.omega[k];
    om /= static_cast<double>(len);
    g.t.push_back(u.t0 + (static_cast<double>(first) + 0.5 * static_cast<double>(len - 1)) * u.dt);
    g.omega.push_back(om);
    g.amplitude.push_back(amp);
    const double fw = whirl_frequency_scale(u, first, len);
    g.f_whirl.push_back(fw);
    g.undersampled.push_back(!(fw <= kUndersampledFraction * g.f_nyquist));
    if (campbell) {
      // forward frequencies, then backward ones at negative frequency
      const CampbellPoint c = campbell->solve(om);
      const std::size_t nn = c.f_forward.size();
      for (std::size_t k = 0; k < nn; ++k) {
        g.campbell[k].push_back(c.f_forward[k]);
        g.campbell[nn + k].push_back(-c.f_backward[k]);
      }
    }
  }
  return g;
}

std::string verdicts_json(const RunVerdicts& v) {
  std::string j = "{\n";
  auto field = [&](const char* k, const std::string& x, bool last = false) {
    j += fmt::format("  \"{}\": {}{}\n", k, x, last ? "" : ",");
  };
  field("t0", num_json(v.t0));
  field("t1", num_json(v.t1));
  field("omega_max", num_json(v.omega_max));
  field("omega_final", num_json(v.omega_final));
  field("t_omega_lim", opt_json(v.t_omega_lim));
  field("limited", v.limited ? "true" : "false");
  field("contact_fraction", num_json(v.contact_fraction));
  field("stick_fraction", num_json(v.stick_fraction));
  field("backward_fraction", num_json(v.backward_fraction));
  field("whip_fraction", num_json(v.whip_fraction));
  field("whirl_fraction", num_json(v.whirl_fraction));
  field("forward_fraction", num_json(v.forward_fraction));
  field("backward_onset", opt_json(v.backward_onset));
  field("whip_onset", opt_json(v.whip_onset));
  field("whirl_onset", opt_json(v.whirl_onset));
  field("sign_backward_fraction", num_json(v.sign_backward_fraction));
  field("sign_backward_onset", opt_json(v.sign_backward_onset));
  field("permanent_contact_onset", opt_json(v.permanent_contact_onset));
  field("max_friction_torque_ratio", num_json(v.max_friction_torque_ratio));
  field("mean_friction_torque_ratio", num_json(v.mean_friction_torque_ratio));
  field("min_dN_over_g0", num_json(v.min_dN_over_g0));
  field("events", fmt::format("{}", v.events), true);
  return j + "}\n";
}

std::vector<std::string> analysis_option_problems(const AnalysisOptions& o) {
  std::vector<std::string> bad;
  auto rule = [&bad](bool ok, const char* name, double x, const char* text) {
    if (!ok) bad.push_back(fmt::format("{} = {}: {}", name, x, text));
  };
  rule(std::isfinite(o.min_turns) && o.min_turns > 0, "--min-turns", o.min_turns,
       "must be finite and > 0 (orbit revolutions)");
  rule(std::isfinite(o.window) && o.window > 0, "--window", o.window,
       "must be finite and > 0 (spectrogram frame length [s])");
  rule(o.overlap >= 0 && o.overlap < 1, "--overlap", o.overlap, "must lie in [0, 1)");
  rule(o.pad >= 1, "--pad", o.pad, "must be >= 1");
  rule(std::isfinite(o.f_max) && o.f_max > 0, "--fmax", o.f_max, "must be finite and > 0 [Hz]");
  // the analysis window: NaN would pass through std::max / std::min as the run's own bounds
  if (o.t0) rule(std::isfinite(*o.t0), "--t-window t0", *o.t0, "must be finite [s]");
  if (o.t1) rule(std::isfinite(*o.t1), "--t-window t1", *o.t1, "must be finite [s]");
  if (o.t0 && o.t1 && std::isfinite(*o.t0) && std::isfinite(*o.t1))
    rule(*o.t0 < *o.t1, "--t-window t1", *o.t1, "must be > t0");
  return bad;
}

namespace {

/// One plane's analysis, computed before anything is written.
struct PlaneAnalysis {
  std::vector<DerivedSample> d;
  RunVerdicts v;
  Spectrum sp;
  std::string sp_note;  ///< why there is no spectrum (empty: there is one)
  Spectrogram sg;
  std::string sg_note;
};

PlaneAnalysis analyse_plane(const RunRecord& r, AnalysisOptions o, int plane) {
  o.plane = plane;
  PlaneAnalysis a;
  a.d = derive(r, plane);
  a.v = verdicts(r, a.d, o);
  // a run with too few samples for a spectrum (a huge output.dt: the initial and final states
  // only) has none, and a run shorter than one spectrogram frame no spectrogram (a short sweep
  // point, say): the other results stand, and analysis.json says why each is absent (the
  // window and the options were checked by verdicts() above)
  try {
    a.sp = full_spectrum(r, o);
  } catch (const std::invalid_argument& e) {
    a.sp_note = e.what();
  }
  try {
    a.sg = spectrogram(r, o);
  } catch (const std::invalid_argument& e) {
    if (o.overlap < 0.0 || o.overlap >= 1.0 || o.pad < 1) throw;  // a bad option is an error
    a.sg_note = e.what();
  }
  return a;
}

/// derived.csv, spectrum.csv, spectrogram.csv and campbell.csv of one plane into dir.
void write_plane_files(const PlaneAnalysis& a, const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create " + dir + ": " + ec.message());
  const auto& d = a.d;
  const auto& sp = a.sp;
  const auto& sg = a.sg;
  fmt::memory_buffer b;
  auto out = std::back_inserter(b);
  fmt::format_to(out,
                 "t,omega,precession,precession_ratio,whirl,regime,dN_over_g0,"
                 "friction_torque_ratio,sustained,sign_run\n");
  for (const auto& x : d) {
    fmt::format_to(out, "{},{},{},{},{},{},{},{},{},{}\n", x.t, x.omega, x.precession,
                   x.precession_ratio, to_string(x.whirl), to_string(x.regime), x.dN_over_g0,
                   x.friction_torque_ratio, x.sustained ? 1 : 0, x.sign_run ? 1 : 0);
  }
  write_file_atomic((fs::path(dir) / "derived.csv").string(), fmt::to_string(b));
  b.clear();
  fmt::format_to(out, "f,amplitude\n");
  for (size_t k = 0; k < sp.f.size(); ++k) fmt::format_to(out, "{},{}\n", sp.f[k], sp.amplitude[k]);
  write_file_atomic((fs::path(dir) / "spectrum.csv").string(), fmt::to_string(b));
  b.clear();
  fmt::format_to(out, "t,f,amplitude\n");
  for (size_t i = 0; i < sg.t.size(); ++i)
    for (size_t k = 0; k < sg.f.size(); ++k)
      fmt::format_to(out, "{},{},{}\n", sg.t[i], sg.f[k], sg.amplitude[i][k]);
  write_file_atomic((fs::path(dir) / "spectrogram.csv").string(), fmt::to_string(b));
  b.clear();
  fmt::format_to(out, "t,omega,f_whirl,undersampled");
  for (const auto& l : sg.campbell_labels) fmt::format_to(out, ",{}", l);
  fmt::format_to(out, "\n");
  for (size_t i = 0; i < sg.t.size(); ++i) {
    fmt::format_to(out, "{},{},{},{}", sg.t[i], sg.omega[i], sg.f_whirl[i],
                   sg.undersampled[i] ? 1 : 0);
    for (const auto& col : sg.campbell) fmt::format_to(out, ",{}", col[i]);
    fmt::format_to(out, "\n");
  }
  write_file_atomic((fs::path(dir) / "campbell.csv").string(), fmt::to_string(b));
}

/// One plane's verdicts with its spectra's notes, as the JSON object of analysis.json.
std::string plane_json(const PlaneAnalysis& a) {
  const auto& sg = a.sg;
  std::string json = verdicts_json(a.v);
  // (the notes quote paths: escaped as JSON strings)
  json.insert(json.size() - 3,
              fmt::format(",\n  \"spectrum\": {}",
                          quoted_string(a.sp_note.empty() ? "written" : "skipped: " + a.sp_note)));
  json.insert(json.size() - 3,
              fmt::format(",\n  \"spectrogram\": {}",
                          quoted_string(a.sg_note.empty() ? "written" : "skipped: " + a.sg_note)));
  if (a.sg_note.empty()) {
    // the frames whose samples alias the orbit's whirl (campbell.csv: f_whirl, undersampled)
    long bad = 0;
    for (const char u : sg.undersampled) bad += u ? 1 : 0;
    std::string spans;
    for (size_t i = 0; i < sg.t.size(); ++i) {
      if (!sg.undersampled[i] || (i > 0 && sg.undersampled[i - 1])) continue;
      size_t j = i;
      while (j + 1 < sg.t.size() && sg.undersampled[j + 1]) ++j;
      spans += fmt::format("{}[{}, {}]", spans.empty() ? "" : ", ", num_json(sg.t[i]),
                           num_json(sg.t[j]));
    }
    json.insert(json.size() - 3,
                fmt::format(",\n  \"spectrogram_nyquist_hz\": {},\n  \"spectrogram_frames\": "
                            "{},\n  \"spectrogram_undersampled_frames\": {},\n  "
                            "\"spectrogram_undersampled_spans\": [{}]",
                            num_json(sg.f_nyquist), sg.t.size(), bad, spans));
  }
  return json;
}

}  // namespace

RunVerdicts write_analysis(const RunRecord& r, const AnalysisOptions& o,
                           const std::string& out_dir) {
  namespace fs = std::filesystem;
  // compute everything first: a bad option fails before any file is written
  const int planes = build_model(r.spec)->contact_count();
  std::vector<PlaneAnalysis> all;
  for (int k = 0; k < planes; ++k) all.push_back(analyse_plane(r, o, k));
  const std::string dir = out_dir.empty() ? (fs::path(r.dir) / "analysis").string() : out_dir;
  // plane 1 in the folder itself (a one-plane run's files as they have always been), plane k in
  // plane_k/
  for (int k = 0; k < planes; ++k)
    write_plane_files(all[static_cast<std::size_t>(k)],
                      k == 0 ? dir : (fs::path(dir) / fmt::format("plane_{}", k + 1)).string());
  std::string json = plane_json(all.front());
  if (planes > 1) {
    // every plane's own verdicts, and the friction torque of all planes together (what brakes
    // the spin): the sum of R_k F_T,k / tau_a over the planes, sample by sample
    std::string arr;
    for (int k = 0; k < planes; ++k) {
      std::string pj = plane_json(all[static_cast<std::size_t>(k)]);
      pj.insert(2, fmt::format("  \"plane\": {},\n", k + 1));
      // indent the object by two spaces inside the array
      std::string ind;
      for (char c : pj) {
        ind += c;
        if (c == '\n') ind += "  ";
      }
      while (!ind.empty() && (ind.back() == ' ' || ind.back() == '\n')) ind.pop_back();
      arr += fmt::format("{}  {}", arr.empty() ? "" : ",\n", ind);
    }
    const auto& d0 = all.front().d;
    double peak = 0.0, integral = 0.0;
    const double t0 = all.front().v.t0, t1 = all.front().v.t1;
    for (std::size_t i = 0; i < d0.size(); ++i) {
      if (d0[i].t < t0 || d0[i].t > t1) continue;
      double sum = 0.0;
      for (const auto& a : all) sum += a.d[i].friction_torque_ratio;
      if (!std::isfinite(sum)) continue;
      peak = std::max(peak, sum);
      if (i + 1 < d0.size()) {
        const double b = std::min(d0[i + 1].t, t1);
        if (b > d0[i].t) integral += sum * (b - d0[i].t);
      }
    }
    json.insert(json.size() - 3,
                fmt::format(",\n  \"planes\": [\n{}\n  ],\n  \"max_total_friction_torque_ratio\": "
                            "{},\n  \"mean_total_friction_torque_ratio\": {}",
                            arr, num_json(peak), num_json(integral / (t1 - t0))));
  }
  write_file_atomic((fs::path(dir) / "analysis.json").string(), json);
  return all.front().v;
}

}  // namespace rubdyn
