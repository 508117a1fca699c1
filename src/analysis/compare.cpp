#include "rubdyn/analysis/compare.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "rubdyn/io/output_reader.hpp"
#include "rubdyn/io/text_files.hpp"

namespace rubdyn {

namespace {

const char* const kStandard[] = {"omega", "x_r", "y_r", "x_s", "y_s", "d_N"};

std::string timeseries_path(const std::string& path) {
  return std::filesystem::is_directory(path) ? path + "/timeseries.csv" : path;
}

/// Linear interpolation of (t, v) at x (t sorted, possibly with repeated times: the later
/// sample of a repeated time is used, i.e. the state just after an event).
double interpolate(const std::vector<double>& t, const std::vector<double>& v, double x) {
  auto it = std::upper_bound(t.begin(), t.end(), x);
  if (it == t.begin()) return v.front();
  const std::size_t j = static_cast<std::size_t>(it - t.begin());
  if (j == t.size()) return v.back();
  const std::size_t i = j - 1;
  if (t[i] == x || t[j] == t[i]) return v[i];
  const double w = (x - t[i]) / (t[j] - t[i]);
  return v[i] + w * (v[j] - v[i]);
}

}  // namespace

const std::vector<double>* Series::column(const std::string& name) const {
  for (std::size_t c = 0; c < names.size(); ++c)
    if (names[c] == name) return &values[c];
  return nullptr;
}

Series read_series(const std::string& path) {
  const CsvTable table = read_csv(timeseries_path(path));
  const std::string& file = table.path;
  Series s;
  s.source = file;
  s.warnings = table.warnings;
  const int tcol = table.column("t");
  if (tcol < 0) throw ReadError(file, 1, "no column named t");
  std::vector<int> cols;  // the numeric columns, decided on the first data row
  for (std::size_t k = 0; k < table.rows.size(); ++k) {
    const auto& f = table.rows[k];
    const long lineno = table.line_of[k];
    if (k == 0) {
      for (std::size_t c = 0; c < f.size(); ++c) {
        double x;
        if (static_cast<int>(c) != tcol && parse_number(f[c], x)) {
          cols.push_back(static_cast<int>(c));
          s.names.push_back(table.header[c]);
        }
      }
      s.values.resize(cols.size());
    }
    double t;
    if (!parse_number(f[tcol], t) || !std::isfinite(t)) {
      throw ReadError(file, lineno,
                      fmt::format("t = '{}' is not a finite number", printable(f[tcol])));
    }
    if (!s.t.empty() && t < s.t.back())
      throw ReadError(file, lineno, fmt::format("t = {} decreases", t));
    s.t.push_back(t);
    for (std::size_t c = 0; c < cols.size(); ++c) {
      double x;
      if (!parse_number(f[cols[c]], x)) {
        throw ReadError(
            file, lineno,
            fmt::format("{} = '{}' is not a number", printable(s.names[c]), printable(f[cols[c]])));
      }
      s.values[c].push_back(x);
    }
  }
  if (s.t.size() < 2) {
    throw ReadError(file, 0,
                    fmt::format("{} sample{}: compare needs at least two", s.t.size(),
                                s.t.size() == 1 ? "" : "s"));
  }
  return s;
}

std::vector<TimedEvent> read_events(const std::string& path) {
  std::vector<TimedEvent> out;
  if (!std::filesystem::is_directory(path)) return out;
  const std::string file = path + "/events.csv";
  if (!std::filesystem::exists(file)) return out;
  // a header-only or empty file (a killed run): no events; a cut last row is dropped (the time
  // series reader warns)
  const CsvTable table = read_csv(file, true);
  if (table.header.empty()) return out;
  const int tc = table.column("t"), kc = table.column("kind");
  if (tc < 0 || kc < 0) throw ReadError(file, 1, "needs columns t and kind");
  for (std::size_t k = 0; k < table.rows.size(); ++k) {
    double t;
    if (!parse_number(table.rows[k][tc], t) || !std::isfinite(t)) {
      throw ReadError(file, table.line_of[k],
                      fmt::format("t = '{}' is not a finite time", printable(table.rows[k][tc])));
    }
    out.push_back({t, table.rows[k][kc]});
  }
  return out;
}

namespace {

/// The rules compare_solutions states for one solution (compare.hpp).
void check_series(const Series& s, const std::vector<TimedEvent>& events) {
  auto bad = [&s](const std::string& what) {
    return std::invalid_argument(fmt::format("compare: {}: {}", s.source, what));
  };
  if (s.names.size() != s.values.size()) {
    throw bad(fmt::format("{} column names for {} columns", s.names.size(), s.values.size()));
  }
  if (s.t.size() < 2) throw bad(fmt::format("{} samples: compare needs at least two", s.t.size()));
  for (std::size_t i = 0; i < s.t.size(); ++i) {
    if (!std::isfinite(s.t[i]))
      throw bad(fmt::format("t[{}] = {}: times must be finite", i, s.t[i]));
    if (i > 0 && s.t[i] < s.t[i - 1]) {
      throw bad(fmt::format("t[{}] = {} < t[{}] = {}: times must not decrease", i, s.t[i], i - 1,
                            s.t[i - 1]));
    }
  }
  for (std::size_t c = 0; c < s.values.size(); ++c) {
    if (s.values[c].size() != s.t.size()) {
      throw bad(fmt::format("column {} has {} values, t has {}", printable(s.names[c]),
                            s.values[c].size(), s.t.size()));
    }
  }
  for (std::size_t k = 0; k < events.size(); ++k) {
    if (!std::isfinite(events[k].t)) {
      throw bad(fmt::format("event {} ({}) at t = {}: times must be finite", k,
                            printable(events[k].kind), events[k].t));
    }
  }
}

}  // namespace

double Comparison::max_event_shift() const {
  double m = 0.0;
  for (const auto& e : matched) m = std::max(m, std::abs(e.t_b - e.t_a));
  return m;
}

Comparison compare_solutions(const Series& a, const Series& b, const std::vector<TimedEvent>& ea,
                             const std::vector<TimedEvent>& eb,
                             std::optional<std::pair<double, double>> window, double event_tol) {
  check_series(a, ea);
  check_series(b, eb);
  if (window && !(std::isfinite(window->first) && std::isfinite(window->second) &&
                  window->first < window->second)) {
    throw std::invalid_argument(
        fmt::format("compare: window [{}, {}]: must be two finite times t0 < t1", window->first,
                    window->second));
  }
  if (!(std::isfinite(event_tol) && event_tol > 0.0)) {
    throw std::invalid_argument(
        fmt::format("compare: event_tol = {}: must be finite and > 0 [s]", event_tol));
  }
  Comparison c;
  c.t0 = std::max(a.t.front(), b.t.front());
  c.t1 = std::min(a.t.back(), b.t.back());
  if (window) {
    c.t0 = std::max(c.t0, window->first);
    c.t1 = std::min(c.t1, window->second);
  }
  if (!(c.t1 > c.t0)) {
    const std::string in_window =
        window ? fmt::format(" inside the window [{}, {}]", window->first, window->second) : "";
    throw std::invalid_argument(fmt::format("compare: {} [{}, {}] and {} [{}, {}] share no time{}",
                                            a.source, a.t.front(), a.t.back(), b.source,
                                            b.t.front(), b.t.back(), in_window));
  }
  std::vector<double> times;
  for (const auto* s : {&a, &b})
    for (double t : s->t)
      if (t >= c.t0 && t <= c.t1) times.push_back(t);
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  c.points = times.size();
  for (const char* name : kStandard) {
    const auto* va = a.column(name);
    const auto* vb = b.column(name);
    if (!va || !vb) {
      c.missing.push_back(name);
      continue;
    }
    ColumnDiff d;
    d.name = name;
    double integral = 0.0, prev_e2 = 0.0;
    for (std::size_t i = 0; i < times.size(); ++i) {
      const double e = interpolate(a.t, *va, times[i]) - interpolate(b.t, *vb, times[i]);
      if (!std::isfinite(e)) {
        // a NaN would drop out of every comparison below (sup 0, rms nan): it is a difference
        if (d.non_finite++ == 0) d.t_sup = times[i];
        d.sup = std::numeric_limits<double>::infinity();
        continue;
      }
      if (std::abs(e) > d.sup) {
        d.sup = std::abs(e);
        d.t_sup = times[i];
      }
      if (i > 0) integral += 0.5 * (prev_e2 + e * e) * (times[i] - times[i - 1]);
      prev_e2 = e * e;
    }
    d.rms = times.size() > 1 ? std::sqrt(integral / (times.back() - times.front())) : d.sup;
    if (d.non_finite > 0) d.rms = std::numeric_limits<double>::infinity();
    c.columns.push_back(d);
  }
  if (c.columns.empty()) {
    std::string names;
    for (const char* n : kStandard) names += (names.empty() ? "" : ", ") + std::string(n);
    throw std::invalid_argument(
        fmt::format("nothing to compare: {} and {} have none of the columns {} in common", a.source,
                    b.source, names));
  }
  // events: greedy matching in time order per kind, inside the window
  auto in_window = [&](const TimedEvent& e) {
    return e.t >= c.t0 - event_tol && e.t <= c.t1 + event_tol;
  };
  std::vector<bool> used(eb.size(), false);
  for (const auto& x : ea) {
    if (!in_window(x)) continue;
    int best = -1;
    for (std::size_t j = 0; j < eb.size(); ++j) {
      if (used[j] || eb[j].kind != x.kind || std::abs(eb[j].t - x.t) > event_tol) continue;
      if (best < 0 || std::abs(eb[j].t - x.t) < std::abs(eb[best].t - x.t))
        best = static_cast<int>(j);
    }
    if (best < 0) {
      c.unmatched_a.push_back(x);
    } else {
      used[best] = true;
      c.matched.push_back({x.kind, x.t, eb[best].t});
    }
  }
  for (std::size_t j = 0; j < eb.size(); ++j)
    if (!used[j] && in_window(eb[j])) c.unmatched_b.push_back(eb[j]);
  return c;
}

std::string comparison_json(const Comparison& c, const std::string& a, const std::string& b) {
  // JSON strings: a folder name may hold a line end or another control character
  // (quoted_string escapes them, as summary.json's strings)
  auto q = [](const std::string& s) { return quoted_string(s); };
  std::string j = fmt::format(
      "{{\n  \"a\": {},\n  \"b\": {},\n  \"t0\": {:.17g},\n  \"t1\": {:.17g},\n  \"points\": {},\n "
      " \"columns\": {{",
      q(a), q(b), c.t0, c.t1, c.points);
  for (std::size_t i = 0; i < c.columns.size(); ++i) {
    const auto& d = c.columns[i];
    // JSON has no infinity: a non-finite difference is written as null (and counted)
    auto num = [](double x) { return std::isfinite(x) ? fmt::format("{:.17g}", x) : "null"; };
    j += fmt::format(
        "{}\n    {}: {{\"sup\": {}, \"rms\": {}, \"t_sup\": {:.17g}, \"non_finite\": {}}}",
        i ? "," : "", q(d.name), num(d.sup), num(d.rms), d.t_sup, d.non_finite);
  }
  j += "\n  },\n  \"missing_columns\": [";
  for (std::size_t i = 0; i < c.missing.size(); ++i) j += (i ? ", " : "") + q(c.missing[i]);
  j += "],\n  \"matched_events\": [";
  for (std::size_t i = 0; i < c.matched.size(); ++i) {
    const auto& m = c.matched[i];
    j += fmt::format(
        "{}\n    {{\"kind\": {}, \"t_a\": {:.17g}, \"t_b\": {:.17g}, \"shift\": {:.17g}}}",
        i ? "," : "", q(m.kind), m.t_a, m.t_b, m.t_b - m.t_a);
  }
  auto list = [&](const std::vector<TimedEvent>& v) {
    std::string s = "[";
    for (std::size_t i = 0; i < v.size(); ++i)
      s += fmt::format("{}{{\"kind\": {}, \"t\": {:.17g}}}", i ? ", " : "", q(v[i].kind), v[i].t);
    return s + "]";
  };
  j += fmt::format(
      "\n  ],\n  \"max_event_shift\": {:.17g},\n  \"unmatched_a\": {},\n  \"unmatched_b\": "
      "{}\n}}\n",
      c.max_event_shift(), list(c.unmatched_a), list(c.unmatched_b));
  return j;
}

std::string comparison_report(const Comparison& c, const std::string& a, const std::string& b) {
  std::string r = fmt::format(
      "compare  a = {}\n         b = {}\nwindow   [{:.9g}, {:.9g}] s, {} sample times\n", a, b,
      c.t0, c.t1, c.points);
  r += fmt::format("{:<8} {:>14} {:>14} {:>14}\n", "column", "sup |a - b|", "rms", "at t [s]");
  for (const auto& d : c.columns) {
    r += fmt::format("{:<8} {:>14.6e} {:>14.6e} {:>14.9g}\n", d.name, d.sup, d.rms, d.t_sup);
    if (d.non_finite > 0)
      r += fmt::format(
          "{:<8} {} sample times where a - b is not finite (NaN or inf), first at "
          "t = {:.9g} s\n",
          "", d.non_finite, d.t_sup);
  }
  if (!c.missing.empty()) {
    r += "not compared (absent from one side):";
    for (const auto& m : c.missing) r += " " + m;
    r += "\n";
  }
  r += fmt::format("events   {} matched, max |shift| {:.3e} s; unmatched: {} in a, {} in b\n",
                   c.matched.size(), c.max_event_shift(), c.unmatched_a.size(),
                   c.unmatched_b.size());
  for (const auto& e : c.unmatched_a)
    r += fmt::format("  only in a: {} at {:.12g} s\n", e.kind, e.t);
  for (const auto& e : c.unmatched_b)
    r += fmt::format("  only in b: {} at {:.12g} s\n", e.kind, e.t);
  return r;
}

}  // namespace rubdyn
