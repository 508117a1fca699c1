// Case files: TOML -> CaseSpec with complete validation, and CaseSpec -> TOML.
// The only file of the project that includes the TOML parser.
#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/solver_registry.hpp"
#include "rubdyn/io/text_files.hpp"
#include "rubdyn/stepping/fixed_step.hpp"

namespace rubdyn {

namespace {

enum class Kind { Number, Integer, String };

/// One key of the schema: where it goes in CaseSpec, whether it is required, its type.
struct KeySpec {
  const char* section;
  const char* key;
  Kind kind;
  bool required;
  std::function<double*(CaseSpec&)> num;        // Number
  std::function<int*(CaseSpec&)> integer;       // Integer
  std::function<std::string*(CaseSpec&)> text;  // String
};

const std::vector<KeySpec>& schema() {
  static const std::vector<KeySpec> s = [] {
    std::vector<KeySpec> v;
    auto num = [&v](const char* sec, const char* key, bool req,
                    std::function<double*(CaseSpec&)> f) {
      v.push_back({sec, key, Kind::Number, req, std::move(f), {}, {}});
    };
    auto integer = [&v](const char* sec, const char* key, std::function<int*(CaseSpec&)> f) {
      v.push_back({sec, key, Kind::Integer, false, {}, std::move(f), {}});
    };
    auto text = [&v](const char* sec, const char* key, std::function<std::string*(CaseSpec&)> f) {
      v.push_back({sec, key, Kind::String, false, {}, {}, std::move(f)});
    };
    num("rotor", "mass", true, [](CaseSpec& c) { return &c.params.rotor.mass; });
    num("rotor", "Jd", true, [](CaseSpec& c) { return &c.params.rotor.Jd; });
    num("rotor", "Jp", true, [](CaseSpec& c) { return &c.params.rotor.Jp; });
    num("rotor", "L", true, [](CaseSpec& c) { return &c.params.rotor.L; });
    num("rotor", "delta", true, [](CaseSpec& c) { return &c.params.rotor.delta; });
    num("rotor", "d", true, [](CaseSpec& c) { return &c.params.rotor.d; });
    num("rotor", "radius", true, [](CaseSpec& c) { return &c.params.rotor.radius; });
    num("bearing", "k", true, [](CaseSpec& c) { return &c.params.bearing.k; });
    num("bearing", "c", true, [](CaseSpec& c) { return &c.params.bearing.c; });
    num("stator", "mass", true, [](CaseSpec& c) { return &c.params.stator.mass; });
    num("stator", "k", true, [](CaseSpec& c) { return &c.params.stator.k; });
    num("stator", "c", true, [](CaseSpec& c) { return &c.params.stator.c; });
    num("stator", "gap", true, [](CaseSpec& c) { return &c.params.stator.gap; });
    num("contact", "mu", true, [](CaseSpec& c) { return &c.params.contact.mu; });
    num("contact", "e_n", false, [](CaseSpec& c) { return &c.params.contact.e_n; });
    num("contact", "e_t", false, [](CaseSpec& c) { return &c.params.contact.e_t; });
    num("loads", "gravity", true, [](CaseSpec& c) { return &c.params.loads.gravity; });
    num("loads", "torque", true, [](CaseSpec& c) { return &c.params.loads.torque; });
    // the keys of the initial state are the model's coordinates and their rates
    static const RotorStatorModel model{RotorStatorParams{}};
    const auto& coords = model.coordinates();
    for (std::size_t i = 0; i < coords.size(); ++i) {
      const auto k = static_cast<Eigen::Index>(i);
      num("initial", coords[i].name.c_str(), false, [k](CaseSpec& c) { return &c.initial.q0[k]; });
    }
    for (std::size_t i = 0; i < coords.size(); ++i) {
      const auto k = static_cast<Eigen::Index>(i);
      num("initial", coords[i].rate_key.c_str(), false,
          [k](CaseSpec& c) { return &c.initial.v0[k]; });
    }
    num("run", "t_start", false, [](CaseSpec& c) { return &c.run.t_start; });
    num("run", "t_end", true, [](CaseSpec& c) { return &c.run.t_end; });
    num("run", "omega_lim", true, [](CaseSpec& c) { return &c.run.omega_lim; });
    num("run", "max_wall", false, [](CaseSpec& c) { return &c.run.max_wall; });
    text("solver", "kind", [](CaseSpec& c) { return &c.solver.kind; });
    num("solver", "rtol", false, [](CaseSpec& c) { return &c.solver.rtol; });
    num("solver", "atol", false, [](CaseSpec& c) { return &c.solver.atol; });
    text("solver", "method", [](CaseSpec& c) { return &c.solver.method; });
    text("solver", "contact_phases", [](CaseSpec& c) { return &c.solver.contact_phases; });
    text("solver", "contact_method", [](CaseSpec& c) { return &c.solver.contact_method; });
    num("solver", "max_events_per_second", false,
        [](CaseSpec& c) { return &c.solver.max_events_per_second; });
    num("solver", "h", false, [](CaseSpec& c) { return &c.solver.h; });
    integer("solver", "itmax", [](CaseSpec& c) { return &c.solver.itmax; });
    num("solver", "qn_tol", false, [](CaseSpec& c) { return &c.solver.qn_tol; });
    num("solver", "theta", false, [](CaseSpec& c) { return &c.solver.theta; });
    num("solver", "eta", false, [](CaseSpec& c) { return &c.solver.eta; });
    text("solver", "projection", [](CaseSpec& c) { return &c.solver.projection; });
    num("output", "dt", false, [](CaseSpec& c) { return &c.output.dt; });
    integer("output", "every", [](CaseSpec& c) { return &c.output.every; });
    text("output", "folder", [](CaseSpec& c) { return &c.output.folder; });
    return v;
  }();
  return s;
}

const std::vector<std::string>& section_names() {
  static const std::vector<std::string> s = {"rotor",   "bearing", "stator", "contact", "loads",
                                             "initial", "run",     "solver", "output"};
  return s;
}

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const bool same = std::tolower(a[i - 1]) == std::tolower(b[j - 1]);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (same ? 0 : 1)});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string suggestion(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = 3;  // suggest only close matches (at most 2 edits)
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  return best.empty() ? "" : fmt::format(" (did you mean '{}'?)", best);
}

/// Where a key's value came from.
struct Origin {
  std::string file;
  int line = 0;
};

/// The value as written (for messages).
std::string node_text(const toml::node& n) {
  if (auto s = n.as_string()) return fmt::format("\"{}\"", s->get());
  if (auto f = n.as_floating_point()) return fmt::format("{}", f->get());
  if (auto i = n.as_integer()) return fmt::format("{}", i->get());
  if (auto b = n.as_boolean()) return b->get() ? "true" : "false";
  if (n.is_table()) return "{table}";
  if (n.is_array()) return "[array]";
  return "(value)";
}

class Loader {
 public:
  explicit Loader(std::string source) : source_(std::move(source)) {}

  CaseSpec load(std::string_view text, const std::vector<std::string>& overrides) {
    toml::table doc;
    try {
      doc = toml::parse(text, source_);
    } catch (const toml::parse_error& e) {
      issues_.push_back({source_, static_cast<int>(e.source().begin.line), "(syntax)", "",
                         std::string(e.description())});
      throw CaseError(issues_);
    }
    apply_overrides(doc, overrides);
    CaseSpec c;
    c.source = source_;
    c.name = std::filesystem::path(source_).stem().string();
    check_structure(doc, c);
    read_values(doc, c);
    // Rules run even when other keys have problems, so that every problem is reported at once.
    // A key that is missing or of the wrong type keeps its (valid) default and so adds nothing.
    check_rules(c);
    if (!issues_.empty()) throw CaseError(issues_);
    return c;
  }

 private:
  Origin origin(const std::string& key, const toml::node* n) const {
    auto it = overridden_.find(key);
    if (it != overridden_.end()) return {"--set", 0};
    return {source_, n ? static_cast<int>(n->source().begin.line) : 0};
  }

  void issue(const std::string& key, const toml::node* n, std::string value, std::string rule) {
    const Origin o = origin(key, n);
    issues_.push_back({o.file, o.line, key, std::move(value), std::move(rule)});
  }

  void apply_overrides(toml::table& doc, const std::vector<std::string>& overrides) {
    for (const auto& ov : overrides) {
      const auto eq = ov.find('=');
      const std::string lhs = eq == std::string::npos ? ov : ov.substr(0, eq);
      const auto dot = lhs.find('.');
      if (eq == std::string::npos || dot == std::string::npos || dot == 0 ||
          dot + 1 == lhs.size()) {
        // (an empty --set '' has no key to name: the text itself is shown)
        issues_.push_back({"--set", 0, lhs.empty() ? "(override)" : lhs, "\"" + ov + "\"",
                           "an override must read section.key=value"});
        continue;
      }
      const std::string section = lhs.substr(0, dot), key = lhs.substr(dot + 1);
      const std::string rhs = ov.substr(eq + 1);
      // The value is read as a TOML value (numbers, booleans, quoted strings); anything that is
      // not one (solver.kind=mj) is taken as a bare string.
      toml::node_view<toml::node> parsed;
      toml::table holder;
      try {
        holder = toml::parse("v = " + rhs);
      } catch (const toml::parse_error&) {
        holder = toml::table{};
        holder.insert("v", rhs);
      }
      if (!doc.contains(section)) doc.insert(section, toml::table{});
      toml::table* sec = doc[section].as_table();
      if (!sec) {
        issues_.push_back({"--set", 0, lhs, rhs, fmt::format("'{}' is not a section", section)});
        continue;
      }
      sec->insert_or_assign(key, *holder.get("v"));
      overridden_.insert(section + "." + key);
    }
  }

  void check_structure(const toml::table& doc, CaseSpec& c) {
    for (const auto& [k, node] : doc) {
      const std::string key(k.str());
      if (key == "name") {
        if (auto s = node.as_string()) {
          c.name = s->get();
        } else {
          issue("name", &node, node_text(node), "must be a string");
        }
        continue;
      }
      if (std::find(section_names().begin(), section_names().end(), key) == section_names().end()) {
        auto sections = section_names();
        sections.push_back("name");
        issue(key, &node, "", "unknown section" + suggestion(key, sections));
        continue;
      }
      const toml::table* sec = node.as_table();
      if (!sec) {
        issue(key, &node, node_text(node), "must be a section ([" + key + "])");
        continue;
      }
      std::vector<std::string> known;
      for (const auto& ks : schema())
        if (key == ks.section) known.push_back(ks.key);
      for (const auto& [kk, vv] : *sec) {
        const std::string name(kk.str());
        if (std::find(known.begin(), known.end(), name) == known.end()) {
          issue(key + "." + name, &vv, node_text(vv), "unknown key" + suggestion(name, known));
        }
      }
    }
  }

  void read_values(const toml::table& doc, CaseSpec& c) {
    for (const auto& ks : schema()) {
      const std::string full = std::string(ks.section) + "." + ks.key;
      const toml::node* sec = doc.get(ks.section);
      const toml::node* n = sec && sec->is_table() ? sec->as_table()->get(ks.key) : nullptr;
      if (!n) {
        if (ks.required) {
          issues_.push_back({source_, sec ? static_cast<int>(sec->source().begin.line) : 0, full,
                             "", "required key is missing"});
        }
        continue;
      }
      present_[full] = n;
      switch (ks.kind) {
        case Kind::Number: {
          double v = 0.0;
          if (auto f = n->as_floating_point()) {
            v = f->get();
          } else if (auto i = n->as_integer()) {
            v = static_cast<double>(i->get());
          } else {
            issue(full, n, node_text(*n), "must be a number");
            break;
          }
          if (!std::isfinite(v)) {
            issue(full, n, node_text(*n), "must be a finite number");
            break;
          }
          *ks.num(c) = v;
          break;
        }
        case Kind::Integer:
          if (auto i = n->as_integer()) {
            // TOML integers are 64-bit: a value outside int would wrap (4294967297 -> 1)
            if (i->get() < std::numeric_limits<int>::min() ||
                i->get() > std::numeric_limits<int>::max()) {
              issue(full, n, node_text(*n),
                    fmt::format("must be an integer in [{}, {}]", std::numeric_limits<int>::min(),
                                std::numeric_limits<int>::max()));
              break;
            }
            *ks.integer(c) = static_cast<int>(i->get());
          } else {
            issue(full, n, node_text(*n), "must be an integer");
          }
          break;
        case Kind::String:
          if (auto s = n->as_string()) {
            *ks.text(c) = s->get();
          } else {
            issue(full, n, node_text(*n), "must be a string");
          }
          break;
      }
    }
  }

  const toml::node* at(const std::string& key) const {
    auto it = present_.find(key);
    return it == present_.end() ? nullptr : it->second;
  }
  bool given(const std::string& key) const { return present_.count(key) > 0; }

  void rule(bool ok, const std::string& key, double value, const std::string& text) {
    if (ok) return;
    const toml::node* n = at(key);
    issue(key, n, n ? node_text(*n) : fmt::format("{:.17g} (default)", value), text);
  }

  void check_rules(const CaseSpec& c) {
    const auto& r = c.params.rotor;
    rule(r.mass > 0, "rotor.mass", r.mass, "must be > 0 (a mass)");
    rule(r.Jd > 0, "rotor.Jd", r.Jd, "must be > 0 (a moment of inertia)");
    rule(r.Jp > 0, "rotor.Jp", r.Jp, "must be > 0 (a moment of inertia)");
    rule(r.L > 0, "rotor.L", r.L, "must be > 0 (a length)");
    rule(r.delta > 0, "rotor.delta", r.delta, "must be > 0 (a length)");
    rule(r.d > 0, "rotor.d", r.d, "must be > 0 (a length); d must lie in (0, L - delta]");
    rule(r.radius > 0, "rotor.radius", r.radius, "must be > 0 (a length)");
    if (r.L > 0 && r.delta > 0) {
      rule(r.delta < r.L, "rotor.delta", r.delta,
           fmt::format("must be < L = {:.17g} (the contact plane lies on the shaft)", r.L));
      if (r.delta < r.L && r.d > 0) {
        rule(r.d <= r.L - r.delta, "rotor.d", r.d,
             fmt::format("must lie in (0, L - delta] = (0, {:.17g}] (G between B and R)",
                         r.L - r.delta));
      }
    }
    rule(c.params.bearing.k > 0, "bearing.k", c.params.bearing.k, "must be > 0 (a stiffness)");
    rule(c.params.bearing.c >= 0, "bearing.c", c.params.bearing.c, "must be >= 0 (a damping)");
    const auto& s = c.params.stator;
    rule(s.mass > 0, "stator.mass", s.mass, "must be > 0 (a mass)");
    rule(s.k > 0, "stator.k", s.k, "must be > 0 (a stiffness)");
    rule(s.c >= 0, "stator.c", s.c, "must be >= 0 (a damping)");
    rule(s.gap > 0, "stator.gap", s.gap, "must be > 0 (the radial clearance g0)");
    const auto& k = c.params.contact;
    rule(k.mu >= 0, "contact.mu", k.mu, "must be >= 0 (a friction coefficient)");
    rule(k.e_n >= 0 && k.e_n <= 1, "contact.e_n", k.e_n, "must lie in [0, 1] (a restitution)");
    rule(k.e_t >= 0 && k.e_t <= 1, "contact.e_t", k.e_t, "must lie in [0, 1] (a restitution)");
    rule(c.params.loads.gravity >= 0, "loads.gravity", c.params.loads.gravity,
         "must be >= 0 (its direction is fixed: -Y)");
    rule(c.run.t_start >= 0, "run.t_start", c.run.t_start, "must be >= 0");
    rule(c.run.t_end > 0, "run.t_end", c.run.t_end, "must be > 0");
    if (c.run.t_end > 0 && c.run.t_start >= 0) {
      rule(c.run.t_end > c.run.t_start, "run.t_end", c.run.t_end,
           fmt::format("must be > run.t_start = {:.17g}", c.run.t_start));
    }
    rule(c.run.omega_lim > 0, "run.omega_lim", c.run.omega_lim, "must be > 0");
    const auto& so = c.solver;
    const SolverEntry* solver = find_solver(so.kind);
    if (!solver) {
      std::vector<std::string> kinds;
      for (const auto& e : solver_registry()) kinds.emplace_back(e.name);
      issue("solver.kind", at("solver.kind"), "\"" + so.kind + "\"",
            "must be one of " + solver_names(", ") + suggestion(so.kind, kinds));
    }
    const bool fixed_step = solver && solver->fixed_step;
    if (so.method != "bdf" && so.method != "adams") {
      issue("solver.method", at("solver.method"), "\"" + so.method + "\"", "must be bdf or adams");
    }
    if (so.contact_phases != "reduced" && so.contact_phases != "projection") {
      issue("solver.contact_phases", at("solver.contact_phases"), "\"" + so.contact_phases + "\"",
            "must be reduced or projection");
    }
    if (so.contact_method != "bdf" && so.contact_method != "adams") {
      issue("solver.contact_method", at("solver.contact_method"), "\"" + so.contact_method + "\"",
            "must be bdf or adams");
    }
    if (so.projection != "mass" && so.projection != "identity") {
      issue("solver.projection", at("solver.projection"), "\"" + so.projection + "\"",
            "must be mass or identity");
    }
    // The event-driven options: the rules are stated once, in hybrid/event_driven.cpp.
    {
      EventDrivenOptions eo;
      eo.rtol = so.rtol;
      eo.atol = so.atol;
      eo.max_events_per_second = so.max_events_per_second;
      eo.output_dt = c.output.dt;
      static const std::map<std::string, std::string> key_of = {
          {"rtol", "solver.rtol"},
          {"atol", "solver.atol"},
          {"max_events_per_second", "solver.max_events_per_second"}};
      for (const auto& p : event_driven_option_problems(eo)) {
        if (!key_of.count(p.option)) continue;  // output_dt: the fixed-step rules report it
        const std::string& key = key_of.at(p.option);
        const toml::node* n = at(key);
        issue(key, n, n ? node_text(*n) : p.value + " (default)", p.rule);
      }
    }
    // The fixed-step options: the rules are stated once, in stepping/fixed_step.cpp. The step
    // count rules (a whole number of steps, at most kMaxFixedSteps) apply to fixed-step runs.
    {
      FixedStepOptions fo;
      fo.h = so.h;
      fo.itmax = so.itmax;
      fo.qn_tol = so.qn_tol;
      fo.theta = so.theta;
      fo.eta = so.eta;
      fo.output_every = c.output.every;
      fo.output_dt = c.output.dt;
      fo.max_wall = c.run.max_wall;  // (the event-driven check states the same rule: not mapped)
      auto bad = fixed_step_option_problems(fo);
      if (fixed_step) {
        for (auto& p : fixed_step_count_problems(fo.h, c.run.t_start, c.run.t_end))
          bad.push_back(p);
      }
      static const std::map<std::string, std::string> key_of = {
          {"h", "solver.h"},           {"itmax", "solver.itmax"},
          {"qn_tol", "solver.qn_tol"}, {"theta", "solver.theta"},
          {"eta", "solver.eta"},       {"t_end", "run.t_end"},
          {"output_dt", "output.dt"},  {"output_every", "output.every"},
          {"max_wall", "run.max_wall"}};
      for (const auto& p : bad) {
        const std::string& key = key_of.at(p.option);
        if (key == "run.t_end" && !(c.run.t_end > c.run.t_start)) continue;  // reported above
        const toml::node* n = at(key);
        issue(key, n, n ? node_text(*n) : p.value + " (default)", p.rule);
      }
    }
    // Output size: at most kMaxOutputRows rows (output.dt = 1e-300 once wrote 117 MB in 5 s on
    // its way to 1e297 rows; t_end = 1e300 is the same mistake).
    if (c.run.t_end > c.run.t_start && c.output.dt > 0 && so.h > 0) {
      const bool every = fixed_step && c.output.every > 0;
      const double span = c.run.t_end - c.run.t_start;
      const double rows = every ? span / so.h / c.output.every : span / c.output.dt;
      if (!(rows <= static_cast<double>(kMaxOutputRows))) {
        // name the key the user just changed, when it is one of them
        const std::string key = every                            ? "output.every"
                                : overridden_.count("run.t_end") ? "run.t_end"
                                                                 : "output.dt";
        const toml::node* n = at(key);
        issue(key, n, n ? node_text(*n) : "(default)",
              fmt::format("the run would write {:.3g} rows of output (about {:.3g} GB), above "
                          "the limit of {:.0e} rows; raise output.dt or shorten run.t_end",
                          rows, rows * 420e-9, static_cast<double>(kMaxOutputRows)));
      }
    }
    // The initial state must not penetrate the stator: d_N = g0 - |(x_r - x_s, y_r - y_s)| >= 0.
    if (s.gap > 0) {
      const Vec& q = c.initial.q0;
      const double dN = s.gap - std::hypot(q[XR] - q[XS], q[YR] - q[YS]);
      // A state on the constraint written by a run (17 significant digits) gives d_N within
      // round-off of 0, of either sign: touching. 64 ulps of g0 is about 3e-18 m for the
      // reference case, six orders below the solver's position tolerance.
      const double roundoff = 64.0 * std::numeric_limits<double>::epsilon() * s.gap;
      if (dN < -roundoff) {
        std::string key = "initial.x_r";
        for (const char* kk : {"initial.x_r", "initial.y_r", "initial.x_s", "initial.y_s"})
          if (given(kk)) {
            key = kk;
            break;
          }
        issue(key, at(key),
              fmt::format("(x_r, y_r, x_s, y_s) = ({:.6g}, {:.6g}, {:.6g}, {:.6g})", q[XR], q[YR],
                          q[XS], q[YS]),
              fmt::format("the initial state penetrates the stator: d_N = g0 - |r - s| = {:.6g} m "
                          "< 0",
                          dN));
      }
    }
  }

  std::string source_;
  std::vector<CaseIssue> issues_;
  std::set<std::string> overridden_;
  std::map<std::string, const toml::node*> present_;
};

}  // namespace

CaseSpec parse_case(std::string_view toml_text, const std::string& source,
                    const std::vector<std::string>& overrides) {
  return Loader(source).load(toml_text, overrides);
}

CaseSpec load_case(const std::string& path, const std::vector<std::string>& overrides) {
  namespace fs = std::filesystem;
  auto refuse = [&path](const std::string& why) {
    throw CaseError({{path, 0, "(file)", "", why}});
  };
  std::error_code ec;
  const auto st = fs::status(path, ec);
  if (fs::is_directory(st)) refuse("is a directory, not a case file");
  // a device (/dev/zero), a pipe or a socket may never end: read at most kMaxCaseBytes
  std::ifstream in(path, std::ios::binary);
  if (!in) refuse(std::string("cannot read the case file: ") + std::strerror(errno));
  std::string text(kMaxCaseBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxCaseBytes) {
    refuse(fmt::format("{} larger than {} bytes: not a case file",
                       fs::is_regular_file(st) ? "a file" : "a special file (device or pipe)",
                       kMaxCaseBytes));
  }
  if (text.find('\0') != std::string::npos) refuse("holds NUL bytes: not a text (TOML) file");
  return parse_case(text, path, overrides);
}

std::string toml_quote(std::string_view text) {
  return quoted_string(text);
}

std::string to_toml(const CaseSpec& c) {
  std::string out = fmt::format("# resolved case: every key with its value (rubdyn)\nname = {}\n",
                                toml_quote(c.name));
  CaseSpec copy = c;  // schema accessors take a mutable CaseSpec
  std::string section;
  for (const auto& ks : schema()) {
    if (section != ks.section) {
      section = ks.section;
      out += fmt::format("\n[{}]\n", section);
    }
    switch (ks.kind) {
      case Kind::Number: {
        // shortest round-trip digits, always as a TOML float: "-0" would read back as the
        // integer 0 and lose the sign of -0.0 (found by tests/fuzz)
        std::string v = fmt::format("{}", *ks.num(copy));
        if (v.find_first_of(".eEn") == std::string::npos) v += ".0";
        out += fmt::format("{} = {}\n", ks.key, v);
        break;
      }
      case Kind::Integer: out += fmt::format("{} = {}\n", ks.key, *ks.integer(copy)); break;
      case Kind::String: out += fmt::format("{} = {}\n", ks.key, toml_quote(*ks.text(copy))); break;
    }
  }
  return out;
}

std::string output_folder(const CaseSpec& c) {
  return c.output.folder.empty() ? "out/" + c.name : c.output.folder;
}

}  // namespace rubdyn
