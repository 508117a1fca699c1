#include "rubdyn/analysis/orbit_case.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <iterator>
#include <map>
#include <numbers>

#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/columns.hpp"
#include "rubdyn/io/json_reader.hpp"
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

namespace {

/// The monodromies' method of a branch with these options (branch.json's "monodromy").
std::string monodromy_method(const CaseBranchOptions& o) {
  return o.orbit.orbit.provider ? std::string(o.orbit.orbit.provider->name())
                                : "finite differences";
}

/// A model's state names: its coordinates, then their rates (branch.csv's state columns).
std::vector<std::string> state_names(const LagrangianModel& model) {
  std::vector<std::string> names;
  for (const auto& c : model.coordinates()) names.push_back(c.name);
  for (const auto& c : model.coordinates()) names.push_back(c.rate);
  return names;
}

/// The index of the branch's first period doubling among its specials (-1: none).
int pd_special(const CaseBranch& b) {
  for (std::size_t i = 0; i < b.branch.specials.size(); ++i)
    if (b.branch.specials[i].kind == "period_doubling") return static_cast<int>(i);
  return -1;
}

}  // namespace

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
  if (o.resume && o.switch_from)
    bad.push_back({cl, 0, "--resume", "", "resumes a branch; --switch starts another: not both"});
  // the earlier branch: of this key, and of this model (its state's coordinates)
  const CaseBranch* old = o.resume ? o.resume : o.switch_from;
  const std::string opt = o.resume ? "--resume" : "--switch";
  if (old && old->key != o.key)
    bad.push_back({cl, 0, opt, old->key,
                   fmt::format("the earlier branch varies {}, not --vary {}", old->key, o.key)});
  if (old && bad.empty()) {
    if (state_names(*build_model(spec)) != old->state_names)
      bad.push_back(
          {cl, 0, opt, "", "the earlier branch's states are of another model (other coordinates)"});
  }
  if (o.resume) {
    const std::string method = monodromy_method(o);
    if (o.resume->periods != o.orbit.periods)
      bad.push_back(
          {cl, 0, "--periods", std::to_string(o.orbit.periods),
           fmt::format("the resumed branch's orbits have {} periods", o.resume->periods)});
    if (o.resume->monodromy != method)
      bad.push_back({cl, 0, "--monodromy", method,
                     fmt::format("the resumed branch's monodromies are by {}: the same method",
                                 o.resume->monodromy)});
  }
  if (o.switch_from) {
    if (spec.loads().spin != SpinDrive::Prescribed)
      bad.push_back({cl, 0, "--switch", "",
                     "branch switching at a period doubling is for forced orbits (a prescribed "
                     "spin)"});
    const auto& sp = o.switch_from->branch.specials;
    const int n = static_cast<int>(sp.size());
    const int k = o.special >= 0 ? o.special : pd_special(*o.switch_from);
    if (k < 0 || k >= n || sp[static_cast<std::size_t>(k)].kind != "period_doubling" ||
        sp[static_cast<std::size_t>(k)].x.size() == 0)
      bad.push_back(
          {cl, 0, o.special >= 0 ? "--special" : "--switch",
           o.special >= 0 ? std::to_string(o.special) : "",
           fmt::format("must name a period doubling with its orbit among the branch's {} special "
                       "points (branch.json's specials, counted from 0)",
                       n)});
    if (!(o.switch_eps > 0.0) || !std::isfinite(o.switch_eps))
      bad.push_back(
          {cl, 0, "--switch-eps", fmt::format("{}", o.switch_eps), "must be finite and > 0"});
    if (!std::isnan(o.switch_offset) && !(o.switch_offset > 0.0 && std::isfinite(o.switch_offset)))
      bad.push_back(
          {cl, 0, "--switch-offset", fmt::format("{}", o.switch_offset), "must be finite and > 0"});
  }
  return bad;
}

namespace {

/// Appends the branch `next` (continued from point n - 1 of `into`, its own first point that
/// point again) to `into`: its points after the first, its specials and section moves with their
/// points renumbered, its outcome, runs and time.
void append_branch(Branch& into, const Branch& next) {
  const int n = static_cast<int>(into.points.size());
  const double s0 = into.points.back().arclength;
  for (std::size_t i = 1; i < next.points.size(); ++i) {
    into.points.push_back(next.points[i]);
    into.points.back().arclength += s0;
  }
  for (BranchSpecial sp : next.specials) {
    sp.after += n - 1;
    into.specials.push_back(std::move(sp));
  }
  for (Branch::SectionMove m : next.section_moves) {
    m.after += n - 1;
    into.section_moves.push_back(m);
  }
  into.outcome = next.outcome;
  into.message = next.message;
  into.runs += next.runs;
  into.wall_seconds += next.wall_seconds;
}

}  // namespace

CaseBranch find_case_branch(const std::string& text, const std::string& source,
                            const std::vector<std::string>& overrides, const CaseBranchOptions& o) {
  const CaseSpec spec = parse_case(text, source, overrides);
  if (auto bad = branch_issues(spec, o); !bad.empty()) throw CaseError(std::move(bad));
  CaseBranch out;
  out.key = o.key;
  out.periods = o.switch_from ? 2 * o.switch_from->periods : o.orbit.periods;
  out.monodromy = monodromy_method(o);
  for (const auto& e : case_values(spec))
    if (e.full() == o.key) out.lambda0 = std::get<double>(e.value);
  const auto model = build_model(spec);
  out.state_names = state_names(*model);
  const int k = out.periods;
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

  if (o.resume) {
    // on from the last point of the earlier branch, the way it went
    const Branch& old = o.resume->branch;
    out.lambda0 = o.resume->lambda0;
    out.branch = old;
    const int n = static_cast<int>(old.points.size());
    if (old.outcome == "events_change" || old.outcome == "lambda_bound" || n >= o.points) {
      out.started = o.resume->started;
      out.nothing_to_resume = true;
      return out;
    }
    // (an end located where the earlier run's steps failed is not an end of the branch)
    std::erase_if(out.branch.specials,
                  [n](const BranchSpecial& sp) { return sp.kind == "end" && sp.after >= n - 1; });
    const BranchPoint& last = old.points.back();
    c.t0 = last.t0;
    c.period = last.period;
    c.max_points = o.points - (n - 1);
    if (n >= 2 && old.points[static_cast<std::size_t>(n - 2)].t0 == last.t0) {
      const BranchPoint& prev = old.points[static_cast<std::size_t>(n - 2)];
      c.previous_x = prev.x0;
      c.previous_period = prev.period;
      c.previous_lambda = prev.lambda;
    } else if (std::isfinite(last.tangent_lambda) && last.tangent_lambda != 0.0) {
      c.direction = last.tangent_lambda > 0 ? +1 : -1;
    }
    const Branch next = continue_forced_orbit(family, last.lambda, last.x0, c);
    out.started =
        fmt::format("resumed from its point {} ({} = {:.10g})", n - 1, o.key, last.lambda);
    if (next.points.empty()) {
      out.branch.outcome = next.outcome;
      out.branch.message = "resuming from the last point: " + next.message;
      out.branch.runs += next.runs;
      out.branch.wall_seconds += next.wall_seconds;
      return out;
    }
    append_branch(out.branch, next);
    return out;
  }

  if (o.switch_from) {
    // the period-2k orbit near the doubling: Newton from the doubling's orbit moved along its
    // multiplier -1's direction, on either side of it
    const CaseBranch& from = *o.switch_from;
    const int ks = o.special >= 0 ? o.special : pd_special(from);
    const BranchSpecial& pd = from.branch.specials[static_cast<std::size_t>(ks)];
    const auto& pts = from.branch.points;
    const std::size_t a = static_cast<std::size_t>(pd.after);
    const BranchPoint* pa = a < pts.size() ? &pts[a] : nullptr;
    const BranchPoint* pb = a + 1 < pts.size() ? &pts[a + 1] : nullptr;
    // the offsets tried: the one given, or half the distance of the points around the doubling
    // and then a quarter of the last, 4 in all (the period-2k orbits split from the period-k
    // one as sqrt(|lambda - lambda_PD|): Newton from the doubling's orbit moved by switch_eps
    // converges where the split is of that order, nearer the doubling on a short branch)
    std::vector<double> deltas = {o.switch_offset};
    if (std::isnan(o.switch_offset)) {
      deltas = {0.5 * (pa && pb ? std::abs(pb->lambda - pa->lambda)
                                : (pa ? std::abs(pa->lambda - pd.lambda) : c.lambda_scale))};
      for (int j = 1; j < 4; ++j) deltas.push_back(0.25 * deltas.back());
    }
    // the side where the period-k orbit has the real multiplier below -1 first (the period-2k
    // orbits of a supercritical doubling lie there), then the other
    int first = o.direction;
    if (pa && pb) {
      const int na = real_multipliers_below_minus_one(pa->floquet);
      const int nb = real_multipliers_below_minus_one(pb->floquet);
      if (na != nb)
        first = (na > nb ? pa->lambda - pd.lambda : pb->lambda - pd.lambda) > 0 ? 1 : -1;
    }
    std::string tried;
    long runs = 0;
    for (const double delta : deltas)
      for (const int side : {first, -first}) {
        const double lambda = pd.lambda + side * delta;
        ParameterModel pm = family(lambda);
        const PeriodMap map(*pm.model, pd.t0, pm.options);
        OrbitOptions o0 = c.orbit;
        o0.samples = 0;
        const Vec guess = pd.x + o.switch_eps * pd.direction;
        const OrbitResult r = find_forced_orbit(map, guess, pm.period, pm.omega, o0);
        runs += r.runs;
        if (!r.converged()) {
          tried += fmt::format("; at {:.10g}: {}", lambda, r.message);
          continue;
        }
        // a period-2k orbit, not the period-k orbit twice: k periods move it by far more than
        // Newton's tolerance (the period-k orbit by its residual, ~tol; the period-2k orbits split
        // from it as sqrt(|lambda - lambda_PD|), 0.04 .. 0.15 of the gap scale on the impact
        // oscillator 0.05 .. 0.6 rad/s from its doubling): 1e4 tol
        const FlowRun half = map.run(r.x0, 0.5 * pm.period);
        ++runs;
        const Vec D = state_scale(*pm.model, pm.omega);
        const double split =
            half.complete()
                ? ((stacked_state(half.samples.back()) - r.x0).array() / D.array()).abs().maxCoeff()
                : 0.0;
        if (!(split > 1e4 * o0.tol)) {
          tried += fmt::format(
              "; at {:.10g}: Newton found the period-{} orbit (moved by {:.2g} in "
              "{} periods)",
              lambda, from.periods, split, from.periods);
          continue;
        }
        c.t0 = pd.t0;
        c.direction = side;
        Branch b = continue_forced_orbit(family, lambda, r.x0, c);
        b.runs += runs;
        out.lambda0 = lambda;
        out.branch = std::move(b);
        out.started = fmt::format(
            "switched at the period doubling at {} = {:.12g} (special {} of a branch of period "
            "{}): "
            "its orbit moved by {:.3g} along the direction of its multiplier -1, Newton at {:.10g} "
            "({:+.3g} from the doubling), whose orbit of period {} moves by {:.3g} (scaled) in {} "
            "periods",
            o.key, pd.lambda, ks, from.periods, o.switch_eps, lambda, side * delta, out.periods,
            split, from.periods);
        return out;
      }
    out.lambda0 = pd.lambda;
    out.branch.outcome = "start_failed";
    out.branch.message =
        fmt::format("no orbit of period {} near the period doubling at {:.12g} on either side{}",
                    out.periods, pd.lambda, tried);
    out.branch.runs = runs;
    return out;
  }

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
  // t0: the section's time, where the state is; tangent_lambda: d key / ds (scaled)
  s += ",corrector_iterations,runs,t0,tangent_lambda";
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
    fmt::format_to(out, ",{},{},{},{}", p.corrector_iterations, p.runs, p.t0, p.tangent_lambda);
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
                 "  \"started\": {},\n  \"outcome\": {},\n  \"message\": {},\n  \"points\": {},\n"
                 "  \"specials\": [",
                 str(b.key), num(b.lambda0), b.periods, str(b.monodromy), str(b.started),
                 str(r.outcome), str(r.message), r.points.size());
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

namespace {

/// Reads a branch folder's files back (read_case_branch), every failure a CaseIssue naming the
/// file, line and key.
class BranchReader {
 public:
  BranchReader(const std::string& source)
      : json_file_(source + "/branch.json"), csv_file_(source + "/branch.csv") {}

  [[noreturn]] void refuse(const std::string& file, int line, const std::string& key,
                           const std::string& value, const std::string& rule) const {
    throw CaseError({{file, line, key, printable_text(value), rule}});
  }

  const JsonValue& member(const JsonValue& obj, const std::string& key, JsonValue::Kind kind,
                          const std::string& where) const {
    const JsonValue* v = obj.find(key);
    if (!v || v->kind != kind)
      refuse(json_file_, 0, where + key, "",
             fmt::format("missing, or not a {} (not a branch.json of rubdyn branch?)",
                         kind == JsonValue::Kind::String   ? "string"
                         : kind == JsonValue::Kind::Number ? "number"
                         : kind == JsonValue::Kind::Array  ? "list"
                                                           : "table"));
    return *v;
  }
  /// A number, or null for NaN.
  double number(const JsonValue& obj, const std::string& key, const std::string& where) const {
    const JsonValue* v = obj.find(key);
    if (v && v->kind == JsonValue::Kind::Null) return std::numeric_limits<double>::quiet_NaN();
    return member(obj, key, JsonValue::Kind::Number, where).number;
  }

  /// branch.json's text as a document: a JSON table with the key (needed first: branch.csv's
  /// column of it).
  JsonValue document(std::string_view text) const {
    JsonValue doc;
    try {
      doc = parse_json(text);
    } catch (const JsonError& e) {
      refuse(json_file_, e.line(), "", "", std::string("not JSON: ") + e.what());
    }
    if (doc.kind != JsonValue::Kind::Object)
      refuse(json_file_, 1, "", "", "must hold one JSON table (a branch.json of rubdyn branch)");
    member(doc, "key", JsonValue::Kind::String, "");
    return doc;
  }

  /// The rest of branch.json (after csv(): its specials' states are named by the csv's columns).
  void json(const JsonValue& doc, CaseBranch& b) const {
    b.lambda0 = number(doc, "from", "");
    // (written since periods and the method were: a branch before them had 1 and differences)
    b.periods = doc.find("periods") ? static_cast<int>(number(doc, "periods", "")) : 1;
    b.monodromy = doc.find("monodromy")
                      ? member(doc, "monodromy", JsonValue::Kind::String, "").string
                      : "finite differences";
    if (doc.find("started")) b.started = member(doc, "started", JsonValue::Kind::String, "").string;
    Branch& r = b.branch;
    r.outcome = member(doc, "outcome", JsonValue::Kind::String, "").string;
    r.message = member(doc, "message", JsonValue::Kind::String, "").string;
    r.runs = static_cast<long>(number(doc, "runs", ""));
    r.wall_seconds = number(doc, "wall_seconds", "");
    const auto& specials = member(doc, "specials", JsonValue::Kind::Array, "").array;
    for (std::size_t i = 0; i < specials.size(); ++i) {
      const JsonValue& x = specials[i];
      const std::string where = fmt::format("specials[{}].", i);
      BranchSpecial sp;
      sp.kind = member(x, "kind", JsonValue::Kind::String, where).string;
      sp.lambda = number(x, "value", where);
      sp.spread = number(x, "spread", where);
      const auto& between = member(x, "between", JsonValue::Kind::Array, where).array;
      if (between.empty() || between[0].kind != JsonValue::Kind::Number)
        refuse(json_file_, 0, where + "between", "", "must be a list of two point numbers");
      sp.after = static_cast<int>(between[0].number);
      sp.how = member(x, "how", JsonValue::Kind::String, where).string;
      if (x.find("state")) {
        sp.t0 = number(x, "t0", where);
        sp.x = named_state(member(x, "state", JsonValue::Kind::Object, where), b.state_names,
                           where + "state");
        sp.direction = named_state(member(x, "direction", JsonValue::Kind::Object, where),
                                   b.state_names, where + "direction");
      }
      r.specials.push_back(std::move(sp));
    }
    if (doc.find("section_moves"))
      for (const JsonValue& m : member(doc, "section_moves", JsonValue::Kind::Array, "").array)
        r.section_moves.push_back({static_cast<int>(number(m, "after", "section_moves.")),
                                   number(m, "t0", "section_moves.")});
  }

  Vec named_state(const JsonValue& obj, const std::vector<std::string>& names,
                  const std::string& where) const {
    Vec x(static_cast<Eigen::Index>(names.size()));
    for (std::size_t j = 0; j < names.size(); ++j)
      x(static_cast<Eigen::Index>(j)) = number(obj, names[j], where + ".");
    if (obj.object.size() != names.size())
      refuse(json_file_, 0, where, "",
             fmt::format("must have the {} coordinates and rates of branch.csv's state",
                         names.size()));
    return x;
  }

  /// branch.csv's points (and the state's names from its header: the columns between
  /// tangent_lambda, or t0, and events).
  void csv(std::string_view text, CaseBranch& b) const {
    std::vector<std::string> lines;
    for (std::size_t at = 0; at < text.size();) {
      const std::size_t e = text.find('\n', at);
      if (e == std::string_view::npos) {
        refuse(csv_file_, static_cast<int>(lines.size()) + 1, "", "",
               "the last row has no line end (the file was cut short)");
      }
      lines.emplace_back(text.substr(at, e - at));
      at = e + 1;
    }
    if (lines.empty()) refuse(csv_file_, 1, "", "", "empty: no header");
    const std::vector<std::string> head = split_csv_line(lines[0]);
    std::map<std::string, std::size_t> col;
    for (std::size_t j = 0; j < head.size(); ++j) col[head[j]] = j;
    const auto need = [&](const std::string& name) {
      const auto it = col.find(name);
      if (it == col.end())
        refuse(csv_file_, 1, name, "", "a column of branch.csv that the header lacks");
      return it->second;
    };
    const std::size_t first_state =
        (col.count("tangent_lambda") ? need("tangent_lambda") : need("t0")) + 1;
    const std::size_t events = need("events");
    if (events != head.size() - 1 || events < first_state)
      refuse(csv_file_, 1, "events", "", "must be the last column, after the state's");
    b.state_names.assign(head.begin() + static_cast<std::ptrdiff_t>(first_state),
                         head.begin() + static_cast<std::ptrdiff_t>(events));
    need(b.key);
    int nm = 0;
    while (col.count(fmt::format("mu{}_re", nm + 1))) ++nm;
    for (std::size_t i = 1; i < lines.size(); ++i) {
      const std::vector<std::string> f = split_csv_line(lines[i]);
      const int line = static_cast<int>(i) + 1;
      if (f.size() != head.size())
        refuse(csv_file_, line, "", "",
               fmt::format("has {} fields, the header {}", f.size(), head.size()));
      const auto value = [&](const std::string& name) {
        const std::string& t = f[need(name)];
        char* end = nullptr;
        const double x = std::strtod(t.c_str(), &end);
        if (t.empty() || *end != '\0') refuse(csv_file_, line, name, t, "must be a number");
        return x;
      };
      BranchPoint p;
      p.lambda = value(b.key);
      p.arclength = value("arclength");
      p.period = value("period");
      p.amplitude = value("amplitude");
      p.F_N_max = value("F_N_max");
      p.F_N_min = value("F_N_min");
      p.d_N_min = value("d_N_min");
      p.d_N_dip = value("d_N_dip");
      p.free_time = value("free_time");
      p.impact_speed_min = value("impact_speed_min");
      p.cone_min = value("cone_min");
      p.residual = value("residual");
      const std::string& st = f[need("stability")];
      p.floquet.stability = st == "stable"     ? Stability::Stable
                            : st == "unstable" ? Stability::Unstable
                                               : Stability::Undecided;
      for (int j = 1; j <= nm; ++j) {
        if (f[need(fmt::format("mu{}_re", j))].empty()) break;
        FloquetMultiplier m;
        m.value = {value(fmt::format("mu{}_re", j)), value(fmt::format("mu{}_im", j))};
        m.error = value(fmt::format("mu{}_error", j));
        p.floquet.multipliers.push_back(std::move(m));
      }
      p.corrector_iterations = static_cast<int>(value("corrector_iterations"));
      p.runs = static_cast<long>(value("runs"));
      p.t0 = value("t0");
      p.tangent_lambda = col.count("tangent_lambda") ? value("tangent_lambda")
                                                     : std::numeric_limits<double>::quiet_NaN();
      p.x0.resize(static_cast<Eigen::Index>(b.state_names.size()));
      for (std::size_t j = 0; j < b.state_names.size(); ++j)
        p.x0(static_cast<Eigen::Index>(j)) = value(b.state_names[j]);
      p.signature = f[events];
      b.branch.points.push_back(std::move(p));
    }
    if (b.branch.points.empty()) refuse(csv_file_, 2, "", "", "no point: the branch is empty");
  }

 private:
  std::string json_file_, csv_file_;
};

}  // namespace

CaseBranch read_case_branch(std::string_view json, std::string_view csv,
                            const std::string& source) {
  const BranchReader r(source);
  CaseBranch b;
  // the key first (the csv's column), the state's names from the csv (the json's state by them)
  const JsonValue doc = r.document(json);
  b.key = doc.find("key")->string;
  r.csv(csv, b);
  r.json(doc, b);
  const int n = static_cast<int>(b.branch.points.size());
  for (const BranchSpecial& sp : b.branch.specials)
    if (sp.after < 0 || sp.after >= n)
      r.refuse(source + "/branch.json", 0, "specials.between", std::to_string(sp.after),
               fmt::format("must be a point of branch.csv (0 to {})", n - 1));
  return b;
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
