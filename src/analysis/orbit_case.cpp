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

std::vector<CaseIssue> orbit_issues(const CaseSpec& spec, const CaseOrbitOptions& o) {
  std::vector<CaseIssue> bad;
  const std::string& f = spec.source;
  if (spec.solver.kind != "event")
    bad.push_back({f, 0, "solver.kind", spec.solver.kind,
                   "rubdyn orbit runs the return map with the event-driven solver: \"event\""});
  const LoadParams& L = spec.loads();
  const std::string cl = "command line";
  if (L.spin != SpinDrive::Prescribed) {
    if (!(o.period > 0.0) || !std::isfinite(o.period))
      bad.push_back({cl, 0, "--period", std::isnan(o.period) ? "" : fmt::format("{}", o.period),
                     "a free spin's orbit (loads.spin = \"torque\") is autonomous: its period is "
                     "an unknown, give a guess > 0 [s] (or prescribe the spin, loads.spin = "
                     "\"prescribed\", for a forced orbit)"});
    if (L.unbalance != 0.0)
      bad.push_back({f, 0, "loads.unbalance", fmt::format("{}", L.unbalance),
                     "must be 0 for a free spin's orbit: the spin angle must be cyclic (with an "
                     "unbalance the orbit would have to close in it too; not implemented)"});
  } else {
    if (!std::isnan(o.period))
      bad.push_back({cl, 0, "--period", fmt::format("{}", o.period),
                     "only for a free spin: a prescribed spin's period is 2 pi k / omega0"});
    if (L.spin_accel != 0.0)
      bad.push_back({f, 0, "loads.spin_accel", fmt::format("{}", L.spin_accel),
                     "must be 0: a forced orbit needs a constant spin speed"});
    else if (!(std::abs(case_omega(spec)) > 0.0))
      bad.push_back(
          {f, 0, "initial.omega0", "0", "must not be 0: the orbit's period is 2 pi k / omega0"});
  }
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
  if (auto bad = orbit_issues(spec, o); !bad.empty()) throw CaseError(std::move(bad));
  CaseOrbit out;
  out.model = build_model(spec);
  out.periods = o.periods;
  out.tol = o.orbit.tol;
  out.autonomous = spec.loads().spin != SpinDrive::Prescribed;
  const MechanicalState s0 = initial_state(spec);
  out.omega = std::abs(out.model->spin(s0.t, s0.q, s0.v));
  const double T =
      out.autonomous ? o.period * o.periods : 2.0 * std::numbers::pi * o.periods / out.omega;
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
  if (out.autonomous)  // the state's velocities scaled by the orbit's frequency
    out.result = find_autonomous_orbit(map, x, T, 2.0 * std::numbers::pi / T,
                                       {out.model->spin_coordinate()}, o.orbit);
  else
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
                 "  \"kind\": {},\n  \"omega\": {},\n  \"periods\": {},\n  \"t0\": {},\n"
                 "  \"period\": {},\n",
                 str(o.autonomous ? "autonomous" : "forced"), num(o.omega), o.periods, num(r.t0),
                 num(r.period));
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
  if (o.autonomous)
    fmt::format_to(out, "  \"trivial_multiplier\": {{\"index\": {}, \"is_one\": {}}},\n",
                   r.floquet.trivial, r.floquet.trivial_ok ? "true" : "false");
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

std::string orbit_csv(const CaseOrbit& o, std::string_view selection) {
  const auto cols = timeseries_columns(*o.model, selection);
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

std::unique_ptr<HeldFolder> open_orbit_folder(const std::string& dir, const CaseSpec& spec,
                                              const std::vector<std::string>& files) {
  auto folder = std::make_unique<HeldFolder>(dir);
  if (!folder->try_lock(true))
    throw FolderError(
        fmt::format("{} is in use by another rubdyn command (it holds the folder's "
                    "lock); choose another --out or wait for it to end",
                    dir));
  folder->check_writable();
  for (const std::string& f : files) {
    const char* name = f.c_str();
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
  write_file_at(folder.fd(), "orbit.csv", dir + "/orbit.csv",
                orbit_csv(o, spec.output.coordinates));
  write_file_at(folder.fd(), "orbit.json", dir + "/orbit.json", orbit_json(spec, o));
}

std::vector<CaseIssue> branch_issues(const CaseSpec& spec, const CaseBranchOptions& o) {
  // a forced orbit (a prescribed constant spin) or an autonomous one (a free spin, --period)
  std::vector<CaseIssue> bad = orbit_issues(spec, o.orbit);
  const std::string cl = "command line";
  bool numeric = false;
  for (const auto& e : case_values(spec))
    if (e.full() == o.key) numeric = std::holds_alternative<double>(e.value);
  if (!numeric)
    bad.push_back({cl, 0, "--vary", o.key,
                   "must name a real-valued key of this case (section.key, as in "
                   "case.resolved.toml)"});
  if (o.points < 2)
    bad.push_back({cl, 0, "--points", std::to_string(o.points), "must be an integer >= 2"});
  if (!(o.ds > 0.0) || !std::isfinite(o.ds))
    bad.push_back({cl, 0, "--ds", fmt::format("{}", o.ds), "must be finite and > 0"});
  if (!(o.ds_max >= o.ds) || !std::isfinite(o.ds_max))
    bad.push_back({cl, 0, "--ds-max", fmt::format("{}", o.ds_max), "must be finite and >= --ds"});
  if (!(o.scale >= 0.0) || !std::isfinite(o.scale))
    bad.push_back({cl, 0, "--scale", fmt::format("{}", o.scale), "must be finite and >= 0"});
  if (std::isinf(o.to)) bad.push_back({cl, 0, "--to", fmt::format("{}", o.to), "must be finite"});
  return bad;
}

CaseBranch find_case_branch(const std::string& text, const std::string& source,
                            const std::vector<std::string>& overrides, const CaseBranchOptions& o) {
  const CaseSpec spec = parse_case(text, source, overrides);
  if (auto bad = branch_issues(spec, o); !bad.empty()) throw CaseError(std::move(bad));
  CaseBranch out;
  out.key = o.key;
  out.periods = o.orbit.periods;
  out.monodromy = o.orbit.orbit.provider ? o.orbit.orbit.provider->name() : "finite differences";
  for (const auto& e : case_values(spec))
    if (e.full() == o.key) out.lambda0 = std::get<double>(e.value);
  const auto model = build_model(spec);
  for (const auto& c : model->coordinates()) out.state_names.push_back(c.name);
  for (const auto& c : model->coordinates()) out.state_names.push_back(c.rate);
  const int k = o.orbit.periods;
  const std::atomic<bool>* stop = o.orbit.stop;
  const double T_guess = o.orbit.period * k;  // an autonomous orbit's (NaN: forced)
  const ModelFamily family = [&text, &source, &overrides, key = o.key, k, stop,
                              T_guess](double lambda) {
    std::vector<std::string> sets = overrides;
    sets.push_back(fmt::format("{}={}", key, lambda));
    const CaseSpec s = parse_case(text, source, sets);
    CaseOrbitOptions oo;
    oo.period = T_guess;
    if (auto bad = orbit_issues(s, oo); !bad.empty()) throw CaseError(std::move(bad));
    ParameterModel pm;
    pm.model = build_model(s);
    const MechanicalState s0 = initial_state(s);
    pm.t0 = s0.t;
    pm.omega = std::abs(pm.model->spin(s0.t, s0.q, s0.v));
    pm.autonomous = s.loads().spin != SpinDrive::Prescribed;
    if (pm.autonomous) pm.pinned = {pm.model->spin_coordinate()};
    pm.period = pm.autonomous ? T_guess : 2.0 * std::numbers::pi * k / pm.omega;
    pm.options = event_driven_options(s);
    pm.options.stop = stop;
    return pm;
  };
  ContinuationOptions c;
  c.ds = o.ds;
  c.ds_max = o.ds_max;
  c.lambda_scale = o.scale > 0 ? o.scale : (out.lambda0 != 0 ? 0.01 * std::abs(out.lambda0) : 1);
  c.max_points = o.points;
  c.direction = o.direction;
  if (std::isfinite(o.to)) (o.to >= out.lambda0 ? c.lambda_max : c.lambda_min) = o.to;
  c.orbit = o.orbit.orbit;
  c.orbit.samples = std::min(c.orbit.samples, 50);  // the amplitude and forces: 50 per period
  const MechanicalState s0 = initial_state(spec);
  Vec x(2 * model->num_dofs());
  x << s0.q, s0.v;
  out.branch = continue_forced_orbit(family, out.lambda0, x, c);
  return out;
}

std::string branch_csv(const CaseBranch& b) {
  std::size_t nm = 0;
  for (const auto& p : b.branch.points) nm = std::max(nm, p.floquet.multipliers.size());
  std::string s = "point,";
  s += b.key;
  s += ",arclength,period,amplitude,F_N_max,F_N_min,d_N_min,d_N_dip,free_time,impact_speed_min,"
       "cone_min,residual,stability,mu_max_abs";
  for (std::size_t j = 1; j <= nm; ++j)
    s += fmt::format(",mu{0}_re,mu{0}_im,mu{0}_abs,mu{0}_error", j);
  s += ",corrector_iterations,runs,t0";  // t0: the section's time, where the state is
  for (const auto& n : b.state_names) {
    s += ',';
    s += n;
  }
  s += ",events\n";
  auto out = std::back_inserter(s);
  for (std::size_t i = 0; i < b.branch.points.size(); ++i) {
    const BranchPoint& p = b.branch.points[i];
    const auto& F = p.floquet.multipliers;
    fmt::format_to(out, "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}", i, p.lambda, p.arclength,
                   p.period, p.amplitude, p.F_N_max, p.F_N_min, p.d_N_min, p.d_N_dip, p.free_time,
                   p.impact_speed_min, p.cone_min, p.residual, to_string(p.floquet.stability),
                   F.empty() ? 0.0 : std::abs(F.front().value));
    for (std::size_t j = 0; j < nm; ++j) {
      if (j < F.size())
        fmt::format_to(out, ",{},{},{},{}", F[j].value.real(), F[j].value.imag(),
                       std::abs(F[j].value), F[j].error);
      else
        s += ",,,,";
    }
    fmt::format_to(out, ",{},{},{}", p.corrector_iterations, p.runs, p.t0);
    for (Eigen::Index j = 0; j < p.x0.size(); ++j) fmt::format_to(out, ",{}", p.x0(j));
    s += ',';
    s += quoted_string(p.signature);
    s += '\n';
  }
  return s;
}

std::string branch_json(const CaseBranch& b) {
  const Branch& r = b.branch;
  std::string s;
  auto out = std::back_inserter(s);
  fmt::format_to(out,
                 "{{\n  \"key\": {},\n  \"from\": {},\n  \"periods\": {},\n  \"monodromy\": {},\n"
                 "  \"outcome\": {},\n  \"message\": {},\n  \"points\": {},\n  \"specials\": [",
                 str(b.key), num(b.lambda0), b.periods, str(b.monodromy), str(r.outcome),
                 str(r.message), r.points.size());
  for (std::size_t i = 0; i < r.specials.size(); ++i) {
    const auto& x = r.specials[i];
    fmt::format_to(out,
                   "{}\n    {{\"kind\": {}, \"value\": {}, \"spread\": {}, \"between\": [{}, {}], "
                   "\"how\": {}",
                   i ? "," : "", str(x.kind), num(x.lambda), num(x.spread), x.after,
                   // null: beyond the last point (the corrector's iterates crossed it)
                   x.after + 1 < static_cast<int>(r.points.size()) ? std::to_string(x.after + 1)
                                                                   : std::string("null"),
                   str(x.how));
    if (x.x.size() == static_cast<Eigen::Index>(b.state_names.size()) &&
        x.direction.size() == x.x.size()) {
      // a period doubling's orbit and the direction of its multiplier -1: the period-2 branch
      fmt::format_to(out, ", \"t0\": {}, \"state\": {{", num(x.t0));
      for (std::size_t j = 0; j < b.state_names.size(); ++j)
        fmt::format_to(out, "{}{}: {}", j ? ", " : "", str(b.state_names[j]),
                       num(x.x(static_cast<Eigen::Index>(j))));
      s += "}, \"direction\": {";
      for (std::size_t j = 0; j < b.state_names.size(); ++j)
        fmt::format_to(out, "{}{}: {}", j ? ", " : "", str(b.state_names[j]),
                       num(x.direction(static_cast<Eigen::Index>(j))));
      s += '}';
    }
    s += '}';
  }
  fmt::format_to(out, "\n  ],\n  \"section_moves\": [");
  for (std::size_t i = 0; i < r.section_moves.size(); ++i)
    fmt::format_to(out, "{}\n    {{\"after\": {}, \"t0\": {}}}", i ? "," : "",
                   r.section_moves[i].after, num(r.section_moves[i].t0));
  fmt::format_to(out, "\n  ],\n  \"runs\": {},\n  \"wall_seconds\": {}\n}}\n", r.runs,
                 num(r.wall_seconds));
  return s;
}

void write_branch_files(const HeldFolder& folder, const CaseBranch& b) {
  const std::string& dir = folder.path();
  write_file_at(folder.fd(), "branch.csv", dir + "/branch.csv", branch_csv(b));
  write_file_at(folder.fd(), "branch.json", dir + "/branch.json", branch_json(b));
}

int exit_code(const CaseBranch& b) {
  const std::string& o = b.branch.outcome;
  if (o == "max_points" || o == "lambda_bound" || o == "events_change") return kExitOk;
  if (b.branch.message.find("interrupted") != std::string::npos) return kExitInterrupted;
  return kExitEarlyEnd;
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
