#include "rubdyn/driver/sweep.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <utility>

#include "rubdyn/core/demand.hpp"
#include "rubdyn/core/run_envelope.hpp"
#include "rubdyn/driver/simulate.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/output_folder.hpp"
#include "rubdyn/io/output_reader.hpp"
#include "rubdyn/io/solver_options.hpp"
#include "rubdyn/io/text_files.hpp"

namespace rubdyn {

namespace {

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  std::istringstream in(s);
  while (std::getline(in, cur, sep)) out.push_back(trim(cur));
  if (!s.empty() && s.back() == sep) out.push_back("");
  return out;
}

double parse_double(const std::string& s, const std::string& what) {
  char* end = nullptr;
  const double x = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(x))
    throw std::invalid_argument(fmt::format("{}: '{}' is not a finite number", what, s));
  return x;
}

std::string opt_csv(const std::optional<double>& x) {
  return x ? fmt::format("{}", *x) : "";
}

// Tighter solver settings for --certify, as case overrides (driver/simulate.hpp).
std::vector<std::string> tight_overrides(const CaseSpec& s) {
  if (!find_solver(s.solver.kind))
    throw std::invalid_argument("unknown solver kind " + s.solver.kind);
  return tighter_settings(s);
}

struct OneRun {
  std::string termination, message;
  bool complete = false;
  double wall = 0;
  RunVerdicts v;
};

std::string file_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// --resume: the folder holds a complete run of exactly this resolved case, its matrices' content
/// included (the copies of a matrices case's files beside case.resolved.toml: a matrix file
/// changed since is another case).
bool already_done(const CaseSpec& spec, const std::string& dir) {
  if (!run_complete(dir) || file_text(dir + "/case.resolved.toml") != resolved_toml(spec))
    return false;
  for (const auto& [name, bytes] : case_matrix_files(spec))
    if (file_text(dir + "/" + name) != bytes) return false;
  return true;
}

/// One run into `dir`. `own` is the worker's stop flag: raised by the sweep's stop (SIGINT,
/// SIGTERM: a watcher copies it) and by a failed write of this run's folder (a full disk, the
/// folder removed), so that the run ends at its next check instead of computing unwritten rows.
OneRun run_point(const CaseSpec& spec, const std::string& dir, const AnalysisOptions& ao,
                 bool resume, const std::atomic<bool>* sweep_stop, std::atomic<bool>* own) {
  own->store(sweep_stop && sweep_stop->load());  // a failure of the previous run is not ours
  const std::atomic<bool>* stop = own;
  OneRun r;
  if (resume && already_done(spec, dir)) {
    r.termination = std::string(to_string(Termination::Completed));
    r.message = "resumed: complete in an earlier sweep";
    r.complete = true;
  } else {
    try {
      RunSummary s;
      std::string write_error;
      {
        OutputFolder sink(dir, spec, own);
        // a point whose case sets no run.max_wall gets the default budget of its plan
        // (core/run_envelope.hpp): a degenerate point ends with time_budget instead of holding
        // its thread; case.resolved.toml keeps the case as given
        CaseSpec budgeted = spec;
        if (!(budgeted.run.max_wall > 0.0)) {
          const SolverEntry* solver = find_solver(spec.solver.kind);
          const double span = spec.run.t_end - spec.run.t_start;
          budgeted.run.max_wall =
              default_wall_budget(span, solver && solver->fixed_step ? span / spec.solver.h : 0.0);
        }
        s = simulate(budgeted, sink, {}, stop);
        write_error = sink.error();
      }
      r.termination = std::string(to_string(s.termination));
      r.message = s.message;
      r.complete = s.complete();
      r.wall = s.wall_seconds;
      if (!write_error.empty()) {  // what the point's summary.json says (OutputFolder::end)
        r.termination = std::string(to_string(Termination::OutputFailure));
        r.message = write_error;
        r.complete = false;
        return r;
      }
    } catch (const PathRefused& e) {  // the output folder could not be prepared
      r.termination = "error";
      r.message = e.what();
      return r;
    } catch (const OutputError& e) {  // a write failed (a full disk, a file size limit)
      r.termination = std::string(to_string(Termination::OutputFailure));
      r.message = e.what();
      return r;
    } catch (const std::exception& e) {  // the output folder could not be prepared
      r.termination = "error";
      r.message = e.what();
      return r;
    }
  }
  try {
    r.v = write_analysis(read_run(dir), ao);
  } catch (const PathRefused& e) {
    r.termination = "error";
    r.complete = false;
    r.message = std::string("analysis: ") + e.what();
  } catch (const OutputError& e) {  // its files could not be written: a write failure
    r.termination = std::string(to_string(Termination::OutputFailure));
    r.complete = false;
    r.message = std::string("analysis: ") + e.what();
  } catch (const std::exception& e) {
    r.termination = "error";
    r.complete = false;
    r.message = std::string("analysis: ") + e.what();
  }
  return r;
}

bool same_verdicts(const RunVerdicts& a, const RunVerdicts& b) {
  return a.limited == b.limited && a.backward_onset.has_value() == b.backward_onset.has_value() &&
         a.whip_onset.has_value() == b.whip_onset.has_value();
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

/// The ensemble columns of a row from its nominal run and its members (see sweep.hpp).
void ensemble_stats(SweepRow& row) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::pair<bool, const RunVerdicts*>> runs{{row.complete, &row.v}};
  for (const auto& m : row.members) runs.emplace_back(m.complete, &m.v);
  row.ensemble_members = static_cast<int>(runs.size());
  row.ensemble_incomplete = 0;
  int complete = 0, limited = 0, backward = 0, whip = 0, rolling = 0;
  row.omega_max_min = row.omega_max_max = nan;
  for (const auto& [ok, verdicts] : runs) {
    if (!ok) {
      ++row.ensemble_incomplete;
      continue;
    }
    const RunVerdicts& v = *verdicts;
    if (complete++ == 0) row.omega_max_min = row.omega_max_max = v.omega_max;
    row.omega_max_min = std::min(row.omega_max_min, v.omega_max);
    row.omega_max_max = std::max(row.omega_max_max, v.omega_max);
    limited += v.limited ? 1 : 0;
    backward += v.backward_onset ? 1 : 0;
    whip += v.whip_fraction > 0 ? 1 : 0;
    rolling += v.stick_fraction > 0 ? 1 : 0;
  }
  auto fraction = [&](int n) { return complete > 0 ? static_cast<double>(n) / complete : nan; };
  row.p_limited = fraction(limited);
  row.p_backward = fraction(backward);
  row.p_whip = fraction(whip);
  row.p_rolling = fraction(rolling);
}

/// FNV-1a, 64 bits: a stable hash (the same on every machine and build) for the plan.
std::string fnv1a64(std::string_view text) {
  std::uint64_t h = 14695981039346656037ull;
  for (const char c : text) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  return fmt::format("{:016x}", h);
}

/// The plan hash: every point's resolved case (varied keys included, in point order) with the
/// content of its matrices (kind "matrices": the hash of each copy a run folder holds, so that
/// shards computed with different matrix files do not merge), and every option that changes what
/// a row says. The shard count is not in it (sweep-merge checks it).
std::string plan_hash(const std::vector<CaseSpec>& specs, const SweepOptions& o, int members) {
  std::string text = "rubdyn sweep plan 1\n";
  for (const auto& v : o.vary) text += fmt::format("vary {} {}\n", v.key, v.values.size());
  for (const auto& c : specs) {
    text += resolved_toml(c) + "\n--\n";
    for (const auto& [name, bytes] : case_matrix_files(c))
      text += fmt::format("{} {}\n", name, fnv1a64(bytes));
  }
  const AnalysisOptions& a = o.analysis;
  text += fmt::format("certify {}\nensemble {} {:.17g} {:.17g}\n", o.certify, members,
                      o.ensemble.domega, o.ensemble.offset);
  text += fmt::format("analysis {:.17g} {:.17g} {:.17g} {} {:.17g} {} {}\n", a.min_turns, a.window,
                      a.overlap, a.pad, a.f_max, a.t0 ? fmt::format("{:.17g}", *a.t0) : "-",
                      a.t1 ? fmt::format("{:.17g}", *a.t1) : "-");
  return fnv1a64(text);
}

/// The "plan" of a sweep-plan.json or shard sidecar text ("" when it has none).
std::string plan_of(const std::string& json) {
  static const std::regex re(R"re("plan":\s*"([0-9a-f]{16})")re");
  std::smatch m;
  return std::regex_search(json, m, re) ? std::string(m[1]) : std::string();
}

std::string text_at(int dir_fd, const std::string& name) {
  const int fd = ::openat(dir_fd, name.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return "";
  struct stat st {};
  std::string text;
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size < (1 << 20)) {
    char buf[4096];
    for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;)
      text.append(buf, static_cast<size_t>(n));
  }
  ::close(fd);
  return text;
}

/// Takes the sweep folder (sweep.hpp): held open, checked writable, locked for the sweep's life
/// (a shard shares the lock with the shards of its plan), its plan written.
std::unique_ptr<HeldFolder> take_sweep_folder(const std::string& out, const std::string& hash,
                                              bool sharded, long points) {
  auto f = std::make_unique<HeldFolder>(out);  // FolderError: exit 2
  f->check_writable();
  std::string found;
  const auto until = std::chrono::steady_clock::now() + kShardLockWait;
  do {
    if (f->try_lock(true)) {  // alone in the folder
      found = plan_of(text_at(f->fd(), "sweep-plan.json"));
      // the merged table of another plan would describe point folders this sweep replaces;
      // that plan's shard tables stay (sweep-merge refuses them by their plan hash)
      if (found != hash && ::unlinkat(f->fd(), "sweep.csv", 0) != 0 && errno != ENOENT)
        throw FolderError(fmt::format("cannot remove {}/sweep.csv (the table of another sweep): {}",
                                      out, std::strerror(errno)));
      try {
        write_file_at(f->fd(), "sweep-plan.json", out + "/sweep-plan.json",
                      fmt::format("{{\"plan\": \"{}\", \"points_total\": {}}}\n", hash, points));
      } catch (const OutputError& e) {
        throw FolderError(e.what());
      }
      if (sharded && !f->try_lock(false))  // converted: the other shards of this plan may come
        throw FolderError(fmt::format("cannot share the lock of {}", out));
      return f;
    }
    if (!sharded) break;
    found = plan_of(text_at(f->fd(), "sweep-plan.json"));
    if (found == hash && f->try_lock(false)) return f;  // a shard of the same plan
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  } while (std::chrono::steady_clock::now() < until);
  throw FolderError(fmt::format(
      "{} is in use by another rubdyn sweep (it holds the folder's lock{}); choose another --out "
      "or wait for it to end",
      out,
      sharded && !found.empty() && found != hash
          ? fmt::format("; its plan is {}, this sweep's {}", found, hash)
          : std::string()));
}

/// A number of the table; NaN (not computed) as an empty field.
std::string num_csv(double x) {
  return std::isnan(x) ? "" : fmt::format("{}", x);
}

}  // namespace

std::vector<std::string> ensemble_option_problems(const EnsembleOptions& e) {
  std::vector<std::string> bad;
  if (e.members < 0 || e.members > kMaxEnsembleMembers)
    bad.push_back(fmt::format("--ensemble {}: must be in [0, {}] (0: no ensemble)", e.members,
                              kMaxEnsembleMembers));
  if (!std::isfinite(e.domega) || e.domega < 0)
    bad.push_back(fmt::format("--ensemble-domega {}: must be finite and >= 0 [rad/s]", e.domega));
  if (!std::isfinite(e.offset) || e.offset < 0)
    bad.push_back(
        fmt::format("--ensemble-offset {}: must be finite, >= 0 and < stator.gap [m]", e.offset));
  return bad;
}

CaseSpec ensemble_member(const CaseSpec& point, int k, const EnsembleOptions& e) {
  RUBDYN_DEMAND(k >= 1 && k <= e.members);
  const int n = e.members;
  // the operations in the documented order (sweep.hpp), so that the doubles can be recomputed
  const double dw = n > 1 ? e.domega * (2.0 * (k - 1) / (n - 1) - 1.0) : e.domega;
  const double a = 2.0 * std::numbers::pi * (k - 1) / n;
  // the spin speed and the rotor centre in the (first) contact plane, as the model names them
  const auto coords = build_model(point)->coordinates();
  const int spin = find_coordinate(coords, CoordinateRole::Spin);
  const PlaneCoordinates pc = plane_coordinates(coords, 0);
  RUBDYN_DEMAND(spin >= 0 && pc.rotor_x >= 0 && pc.rotor_y >= 0);
  CaseSpec m = point;
  m.initial.v0[spin] = point.initial.v0[spin] + dw;
  m.initial.q0[pc.rotor_x] = point.initial.q0[pc.rotor_x] + e.offset * std::cos(a);
  m.initial.q0[pc.rotor_y] = point.initial.q0[pc.rotor_y] + e.offset * std::sin(a);
  return m;
}

Variation parse_variation(const std::string& text) {
  const auto eq = text.find('=');
  const std::string rule =
      "expected SECTION.KEY=v1,v2,... or SECTION.KEY=a:b:n (n >= 2 values from a to b)";
  if (eq == std::string::npos || eq == 0)
    throw std::invalid_argument(fmt::format("--vary '{}': {}", text, rule));
  Variation v;
  v.key = trim(text.substr(0, eq));
  const std::string rhs = trim(text.substr(eq + 1));
  if (v.key.find('.') == std::string::npos)
    throw std::invalid_argument(
        fmt::format("--vary '{}': key '{}' has no section; {}", text, v.key, rule));
  const auto colon = split(rhs, ':');
  if (colon.size() == 3) {
    const double a = parse_double(colon[0], "--vary " + text);
    const double b = parse_double(colon[1], "--vary " + text);
    const double n = parse_double(colon[2], "--vary " + text);
    if (n < 2 || n != std::floor(n) || n > 100000)
      throw std::invalid_argument(
          fmt::format("--vary '{}': count {} must be an integer in [2, 100000]", text, colon[2]));
    const int m = static_cast<int>(n);
    for (int i = 0; i < m; ++i)
      v.values.push_back(fmt::format("{:.15g}", a + (b - a) * i / (m - 1.0)));
    return v;
  }
  if (colon.size() != 1) throw std::invalid_argument(fmt::format("--vary '{}': {}", text, rule));
  v.values = split(rhs, ',');
  for (const auto& x : v.values)
    if (x.empty())
      throw std::invalid_argument(fmt::format("--vary '{}': empty value; {}", text, rule));
  if (v.values.empty()) throw std::invalid_argument(fmt::format("--vary '{}': {}", text, rule));
  return v;
}

namespace {
/// A decimal integer of at most 9 digits (fits in int), or -1.
int small_int(const std::string& digits) {
  return digits.size() <= 9 ? std::stoi(digits) : -1;
}
}  // namespace

Shard parse_shard(const std::string& text) {
  static const std::regex re(R"(\s*(\d+)\s*/\s*(\d+)\s*)");
  std::smatch m;
  Shard s;
  if (trim(text).empty())
    throw std::invalid_argument(
        "--shard '': expected i/N (an unset job-array variable? without --shard the whole sweep "
        "runs in every task)");
  if (!std::regex_match(text, m, re) || (s.index = small_int(m[1])) < 1 ||
      (s.count = small_int(m[2])) < s.index) {
    throw std::invalid_argument(
        fmt::format("--shard '{}': expected i/N with 1 <= i <= N <= 999999999 (e.g. 3/8)", text));
  }
  return s;
}

double sweep_point_count(const std::vector<Variation>& vary) {
  double n = 1.0;
  for (const auto& v : vary) n *= static_cast<double>(v.values.size());
  return n;
}

std::vector<std::string> SweepPoint::overrides() const {
  std::vector<std::string> out;
  for (size_t k = 0; k < keys.size(); ++k) out.push_back(keys[k] + "=" + values[k]);
  return out;
}

std::vector<SweepPoint> sweep_points(const std::vector<Variation>& vary) {
  std::vector<SweepPoint> pts(1);
  for (const auto& var : vary) {
    std::vector<SweepPoint> next;
    for (const auto& p : pts) {
      for (const auto& x : var.values) {
        SweepPoint q = p;
        q.keys.push_back(var.key);
        q.values.push_back(x);
        next.push_back(q);
      }
    }
    pts = std::move(next);
  }
  for (size_t i = 0; i < pts.size(); ++i) pts[i].index = static_cast<long>(i);
  return pts;
}

std::string sweep_csv(const std::vector<std::string>& keys, const std::vector<SweepRow>& rows,
                      bool certify, bool ensemble) {
  std::string s = "point";
  for (const auto& k : keys) {
    s += ',';
    s += k;
  }
  s += ",termination,complete,omega_max,omega_final,t_omega_lim,limited,contact_fraction,"
       "backward_fraction,backward_onset,whip_fraction,whip_onset,sign_backward_onset,"
       "permanent_contact_onset,stick_fraction,max_friction_torque_ratio,events,wall_seconds,"
       "folder";
  if (certify)
    s += ",certified,tight_termination,tight_limited,tight_backward,tight_whip,"
         "tight_omega_max";
  if (ensemble)
    s += ",ensemble_members,ensemble_incomplete,p_limited,p_backward,p_whip,p_rolling,"
         "omega_max_min,omega_max_max";
  s += "\n";
  for (const auto& r : rows) {
    s += fmt::format("{}", r.point.index);
    for (const auto& x : r.point.values) {
      s += ',';  // (not "," + x: g++ 12 -Wrestrict false positive on operator+)
      s += csv_field(x);
    }
    const auto& v = r.v;
    s += fmt::format(",{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}", r.termination,
                     r.complete ? "yes" : "no", v.omega_max, v.omega_final, opt_csv(v.t_omega_lim),
                     v.limited ? "yes" : "no", v.contact_fraction, v.backward_fraction,
                     opt_csv(v.backward_onset), v.whip_fraction, opt_csv(v.whip_onset),
                     opt_csv(v.sign_backward_onset), opt_csv(v.permanent_contact_onset),
                     v.stick_fraction, v.max_friction_torque_ratio, v.events, r.wall_seconds,
                     csv_field(r.folder));
    if (certify) {
      const auto& t = r.tight;
      s += fmt::format(",{},{},{},{},{},{}", r.certified ? "yes" : "no", r.tight_termination,
                       t.limited ? "yes" : "no", t.backward_onset ? "yes" : "no",
                       t.whip_onset ? "yes" : "no", t.omega_max);
    }
    if (ensemble) {
      s += fmt::format(",{},{},{},{},{},{},{},{}", r.ensemble_members, r.ensemble_incomplete,
                       num_csv(r.p_limited), num_csv(r.p_backward), num_csv(r.p_whip),
                       num_csv(r.p_rolling), num_csv(r.omega_max_min), num_csv(r.omega_max_max));
    }
    s += "\n";
  }
  return s;
}

std::vector<SweepRow> run_sweep(const SweepOptions& o) {
  namespace fs = std::filesystem;
  // every option first: nothing runs (or is allocated for 1e10 points) before all are checked
  std::vector<std::string> bad = analysis_option_problems(o.analysis);
  for (const auto& b : ensemble_option_problems(o.ensemble)) bad.push_back(b);
  std::set<std::string> seen;
  for (const auto& v : o.vary)
    if (!seen.insert(v.key).second)
      bad.push_back(
          fmt::format("--vary {}: the key is varied twice (give one list of values)", v.key));
  if (o.jobs < 1) bad.push_back(fmt::format("jobs = {}: must be >= 1", o.jobs));
  const double count = sweep_point_count(o.vary);
  const int members = std::clamp(o.ensemble.members, 0, kMaxEnsembleMembers);  // checked above
  if (count * (members + 1) > static_cast<double>(o.max_points)) {
    const std::string what =
        members > 0 ? fmt::format("{:.6g} runs ({:.6g} points x {} with --ensemble {})",
                                  count * (members + 1), count, members + 1, members)
                    : fmt::format("{:.6g} points", count);
    bad.push_back(fmt::format("{}, above the limit of {} (give --max-points N to run them)", what,
                              o.max_points));
  }
  if (!bad.empty()) {
    std::string text = "invalid sweep:";
    for (const auto& b : bad) text += "\n  " + b;
    throw std::invalid_argument(text);
  }
  const auto all = sweep_points(o.vary);
  RUBDYN_DEMAND(static_cast<double>(all.size()) == count);  // the product, as counted above
  // validate every point first: a bad value stops the sweep before anything is written
  // (the case file read once: a FIFO, <(gen-case), can be read only once)
  const std::string case_text = read_case_file(o.case_path);
  std::vector<CaseSpec> specs;
  specs.reserve(all.size());
  for (const auto& p : all) {
    auto sets = o.sets;
    for (const auto& x : p.overrides()) sets.push_back(x);
    specs.push_back(parse_case(case_text, o.case_path, sets));
  }
  if (members > 0) {  // the offset must leave every point's rotor inside its clearance
    long over = 0;
    size_t first = 0;
    double first_gap = 0.0;
    for (size_t i = 0; i < specs.size(); ++i) {
      const double g0 = build_model(specs[i])->gap_scale(0);
      if (!(o.ensemble.offset < g0) && over++ == 0) {
        first = i;
        first_gap = g0;
      }
    }
    if (over > 0)
      throw std::invalid_argument(fmt::format(
          "invalid sweep:\n  --ensemble-offset {}: must be < stator.gap = {} m (the rotor is "
          "released that far off its position, inside the clearance); broken at {} point{} "
          "(first: point {})",
          o.ensemble.offset, first_gap, over, over == 1 ? "" : "s", first));
  }
  std::vector<size_t> mine;
  for (size_t i = 0; i < all.size(); ++i)
    if (static_cast<int>(i % static_cast<size_t>(o.shard.count)) == o.shard.index - 1)
      mine.push_back(i);
  std::vector<CaseSpec> tight;
  if (o.certify) {
    for (size_t i : mine) {
      auto sets = o.sets;
      for (const auto& x : all[i].overrides()) sets.push_back(x);
      for (const auto& x : tight_overrides(specs[i])) sets.push_back(x);
      tight.push_back(parse_case(case_text, o.case_path, sets));
    }
  }
  // the members of this shard's points, each validated as a case (read back from its TOML)
  std::vector<std::vector<CaseSpec>> member_specs(mine.size());
  for (size_t k = 0; k < mine.size(); ++k) {
    for (int m = 1; m <= members; ++m) {
      member_specs[k].push_back(ensemble_member(specs[mine[k]], m, o.ensemble));
      try {
        parse_case(to_toml(member_specs[k].back()), o.case_path);
      } catch (const CaseError& e) {
        auto issues = e.issues();
        for (auto& x : issues) {
          x.file = fmt::format("{} (point {}, --ensemble member {})", o.case_path, mine[k], m);
          x.line = 0;
        }
        throw CaseError(issues);
      }
    }
  }
  // the folder is taken (locked, checked, its plan written) before anything runs: a folder
  // that cannot be prepared or is in use is refused with nothing run (FolderError, exit 2)
  const std::string hash = plan_hash(specs, o, members);
  const std::unique_ptr<HeldFolder> folder =
      take_sweep_folder(o.out, hash, o.shard.count > 1, static_cast<long>(all.size()));
  if (o.plan) {
    SweepPlan p;
    p.hash = hash;
    p.points = static_cast<long>(all.size());
    auto add = [&p](const CaseSpec& c) {
      ++p.runs;
      const double span = c.run.t_end - c.run.t_start;
      p.simulated_seconds += span;
      const SolverEntry* solver = find_solver(c.solver.kind);
      const bool every = solver && solver->fixed_step && c.output.every > 0;
      p.output_rows += every ? span / c.solver.h / c.output.every : span / c.output.dt;
    };
    for (size_t i : mine) add(specs[i]);
    for (const auto& t : tight) add(t);
    for (const auto& ms : member_specs)
      for (const auto& m : ms) add(m);
    p.output_bytes = 420.0 * p.output_rows;
    o.plan(p);
  }

  // One task per point (with its tight run) and per member, in point order: each writes only its
  // own slot, so the threads share nothing but the task counter and the progress call.
  struct Task {
    size_t k;  ///< index in mine
    int m;     ///< 0: the point, else the ensemble member
  };
  std::vector<Task> tasks;
  for (size_t k = 0; k < mine.size(); ++k)
    for (int m = 0; m <= members; ++m) tasks.push_back({k, m});
  std::vector<SweepRow> rows(mine.size());
  for (size_t k = 0; k < mine.size(); ++k) {
    rows[k].point = all[mine[k]];
    rows[k].folder = (fs::path(o.out) / fmt::format("p{:04d}", mine[k])).string();
    rows[k].members.resize(static_cast<size_t>(members));
    for (int m = 1; m <= members; ++m)
      rows[k].members[static_cast<size_t>(m - 1)].folder =
          fmt::format("{}-e{:02d}", rows[k].folder, m);
  }
  std::atomic<size_t> next{0};
  std::mutex mtx;
  long done = 0;
  auto worker = [&](std::atomic<bool>* own) {
    for (size_t t = next++; t < tasks.size(); t = next++) {
      const auto [k, m] = tasks[t];
      SweepRow& row = rows[k];
      const bool stopped = o.stop && o.stop->load();  // the rest is not run (--resume runs it)
      if (m > 0) {
        SweepMember& member = row.members[static_cast<size_t>(m - 1)];
        if (stopped) {
          member.termination = "not_run";
          member.message = "the sweep was interrupted before this member";
        } else {
          const OneRun r = run_point(member_specs[k][static_cast<size_t>(m - 1)], member.folder,
                                     o.analysis, o.resume, o.stop, own);
          member.termination = r.termination;
          member.message = r.message;
          member.complete = r.complete;
          member.v = r.v;
        }
      } else if (stopped) {
        row.termination = "not_run";
        row.message = "the sweep was interrupted before this point";
      } else {
        const OneRun r = run_point(specs[mine[k]], row.folder, o.analysis, o.resume, o.stop, own);
        row.termination = r.termination;
        row.message = r.message;
        row.complete = r.complete;
        row.wall_seconds = r.wall;
        row.v = r.v;
        if (o.certify) {
          const OneRun t =
              run_point(tight[k], row.folder + "-tight", o.analysis, o.resume, o.stop, own);
          row.certified_run = true;
          row.tight_termination = t.termination;
          row.tight = t.v;
          row.certified = r.complete && t.complete && same_verdicts(r.v, t.v);
        }
      }
      if (stopped) continue;
      std::lock_guard<std::mutex> lock(mtx);
      ++done;
      if (o.progress) o.progress(done, static_cast<long>(tasks.size()));
    }
  };
  const int n = std::max(1, std::min<int>(o.jobs, static_cast<int>(tasks.size())));
  std::vector<std::atomic<bool>> own(static_cast<size_t>(n));  // each worker's stop flag
  std::atomic<bool> finished{false};
  std::thread watcher;  // copies the sweep's stop into every worker's flag
  if (o.stop)
    watcher = std::thread([&] {
      while (!finished.load()) {
        if (o.stop->load())
          for (auto& f : own) f.store(true);
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    });
  std::vector<std::thread> pool;
  for (int j = 1; j < n; ++j) pool.emplace_back(worker, &own[static_cast<size_t>(j)]);
  worker(&own[0]);
  for (auto& t : pool) t.join();
  finished.store(true);
  if (watcher.joinable()) watcher.join();
  if (members > 0)
    for (auto& row : rows) ensemble_stats(row);

  std::vector<std::string> keys;
  for (const auto& v : o.vary) keys.push_back(v.key);
  const std::string table = sweep_csv(keys, rows, o.certify, members > 0);
  // a folder removed or replaced meanwhile: the table would describe folders that are gone
  if (!folder->intact())
    throw OutputError(folder->lost_message() + "; the sweep's table is not written");
  const int fd = folder->fd();
  if (o.shard.count == 1) {
    write_file_at(fd, "sweep.csv", (fs::path(o.out) / "sweep.csv").string(), table);
  } else {
    const std::string stem = fmt::format("sweep-shard-{}-of-{}", o.shard.index, o.shard.count);
    // the plan and the ensemble's settings, which sweep-merge requires to be the same in every
    // shard
    const std::string ensemble =
        members > 0 ? fmt::format("{{\"members\": {}, \"domega\": {}, \"offset\": {}}}", members,
                                  o.ensemble.domega, o.ensemble.offset)
                    : "{\"members\": 0}";
    write_file_at(fd, stem + ".json", (fs::path(o.out) / (stem + ".json")).string(),
                  fmt::format("{{\"shard\": {}, \"shards\": {}, \"points_total\": {}, "
                              "\"plan\": \"{}\", \"certify\": {}, \"ensemble\": {}}}\n",
                              o.shard.index, o.shard.count, all.size(), hash,
                              o.certify ? "true" : "false", ensemble));
    write_file_at(fd, stem + ".csv", (fs::path(o.out) / (stem + ".csv")).string(), table);
  }
  return rows;
}

namespace {

bool full_number(const std::string& x) {
  char* end = nullptr;
  errno = 0;
  (void)std::strtod(x.c_str(), &end);
  return !x.empty() && end == x.c_str() + x.size() && x.find_first_of(" \t") == std::string::npos;
}

bool full_count(const std::string& x) {
  if (x.empty() || x.size() > 18 || x.find_first_not_of("0123456789") != std::string::npos)
    return false;
  return true;
}

bool is_termination(const std::string& x) {
  if (x == "error" || x == "not_run") return true;
  for (int k = 0; k <= static_cast<int>(kLastTermination); ++k)
    if (x == to_string(static_cast<Termination>(k))) return true;
  return false;
}

/// What a field of the sweep table must be, by its column (sweep_csv): the rule it breaks, or
/// "" when it is valid. Columns between "point" and "termination" are the varied keys.
std::string field_rule(const std::string& column, const std::string& x, bool varied) {
  static const std::set<std::string> numbers = {
      "omega_max",      "omega_final",    "contact_fraction",          "backward_fraction",
      "whip_fraction",  "stick_fraction", "max_friction_torque_ratio", "wall_seconds",
      "tight_omega_max"};
  static const std::set<std::string> optional_numbers = {"t_omega_lim",
                                                         "backward_onset",
                                                         "whip_onset",
                                                         "sign_backward_onset",
                                                         "permanent_contact_onset",
                                                         "p_limited",
                                                         "p_backward",
                                                         "p_whip",
                                                         "p_rolling",
                                                         "omega_max_min",
                                                         "omega_max_max"};
  static const std::set<std::string> counts = {"events", "ensemble_members", "ensemble_incomplete"};
  static const std::set<std::string> flags = {"complete",      "limited",        "certified",
                                              "tight_limited", "tight_backward", "tight_whip"};
  if (varied) return x.empty() ? "must be the point's value of the varied key" : "";
  if (numbers.count(column)) return full_number(x) ? "" : "must be a number";
  if (optional_numbers.count(column))
    return x.empty() || full_number(x) ? "" : "must be a number or empty";
  if (counts.count(column)) return full_count(x) ? "" : "must be a count (digits)";
  if (flags.count(column)) return x == "yes" || x == "no" ? "" : "must be yes or no";
  if (column == "termination") return is_termination(x) ? "" : "must be a termination";
  if (column == "tight_termination")
    return x.empty() || is_termination(x) ? "" : "must be a termination or empty";
  if (column == "folder") return "";  // checked against the point index by the caller
  return "is not a column of a sweep table";
}

}  // namespace

long merge_sweep_shards(const std::string& out) {
  namespace fs = std::filesystem;
  static const std::regex re(R"(sweep-shard-(\d+)-of-(\d+)\.csv)");
  std::map<int, fs::path> shards;
  int count = -1;
  std::error_code ec;
  if (!fs::is_directory(out, ec)) throw std::runtime_error(out + ": not a directory");
  // the folder's lock: shards still running hold it (shared), and so would another merge
  HeldFolder folder(out);
  if (!folder.try_lock(true))
    throw std::runtime_error(
        fmt::format("{} is in use by a running rubdyn sweep (it holds the "
                    "folder's lock): merge once every shard has ended",
                    out));
  for (const auto& e : fs::directory_iterator(out)) {
    std::smatch m;
    const std::string name = e.path().filename().string();
    if (!std::regex_match(name, m, re)) continue;
    const int i = small_int(m[1]), n = small_int(m[2]);
    if (i < 1 || n < i)
      throw std::runtime_error(fmt::format("{}: not a shard i of N with 1 <= i <= N", name));
    if (name != fmt::format("sweep-shard-{}-of-{}.csv", i, n))
      throw std::runtime_error(fmt::format(
          "{}/{}: not a name rubdyn writes (sweep-shard-{}-of-{}.csv): rename or remove it", out,
          name, i, n));
    if (count >= 0 && n != count)
      throw std::runtime_error(
          fmt::format("{}: shards of {} and of {} sweeps mixed", out, count, n));
    count = n;
    shards[i] = e.path();
  }
  if (count < 0) throw std::runtime_error(out + ": no sweep-shard-i-of-N.csv files");
  std::string header, body, ensemble, plan;
  std::map<long, std::string> lines;
  long total = -1;
  for (int i = 1; i <= count; ++i) {
    if (!shards.count(i))
      throw std::runtime_error(fmt::format("{}: shard {} of {} missing (sweep-shard-{}-of-{}.csv)",
                                           out, i, count, i, count));
    const fs::path side = fs::path(out) / fmt::format("sweep-shard-{}-of-{}.json", i, count);
    const std::string text = text_at(folder.fd(), side.filename().string());
    if (text.empty()) throw std::runtime_error(side.string() + ": missing or empty");
    static const std::regex tot(R"("points_total":\s*(\d+))");
    static const std::regex shard_re(R"("shard":\s*(\d+),\s*"shards":\s*(\d+))");
    std::smatch m;
    if (!std::regex_search(text, m, tot))
      throw std::runtime_error(side.string() + ": missing or without points_total");
    const std::string digits = m[1];
    if (digits.size() > 15)
      throw std::runtime_error(side.string() + ": points_total " + digits + " is not a count");
    const long t = std::stol(digits);
    if (total >= 0 && t != total)
      throw std::runtime_error(
          fmt::format("{}: points_total {} differs from {} of shard 1", side.string(), t, total));
    total = t;
    if (!std::regex_search(text, m, shard_re) || small_int(m[1]) != i || small_int(m[2]) != count)
      throw std::runtime_error(
          fmt::format("{}: does not say shard {} of {}", side.string(), i, count));
    // the same ensemble settings (none in a shard written before ensembles existed): the P
    // columns of two different ensembles would look alike in one table
    static const std::regex ens(R"("ensemble":\s*(\{[^}]*\}))");
    const std::string e =
        std::regex_search(text, m, ens) ? std::string(m[1]) : std::string("{\"members\": 0}");
    if (i == 1) ensemble = e;
    if (e != ensemble)
      throw std::runtime_error(
          fmt::format("{}: ensemble {} differs from {} of shard 1", side.string(), e, ensemble));
    // one plan: shards of two sweeps with the same point count would merge into one table
    const std::string p = plan_of(text);
    if (p.empty())
      throw std::runtime_error(side.string() +
                               ": no plan hash (written by another rubdyn, or edited): re-run "
                               "this shard");
    if (i == 1) plan = p;
    if (p != plan)
      throw std::runtime_error(
          fmt::format("{}: plan {} differs from {} of shard 1 (shards of two different sweeps)",
                      side.string(), p, plan));
    const CsvTable table = read_csv(shards[i].string());
    if (!table.warnings.empty())
      throw std::runtime_error(table.warnings.front() + " (a shard must be complete to merge)");
    if (header.empty()) header = table.header_text;
    if (table.header_text != header)
      throw std::runtime_error(shards[i].string() + ":1: header differs from shard 1's");
    const int term = table.column("termination"), folder_col = table.column("folder");
    if (table.header.empty() || table.header[0] != "point" || term < 1 || folder_col < 0)
      throw std::runtime_error(shards[i].string() +
                               ":1: not a sweep table (point, the varied keys, termination, ...)");
    for (std::size_t k = 0; k < table.rows.size(); ++k) {
      const auto& row = table.rows[k];
      const std::string& first = row[0];
      const long ln = table.line_of[k];
      char* end = nullptr;
      errno = 0;
      const long idx = std::strtol(first.c_str(), &end, 10);
      if (!full_count(first) || *end != '\0' || errno != 0 || idx < 0 || idx >= total)
        throw std::runtime_error(fmt::format("{}:{}: point index '{}' is not in [0, {})",
                                             shards[i].string(), ln, first, total));
      if (idx % count != i - 1)
        throw std::runtime_error(
            fmt::format("{}:{}: point {} does not belong to shard {} of {} (index % {} = {})",
                        shards[i].string(), ln, idx, i, count, count, idx % count + 1));
      if (lines.count(idx))
        throw std::runtime_error(
            fmt::format("{}:{}: point {} appears twice", shards[i].string(), ln, idx));
      for (std::size_t c = 1; c < row.size(); ++c) {
        const std::string& column = table.header[c];
        const std::string rule = field_rule(column, row[c], static_cast<int>(c) < term);
        if (!rule.empty())
          throw std::runtime_error(fmt::format("{}:{}: column {}: '{}' {}", shards[i].string(), ln,
                                               column, row[c], rule));
      }
      const std::string want = fmt::format("p{:04d}", idx);
      if (fs::path(row[static_cast<std::size_t>(folder_col)]).filename() != want)
        throw std::runtime_error(
            fmt::format("{}:{}: column folder: '{}' must be the point's "
                        "folder .../{}",
                        shards[i].string(), ln, row[static_cast<std::size_t>(folder_col)], want));
      lines[idx] = table.text[k];
    }
  }
  std::vector<long> missing;
  for (long p = 0; p < total; ++p)
    if (!lines.count(p)) missing.push_back(p);
  if (!missing.empty())
    throw std::runtime_error(fmt::format("{}: {} of {} points missing (first: {})", out,
                                         missing.size(), total, missing.front()));
  std::string text = header + "\n";
  for (const auto& [idx, line] : lines) text += line + "\n";
  write_file_at(folder.fd(), "sweep.csv", (fs::path(out) / "sweep.csv").string(), text);
  return static_cast<long>(lines.size());
}

}  // namespace rubdyn
