// OutputFolder: timeseries.csv, events.csv, summary.json, case.resolved.toml.
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "rubdyn/core/demand.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/output_folder.hpp"
#include "rubdyn/io/reduction_files.hpp"
#include "rubdyn/io/text_files.hpp"
#include "rubdyn/model/matrix_model.hpp"
#include "rubdyn/model/rotor_stator_params.hpp"

namespace rubdyn {

namespace {

/// The most contacts of any model (the rigid rotor's [[plane]]s, a matrices model's
/// [[contact_node]]s): the planes whose derived files a new run removes.
constexpr int kMaxDerivedPlanes = std::max(kMaxPlanes, kMaxContactNodes);

/// "cannot write PATH: reason", the reason from errno (set by the failed call).
std::string cannot_write(const std::string& path) {
  return fmt::format("cannot write {}: {}", path,
                     errno ? std::strerror(errno) : "write failed (no reason given)");
}

void write_or_throw(std::FILE* f, const std::string& text, const std::string& path) {
  errno = 0;
  if (std::fwrite(text.data(), 1, text.size(), f) != text.size()) {
    throw std::runtime_error(cannot_write(path));
  }
}

/// A JSON string: the same escaping as a TOML basic string (quoted_string, text_files.hpp).
std::string json_string(std::string_view s) {
  return quoted_string(s);
}

/// JSON has no NaN or infinity: they are written as null.
std::string json_number(double x) {
  return std::isfinite(x) ? fmt::format("{:.17g}", x) : "null";
}

/// Links of a folder held open: 0 once it was removed.
long fstat_nlink(int fd) {
  struct stat st {};
  return ::fstat(fd, &st) == 0 ? static_cast<long>(st.st_nlink) : 0;
}

}  // namespace

HeldFolder::HeldFolder(const std::string& dir) : dir_(dir) {
  namespace fs = std::filesystem;
  if (dir.empty()) throw FolderError("an empty path is no output folder");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw FolderError(fmt::format("cannot create {}: {}", dir, ec.message()));
  fd_ = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0)
    throw FolderError(errno == ENOTDIR
                          ? fmt::format("{}: not a directory", dir)
                          : fmt::format("cannot open {}: {}", dir, std::strerror(errno)));
}

HeldFolder::~HeldFolder() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

bool HeldFolder::try_lock(bool exclusive) {
  if (::flock(fd_, (exclusive ? LOCK_EX : LOCK_SH) | LOCK_NB) == 0) return true;
  if (errno != EWOULDBLOCK)
    throw FolderError(fmt::format("cannot lock {}: {}", dir_, std::strerror(errno)));
  return false;
}

void HeldFolder::check_writable() const {
  // access() answers for root as if every folder were writable; a real write answers for all:
  // a file created and removed again (O_TMPFILE leaves no name even if we are killed here)
  int probe = ::openat(fd_, ".", O_TMPFILE | O_WRONLY | O_CLOEXEC, 0600);
  if (probe < 0 && (errno == EOPNOTSUPP || errno == EISDIR || errno == EINVAL)) {
    // a file system without O_TMPFILE: the permission check alone
    if (::faccessat(fd_, ".", W_OK | X_OK, 0) == 0) return;
  } else if (probe >= 0) {
    ::close(probe);
    return;
  }
  throw FolderError(fmt::format("cannot write into {}: {}", dir_, std::strerror(errno)));
}

bool HeldFolder::intact() const {
  struct stat held {
  }, now{};
  if (::fstat(fd_, &held) != 0 || held.st_nlink == 0) return false;  // removed
  if (::stat(dir_.c_str(), &now) != 0) return false;                 // the path leads nowhere
  return now.st_dev == held.st_dev && now.st_ino == held.st_ino;     // or to another folder
}

std::string HeldFolder::lost_message() const {
  return fmt::format(
      "the output folder {} was removed or replaced while rubdyn was writing into it (what was "
      "written went with the folder; nothing is written into a folder that took its path)",
      dir_);
}

OutputFolder::OutputFolder(const std::string& dir, const CaseSpec& spec, std::atomic<bool>* stop)
    : dir_(dir), stop_(stop) {
  {
    const std::unique_ptr<LagrangianModel> model = build_model(spec);
    columns_ = timeseries_columns(*model, spec.output.coordinates);
    if (!writes_every_coordinate(*model, spec.output.coordinates)) {
      state_columns_ = timeseries_columns(*model);
      last_ = Sample(model->num_dofs(), model->contact_count(),
                     static_cast<int>(model->observables().size()));
    }
    event_columns_ = event_columns(model->contact_count());
    n_dofs_ = model->num_dofs();
    n_contacts_ = model->contact_count();
    n_observables_ = static_cast<int>(model->observables().size());
  }
  folder_ = std::make_unique<HeldFolder>(dir);
  // Advisory lock on the directory itself (no lock file left behind): a second run into the
  // same folder would interleave its rows with ours.
  if (!folder_->try_lock(true))
    throw FolderError(
        fmt::format("{} is in use by another rubdyn run (it holds the folder's "
                    "lock); choose another --out or wait for it to end",
                    dir));
  // Everything that can be checked is checked before the first byte is written: the folder
  // and the files this run replaces must be writable; a summary.json of an earlier run must go
  // (it would describe another run next to our files), and so must what was derived from it.
  const int fd = folder_->fd();
  auto fail = [&](const std::string& what) {
    folder_.reset();  // unlocked
    throw FolderError(what);
  };
  try {
    folder_->check_writable();
  } catch (const FolderError& e) {
    fail(e.what());
  }
  for (const char* name : {"case.resolved.toml", "timeseries.csv", "events.csv", "state.csv"}) {
    struct stat st {};
    if (::fstatat(fd, name, &st, AT_SYMLINK_NOFOLLOW) == 0 && ::faccessat(fd, name, W_OK, 0) != 0)
      fail(fmt::format("cannot write {}/{}: {}", dir, name, std::strerror(errno)));
  }
  if (::unlinkat(fd, "summary.json", 0) != 0 && errno != ENOENT)
    fail(fmt::format("cannot remove the old {}/summary.json: {}", dir, std::strerror(errno)));
  // a folder of derived files is entered only when it is a real folder (never through a link)
  const auto real_dir = [fd](const std::string& name) {
    struct stat st {};
    return ::fstatat(fd, name.c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0 && S_ISDIR(st.st_mode);
  };
  const bool analysis_dir = real_dir("analysis");
  // an earlier run's copies of its matrix files that this case does not write
  const auto matrices = case_matrix_files(spec);
  std::vector<std::string> stale;
  for (const char* key : kCaseMatrixKeys) {
    const std::string name = case_matrix_file(key);
    if (std::none_of(matrices.begin(), matrices.end(),
                     [&](const auto& m) { return m.first == name; }))
      stale.push_back(name);
  }
  std::vector<std::string> removable = derived_files();
  // an earlier run's full states, when this run writes every coordinate to timeseries.csv
  if (state_columns_.empty()) removable.emplace_back("state.csv");
  removable.insert(removable.end(), stale.begin(), stale.end());
  for (const std::string& name : removable) {
    if (name.starts_with("analysis/")) {
      if (!analysis_dir) continue;
      const auto slash = name.rfind('/');
      if (slash > 8 && !real_dir(name.substr(0, slash))) continue;  // analysis/plane_k
    }
    struct stat st {};
    if (::fstatat(fd, name.c_str(), &st, AT_SYMLINK_NOFOLLOW) != 0 || !S_ISREG(st.st_mode))
      continue;
    if (::unlinkat(fd, name.c_str(), 0) != 0 && errno != ENOENT)
      fail(fmt::format("cannot remove {}/{} (derived from an earlier run in this folder): {}", dir,
                       name, std::strerror(errno)));
  }
  // the folders, innermost first, only when that left them empty: kept otherwise
  if (analysis_dir)
    for (const std::string& name : derived_folders())
      if (real_dir(name)) ::unlinkat(fd, name.c_str(), AT_REMOVEDIR);
  try {
    // the matrices first: a case.resolved.toml on disk always has its files beside it
    for (const auto& [name, bytes] : matrices) write_file_at(fd, name, dir + "/" + name, bytes);
    write_file_at(fd, "case.resolved.toml", dir + "/case.resolved.toml", resolved_toml(spec));
    write_reduction_files(fd, dir, spec);  // (a reduced matrices model's; io/reduction_files.hpp)
    write_output_modes_files(fd, dir, spec);  // (output.modes's; the same)
    ts_ = open_output_stream_at(fd, "timeseries.csv", dir + "/timeseries.csv");
    ev_ = open_output_stream_at(fd, "events.csv", dir + "/events.csv");
    if (!state_columns_.empty()) st_ = open_output_stream_at(fd, "state.csv", dir + "/state.csv");
    const auto header = [](const auto& columns) {
      std::string h;
      for (const auto& c : columns) h += (h.empty() ? "" : ",") + c.name;
      return h + "\n";
    };
    write_or_throw(ts_, header(columns_), dir + "/timeseries.csv");
    write_or_throw(ev_, header(event_columns_), dir + "/events.csv");
    if (st_) write_or_throw(st_, header(state_columns_), dir + "/state.csv");
    // headers on disk at once: a run killed before its first flush still leaves valid files
    if (std::fflush(ts_) != 0) throw std::runtime_error(cannot_write(dir + "/timeseries.csv"));
    if (std::fflush(ev_) != 0) throw std::runtime_error(cannot_write(dir + "/events.csv"));
    if (st_ && std::fflush(st_) != 0) throw std::runtime_error(cannot_write(dir + "/state.csv"));
  } catch (const std::runtime_error& e) {
    for (std::FILE* f : {ts_, ev_, st_})
      if (f) std::fclose(f);
    ts_ = ev_ = st_ = nullptr;
    fail(e.what());
  }
}

OutputFolder::~OutputFolder() {
  for (std::FILE* f : {ts_, ev_, st_})
    if (f) std::fclose(f);
}

void OutputFolder::failed(const std::string& file) {
  if (error_.empty()) error_ = cannot_write(dir_ + "/" + file);
  if (stop_) stop_->store(true);
}

void OutputFolder::check_folder() {
  since_check_ = 0;
  if (!error_.empty() || folder_->intact()) return;
  error_ = folder_->lost_message();
  if (stop_) stop_->store(true);
}

void OutputFolder::sample(const Sample& s) {
  if (++since_check_ >= kCheckEverySamples) check_folder();
  if (!ts_ || !error_.empty()) return;
  // a sample of another model's size is a bug of the caller, not bad input
  RUBDYN_DEMAND(s.q.size() == n_dofs_ && s.v.size() == n_dofs_ &&
                static_cast<int>(s.contacts.size()) == n_contacts_ &&
                s.observables.size() == n_observables_);
  format_row(s, columns_);
  if (std::fwrite(buf_.data(), 1, buf_.size(), ts_) != buf_.size()) failed("timeseries.csv");
  if (!st_) return;
  if (state_next_) {
    // the first sample or the one after an event: on disk at once (rare), so that a run that
    // dies keeps the state after its last event
    state_row(s);
    if (error_.empty() && std::fflush(st_) != 0) failed("state.csv");
    state_next_ = false;
    last_in_state_ = true;
  } else {
    last_in_state_ = false;
  }
  // kept for the end (the sizes are the model's: an assignment, no allocation)
  last_.t = s.t;
  last_.q = s.q;
  last_.v = s.v;
  last_.contacts = s.contacts;
  last_.observables = s.observables;
  have_last_ = true;
}

void OutputFolder::format_row(const Sample& s, const std::vector<SampleColumn>& columns) {
  // Shortest representation that reads back to the same double ({} in fmt: Dragonbox), exact
  // like %.17g but about 3x cheaper, which matters: at 0.1 ms output the rows cost as much as
  // the event-driven integration of the reference case.
  buf_.clear();
  auto out = std::back_inserter(buf_);
  for (std::size_t i = 0; i < columns.size(); ++i) {
    const SampleColumn& c = columns[i];
    if (i > 0) buf_.push_back(',');
    if (c.field == SampleField::Phase) {
      const auto p = to_string(s.contacts[static_cast<std::size_t>(c.index)].phase);
      buf_.append(p);
    } else {
      fmt::format_to(out, "{}", sample_value(s, c));
    }
  }
  buf_.push_back('\n');
}

void OutputFolder::state_row(const Sample& s) {
  if (!st_ || !error_.empty()) return;
  format_row(s, state_columns_);
  if (std::fwrite(buf_.data(), 1, buf_.size(), st_) != buf_.size()) failed("state.csv");
}

void OutputFolder::event(const EventRecord& e) {
  check_folder();
  if (!ev_ || !error_.empty()) return;
  auto csv_text = [](const std::string& s) {
    std::string out = "\"";
    for (char ch : s) out += ch == '"' ? std::string("\"\"") : std::string(1, ch);
    return out + "\"";
  };
  std::string row;
  for (const EventColumn& c : event_columns_) {
    if (!row.empty()) row += ',';
    switch (c.field) {
      case EventField::Time: row += fmt::format("{:.17g}", e.t); break;
      case EventField::Kind: row += to_string(e.kind); break;
      case EventField::PhaseBefore: row += to_string(e.phase_before); break;
      case EventField::PhaseAfter: row += to_string(e.phase_after); break;
      case EventField::Contact: row += fmt::format("{}", e.contact + 1); break;
      case EventField::Text: row += csv_text(event_text(e, c.name)); break;
      case EventField::Number: {
        const double x = event_number(e, c.name);
        // an absent number (the accumulation time of an event that is no Zeno) is empty
        if (!std::isnan(x) || c.name != "t_accumulation") row += fmt::format("{:.17g}", x);
        break;
      }
    }
  }
  row += '\n';
  // events are rare: flush both files so that a run that dies keeps everything up to here (the
  // state after this event goes to state.csv with the next sample, flushed there)
  if (std::fwrite(row.data(), 1, row.size(), ev_) != row.size() || std::fflush(ev_) != 0) {
    failed("events.csv");
  } else if (std::fflush(ts_) != 0) {
    failed("timeseries.csv");
  }
  state_next_ = true;
}

void OutputFolder::end(const RunSummary& s) {
  // fclose flushes what is buffered: its failure is a failed write like any other
  if (ts_ && std::fclose(ts_) != 0) failed("timeseries.csv");
  if (ev_ && std::fclose(ev_) != 0) failed("events.csv");
  if (st_) {
    // the last sample's full state: where a restart of this run starts
    if (have_last_ && !last_in_state_) state_row(last_);
    if (std::fclose(st_) != 0) failed("state.csv");
  }
  ts_ = ev_ = st_ = nullptr;
  check_folder();
  RunSummary out = s;
  if (!error_.empty()) {
    out.termination = Termination::OutputFailure;
    // the solver's own reason, unless it only obeyed the stop that the failure raised
    const bool own = !s.complete() && s.termination != Termination::Interrupted;
    out.message = error_ + (own ? " (the solver also ended: " + s.message + ")" : std::string());
  }
  try {
    // into the folder held open: a folder that took our path is not ours to write into
    if (error_.empty() || folder_->intact() || fstat_nlink(folder_->fd()) > 0)
      write_file_at(folder_->fd(), "summary.json", dir_ + "/summary.json", summary_json(out));
    else
      throw OutputError("cannot write " + dir_ + "/summary.json: the folder was removed");
  } catch (const std::runtime_error& e) {
    // the first failure first: the file whose write failed is what the user must look at
    if (error_.empty()) {
      error_ = e.what();
      throw OutputError(e.what());
    }
    throw OutputError(error_ + "; " + e.what());
  }
}

std::vector<std::string> derived_files() {
  std::vector<std::string> out;
  // analysis/plane_k/ of every plane k >= 2 first, then analysis/'s own and the figures
  for (int k = 2; k <= kMaxDerivedPlanes; ++k)
    for (const char* f : kPlaneAnalysisFiles)
      out.push_back(fmt::format("analysis/plane_{}/{}", k, f));
  for (const char* f : kDerivedFiles) out.emplace_back(f);
  for (int k = 1; k <= kMaxDerivedPlanes; ++k)
    for (const char* f : kPlaneFigures) out.push_back(fmt::format("{}_{}.png", f, k));
  return out;
}

std::vector<std::string> derived_folders() {
  std::vector<std::string> out;
  for (int k = 2; k <= kMaxDerivedPlanes; ++k) out.push_back(fmt::format("analysis/plane_{}", k));
  out.emplace_back("analysis");
  return out;
}

std::string summary_json(const RunSummary& s) {
  std::string j = "{\n";
  auto field = [&j](const char* name, const std::string& value) {
    j += fmt::format("  \"{}\": {},\n", name, value);
  };
  field("solver", json_string(s.solver));
  field("options", s.options.empty() ? "{}" : s.options);
  field("complete", s.complete() ? "true" : "false");
  field("termination", json_string(to_string(s.termination)));
  field("message", json_string(s.message));
  if (!s.model.empty()) field("model", json_string(s.model));
  field("t_start", json_number(s.t_start));
  field("t_end_requested", json_number(s.t_end_requested));
  field("t_reached", json_number(s.t_reached));
  field("wall_seconds", json_number(s.wall_seconds));
  field("steps", fmt::format("{}", s.steps));
  field("rhs_evals", fmt::format("{}", s.rhs_evals));
  field("jac_evals", fmt::format("{}", s.jac_evals));
  field("root_evals", fmt::format("{}", s.root_evals));
  field("newton_iters", fmt::format("{}", s.newton_iters));
  field("err_test_fails", fmt::format("{}", s.err_test_fails));
  field("conv_fails", fmt::format("{}", s.conv_fails));
  field("suppressed_witnesses", fmt::format("{}", s.suppressed_witnesses));
  std::string ev = "{";
  for (int k = 0; k < kNumEventKinds; ++k)
    ev += fmt::format("{}\"{}\": {}", k ? ", " : "", to_string(static_cast<EventKind>(k)),
                      s.events[k]);
  field("events", ev + "}");
  const double span = s.t_reached - s.t_start;
  std::string pt = "{", pf = "{";
  for (int k = 0; k < kNumPhases; ++k) {
    const auto name = to_string(static_cast<Phase>(k));
    pt += fmt::format("{}\"{}\": {}", k ? ", " : "", name, json_number(s.phase_time[k]));
    pf += fmt::format("{}\"{}\": {}", k ? ", " : "", name,
                      json_number(span > 0 ? s.phase_time[k] / span : 0.0));
  }
  field("phase_time", pt + "}");
  field("phase_fraction", pf + "}");
  long measured = 0;
  for (long n : s.phase_steps) measured += n;
  if (measured > 0) {
    std::string ps = "{", pw = "{";
    for (int k = 0; k < kNumPhases; ++k) {
      const auto name = to_string(static_cast<Phase>(k));
      ps += fmt::format("{}\"{}\": {}", k ? ", " : "", name, s.phase_steps[k]);
      pw += fmt::format("{}\"{}\": {}", k ? ", " : "", name, json_number(s.phase_wall[k]));
    }
    field("phase_steps", ps + "}");
    field("phase_wall_seconds", pw + "}");
  }
  field("max_penetration", json_number(s.max_penetration));
  field("min_F_N_in_contact", json_number(s.min_F_N_in_contact));
  field("max_cone_violation", json_number(s.max_cone_violation));
  field("max_drift_position", json_number(s.max_drift_position));
  field("max_drift_velocity", json_number(s.max_drift_velocity));
  field("energy_initial", json_number(s.energy_initial));
  field("energy_final", json_number(s.energy_final));
  field("work_torque", json_number(s.work_torque));
  field("work_damping", json_number(s.work_damping));
  field("work_friction", json_number(s.work_friction));
  field("work_impacts", json_number(s.work_impacts));
  field("energy_residual", json_number(s.energy_residual));
  field("omega_max", json_number(s.omega_max));
  field("omega_final", json_number(s.omega_final));
  j += fmt::format("  \"t_omega_lim\": {}\n}}\n", json_number(s.t_omega_lim));
  return j;
}

}  // namespace rubdyn
