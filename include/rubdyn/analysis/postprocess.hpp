#pragma once
// Post-processing of an output folder (rubdyn analyze; the paper's section 5 quantities). Reads
// only the folder: timeseries.csv for the motion and case.resolved.toml for the parameters.
//
// Definitions (per output sample; Y up, spin theta' > 0 counterclockwise about +Z):
//   s = r_r - r_s                   rotor centre relative to the stator centre in the contact
//                                   plane analysed (LagrangianModel::plane_motion; R for the
//                                   paper's rotor; with several planes, each plane in turn)
//   precession  Omega_p = (s_x s_y' - s_y s_x') / |s|^2  [rad/s]: the angular speed of the rotor
//               orbit relative to the stator, positive in the spin direction (counterclockwise);
//               undefined (NaN) while |s| < 1e-3 g0 (centred rotor: no orbit angle)
//   precession ratio  Omega_p / omega
//   whirl       forward if Omega_p omega > 0, backward if < 0 (none when undefined)
//   regime      free, sliding (slip+ or slip-), rolling (stick)
//   dry whip    backward whirl while sliding; dry whirl: backward whirl while rolling (rolling
//               without slip whirls at -R_r omega / g0: 250 x the spin, backward, for the
//               reference case)
//   friction torque ratio  R_r F_T / tau_a (the plane's R_r and F_T): the friction torque about the
//   shaft, positive when it
//               brakes a positive spin (the generalised force on theta is -R_r F_T), over the
//               driving torque
//   d_N / g0    normalised gap
// Time fractions are time-weighted over the run (each sample's state holds until the next
// sample; the two rows written at an event time take no time).
// Sustained whirl. The local precession changes sign whenever the rotor rocks to and fro in the
// clearance (the reference case slides at the bottom of the stator doing just that), so a whirl
// counts only when the orbit goes round: a run of consecutive samples in contact with the same
// whirl direction is sustained when the orbit angle it covers, the integral of |Omega_p| dt
// (trapezoidal; exact enough even when the whirl is faster than the sampling, since Omega_p
// itself varies slowly), reaches 2 pi `min_turns`. Backward-whirl onset = start of the first
// sustained backward run; whip onset = first sliding sample of a sustained backward run; the
// whip and dry-whirl fractions split the sustained backward time by regime.
// Precession-sign whirl (partial contact allowed): the same rule without the contact condition,
// i.e. runs of consecutive samples with the same precession sign, in contact or in flight,
// covering 2 pi `min_turns` of orbit angle. Its onset comes earlier than the sustained one when
// the orbit turns backward while the rotor still bounces. Both are reported; the whip verdicts
// (whip_onset, whip_fraction, sweep's whip column) use the sustained whirl, because that is the
// one that matches the paper's description of whip onset (contact permanent first, then the
// precession strictly negative, then the friction torque above the drive and the speed falling):
// the evidence is validation/paper/whirl.py.
// Permanent contact onset: the start of the last contact stretch of the window when it lasts to
// the window's end (no lift-off after it); none when the window ends in free flight.
//
// Spectra of z = x_r + i y_r (the rotor orbit at R; negative frequencies = backward whirl): the
// signal is resampled on a uniform grid (the most frequent sample spacing, linear interpolation
// across event rows), a Hann window is applied and the amplitude |Z(f)| / sum(w) is given, so a
// circular whirl a e^{i 2 pi f0 t} appears with amplitude a at f0 (up to the window's leakage).
// The spectrogram uses frames of `window` seconds shifted by window (1 - overlap), each frame
// zero-padded to at least `pad` times its length (a finer frequency grid, not a finer
// resolution). Alongside it, the Campbell curves of the coupled system (analysis/campbell.hpp) at
// the frame's mean spin speed, backward modes at negative frequency.
#include <optional>
#include <string>
#include <vector>

#include "rubdyn/core/run_types.hpp"
#include "rubdyn/io/case_spec.hpp"
#include "rubdyn/io/output_reader.hpp"

namespace rubdyn {

// RunRecord and read_run (the output folder read back): rubdyn/io/output_reader.hpp

enum class Whirl { None, Forward, Backward };
enum class Regime { Free, Sliding, Rolling };
std::string_view to_string(Whirl w);
std::string_view to_string(Regime r);

struct DerivedSample {
  double t = 0, omega = 0;
  double precession = 0, precession_ratio = 0;  ///< NaN when undefined
  Whirl whirl = Whirl::None;
  Regime regime = Regime::Free;
  double dN_over_g0 = 0, friction_torque_ratio = 0;
  bool sustained = false;  ///< part of a sustained whirl run (set by verdicts())
  bool sign_run = false;   ///< part of a precession-sign whirl run (set by verdicts())
};

struct AnalysisOptions {
  double min_turns = 1.0;        ///< sustained whirl: orbit revolutions in one run (> 0)
  double window = 0.04;          ///< spectrogram frame length [s]
  double overlap = 0.75;         ///< spectrogram frame overlap, in [0, 1)
  int pad = 4;                   ///< zero-padding factor of each frame (>= 1)
  double f_max = 2000.0;         ///< frequencies kept in the spectra: |f| <= f_max [Hz]
  std::optional<double> t0, t1;  ///< analysis window (default: the whole run)
  int plane = 0;  ///< the contact plane analysed (0-based contact index; spectra, spectrogram)
};

/// Every rule `o` breaks, one message each naming the option (empty: valid): min_turns > 0,
/// window > 0, overlap in [0, 1), pad >= 1, f_max > 0, t0 < t1 when both are given, all
/// finite. Checked by analyze and by a sweep before its first point.
std::vector<std::string> analysis_option_problems(const AnalysisOptions& o);

struct RunVerdicts {
  double t0 = 0, t1 = 0;  ///< the analysed window [s]
  double omega_max = 0, omega_final = 0;
  std::optional<double> t_omega_lim;  ///< first time omega >= omega_lim (interpolated)
  bool limited = false;               ///< omega stayed below omega_lim over the window
  double contact_fraction = 0, stick_fraction = 0;
  double backward_fraction = 0;  ///< sustained backward whirl (in contact)
  double whip_fraction = 0;      ///< sustained backward whirl, sliding
  double whirl_fraction = 0;     ///< sustained backward whirl, rolling
  double forward_fraction = 0;   ///< sustained forward whirl (in contact)
  std::optional<double> backward_onset, whip_onset, whirl_onset;  ///< see the header comment
  double sign_backward_fraction = 0;              ///< precession-sign backward whirl (any regime)
  std::optional<double> sign_backward_onset;      ///< start of its first run
  std::optional<double> permanent_contact_onset;  ///< see the header comment
  double max_friction_torque_ratio = 0, mean_friction_torque_ratio = 0;  ///< over the window
  double min_dN_over_g0 = 0;                                             ///< < 0: penetration
  long events = 0;  ///< rows of events.csv (every kind), whole run
};

struct Spectrum {
  std::vector<double> f;          ///< [Hz], ascending, negative = backward
  std::vector<double> amplitude;  ///< [m]
};
struct Spectrogram {
  std::vector<double> t;                       ///< frame centres [s]
  std::vector<double> omega;                   ///< mean spin speed of each frame [rad/s]
  std::vector<double> f;                       ///< [Hz], ascending
  std::vector<std::vector<double>> amplitude;  ///< amplitude[frame][k] [m]
  /// Campbell frequencies of the model's tied linearisation at each frame's omega [Hz]:
  /// campbell[label][frame], labels f1f, f2f, ..., f1b, f2b, ... (forward >= 0, backward <= 0);
  /// none when the model has no such linearisation.
  std::vector<std::string> campbell_labels;
  std::vector<std::vector<double>> campbell;
  /// Aliasing: the samples' Nyquist frequency 1 / (2 dt) [Hz]; per frame the whirl frequency
  /// scale max |z'| / (2 pi max |z - mean z|) [Hz] from the velocities (exact for a circular
  /// whirl; above the Nyquist frequency it proves content the samples alias, by Bernstein's
  /// inequality), and the frame marked undersampled when that scale exceeds
  /// kUndersampledFraction of the Nyquist frequency. In rolling the orbit whirls at R_r / g0
  /// times the spin: at output.dt = 1e-4 every rolling frame is undersampled.
  double f_nyquist = 0.0;
  std::vector<double> f_whirl;
  std::vector<char> undersampled;
};

/// A frame is undersampled when its whirl frequency scale exceeds this fraction of the Nyquist
/// frequency: a margin of 2 for frames that mix whirls (the scale of a mixture can sit below
/// its fastest component).
inline constexpr double kUndersampledFraction = 0.5;

/// The derived samples of contact plane `plane` (0-based). Throws std::invalid_argument when the
/// model has no such plane or cannot locate its centres (LagrangianModel::plane_motion).
std::vector<DerivedSample> derive(const RunRecord& r, int plane = 0);
/// Also marks d[i].sustained. verdicts, full_spectrum and spectrogram throw
/// std::invalid_argument for a run without samples, a sample time that is not finite, times
/// that decrease, or a window that does not overlap the run.
RunVerdicts verdicts(const RunRecord& r, std::vector<DerivedSample>& d,
                     const AnalysisOptions& o = {});
/// Throws std::invalid_argument on fewer than 8 uniform samples in the window.
Spectrum full_spectrum(const RunRecord& r, const AnalysisOptions& o = {});
/// Throws std::invalid_argument on a window shorter than 8 samples or longer than the run, or on
/// an overlap outside [0, 1).
Spectrogram spectrogram(const RunRecord& r, const AnalysisOptions& o = {});

/// Writes dir/analysis/{derived.csv, spectrum.csv, spectrogram.csv, campbell.csv,
/// analysis.json} (or into out_dir); each file written to a temporary name and renamed, so a
/// failure leaves no half-written file. Returns the verdicts. A model with several contact
/// planes: those files are plane 1's, and plane k's derived, spectrum, spectrogram and campbell
/// files are in the subfolder plane_k/ (k = 2..K); analysis.json keeps plane 1's verdicts at
/// its top level (as for one plane) and adds "planes" (each plane's verdicts with its number)
/// and the friction torque of all planes together, max_total_friction_torque_ratio and
/// mean_total_friction_torque_ratio (sum over the planes of R_k F_T,k / tau_a). The analysis
/// options' `plane` is ignored here: every plane is written.
RunVerdicts write_analysis(const RunRecord& r, const AnalysisOptions& o,
                           const std::string& out_dir = "");
std::string verdicts_json(const RunVerdicts& v);

}  // namespace rubdyn
