#pragma once
// Comparing two solutions: time series differences and matched events (rubdyn compare).
//
// A solution is an output folder (timeseries.csv, events.csv) or any CSV file with a `t` column
// and some of the standard column names (omega, x_r, y_r, x_s, y_s, d_N), so that users can
// compare a run of their own solver. Differences are taken on the union of the two sets of
// sample times inside the window, each series linearly interpolated there; at a time sampled
// twice (before and after an event) the later sample is used. sup = max |a - b|, rms = the
// time-weighted root mean square (trapezoidal rule) over the window.
// Events of the same kind (impact, liftoff, stick, slip, ...) are matched in time order to the
// nearest unmatched event of the other solution within `event_tol`; the rest are unmatched.
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rubdyn {

struct Series {
  std::string source;
  std::vector<double> t;
  std::vector<std::string> names;           ///< numeric columns other than t
  std::vector<std::vector<double>> values;  ///< values[c][i]
  /// What the reader tolerated, e.g. a last row without its line end (a run that was killed)
  /// that it dropped; the CLI prints them.
  std::vector<std::string> warnings;
  const std::vector<double>* column(const std::string& name) const;
};

struct TimedEvent {
  double t = 0.0;
  std::string kind;
};

/// Reads a solution: a folder (timeseries.csv and, if present, events.csv) or a CSV file,
/// through the output folders' CSV reader (io/output_reader.hpp: a cut last row dropped with a
/// warning, CRLF read as LF). Throws ReadError naming the file, line and problem on bad input
/// (not text, a short row, a t that is not finite or decreases, fewer than two samples).
Series read_series(const std::string& path);
std::vector<TimedEvent> read_events(const std::string& path);  ///< empty for a plain CSV

struct ColumnDiff {
  std::string name;
  double sup = 0.0, rms = 0.0, t_sup = 0.0;  ///< t_sup: where the sup is reached
  /// Sample times where a - b is not finite (a NaN or inf on one side or both): each is a
  /// difference, never skipped; with any, sup and rms are infinite and t_sup is the first.
  long non_finite = 0;
};
struct EventMatch {
  std::string kind;
  double t_a = 0.0, t_b = 0.0;  ///< shift = t_b - t_a
};
struct Comparison {
  double t0 = 0.0, t1 = 0.0;
  std::size_t points = 0;  ///< sample times used
  std::vector<ColumnDiff> columns;
  std::vector<std::string> missing;  ///< standard columns absent from one of the solutions
  std::vector<EventMatch> matched;
  std::vector<TimedEvent> unmatched_a, unmatched_b;
  double max_event_shift() const;
};

/// Compares b against a over [t0, t1] (default: the overlap of the two time ranges).
/// Throws std::invalid_argument naming the solution (its `source`) and the rule for inputs that
/// are not two solutions: fewer than two samples, a column whose length differs from t's, a time
/// (sample or event) that is not finite, times that decrease; for a window that is not two finite
/// times t0 < t1, an event_tol that is not finite and > 0; and when the solutions do not overlap
/// in the window or share none of the standard columns. NaN values in the columns are allowed
/// (counted as non_finite differences).
Comparison compare_solutions(const Series& a, const Series& b, const std::vector<TimedEvent>& ea,
                             const std::vector<TimedEvent>& eb,
                             std::optional<std::pair<double, double>> window = std::nullopt,
                             double event_tol = 1e-3);

std::string comparison_json(const Comparison& c, const std::string& a, const std::string& b);
std::string comparison_report(const Comparison& c, const std::string& a, const std::string& b);

}  // namespace rubdyn
