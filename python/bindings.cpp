// rubdyn._core: the C++ library seen from Python. Thin: loading a case (CaseError with every
// issue), one run into a MemorySink (GIL released), the summary and comparison as the C++ JSON
// writers produce them, the Campbell diagram and the model's mechanics for a user's own scheme.
// The Python package (python/rubdyn/) builds its results and plots on top of this.
#include <fmt/format.h>
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rubdyn/analysis/campbell.hpp"
#include "rubdyn/analysis/compare.hpp"
#include "rubdyn/analysis/orbit_case.hpp"
#include "rubdyn/analysis/postprocess.hpp"
#include "rubdyn/core/run_types.hpp"
#include "rubdyn/driver/simulate.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/columns.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/output_folder.hpp"
#include "rubdyn/io/output_reader.hpp"
#include "rubdyn/io/solver_options.hpp"
#include "rubdyn/model/lagrangian_model.hpp"

namespace py = pybind11;
using namespace rubdyn;

namespace {

std::string fmt_size(const char* what, Eigen::Index got, int want) {
  return std::string(what) + " has " + std::to_string(got) + " entries, the model " +
         std::to_string(want);
}

/// A validated case and how it was made: run() re-parses its text with the extra overrides, as
/// the CLI parses the file with them (load_case(path, --set ... + solver options)), so that the
/// numbers are the CLI's. The text, and the matrix files a case of kind "matrices" read, are a
/// snapshot taken when the case was loaded: editing the files afterwards changes nothing.
struct Case {
  CaseSpec spec;
  std::string path;                    ///< empty when the case came from TOML text
  std::string text;                    ///< the TOML text (of the file, as it was loaded)
  std::vector<std::string> overrides;  ///< "section.key=value"
  /// the matrix files as first read (shared by the cases made from this one with more
  /// overrides; a file an override names anew is read once and kept too)
  std::shared_ptr<MatrixSnapshot> matrices = std::make_shared<MatrixSnapshot>();
};

Case make_case_from_file(const std::string& path, const std::vector<std::string>& overrides) {
  // read once, as the CLI reads it (io/case_io.hpp: a regular file or a FIFO, at most
  // kMaxCaseBytes, no NUL byte; CaseError naming the file otherwise), then kept as the snapshot
  std::string text = read_case_file(path);
  auto matrices = std::make_shared<MatrixSnapshot>();
  // what load_case does with the text
  CaseSpec spec = parse_case(text, path, overrides, matrices.get());
  return Case{std::move(spec), path, std::move(text), overrides, std::move(matrices)};
}

Case make_case_from_text(const std::string& text, const std::string& source,
                         const std::vector<std::string>& overrides,
                         std::shared_ptr<MatrixSnapshot> matrices = nullptr) {
  if (!matrices) matrices = std::make_shared<MatrixSnapshot>();
  Case c{parse_case(text, source, overrides, matrices.get()), {}, text, overrides, matrices};
  c.spec.source = source;
  return c;
}

/// The case with more overrides on top (later ones win), parsed from the case's snapshot of its
/// text (and of its matrix files) the way the CLI parses the file.
Case with_overrides(const Case& c, const std::vector<std::string>& more) {
  std::vector<std::string> all = c.overrides;
  all.insert(all.end(), more.begin(), more.end());
  Case out = make_case_from_text(c.text, c.spec.source, all, c.matrices);
  out.path = c.path;
  return out;
}

template <class T>
py::array_t<T> to_array(std::vector<T>&& v) {
  py::array_t<T> a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

/// Samples as columns named as in timeseries.csv (io/columns.hpp's SeriesTable); phase columns
/// as their codes (Phase enum values).
py::dict series_dict(SeriesTable&& t) {
  py::dict d;
  for (std::size_t c = 0; c < t.columns.size(); ++c) {
    const SampleColumn& sc = t.columns[c];
    std::vector<double>& v = t.values[c];
    if (sc.field == SampleField::Phase) {
      std::vector<std::int8_t> phase(v.size());
      for (std::size_t i = 0; i < v.size(); ++i) phase[i] = static_cast<std::int8_t>(v[i]);
      d[py::str(sc.name)] = to_array(std::move(phase));
    } else {
      d[py::str(sc.name)] = to_array(std::move(v));
    }
  }
  return d;
}

/// Events as columns named as in events.csv (kinds and phases as the CSV's words; the table of
/// io/columns.hpp).
py::dict event_columns_of(const std::vector<EventRecord>& events, int contacts) {
  py::dict d;
  for (const EventColumn& c : event_columns(contacts)) {
    if (c.field == EventField::Number || c.field == EventField::Time ||
        c.field == EventField::Contact) {
      std::vector<double> v(events.size());
      for (std::size_t i = 0; i < events.size(); ++i) v[i] = event_number(events[i], c.name);
      d[py::str(c.name)] = to_array(std::move(v));
      continue;
    }
    py::list l;
    for (const auto& e : events) {
      switch (c.field) {
        case EventField::Kind: l.append(py::str(std::string(to_string(e.kind)))); break;
        case EventField::PhaseBefore:
          l.append(py::str(std::string(to_string(e.phase_before))));
          break;
        case EventField::PhaseAfter:
          l.append(py::str(std::string(to_string(e.phase_after))));
          break;
        default: l.append(py::str(event_text(e, c.name))); break;
      }
    }
    d[py::str(c.name)] = l;
  }
  return d;
}

/// Runs `work` on a worker thread while the calling thread waits with the GIL released; every
/// 50 ms the calling thread takes the GIL to let Python handle its signals (only the main thread
/// can): Ctrl-C raises `stop`, which `work` obeys at its next check. An exception of `work` is
/// re-raised here; returns whether Ctrl-C came (the caller raises KeyboardInterrupt, after its own
/// errors).
bool run_interruptibly(std::atomic<bool>& stop, const std::function<void()>& work) {
  std::exception_ptr error;
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    auto done = std::async(std::launch::async, [&] {
      try {
        work();
      } catch (...) {
        error = std::current_exception();
      }
    });
    while (done.wait_for(std::chrono::milliseconds(50)) != std::future_status::ready) {
      py::gil_scoped_acquire acquire;
      if (PyErr_CheckSignals() != 0) {
        PyErr_Clear();  // raised by the caller, once the work has ended
        interrupted = true;
        stop = true;
      }
    }
  }
  if (error) std::rethrow_exception(error);
  return interrupted;
}

[[noreturn]] void raise_keyboard_interrupt() {
  PyErr_SetNone(PyExc_KeyboardInterrupt);
  throw py::error_already_set();
}

/// One run. It goes on a worker thread while the calling thread waits with the GIL released;
/// every 50 ms the calling thread takes the GIL to let Python handle its signals (only the main
/// thread can): Ctrl-C sets the solver's stop flag, the run ends at its next output sample (a
/// fixed-step run: its next step) and KeyboardInterrupt is raised. `progress` is called from the
/// worker at output samples (every solver), at most every progress_interval seconds of
/// wall time; an exception it raises stops the run the same way and is re-raised.
py::tuple run_case(const Case& c, const py::object& progress, double progress_interval) {
  MemorySink sink;
  RunSummary summary;
  std::exception_ptr callback_error;
  std::atomic<bool> stop{false};
  ProgressFn fn;
  if (!progress.is_none()) {
    auto last = std::chrono::steady_clock::now();
    bool first = true;
    fn = [&, last, first](double t, long events, double omega, Phase phase) mutable {
      if (callback_error) return;
      const auto now = std::chrono::steady_clock::now();
      if (!first && std::chrono::duration<double>(now - last).count() < progress_interval) return;
      first = false;
      last = now;
      py::gil_scoped_acquire acquire;
      try {
        progress(t, events, omega, std::string(to_string(phase)));
      } catch (...) {
        callback_error = std::current_exception();
        stop = true;
      }
    };
  }
  const bool interrupted =
      run_interruptibly(stop, [&] { summary = simulate(c.spec, sink, fn, &stop); });
  if (callback_error) std::rethrow_exception(callback_error);
  if (interrupted) raise_keyboard_interrupt();
  const std::unique_ptr<LagrangianModel> model = build_model(c.spec);
  return py::make_tuple(series_dict(series_table(*model, sink.samples, c.spec.output.coordinates)),
                        event_columns_of(sink.events, model->contact_count()),
                        summary_json(summary));
}

/// rubdyn.branch: the case's forced orbit followed in a case key (analysis/orbit_case.hpp,
/// find_case_branch), the case re-read from its text with its overrides and key = value at every
/// value, on a worker thread as orbit_case (Ctrl-C ends the running run). `earlier`: an earlier
/// branch's (branch.json, branch.csv, case.resolved.toml) texts, resumed (`resume`) or switched
/// from (`special`, `switch_offset`, `switch_eps`), of the same case (its resolved TOML) as the
/// CLI asks. Returns (branch.json's text, branch.csv's text, the CLI's exit code, the case's
/// resolved TOML). CaseError for bad input, as the CLI's exit 2.
py::tuple branch_case(const Case& c, const std::string& key, double to, int points, double ds,
                      double ds_max, double scale, bool down, double tol, int max_iter, int samples,
                      int periods, double period, bool sensitivities,
                      const std::optional<py::tuple>& earlier, bool resume, int special,
                      double switch_offset, double switch_eps) {
  static const SensitivityMonodromy sens;
  CaseBranchOptions o;
  o.key = key;
  o.to = to;
  o.points = points;
  o.ds = ds;
  o.ds_max = ds_max;
  o.scale = scale;
  o.direction = down ? -1 : +1;
  o.orbit.orbit.tol = tol;
  o.orbit.orbit.max_iterations = max_iter;
  o.orbit.orbit.samples = samples;
  o.orbit.periods = periods;
  o.orbit.period = period;
  if (sensitivities) o.orbit.orbit.provider = &sens;
  o.special = special;
  o.switch_offset = switch_offset;
  o.switch_eps = switch_eps;
  const std::string resolved = to_toml(c.spec);
  std::optional<CaseBranch> old;
  if (earlier) {
    const std::string what = resume ? "resume" : "switch";
    if ((*earlier)[2].cast<std::string>() != resolved)
      throw CaseError({{"rubdyn.branch", 0, what, "",
                        "the earlier branch is of another case or other settings (its resolved "
                        "case differs from this call's, with its overrides and tolerances)"}});
    old = read_case_branch((*earlier)[0].cast<std::string>(), (*earlier)[1].cast<std::string>(),
                           "<rubdyn.Branch>");
    (resume ? o.resume : o.switch_from) = &*old;
  }
  if (auto bad = branch_issues(c.spec, o); !bad.empty()) throw CaseError(std::move(bad));
  std::atomic<bool> stop{false};
  o.orbit.stop = &stop;
  CaseBranch b;
  if (run_interruptibly(stop, [&] {
        b = find_case_branch(c.text, c.path.empty() ? std::string("<string>") : c.path, c.overrides,
                             o);
      }))
    raise_keyboard_interrupt();
  return py::make_tuple(branch_json(b), branch_csv(b), exit_code(b), resolved);
}

/// rubdyn.orbit: the case's forced orbit (analysis/orbit_case.hpp), searched on a worker thread
/// as run_case runs (Ctrl-C raises the stop flag; the search ends at its running run). Returns
/// (orbit.json's text, the sampled period's columns, its events, its summary.json, the
/// monodromy matrix, the CLI's exit code).
py::tuple orbit_case(const Case& c, int periods, int settle, double tol, int max_iter, int samples,
                     double period, bool sensitivities) {
  static const SensitivityMonodromy sens;
  CaseOrbitOptions o;
  if (sensitivities) o.orbit.provider = &sens;
  o.period = period;
  o.periods = periods;
  o.settle = settle;
  o.orbit.tol = tol;
  o.orbit.max_iterations = max_iter;
  o.orbit.samples = samples;
  std::atomic<bool> stop{false};
  o.stop = &stop;
  CaseOrbit r;
  if (run_interruptibly(stop, [&] { r = find_case_orbit(c.spec, o); })) raise_keyboard_interrupt();
  const FlowRun& run = r.result.orbit;
  return py::make_tuple(orbit_json(c.spec, r),
                        series_dict(series_table(*r.model, run.samples, c.spec.output.coordinates)),
                        event_columns_of(run.events, r.model->contact_count()),
                        summary_json(run.summary), Mat(r.result.monodromy.M), exit_code(r.result));
}

/// A numpy array (any real dtype, any stride) as a vector of doubles; `what` names it in errors.
std::vector<double> doubles(const py::handle& h, const std::string& what) {
  py::array_t<double, py::array::c_style | py::array::forcecast> a;
  try {
    a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(h);
  } catch (const py::error_already_set&) {
  }
  if (!a) throw py::type_error(what + ": not an array of numbers");
  if (a.ndim() != 1) {
    throw py::value_error(what + ": " + std::to_string(a.ndim()) +
                          "-dimensional, a column is one-dimensional");
  }
  return std::vector<double>(a.data(), a.data() + a.size());
}

/// A Series from Python's arrays (compare_solutions checks lengths, times and windows).
Series series_from(const std::string& source, const py::handle& t,
                   const std::vector<std::string>& names, const py::list& values) {
  Series s;
  s.source = source;
  s.t = doubles(t, source + "['t']");
  s.names = names;
  if (names.size() != values.size()) throw py::value_error(source + ": names and values differ");
  for (std::size_t c = 0; c < names.size(); ++c)
    s.values.push_back(doubles(values[c], source + "['" + names[c] + "']"));
  return s;
}

std::vector<TimedEvent> events_from(const std::vector<std::pair<double, std::string>>& ev) {
  std::vector<TimedEvent> out;
  out.reserve(ev.size());
  for (const auto& [t, kind] : ev) out.push_back({t, kind});
  return out;
}

py::dict campbell_dict(const CampbellDiagram& d) {
  py::dict r;
  auto arr = [](const std::vector<double>& v) { return to_array(std::vector<double>(v)); };
  r["damped"] = d.damped;
  r["omega"] = arr(d.omega);
  r["labels"] = d.labels;
  for (std::size_t k = 0; k < d.labels.size(); ++k) {
    r[py::str(d.labels[k])] = arr(d.f[k]);
    if (d.damped) r[py::str("zeta_" + d.labels[k].substr(1))] = arr(d.zeta[k]);
  }
  r["labels_ok"] = d.labels_ok();
  r["unlabelled"] = arr(d.unlabelled);
  r["csv"] = campbell_csv(d);
  return r;
}

/// Samples held in memory (columns named as in timeseries.csv, phase as codes) as a RunRecord
/// of the case's model.
RunRecord record_of_columns(const Case& c, const py::dict& columns, const std::string& source) {
  auto col = [&](const char* name) {
    if (!columns.contains(name)) throw py::value_error(std::string("no column ") + name);
    return columns[name].cast<py::array_t<double, py::array::forcecast>>();
  };
  const auto t = col("t");
  const std::size_t n = static_cast<std::size_t>(t.size());
  RunRecord r;
  r.dir = source;  // names the samples in messages
  r.spec = c.spec;
  const std::unique_ptr<LagrangianModel> model = build_model(c.spec);
  // the columns the case writes (output.coordinates); a coordinate it does not write is NaN
  SeriesTable tab;
  tab.columns = timeseries_columns(*model, c.spec.output.coordinates);
  for (const SampleColumn& sc : tab.columns) {
    const auto a = col(sc.name.c_str());
    if (static_cast<std::size_t>(a.size()) != n)
      throw py::value_error("column " + sc.name + " is not as long as t");
    std::vector<double> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = a.at(static_cast<py::ssize_t>(i));
    tab.values.push_back(std::move(v));
  }
  try {
    r.samples = samples_of(*model, tab);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
  r.every_coordinate = writes_every_coordinate(*model, c.spec.output.coordinates);
  return r;
}

/// The centres of contact plane `plane` (1-based) at every sample (LagrangianModel::
/// plane_motion): the rotor's point x_r, y_r and the ring's centre x_s, y_s, with their rates.
py::dict plane_columns(const Case& c, const py::dict& columns, int plane) {
  const RunRecord r = record_of_columns(c, columns, "result");
  const std::unique_ptr<LagrangianModel> model = build_model(c.spec);
  if (plane < 1 || plane > model->contact_count())
    throw py::value_error(fmt::format("plane {}: the model '{}' has {} contact plane(s)", plane,
                                      model->name(), model->contact_count()));
  const std::size_t n = r.samples.size();
  std::vector<std::vector<double>> cols(8, std::vector<double>(n));
  PlaneMotion pm;
  for (std::size_t i = 0; i < n; ++i) {
    const Sample& s = r.samples[i];
    if (!model->plane_motion(plane - 1, s.t, s.q, s.v, pm))
      throw py::value_error(fmt::format("plane {}: the model '{}' does not locate its centres",
                                        plane, model->name()));
    const double x[8] = {pm.rotor.x(),  pm.rotor.y(),  pm.rotor_rate.x(),  pm.rotor_rate.y(),
                         pm.stator.x(), pm.stator.y(), pm.stator_rate.x(), pm.stator_rate.y()};
    for (int k = 0; k < 8; ++k) cols[static_cast<std::size_t>(k)][i] = x[k];
  }
  const char* names[8] = {"x_r", "y_r", "vx_r", "vy_r", "x_s", "y_s", "vx_s", "vy_s"};
  py::dict out;
  for (int k = 0; k < 8; ++k)
    out[names[k]] = to_array(std::move(cols[static_cast<std::size_t>(k)]));
  return out;
}

/// `rubdyn analyze` on samples held in memory (columns named as in timeseries.csv, phase as
/// codes) for contact plane `plane` (1-based): the verdicts as analysis.json writes them, and
/// derived.csv's columns.
py::tuple analyze_columns(const Case& c, const py::dict& columns, long events, double min_turns,
                          std::optional<double> t0, std::optional<double> t1,
                          const std::string& source, int plane) {
  AnalysisOptions o;
  o.min_turns = min_turns;
  o.t0 = t0;
  o.t1 = t1;
  const auto bad = analysis_option_problems(o);
  if (!bad.empty()) throw py::value_error(bad.front());
  RunRecord r = record_of_columns(c, columns, source);
  r.events = events;
  std::vector<DerivedSample> d;
  try {
    d = derive(r, plane - 1);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
  const RunVerdicts v = verdicts(r, d, o);
  py::dict out;
  auto number = [&](const char* name, auto get) {
    std::vector<double> a(d.size());
    for (std::size_t i = 0; i < d.size(); ++i) a[i] = get(d[i]);
    out[name] = to_array(std::move(a));
  };
  auto words = [&](const char* name, auto get) {
    py::list l;
    for (const auto& x : d) l.append(py::str(std::string(get(x))));
    out[name] = l;
  };
  number("t", [](const DerivedSample& x) { return x.t; });
  number("omega", [](const DerivedSample& x) { return x.omega; });
  number("precession", [](const DerivedSample& x) { return x.precession; });
  number("precession_ratio", [](const DerivedSample& x) { return x.precession_ratio; });
  words("whirl", [](const DerivedSample& x) { return to_string(x.whirl); });
  words("regime", [](const DerivedSample& x) { return to_string(x.regime); });
  number("dN_over_g0", [](const DerivedSample& x) { return x.dN_over_g0; });
  number("friction_torque_ratio", [](const DerivedSample& x) { return x.friction_torque_ratio; });
  number("sustained", [](const DerivedSample& x) { return x.sustained ? 1.0 : 0.0; });
  number("sign_run", [](const DerivedSample& x) { return x.sign_run ? 1.0 : 0.0; });
  return py::make_tuple(verdicts_json(v), out);
}

py::dict kinematics_dict(const ContactKinematics& k) {
  py::dict d;
  d["d_N"] = k.d_N;
  d["W_N"] = k.W_N;
  d["W_T"] = k.W_T;
  d["v_N"] = k.v_N;
  d["v_t"] = k.v_t;
  d["b_N"] = k.b_N;
  d["b_T"] = k.b_T;
  d["wdot_N"] = k.wdot_N;
  d["wdot_T"] = k.wdot_T;
  d["normal_defined"] = k.normal_defined;
  return d;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "rubdyn's C++ library (use the package rubdyn, not this module directly)";

  // CaseError(ValueError): str() is the CLI's message; .issues lists (file, line, key, value,
  // rule) dicts.
  static py::exception<CaseError> case_error(m, "CaseError", PyExc_ValueError);
  // ReadError(ValueError): a malformed output folder or CSV file; str() is the CLI's message
  // ("file:line: problem"), .file and .line (0: the file as a whole) name the place.
  static py::exception<ReadError> read_error(m, "ReadError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ReadError& e) {
      py::object exc = py::handle(read_error.ptr())(py::str(e.what()));
      exc.attr("file") = py::str(e.file());
      exc.attr("line") = e.line();
      PyErr_SetObject(read_error.ptr(), exc.ptr());
    } catch (const CaseError& e) {
      py::list issues;
      for (const auto& i : e.issues()) {
        py::dict d;
        d["file"] = i.file;
        d["line"] = i.line;
        d["key"] = i.key;
        d["value"] = i.value;
        d["rule"] = i.rule;
        d["message"] = format_issue(i);
        issues.append(d);
      }
      py::object exc = py::handle(case_error.ptr())(py::str(e.what()));
      exc.attr("issues") = issues;
      PyErr_SetObject(case_error.ptr(), exc.ptr());
    }
  });

  py::class_<Case>(m, "Case", "A validated case (load it with rubdyn.load_case)")
      .def_property_readonly("name", [](const Case& c) { return c.spec.name; })
      .def_property_readonly("source", [](const Case& c) { return c.spec.source; })
      .def_property_readonly("path", [](const Case& c) { return c.path; })
      .def_property_readonly("overrides", [](const Case& c) { return c.overrides; })
      .def_property_readonly("solver", [](const Case& c) { return c.spec.solver.kind; })
      .def_property_readonly("rtol", [](const Case& c) { return c.spec.solver.rtol; })
      .def_property_readonly("h", [](const Case& c) { return c.spec.solver.h; })
      .def_property_readonly("t_end", [](const Case& c) { return c.spec.run.t_end; })
      .def_property_readonly("omega_lim", [](const Case& c) { return c.spec.run.omega_lim; })
      .def_property_readonly("output_dt", [](const Case& c) { return c.spec.output.dt; })
      .def_property_readonly(
          "kind", [](const Case& c) { return c.spec.model; },
          "[model] kind: \"rigid-rotor\", \"jeffcott\" or \"matrices\"")
      .def_property_readonly("model",
                             [](const Case& c) { return std::string(build_model(c.spec)->name()); })
      .def(
          "values",
          [](const Case& c) {
            py::dict d;
            for (const CaseEntry& e : case_values(c.spec)) d[py::str(e.full())] = e.value;
            return d;
          },
          "Every key of the case (\"section.key\") with its value, defaults and overrides "
          "filled in: case.resolved.toml as a dict")
      .def(
          "__getitem__",
          [](const Case& c, const std::string& key) {
            for (const CaseEntry& e : case_values(c.spec))
              if (e.full() == key) return py::cast(e.value);
            throw py::key_error(key + ": not a key of this " + c.spec.model +
                                " case (Case.values() lists them)");
          },
          "The value of one key, e.g. case[\"rotor.mass\"]")
      .def_property_readonly("gap", [](const Case& c) { return build_model(c.spec)->gap_scale(0); })
      .def_property_readonly("radius",
                             [](const Case& c) { return build_model(c.spec)->contact_radius(0); })
      .def_property_readonly("mu",
                             [](const Case& c) { return build_model(c.spec)->contact_law(0).mu; })
      .def_property_readonly("torque", [](const Case& c) { return nominal_torque(c.spec); })
      .def_property_readonly(
          "contacts",
          [](const Case& c) {
            const auto model = build_model(c.spec);
            py::list out;
            for (int k = 0; k < model->contact_count(); ++k) {
              py::dict d;
              d["gap"] = model->gap_scale(k);
              d["radius"] = model->contact_radius(k);
              d["mu"] = model->contact_law(k).mu;
              d["e_n"] = model->contact_law(k).e_n;
              d["e_t"] = model->contact_law(k).e_t;
              out.append(d);
            }
            return out;
          },
          "Each contact plane's gap, seal radius and law (gap, radius, mu, e_n, e_t), in the "
          "order of the columns d_N_1, ...")
      .def_property_readonly("q0", [](const Case& c) { return Vec(c.spec.initial.q0); })
      .def_property_readonly("v0", [](const Case& c) { return Vec(c.spec.initial.v0); })
      .def_property_readonly(
          "columns",
          [](const Case& c) {
            std::vector<std::string> names;
            for (const auto& sc :
                 timeseries_columns(*build_model(c.spec), c.spec.output.coordinates))
              names.push_back(sc.name);
            return names;
          },
          "timeseries.csv's columns for this case (its model, output.coordinates)")
      .def_property_readonly("output_folder", [](const Case& c) { return output_folder(c.spec); })
      .def(
          "to_toml", [](const Case& c) { return to_toml(c.spec); },
          "The case with every default and override filled in (case.resolved.toml)")
      .def("__repr__", [](const Case& c) {
        return "<rubdyn.Case " + c.spec.name + " from " + c.spec.source + ">";
      });

  m.def(
      "solvers",
      [] {
        py::list out;
        for (const auto& e : solver_registry()) {
          py::dict d;
          d["name"] = std::string(e.name);
          d["summary"] = std::string(e.summary);
          d["fixed_step"] = e.fixed_step;
          py::list keys;
          for (const auto k : e.keys) keys.append(std::string(k));
          d["keys"] = keys;
          out.append(d);
        }
        return out;
      },
      "The solver registry (io/solver_options.hpp): name, summary, fixed_step, the [solver] keys "
      "each reads");
  m.def("load_case", &make_case_from_file, py::arg("path"),
        py::arg("overrides") = std::vector<std::string>{});
  m.def(
      "parse_case",
      [](const std::string& text, const std::string& source,
         const std::vector<std::string>& overrides) {
        return make_case_from_text(text, source, overrides);
      },
      py::arg("text"), py::arg("source") = "<string>",
      py::arg("overrides") = std::vector<std::string>{});
  m.def("with_overrides", &with_overrides, py::arg("case"), py::arg("overrides"));
  m.def("analyze", &analyze_columns, py::arg("case"), py::arg("columns"), py::arg("events"),
        py::arg("min_turns"), py::arg("t0") = py::none(), py::arg("t1") = py::none(),
        py::arg("source") = "result", py::arg("plane") = 1);
  m.def("plane_columns", &plane_columns, py::arg("case"), py::arg("columns"), py::arg("plane"),
        "The centres of contact plane `plane` (1-based) at every sample: x_r, y_r, vx_r, vy_r "
        "(the rotor's point), x_s, y_s, vx_s, vy_s (the ring's centre; 0 for a fixed ring)");
  m.def("run", &run_case, py::arg("case"), py::arg("progress") = py::none(),
        py::arg("progress_interval") = 0.1,
        "(columns, events, summary_json) of one run; the GIL is released while it runs");

  m.def("orbit", &orbit_case, py::arg("case"), py::arg("periods") = 1, py::arg("settle") = 0,
        py::arg("tol") = OrbitOptions{}.tol, py::arg("max_iter") = OrbitOptions{}.max_iterations,
        py::arg("samples") = OrbitOptions{}.samples,
        py::arg("period") = std::numeric_limits<double>::quiet_NaN(),
        py::arg("sensitivities") = false,
        "(orbit_json, columns, events, summary_json, monodromy, exit_code) of `rubdyn orbit`");
  m.def("branch", &branch_case, py::arg("case"), py::arg("key"), py::arg("to"), py::arg("points"),
        py::arg("ds"), py::arg("ds_max"), py::arg("scale"), py::arg("down"), py::arg("tol"),
        py::arg("max_iter"), py::arg("samples"), py::arg("periods") = 1,
        py::arg("period") = std::numeric_limits<double>::quiet_NaN(),
        py::arg("sensitivities") = false, py::arg("earlier") = py::none(),
        py::arg("resume") = false, py::arg("special") = -1,
        py::arg("switch_offset") = std::numeric_limits<double>::quiet_NaN(),
        py::arg("switch_eps") = 0.05,
        "(branch_json, branch_csv, exit_code, resolved_case) of `rubdyn branch`");

  m.def(
      "campbell",
      [](const Case& c, std::optional<double> omega_max, int points, bool damped) {
        // the CLI's linear model (tied, or free where no tied system exists); CaseError
        const CampbellModel cm = campbell_model(c.spec);
        py::dict d = campbell_dict(compute_campbell_diagram(
            cm.lm, omega_max.value_or(c.spec.run.omega_lim), points, damped));
        d["tied"] = cm.tied;
        return d;
      },
      py::arg("case"), py::arg("omega_max") = py::none(), py::arg("points") = 201,
      py::arg("damped") = false);

  // rubdyn.read: the C++ reader of output folders (io/output_reader.hpp), the one the CLI uses.
  m.def(
      "read_run",
      [](const std::string& dir) {
        RunFiles f;
        {
          py::gil_scoped_release release;
          f = read_run_files(dir);  // ReadError (file, line, column) or CaseError
        }
        const int contacts = f.model->contact_count();
        py::object summary = py::none();
        if (!f.summary_json.empty()) summary = py::str(f.summary_json);
        return py::make_tuple(series_dict(std::move(f.series)),
                              event_columns_of(f.events, contacts), summary, f.warnings);
      },
      py::arg("dir"),
      "(columns, events, summary_json or None, warnings) of an output folder, read by the C++ "
      "reader (io/output_reader.hpp): the columns by the model's column table, the events by "
      "events.csv's; a cut last row is dropped with a warning");

  // rubdyn compare: the C++ readers (compare.hpp's read_series / read_events, which read through
  // io/output_reader's CSV reader, exactly as `rubdyn compare` reads) and measures, returned as
  // comparison_json's text and the CLI's report.
  m.def(
      "read_solution",
      [](const std::string& path) {
        Series s;
        std::vector<TimedEvent> ev;
        {
          py::gil_scoped_release release;
          s = read_series(path);
          ev = read_events(path);
        }
        py::list values;
        for (auto& v : s.values) values.append(to_array(std::move(v)));
        py::list events;
        for (const auto& e : ev) events.append(py::make_tuple(e.t, e.kind));
        return py::make_tuple(to_array(std::move(s.t)), s.names, values, events, s.warnings);
      },
      py::arg("path"),
      "(t, names, values, events, warnings) of an output folder or CSV file, read as `rubdyn "
      "compare` reads it");
  m.def(
      "compare_series",
      [](const std::string& name_a, const py::handle& t_a, const std::vector<std::string>& names_a,
         const py::list& values_a, const std::vector<std::pair<double, std::string>>& events_a,
         const std::string& name_b, const py::handle& t_b, const std::vector<std::string>& names_b,
         const py::list& values_b, const std::vector<std::pair<double, std::string>>& events_b,
         std::optional<std::pair<double, double>> window, double event_tol) {
        const Series a = series_from(name_a, t_a, names_a, values_a);
        const Series b = series_from(name_b, t_b, names_b, values_b);
        const Comparison c = compare_solutions(a, b, events_from(events_a), events_from(events_b),
                                               window, event_tol);
        return py::make_tuple(comparison_json(c, name_a, name_b),
                              comparison_report(c, name_a, name_b));
      },
      py::arg("name_a"), py::arg("t_a"), py::arg("names_a"), py::arg("values_a"),
      py::arg("events_a"), py::arg("name_b"), py::arg("t_b"), py::arg("names_b"),
      py::arg("values_b"), py::arg("events_b"), py::arg("window") = py::none(),
      py::arg("event_tol") = 1e-3);

  // The model's mechanics, for a user's own time-stepping scheme (any model of the registry):
  //   M(q) dv/dt = f(t, q, v) + W_N(q) F_N + W_T(q) F_T,  dq/dt = v.
  using ModelPtr = std::shared_ptr<LagrangianModel>;
  auto check_size = [](const ModelPtr& m, const Vec& x, const char* what) {
    if (x.size() != m->num_dofs()) throw py::value_error(fmt_size(what, x.size(), m->num_dofs()));
  };
  py::class_<LagrangianModel, ModelPtr>(
      m, "Model", "The model of a case (any [model] kind): M(q), f(t, q, v), contact, coordinates")
      .def(py::init([](const Case& c) { return ModelPtr(build_model(c.spec)); }), py::arg("case"))
      .def_property_readonly("name", [](const ModelPtr& mdl) { return std::string(mdl->name()); })
      .def_property_readonly("num_dofs", [](const ModelPtr& mdl) { return mdl->num_dofs(); })
      .def_property_readonly(
          "coordinates",
          [](const ModelPtr& mdl) {
            py::list l;
            for (const auto& c : mdl->coordinates()) {
              py::dict d;
              d["name"] = c.name;
              d["rate"] = c.rate;
              d["rate_key"] = c.rate_key;
              d["unit"] = c.unit;
              d["meaning"] = c.meaning;
              d["role"] = std::string(to_string(c.role));
              d["plane"] = c.plane;
              l.append(d);
            }
            return l;
          },
          "the coordinates in q order: name, rate, rate_key, unit, meaning, role, plane")
      .def_property_readonly("position_names",
                             [](const ModelPtr& mdl) {
                               std::vector<std::string> n;
                               for (const auto& c : mdl->coordinates()) n.push_back(c.name);
                               return n;
                             })
      .def_property_readonly("rate_names",
                             [](const ModelPtr& mdl) {
                               std::vector<std::string> n;
                               for (const auto& c : mdl->coordinates()) n.push_back(c.rate);
                               return n;
                             })
      .def_property_readonly("columns",
                             [](const ModelPtr& mdl) {
                               std::vector<std::string> n;
                               for (const auto& c : timeseries_columns(*mdl)) n.push_back(c.name);
                               return n;
                             })
      .def(
          "mass_matrix",
          [check_size](const ModelPtr& mdl, const Vec& q) {
            check_size(mdl, q, "q");
            Mat M(mdl->num_dofs(), mdl->num_dofs());
            mdl->mass_matrix(q, M);
            return M;
          },
          py::arg("q"), "M(q) [n x n]")
      .def(
          "smooth_forces",
          [check_size](const ModelPtr& mdl, double t, const Vec& q, const Vec& v) {
            check_size(mdl, q, "q");
            check_size(mdl, v, "v");
            Vec f(mdl->num_dofs());
            mdl->smooth_forces(t, q, v, f);
            return f;
          },
          py::arg("t"), py::arg("q"), py::arg("v"),
          "f(t, q, v): loads, gyroscopic, damping, stiffness, gravity (no contact)")
      .def(
          "smooth_force_jacobians",
          [check_size](const ModelPtr& mdl, double t, const Vec& q, const Vec& v) {
            check_size(mdl, q, "q");
            check_size(mdl, v, "v");
            const int n = mdl->num_dofs();
            Mat dq(n, n), dv(n, n);
            mdl->smooth_force_jacobians(t, q, v, dq, dv);
            return py::make_tuple(dq, dv);
          },
          py::arg("t"), py::arg("q"), py::arg("v"), "(df/dq, df/dv)")
      .def(
          "contact",
          [check_size](const ModelPtr& mdl, const Vec& q, const Vec& v, double t, int k) {
            check_size(mdl, q, "q");
            check_size(mdl, v, "v");
            if (k < 0 || k >= mdl->contact_count()) throw py::index_error("no such contact");
            ContactKinematics c(mdl->num_dofs());
            mdl->compute_contact(k, t, q, v, c);
            return kinematics_dict(c);
          },
          py::arg("q"), py::arg("v"), py::arg("t") = 0.0, py::arg("k") = 0,
          "dict d_N, W_N, W_T, v_N, v_t, b_N, b_T, wdot_N, wdot_T, normal_defined of contact k "
          "(see contact_kinematics.hpp)")
      .def(
          "potential_energy",
          [check_size](const ModelPtr& mdl, const Vec& q, double t) {
            check_size(mdl, q, "q");
            return mdl->potential_energy(t, q);
          },
          py::arg("q"), py::arg("t") = 0.0)
      .def(
          "kinetic_energy",
          [check_size](const ModelPtr& mdl, const Vec& q, const Vec& v, double t) {
            check_size(mdl, q, "q");
            check_size(mdl, v, "v");
            return mdl->kinetic_energy(t, q, v);
          },
          py::arg("q"), py::arg("v"), py::arg("t") = 0.0)
      .def(
          "linearize",
          [](const ModelPtr& mdl, const std::string& mode) -> py::object {
            if (mode != "tied" && mode != "free")
              throw py::value_error("mode must be 'tied' or 'free'");
            const auto lm =
                mdl->linearize(mode == "tied" ? Linearization::Tied : Linearization::Free);
            if (!lm) return py::none();
            py::dict d;
            d["names"] = lm->names;
            d["M"] = lm->M;
            d["G"] = lm->G;
            d["D"] = lm->D;
            d["K"] = lm->K;
            d["nodes"] = lm->nodes;
            return d;
          },
          py::arg("mode") = "tied",
          "M x'' + (Omega G + D) x' + K x = 0 about the centred position (dict), or None")
      .def_property_readonly("contact_count",
                             [](const ModelPtr& mdl) { return mdl->contact_count(); })
      .def_property_readonly("gap", [](const ModelPtr& mdl) { return mdl->gap_scale(0); })
      .def_property_readonly("radius", [](const ModelPtr& mdl) { return mdl->contact_radius(0); })
      .def_property_readonly("mu", [](const ModelPtr& mdl) { return mdl->contact_law(0).mu; })
      .def_property_readonly("e_n", [](const ModelPtr& mdl) { return mdl->contact_law(0).e_n; })
      .def_property_readonly("e_t", [](const ModelPtr& mdl) { return mdl->contact_law(0).e_t; })
      .def_property_readonly("spin_coordinate",
                             [](const ModelPtr& mdl) { return mdl->spin_coordinate(); });

  m.def(
      "event_fields",
      [](int contacts) {
        std::vector<std::string> n;
        for (const auto& c : event_columns(contacts)) n.push_back(c.name);
        return n;
      },
      py::arg("contacts") = 1, "events.csv's columns (io/columns.hpp)");
  std::vector<std::string> phases;
  for (int i = 0; i < kNumPhases; ++i) phases.emplace_back(to_string(static_cast<Phase>(i)));
  m.attr("PHASE_NAMES") = phases;
}
