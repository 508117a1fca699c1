// Starting from a sample of another run's output folder (restart.hpp).
#include "restart.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <stdexcept>

#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/columns.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/output_reader.hpp"

namespace rubdyn::app {

/// The overrides that start a run from a sample of the output folder `from`: run.t_start and
/// every initial.* key, written in the shortest form that reads back to the same double (the
/// samples carry 17 significant digits, so the state is exact). The sample is the one at `at`
/// (the last of the rows at that time: after an event) or the last complete one.
std::vector<std::string> restart_overrides(const std::string& from,
                                           const std::optional<std::string>& at,
                                           const CaseSpec* plain, std::string_view command) {
  const RunRecord r = read_run(from);
  for (const auto& w : r.warnings)
    std::fprintf(stderr, "%.*s: warning: %s\n", static_cast<int>(command.size()), command.data(),
                 w.c_str());
  if (plain) {
    const auto names = [](const CaseSpec& c) {
      std::string t;
      for (const auto& x : initial_coordinates(c)) t += (t.empty() ? "" : ", ") + x.name;
      return t;
    };
    const std::string theirs = names(r.spec), ours = names(*plain);
    if (r.spec.model != plain->model || theirs != ours)
      throw CaseError(
          {{"command line", 0, "--from", from,
            fmt::format("holds a run of model '{}' with coordinates ({}), where the case is of "
                        "model '{}' with coordinates ({}): a restart sets every coordinate from "
                        "the sample, so the case must be of the folder's model and layout (its "
                        "case.resolved.toml is one)",
                        r.spec.model, theirs, plain->model, ours)}});
  }
  // a run that wrote a selection of its coordinates (output.coordinates) restarts from the
  // full states of its state.csv: its first sample, after each event, its last sample
  const std::vector<Sample>& rows = r.every_coordinate ? r.samples : r.states;
  const std::string file = r.every_coordinate ? "timeseries.csv" : "state.csv";
  if (rows.empty())
    throw std::runtime_error("--from " + from + ": no samples to start from" +
                             (r.every_coordinate
                                  ? std::string()
                                  : " (its timeseries.csv holds a selection of "
                                    "the coordinates, and state.csv no full state)"));
  const Sample* s = &rows.back();
  if (at) {
    char* end = nullptr;
    const double T = std::strtod(at->c_str(), &end);
    if (at->empty() || *end != '\0' || !std::isfinite(T))
      throw CaseError({{"command line", 0, "--at", *at, "must be a finite time [s]"}});
    // a time typed in decimal (0.01) and a grid time t0 + k dt (0.010000000000000002) differ
    // by a few ulps: 1e-12 relative matches them and no two distinct samples
    const double tol = 1e-12 * std::max(1.0, std::abs(T));
    s = nullptr;
    for (const auto& x : rows)
      if (std::abs(x.t - T) <= tol) s = &x;
    if (!s) {
      const Sample* before = nullptr;
      for (const auto& x : rows)
        if (x.t < T) before = &x;
      throw CaseError(
          {{"command line", 0, "--at", *at,
            fmt::format("no sample of {}/{} at this time (samples from {:.17g} to {:.17g} s{}{})",
                        from, file, rows.front().t, rows.back().t,
                        before ? fmt::format("; the last before it is at {:.17g} s", before->t)
                               : std::string(),
                        r.every_coordinate
                            ? std::string()
                            : "; the run wrote a selection of its coordinates "
                              "(output.coordinates), so it restarts from the full states of "
                              "state.csv: its first sample, the sample after each event and "
                              "its last")}});
    }
  } else if (!r.complete) {
    std::fprintf(stderr,
                 "%.*s: note: %s is incomplete; starting from its last sample, t = %.17g s\n",
                 static_cast<int>(command.size()), command.data(), from.c_str(), s->t);
  }
  std::vector<std::string> sets = {fmt::format("run.t_start={}", s->t)};
  // every initial-state key from the sample's column of the same name (a coordinate, its rate,
  // or an observable: a prescribed spin's theta and omega)
  const auto model = build_model(r.spec);
  const auto cols = timeseries_columns(*model);
  auto column = [&](const std::string& name) -> const SampleColumn* {
    for (const auto& c : cols)
      if (c.name == name) return &c;
    return nullptr;
  };
  for (const auto& c : initial_coordinates(r.spec)) {
    const SampleColumn* pos = column(c.name);
    const SampleColumn* rate = column(c.rate);
    if (pos) sets.push_back(fmt::format("initial.{}={}", c.name, sample_value(*s, *pos)));
    if (rate) sets.push_back(fmt::format("initial.{}={}", c.rate_key, sample_value(*s, *rate)));
  }
  return sets;
}

std::vector<std::string> restart_overrides_keeping_length(const std::string& from,
                                                          const std::optional<std::string>& at,
                                                          const std::string& path,
                                                          const std::vector<std::string>& sets,
                                                          std::string_view command) {
  std::optional<CaseSpec> plain;
  try {
    plain = load_case(path, sets);
  } catch (const CaseError&) {
    // reported by the caller's load, with the restart's keys
  }
  std::vector<std::string> out = restart_overrides(from, at, plain ? &*plain : nullptr, command);
  const std::string key = "run.t_start=";
  if (plain && !out.empty() && out.front().starts_with(key)) {
    const double t = std::stod(out.front().substr(key.size()));
    out.push_back(fmt::format("run.t_end={}", t + (plain->run.t_end - plain->run.t_start)));
  }
  return out;
}

}  // namespace rubdyn::app
