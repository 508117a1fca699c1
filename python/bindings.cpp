// rubdyn._core: the C++ library seen from Python. Thin: loading a case (CaseError with every
// issue), one run into a MemorySink (GIL released), the summary and comparison as the C++ JSON
// writers produce them, the Campbell diagram and the model's mechanics for a user's own scheme.
// The Python package (python/rubdyn/) builds its results and plots on top of this.
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <exception>
#include <future>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rubdyn/analysis/campbell.hpp"
#include "rubdyn/analysis/compare.hpp"
#include "rubdyn/analysis/postprocess.hpp"
#include "rubdyn/core/run_types.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/output_folder.hpp"
#include "rubdyn/io/simulate.hpp"
#include "rubdyn/io/solver_registry.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"

namespace py = pybind11;
using namespace rubdyn;

namespace {

/// A validated case and how it was made: run() reloads the file with the extra overrides, as the
/// CLI does (load_case(path, --set ... + solver options)), so that the numbers are the CLI's.
struct Case {
  CaseSpec spec;
  std::string path;                    ///< empty when the case came from TOML text
  std::string text;                    ///< the TOML text (when path is empty)
  std::vector<std::string> overrides;  ///< "section.key=value"
};

Case make_case_from_file(const std::string& path, const std::vector<std::string>& overrides) {
  return Case{load_case(path, overrides), path, {}, overrides};
}

Case make_case_from_text(const std::string& text, const std::string& source,
                         const std::vector<std::string>& overrides) {
  Case c{parse_case(text, source, overrides), {}, text, overrides};
  c.spec.source = source;
  return c;
}

/// The case with more overrides on top (later ones win), loaded the way the CLI loads it.
Case with_overrides(const Case& c, const std::vector<std::string>& more) {
  std::vector<std::string> all = c.overrides;
  all.insert(all.end(), more.begin(), more.end());
  if (!c.path.empty()) return make_case_from_file(c.path, all);
  return make_case_from_text(c.text, c.spec.source, all);
}

template <class T>
py::array_t<T> to_array(std::vector<T>&& v) {
  py::array_t<T> a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

/// Samples as columns named as in timeseries.csv; phase as its code (Phase enum value).
py::dict sample_columns(const std::vector<Sample>& samples) {
  const std::size_t n = samples.size();
  py::dict d;
  auto column = [&](const char* name, auto get) {
    std::vector<double> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = get(samples[i]);
    d[name] = to_array(std::move(v));
  };
  column("t", [](const Sample& s) { return s.t; });
  for (int j = 0; j < kNumDofs; ++j) column(kDofNames[j], [j](const Sample& s) { return s.q[j]; });
  for (int j = 0; j < kNumDofs; ++j) column(kVelNames[j], [j](const Sample& s) { return s.v[j]; });
  column("d_N", [](const Sample& s) { return s.d_N; });
  column("v_N", [](const Sample& s) { return s.v_N; });
  column("v_t", [](const Sample& s) { return s.v_t; });
  column("F_N", [](const Sample& s) { return s.F_N; });
  column("F_T", [](const Sample& s) { return s.F_T; });
  std::vector<std::int8_t> phase(n);
  for (std::size_t i = 0; i < n; ++i) phase[i] = static_cast<std::int8_t>(samples[i].phase);
  d["phase"] = to_array(std::move(phase));
  return d;
}

/// Events as columns named as in events.csv (kinds and phases as the CSV's words).
py::dict event_columns(const std::vector<EventRecord>& events) {
  const std::size_t n = events.size();
  py::dict d;
  auto number = [&](const char* name, auto get) {
    std::vector<double> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = get(events[i]);
    d[name] = to_array(std::move(v));
  };
  auto text = [&](const char* name, auto get) {
    py::list l;
    for (const auto& e : events) l.append(py::str(std::string(get(e))));
    d[name] = l;
  };
  number("t", [](const EventRecord& e) { return e.t; });
  text("kind", [](const EventRecord& e) { return to_string(e.kind); });
  text("phase_before", [](const EventRecord& e) { return to_string(e.phase_before); });
  text("phase_after", [](const EventRecord& e) { return to_string(e.phase_after); });
  number("d_N", [](const EventRecord& e) { return e.d_N; });
  number("v_N_minus", [](const EventRecord& e) { return e.v_N_minus; });
  number("v_N_plus", [](const EventRecord& e) { return e.v_N_plus; });
  number("v_t_minus", [](const EventRecord& e) { return e.v_t_minus; });
  number("v_t_plus", [](const EventRecord& e) { return e.v_t_plus; });
  number("P_N", [](const EventRecord& e) { return e.P_N; });
  number("P_T", [](const EventRecord& e) { return e.P_T; });
  number("F_N", [](const EventRecord& e) { return e.F_N; });
  number("F_T", [](const EventRecord& e) { return e.F_T; });
  number("t_accumulation", [](const EventRecord& e) { return e.t_accumulation; });
  text("witness", [](const EventRecord& e) { return e.witness; });
  text("note", [](const EventRecord& e) { return e.note; });
  return d;
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
  std::exception_ptr callback_error, run_error;
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
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    auto done = std::async(std::launch::async, [&] {
      try {
        summary = simulate(c.spec, sink, fn, &stop);
      } catch (...) {
        run_error = std::current_exception();
      }
    });
    while (done.wait_for(std::chrono::milliseconds(50)) != std::future_status::ready) {
      py::gil_scoped_acquire acquire;
      if (PyErr_CheckSignals() != 0) {
        PyErr_Clear();  // raised again below, once the run has ended
        interrupted = true;
        stop = true;
      }
    }
  }
  if (run_error) std::rethrow_exception(run_error);
  if (callback_error) std::rethrow_exception(callback_error);
  if (interrupted) {
    PyErr_SetNone(PyExc_KeyboardInterrupt);
    throw py::error_already_set();
  }
  return py::make_tuple(sample_columns(sink.samples), event_columns(sink.events),
                        summary_json(summary));
}

Series series_from(const std::string& source, std::vector<double> t, std::vector<std::string> names,
                   std::vector<std::vector<double>> values) {
  Series s;
  s.source = source;
  s.t = std::move(t);
  s.names = std::move(names);
  s.values = std::move(values);
  if (s.names.size() != s.values.size()) throw std::invalid_argument("names and values differ");
  for (const auto& v : s.values) {
    if (v.size() != s.t.size()) throw std::invalid_argument("a column's length differs from t's");
  }
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
  for (const auto& [name, v] : {std::pair{"f1b", &d.f1b}, std::pair{"f1f", &d.f1f},
                                std::pair{"f2b", &d.f2b}, std::pair{"f2f", &d.f2f}}) {
    r[name] = arr(*v);
  }
  if (d.damped) {
    for (const auto& [name, v] :
         {std::pair{"zeta_1b", &d.zeta_1b}, std::pair{"zeta_1f", &d.zeta_1f},
          std::pair{"zeta_2b", &d.zeta_2b}, std::pair{"zeta_2f", &d.zeta_2f}}) {
      r[name] = arr(*v);
    }
  }
  r["labels_ok"] = d.labels_ok();
  r["unlabelled"] = arr(d.unlabelled);
  r["csv"] = campbell_csv(d);
  return r;
}

/// `rubdyn analyze` on samples held in memory (columns named as in timeseries.csv, phase as
/// codes): the verdicts as analysis.json writes them, and derived.csv's columns.
py::tuple analyze_columns(const Case& c, const py::dict& columns, long events, double min_turns,
                          std::optional<double> t0, std::optional<double> t1) {
  AnalysisOptions o;
  o.min_turns = min_turns;
  o.t0 = t0;
  o.t1 = t1;
  const auto bad = analysis_option_problems(o);
  if (!bad.empty()) throw py::value_error(bad.front());
  auto col = [&](const char* name) {
    if (!columns.contains(name)) throw py::value_error(std::string("no column ") + name);
    return columns[name].cast<py::array_t<double, py::array::forcecast>>();
  };
  const auto t = col("t");
  const std::size_t n = static_cast<std::size_t>(t.size());
  RunRecord r;
  r.dir = c.spec.source;
  r.spec = c.spec;
  r.events = events;
  r.samples.resize(n);
  auto fill = [&](const char* name, auto set) {
    const auto a = col(name);
    if (static_cast<std::size_t>(a.size()) != n)
      throw py::value_error(std::string("column ") + name + " is not as long as t");
    for (std::size_t i = 0; i < n; ++i) set(r.samples[i], a.at(static_cast<py::ssize_t>(i)));
  };
  fill("t", [](Sample& s, double x) { s.t = x; });
  for (int j = 0; j < kNumDofs; ++j) {
    fill(kDofNames[j], [j](Sample& s, double x) { s.q[j] = x; });
    fill(kVelNames[j], [j](Sample& s, double x) { s.v[j] = x; });
  }
  fill("d_N", [](Sample& s, double x) { s.d_N = x; });
  fill("v_N", [](Sample& s, double x) { s.v_N = x; });
  fill("v_t", [](Sample& s, double x) { s.v_t = x; });
  fill("F_N", [](Sample& s, double x) { s.F_N = x; });
  fill("F_T", [](Sample& s, double x) { s.F_T = x; });
  fill("phase", [](Sample& s, double x) {
    if (!(x >= 0 && x <= static_cast<double>(Phase::Stick) && x == static_cast<int>(x)))
      throw py::value_error("phase codes must be 0 (free) to 3 (stick)");
    s.phase = static_cast<Phase>(static_cast<int>(x));
  });
  std::vector<DerivedSample> d = derive(r);
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
  d["W_N"] = Vec7(k.W_N);
  d["W_T"] = Vec7(k.W_T);
  d["v_N"] = k.v_N;
  d["v_t"] = k.v_t;
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
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
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
      .def_property_readonly("gap", [](const Case& c) { return c.spec.params.stator.gap; })
      .def_property_readonly("radius", [](const Case& c) { return c.spec.params.rotor.radius; })
      .def_property_readonly("mu", [](const Case& c) { return c.spec.params.contact.mu; })
      .def_property_readonly("torque", [](const Case& c) { return c.spec.params.loads.torque; })
      .def_property_readonly("q0", [](const Case& c) { return Vec7(c.spec.initial.q0); })
      .def_property_readonly("v0", [](const Case& c) { return Vec7(c.spec.initial.v0); })
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
      "The solver registry (io/solver_registry.hpp): name, summary, fixed_step, the [solver] keys "
      "each reads");
  m.def("load_case", &make_case_from_file, py::arg("path"),
        py::arg("overrides") = std::vector<std::string>{});
  m.def("parse_case", &make_case_from_text, py::arg("text"), py::arg("source") = "<string>",
        py::arg("overrides") = std::vector<std::string>{});
  m.def("with_overrides", &with_overrides, py::arg("case"), py::arg("overrides"));
  m.def("analyze", &analyze_columns, py::arg("case"), py::arg("columns"), py::arg("events"),
        py::arg("min_turns"), py::arg("t0") = py::none(), py::arg("t1") = py::none());
  m.def("run", &run_case, py::arg("case"), py::arg("progress") = py::none(),
        py::arg("progress_interval") = 0.1,
        "(columns, events, summary_json) of one run; the GIL is released while it runs");

  m.def(
      "campbell",
      [](const Case& c, std::optional<double> omega_max, int points, bool damped) {
        return campbell_dict(compute_campbell_diagram(
            c.spec.params, omega_max.value_or(c.spec.run.omega_lim), points, damped));
      },
      py::arg("case"), py::arg("omega_max") = py::none(), py::arg("points") = 201,
      py::arg("damped") = false);

  // rubdyn compare: the C++ readers and measures, returned as comparison_json's text and the
  // CLI's report.
  m.def(
      "compare_paths",
      [](const std::string& a, const std::string& b,
         std::optional<std::pair<double, double>> window, double event_tol) {
        const Comparison c = compare_solutions(read_series(a), read_series(b), read_events(a),
                                               read_events(b), window, event_tol);
        return py::make_tuple(comparison_json(c, a, b), comparison_report(c, a, b));
      },
      py::arg("a"), py::arg("b"), py::arg("window") = py::none(), py::arg("event_tol") = 1e-3);
  m.def(
      "compare_series",
      [](const std::string& name_a, std::vector<double> t_a, std::vector<std::string> names_a,
         std::vector<std::vector<double>> values_a,
         const std::vector<std::pair<double, std::string>>& events_a, const std::string& name_b,
         std::vector<double> t_b, std::vector<std::string> names_b,
         std::vector<std::vector<double>> values_b,
         const std::vector<std::pair<double, std::string>>& events_b,
         std::optional<std::pair<double, double>> window, double event_tol) {
        const Series a =
            series_from(name_a, std::move(t_a), std::move(names_a), std::move(values_a));
        const Series b =
            series_from(name_b, std::move(t_b), std::move(names_b), std::move(values_b));
        const Comparison c = compare_solutions(a, b, events_from(events_a), events_from(events_b),
                                               window, event_tol);
        return py::make_tuple(comparison_json(c, name_a, name_b),
                              comparison_report(c, name_a, name_b));
      },
      py::arg("name_a"), py::arg("t_a"), py::arg("names_a"), py::arg("values_a"),
      py::arg("events_a"), py::arg("name_b"), py::arg("t_b"), py::arg("names_b"),
      py::arg("values_b"), py::arg("events_b"), py::arg("window") = py::none(),
      py::arg("event_tol") = 1e-3);

  // The model's mechanics, for a user's own time-stepping scheme:
  //   M(q) dv/dt = f(t, q, v) + W_N(q) F_N + W_T(q) F_T,  dq/dt = v.
  py::class_<RotorStatorModel>(m, "Model",
                               "The rotor-stator model of a case: M(q), f(t, q, v), contact")
      .def(py::init([](const Case& c) { return RotorStatorModel(c.spec.params); }), py::arg("case"))
      .def(
          "mass_matrix",
          [](const RotorStatorModel& mdl, const Vec7& q) {
            Mat7 M;
            mdl.mass_matrix(q, M);
            return M;
          },
          py::arg("q"), "M(q) [7x7]")
      .def(
          "smooth_forces",
          [](const RotorStatorModel& mdl, double t, const Vec7& q, const Vec7& v) {
            Vec7 f;
            mdl.smooth_forces(t, q, v, f);
            return f;
          },
          py::arg("t"), py::arg("q"), py::arg("v"),
          "f(t, q, v): loads, gyroscopic, damping, stiffness, gravity (no contact)")
      .def(
          "smooth_force_jacobians",
          [](const RotorStatorModel& mdl, double t, const Vec7& q, const Vec7& v) {
            Mat7 dq, dv;
            mdl.smooth_force_jacobians(t, q, v, dq, dv);
            return py::make_tuple(dq, dv);
          },
          py::arg("t"), py::arg("q"), py::arg("v"), "(df/dq, df/dv)")
      .def(
          "contact",
          [](const RotorStatorModel& mdl, const Vec7& q, const Vec7& v) {
            return kinematics_dict(mdl.contact(q, v));
          },
          py::arg("q"), py::arg("v"),
          "dict d_N, W_N, W_T, v_N, v_t, wdot_N, wdot_T, normal_defined (see "
          "contact_kinematics.hpp)")
      .def("potential_energy", &RotorStatorModel::potential_energy, py::arg("q"))
      .def("kinetic_energy", &RotorStatorModel::kinetic_energy, py::arg("q"), py::arg("v"))
      .def_property_readonly("gap", &RotorStatorModel::gap_scale)
      .def_property_readonly("mu", [](const RotorStatorModel& mdl) { return mdl.contact_law().mu; })
      .def_property_readonly("e_n",
                             [](const RotorStatorModel& mdl) { return mdl.contact_law().e_n; })
      .def_property_readonly("e_t",
                             [](const RotorStatorModel& mdl) { return mdl.contact_law().e_t; })
      .def_property_readonly("spin_coordinate", &RotorStatorModel::spin_coordinate)
      .def_property_readonly("G", [](const RotorStatorModel& mdl) { return Mat7(mdl.G()); })
      .def_property_readonly("D", [](const RotorStatorModel& mdl) { return Mat7(mdl.D()); })
      .def_property_readonly("K", [](const RotorStatorModel& mdl) { return Mat7(mdl.K()); })
      .def_property_readonly("f_ext",
                             [](const RotorStatorModel& mdl) { return Vec7(mdl.f_ext()); });

  m.attr("DOF_NAMES") = std::vector<std::string>(kDofNames, kDofNames + kNumDofs);
  m.attr("VEL_NAMES") = std::vector<std::string>(kVelNames, kVelNames + kNumDofs);
  std::vector<std::string> phases;
  for (int i = 0; i < kNumPhases; ++i) phases.emplace_back(to_string(static_cast<Phase>(i)));
  m.attr("PHASE_NAMES") = phases;
}
