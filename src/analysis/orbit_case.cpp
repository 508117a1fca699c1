#include "rubdyn/analysis/orbit_case.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <iterator>
#include <numbers>

#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/columns.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/solver_options.hpp"
#include "rubdyn/io/text_files.hpp"

namespace rubdyn {

namespace {

std::string num(double x) {
  return std::isfinite(x) ? fmt::format("{:.17g}", x) : "null";
}
std::string str(std::string_view s) {
  return quoted_string(s);
}

double case_omega(const CaseSpec& spec) {
  const auto model = build_model(spec);
  const MechanicalState s0 = initial_state(spec);
  return model->spin(s0.t, s0.q, s0.v);
}

}  // namespace

std::vector<CaseIssue> forced_orbit_issues(const CaseSpec& spec, const CaseOrbitOptions& o) {
  std::vector<CaseIssue> bad;
  const std::string& f = spec.source;
  if (spec.solver.kind != "event")
    bad.push_back({f, 0, "solver.kind", spec.solver.kind,
                   "rubdyn orbit runs the return map with the event-driven solver: \"event\""});
  const LoadParams& L = spec.loads();
  if (L.spin != SpinDrive::Prescribed) {
    bad.push_back({f, 0, "loads.spin", std::string(to_string(L.spin)),
                   "a forced orbit needs a prescribed constant spin (loads.spin = \"prescribed\", "
                   "loads.spin_accel = 0), whose period 2 pi k / omega0 makes the model periodic; "
                   "orbits of a free spin (the period an unknown) are not implemented yet"});
  } else {
    if (L.spin_accel != 0.0)
      bad.push_back({f, 0, "loads.spin_accel", fmt::format("{}", L.spin_accel),
                     "must be 0: a forced orbit needs a constant spin speed"});
    else if (!(std::abs(case_omega(spec)) > 0.0))
      bad.push_back(
          {f, 0, "initial.omega0", "0", "must not be 0: the orbit's period is 2 pi k / omega0"});
  }
  const std::string cl = "command line";
  if (o.periods < 1)
    bad.push_back({cl, 0, "--periods", std::to_string(o.periods), "must be an integer >= 1"});
  if (o.settle < 0)
    bad.push_back({cl, 0, "--settle", std::to_string(o.settle), "must be an integer >= 0"});
  if (!(o.orbit.tol > 0.0) || !std::isfinite(o.orbit.tol))
    bad.push_back({cl, 0, "--tol", fmt::format("{}", o.orbit.tol), "must be finite and > 0"});
  if (o.orbit.max_iterations < 1)
    bad.push_back(
        {cl, 0, "--max-iter", std::to_string(o.orbit.max_iterations), "must be an integer >= 1"});
  if (o.orbit.samples < 1)
    bad.push_back({cl, 0, "--samples", std::to_string(o.orbit.samples),
                   "must be an integer >= 1 (samples of the orbit per period)"});
  return bad;
}

CaseOrbit find_case_orbit(const CaseSpec& spec, const CaseOrbitOptions& o) {
  if (auto bad = forced_orbit_issues(spec, o); !bad.empty()) throw CaseError(std::move(bad));
  CaseOrbit out;
  out.model = build_model(spec);
  out.periods = o.periods;
  out.tol = o.orbit.tol;
  const MechanicalState s0 = initial_state(spec);
  out.omega = std::abs(out.model->spin(s0.t, s0.q, s0.v));
  const double T = 2.0 * std::numbers::pi * o.periods / out.omega;
  EventDrivenOptions opt = event_driven_options(spec);
  opt.stop = o.stop;
  Vec x(2 * out.model->num_dofs());
  x << s0.q, s0.v;
  double t0 = s0.t;
  if (o.settle > 0) {
    const PeriodMap transient(*out.model, t0, opt);
    const FlowRun r = transient.run(x, o.settle * T);
    if (!r.complete()) {
      out.result.t0 = t0;
      out.result.period = T;
      out.result.x0 = x;
      out.result.outcome = OrbitOutcome::RunFailed;
      out.result.run_termination = r.summary.termination;
      out.result.message =
          fmt::format("the transient of {} periods (--settle) ended early ({}): {}", o.settle,
                      to_string(r.summary.termination), r.summary.message);
      out.result.orbit = r;
      return out;
    }
    x = stacked_state(r.samples.back());
    t0 = r.samples.back().t;
  }
  const PeriodMap map(*out.model, t0, opt);
  out.result = find_forced_orbit(map, x, T, out.omega, o.orbit);
  return out;
}

std::string orbit_json(const CaseSpec& spec, const CaseOrbit& o) {
  const OrbitResult& r = o.result;
  const LagrangianModel& m = *o.model;
  const int n = m.num_dofs();
  std::vector<std::string> names;
  for (const auto& c : m.coordinates()) names.push_back(c.name);
  for (const auto& c : m.coordinates()) names.push_back(c.rate);
  std::string s = "{\n";
  auto out = std::back_inserter(s);
  auto phases = [](const std::vector<Phase>& p) {
    std::string t = "[";
    for (std::size_t k = 0; k < p.size(); ++k)
      t += (k ? ", " : "") + quoted_string(to_string(p[k]));
    return t + "]";
  };
  fmt::format_to(out, "  \"case\": {},\n  \"outcome\": {},\n  \"converged\": {},\n", str(spec.name),
                 str(to_string(r.outcome)), r.converged() ? "true" : "false");
  fmt::format_to(out, "  \"message\": {},\n", str(r.message));
  if (r.outcome == OrbitOutcome::RunFailed)
    fmt::format_to(out, "  \"run_termination\": {},\n", str(to_string(r.run_termination)));
  fmt::format_to(out,
                 "  \"kind\": \"forced\",\n  \"omega\": {},\n  \"periods\": {},\n  \"t0\": {},\n"
                 "  \"period\": {},\n",
                 num(o.omega), o.periods, num(r.t0), num(r.period));
  fmt::format_to(out,
                 "  \"section\": {{\"phases\": {}, \"constraints\": {}, \"coordinates\": {}, "
                 "\"chart\": {}}},\n",
                 phases(r.section_phases), r.constraints, r.chart_dim,
                 str(r.constraints ? "tangent coordinates of the contact phase's constraint "
                                     "manifold (docs/orbits.md)"
                                   : "the state itself (free flight at the section)"));
  fmt::format_to(out, "  \"tol\": {},\n  \"residual\": {},\n", num(o.tol), num(r.residual));
  s += "  \"newton\": [";
  for (std::size_t i = 0; i < r.history.size(); ++i) {
    const auto& h = r.history[i];
    fmt::format_to(out,
                   "{}\n    {{\"iteration\": {}, \"residual\": {}, \"step\": {}, \"damping\": {}, "
                   "\"jacobian\": {}, \"events\": {}, \"runs\": {}}}",
                   i ? "," : "", h.iteration, num(h.residual), num(h.step), num(h.damping),
                   str(h.jacobian), str(h.signature), h.runs);
  }
  s += "\n  ],\n  \"state\": {";
  for (int i = 0; i < 2 * n && r.x0.size() == 2 * n; ++i)
    fmt::format_to(out, "{}{}: {}", i ? ", " : "", str(names[static_cast<std::size_t>(i)]),
                   num(r.x0(i)));
  s += "},\n";
  const Monodromy& M = r.monodromy;
  fmt::format_to(out,
                 "  \"monodromy\": {{\"method\": {}, \"ok\": {}, \"failure\": {}, \"error\": {}, "
                 "\"runs\": {}, \"sequence_changed\": {}, \"sequence_note\": {},\n",
                 str(M.method), M.ok ? "true" : "false", str(M.failure), num(M.error), M.runs,
                 M.sequence_changed ? "true" : "false", str(M.sequence_note));
  auto list = [&](const std::vector<double>& v) {
    std::string t = "[";
    for (std::size_t i = 0; i < v.size(); ++i) t += (i ? ", " : "") + num(v[i]);
    return t + "]";
  };
  fmt::format_to(out, "    \"steps\": {}, \"differences\": {}, \"chosen\": {},\n", list(M.steps),
                 list(M.differences), M.chosen);
  s += "    \"matrix\": [";
  for (Eigen::Index i = 0; i < M.M.rows(); ++i) {
    std::vector<double> row(static_cast<std::size_t>(M.M.cols()));
    for (Eigen::Index j = 0; j < M.M.cols(); ++j) row[static_cast<std::size_t>(j)] = M.M(i, j);
    s += (i ? ",\n      " : "") + list(row);
  }
  s += "]},\n  \"multipliers\": [";
  const auto& F = r.floquet.multipliers;
  for (std::size_t i = 0; i < F.size(); ++i) {
    const auto& f = F[i];
    fmt::format_to(out,
                   "{}\n    {{\"re\": {}, \"im\": {}, \"abs\": {}, \"error\": {}, "
                   "\"condition\": {}, \"direction\": {{",
                   i ? "," : "", num(f.value.real()), num(f.value.imag()), num(std::abs(f.value)),
                   num(f.error), num(f.condition));
    for (Eigen::Index j = 0; j < f.direction.size() && j < 2 * n; ++j)
      fmt::format_to(out, "{}{}: [{}, {}]", j ? ", " : "", str(names[static_cast<std::size_t>(j)]),
                     num(f.direction(j).real()), num(f.direction(j).imag()));
    s += "}}";
  }
  fmt::format_to(out, "\n  ],\n  \"stability\": {},\n  \"stability_reason\": {},\n",
                 str(to_string(r.floquet.stability)), str(r.floquet.reason));
  s += "  \"events_per_period\": {";
  for (int k = 0; k < kNumEventKinds; ++k)
    fmt::format_to(out, "{}{}: {}", k ? ", " : "", str(to_string(static_cast<EventKind>(k))),
                   r.event_counts[static_cast<std::size_t>(k)]);
  s += "},\n  \"phase_time\": {";
  for (int k = 0; k < kNumPhases; ++k)
    fmt::format_to(out, "{}{}: {}", k ? ", " : "", str(to_string(static_cast<Phase>(k))),
                   num(r.phase_time[static_cast<std::size_t>(k)]));
  s += "},\n  \"events\": [";
  for (std::size_t i = 0; i < r.events.size(); ++i) {
    const auto& e = r.events[i];
    fmt::format_to(out,
                   "{}\n    {{\"t\": {}, \"kind\": {}, \"contact\": {}, \"before\": {}, "
                   "\"after\": {}}}",
                   i ? "," : "", num(e.t), str(to_string(e.kind)), e.contact + 1,
                   str(to_string(e.before)), str(to_string(e.after)));
  }
  fmt::format_to(out, "\n  ],\n  \"sequence\": {},\n",
                 str(r.orbit.samples.empty() ? std::string() : event_signature(r.orbit, r.t0)));
  fmt::format_to(out, "  \"runs\": {},\n  \"wall_seconds\": {}\n}}\n", r.runs, num(r.wall_seconds));
  return s;
}

std::string orbit_csv(const CaseOrbit& o) {
  const auto cols = timeseries_columns(*o.model);
  std::string s;
  for (std::size_t i = 0; i < cols.size(); ++i) s += (i ? "," : "") + cols[i].name;
  s += '\n';
  auto out = std::back_inserter(s);
  for (const Sample& x : o.result.orbit.samples) {
    for (std::size_t i = 0; i < cols.size(); ++i) {
      if (i) s += ',';
      if (cols[i].field == SampleField::Phase)
        s += to_string(x.contacts[static_cast<std::size_t>(cols[i].index)].phase);
      else
        fmt::format_to(out, "{}", sample_value(x, cols[i]));
    }
    s += '\n';
  }
  return s;
}

std::unique_ptr<HeldFolder> open_orbit_folder(const std::string& dir, const CaseSpec& spec) {
  auto folder = std::make_unique<HeldFolder>(dir);
  if (!folder->try_lock(true))
    throw FolderError(
        fmt::format("{} is in use by another rubdyn command (it holds the folder's "
                    "lock); choose another --out or wait for it to end",
                    dir));
  folder->check_writable();
  for (const char* name : {"orbit.json", "orbit.csv"}) {
    struct stat st {};
    if (::fstatat(folder->fd(), name, &st, AT_SYMLINK_NOFOLLOW) != 0 || !S_ISREG(st.st_mode))
      continue;
    if (::unlinkat(folder->fd(), name, 0) != 0 && errno != ENOENT)
      throw FolderError(
          fmt::format("cannot remove the old {}/{}: {}", dir, name, std::strerror(errno)));
  }
  try {
    write_file_at(folder->fd(), "case.resolved.toml", dir + "/case.resolved.toml", to_toml(spec));
  } catch (const OutputError& e) {
    throw FolderError(e.what());
  }
  return folder;
}

void write_orbit_files(const HeldFolder& folder, const CaseSpec& spec, const CaseOrbit& o) {
  const std::string& dir = folder.path();
  write_file_at(folder.fd(), "orbit.csv", dir + "/orbit.csv", orbit_csv(o));
  write_file_at(folder.fd(), "orbit.json", dir + "/orbit.json", orbit_json(spec, o));
}

int exit_code(const OrbitResult& r) {
  if (r.converged()) return kExitOk;
  if (r.outcome == OrbitOutcome::RunFailed) {
    const int c = exit_code(r.run_termination);
    if (c == kExitInterrupted) return c;
  }
  return kExitEarlyEnd;
}

}  // namespace rubdyn
