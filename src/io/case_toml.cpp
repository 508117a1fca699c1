// Case files: TOML -> CaseSpec with complete validation, and CaseSpec -> TOML.
// The only file of the project that includes the TOML parser.
#include <fmt/format.h>
#include <toml++/toml.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/columns.hpp"
#include "rubdyn/io/matrix_files.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/solver_options.hpp"
#include "rubdyn/io/text_files.hpp"
#include "rubdyn/model/matrix_model.hpp"
#include "rubdyn/model/matrix_reduction.hpp"
#include "rubdyn/stepping/fixed_step.hpp"

namespace rubdyn {

namespace {

enum class Kind { Number, Integer, String, Bool, Choice };

/// One key of the schema: where it goes in CaseSpec, when it is required or refused, its type.
struct KeySpec {
  std::string section, key;
  Kind kind = Kind::Number;
  /// Required in this case (empty: optional).
  std::function<bool(const CaseSpec&)> required;
  /// Why the key must not be given in this case ("": accepted; empty function: always).
  std::function<std::string(const CaseSpec&)> refused;
  std::function<double*(CaseSpec&)> num;        // Number
  std::function<int*(CaseSpec&)> integer;       // Integer
  std::function<std::string*(CaseSpec&)> text;  // String
  std::function<bool*(CaseSpec&)> flag;         // Bool
  // Choice: one of `choices`, stored by set/get
  std::vector<std::string> choices;
  std::function<std::string(const CaseSpec&)> get;
  std::function<void(CaseSpec&, const std::string&)> set;
  std::string full() const { return section + "." + key; }
};

/// Builds a schema: the keys in the order of case.resolved.toml.
class SchemaBuilder {
 public:
  using Pred = std::function<bool(const CaseSpec&)>;
  using Why = std::function<std::string(const CaseSpec&)>;
  void num(const std::string& sec, const std::string& key, bool req,
           std::function<double*(CaseSpec&)> f, Why refused = {}, Pred req_if = {}) {
    KeySpec k = make(sec, key, Kind::Number);
    k.refused = std::move(refused);
    k.required = req ? Pred([](const CaseSpec&) { return true; }) : std::move(req_if);
    k.num = std::move(f);
    keys.push_back(std::move(k));
  }
  void integer(const std::string& sec, const std::string& key, std::function<int*(CaseSpec&)> f) {
    KeySpec k = make(sec, key, Kind::Integer);
    k.integer = std::move(f);
    keys.push_back(std::move(k));
  }
  void text(const std::string& sec, const std::string& key,
            std::function<std::string*(CaseSpec&)> f) {
    KeySpec k = make(sec, key, Kind::String);
    k.text = std::move(f);
    keys.push_back(std::move(k));
  }
  void flag(const std::string& sec, const std::string& key, std::function<bool*(CaseSpec&)> f) {
    KeySpec k = make(sec, key, Kind::Bool);
    k.flag = std::move(f);
    keys.push_back(std::move(k));
  }
  void choice(const std::string& sec, const std::string& key, std::vector<std::string> words,
              std::function<std::string(const CaseSpec&)> get,
              std::function<void(CaseSpec&, const std::string&)> set, Why refused = {}) {
    KeySpec k = make(sec, key, Kind::Choice);
    k.refused = std::move(refused);
    k.choices = std::move(words);
    k.get = std::move(get);
    k.set = std::move(set);
    keys.push_back(std::move(k));
  }
  std::vector<KeySpec> keys;

 private:
  static KeySpec make(const std::string& sec, const std::string& key, Kind kind) {
    KeySpec k;
    k.section = sec;
    k.key = key;
    k.kind = kind;
    return k;
  }
};

// ---- each model's own keys -------------------------------------------------------------------

/// The section of plane k (0-based) of a rigid rotor's [[plane]] array: "plane.<k+1>" (the
/// array's tables are read as these sections; case.resolved.toml writes them back as [[plane]]).
std::string plane_section(std::size_t k) {
  return "plane." + std::to_string(k + 1);
}

/// The section of contact node k (0-based) of a matrices model's [[contact_node]] array:
/// "contact_node.<k+1>" (written back as [[contact_node]]).
std::string node_section(std::size_t k) {
  return "contact_node." + std::to_string(k + 1);
}

void rigid_rotor_keys(SchemaBuilder& b, const CaseSpec& spec) {
  using S = const CaseSpec&;
  const auto single = [](S c) { return c.params.planes.empty(); };
  // with [[plane]] tables each plane has its own seal, ring and law: the single plane's keys
  // are refused with where they now live
  const auto moved = [](const char* where) {
    return [where](S c) {
      return c.params.planes.empty()
                 ? std::string()
                 : fmt::format("with [[plane]] tables each plane has its own {}", where);
    };
  };
  b.num("rotor", "mass", true, [](CaseSpec& c) { return &c.params.rotor.mass; });
  b.num("rotor", "Jd", true, [](CaseSpec& c) { return &c.params.rotor.Jd; });
  b.num("rotor", "Jp", true, [](CaseSpec& c) { return &c.params.rotor.Jp; });
  b.num("rotor", "L", true, [](CaseSpec& c) { return &c.params.rotor.L; });
  b.num("rotor", "delta", true, [](CaseSpec& c) { return &c.params.rotor.delta; });
  b.num("rotor", "d", true, [](CaseSpec& c) { return &c.params.rotor.d; });
  b.num(
      "rotor", "radius", false, [](CaseSpec& c) { return &c.params.rotor.radius; },
      moved("seal radius: radius in each [[plane]]"), single);
  b.num("bearing", "k", true, [](CaseSpec& c) { return &c.params.bearing.k; });
  b.num("bearing", "c", true, [](CaseSpec& c) { return &c.params.bearing.c; });
  const auto ring = moved(
      "ring: stator_mass, stator_k, stator_c (or stator_rigid = true) and gap in each "
      "[[plane]]");
  b.num(
      "stator", "mass", false, [](CaseSpec& c) { return &c.params.stator.mass; }, ring, single);
  b.num(
      "stator", "k", false, [](CaseSpec& c) { return &c.params.stator.k; }, ring, single);
  b.num(
      "stator", "c", false, [](CaseSpec& c) { return &c.params.stator.c; }, ring, single);
  b.num(
      "stator", "gap", false, [](CaseSpec& c) { return &c.params.stator.gap; }, ring, single);
  // the planes: one section per table of the [[plane]] array
  for (std::size_t k = 0; k < spec.params.planes.size(); ++k) {
    const std::string sec = plane_section(k);
    auto at = [k](CaseSpec& c) -> PlaneParams& { return c.params.planes[k]; };
    b.num(sec, "position", true, [at](CaseSpec& c) { return &at(c).position; });
    b.num(sec, "radius", true, [at](CaseSpec& c) { return &at(c).radius; });
    b.num(sec, "gap", true, [at](CaseSpec& c) { return &at(c).gap; });
    b.num(sec, "mu", true, [at](CaseSpec& c) { return &at(c).contact.mu; });
    b.num(sec, "e_n", false, [at](CaseSpec& c) { return &at(c).contact.e_n; });
    b.num(sec, "e_t", false, [at](CaseSpec& c) { return &at(c).contact.e_t; });
    b.flag(sec, "stator_rigid", [at](CaseSpec& c) { return &at(c).rigid; });
    const auto sprung = [k](S c) { return !c.params.planes[k].rigid; };
    const auto rigid_refuses = [k](S c) {
      return c.params.planes[k].rigid
                 ? std::string(
                       "a rigid ring (stator_rigid = true) is fixed, without mass, spring or "
                       "damper: remove this key")
                 : std::string();
    };
    b.num(
        sec, "stator_mass", false, [at](CaseSpec& c) { return &at(c).mass; }, rigid_refuses,
        sprung);
    b.num(
        sec, "stator_k", false, [at](CaseSpec& c) { return &at(c).k; }, rigid_refuses, sprung);
    b.num(
        sec, "stator_c", false, [at](CaseSpec& c) { return &at(c).c; }, rigid_refuses, sprung);
  }
}

void jeffcott_keys(SchemaBuilder& b) {
  b.num("rotor", "mass", true, [](CaseSpec& c) { return &c.jeffcott.rotor.mass; });
  b.num("rotor", "k", true, [](CaseSpec& c) { return &c.jeffcott.rotor.k; });
  b.num("rotor", "c", true, [](CaseSpec& c) { return &c.jeffcott.rotor.c; });
  b.num("rotor", "radius", true, [](CaseSpec& c) { return &c.jeffcott.rotor.radius; });
  b.num("rotor", "Jp", true, [](CaseSpec& c) { return &c.jeffcott.rotor.Jp; });
  b.flag("stator", "rigid", [](CaseSpec& c) { return &c.jeffcott.stator.rigid; });
  // a rigid stator is a fixed ring: no mass, spring or damper, and no coordinates
  const auto sprung = [](const CaseSpec& c) { return !c.jeffcott.stator.rigid; };
  const auto rigid_refuses = [](const CaseSpec& c) {
    return c.jeffcott.stator.rigid
               ? std::string(
                     "a rigid stator (stator.rigid = true) is a fixed ring without "
                     "mass, spring or damper: remove this key")
               : std::string();
  };
  b.num(
      "stator", "mass", false, [](CaseSpec& c) { return &c.jeffcott.stator.mass; }, rigid_refuses,
      sprung);
  b.num(
      "stator", "k", false, [](CaseSpec& c) { return &c.jeffcott.stator.k; }, rigid_refuses,
      sprung);
  b.num(
      "stator", "c", false, [](CaseSpec& c) { return &c.jeffcott.stator.c; }, rigid_refuses,
      sprung);
  b.num("stator", "gap", true, [](CaseSpec& c) { return &c.jeffcott.stator.gap; });
}

/// [reduction] of kind "matrices" (model/matrix_reduction.hpp): read before the other keys, as
/// the files are, since the reduced model's coordinates are the case's (Loader::read_reduction).
void reduction_keys(SchemaBuilder& b) {
  using S = const CaseSpec&;
  b.choice(
      "reduction", "method", {"none", "modal", "craig-bampton"},
      [](S c) { return std::string(to_string(c.reduction.method)); },
      [](CaseSpec& c, const std::string& w) {
        c.reduction.method = w == "modal"           ? ReductionMethod::Modal
                             : w == "craig-bampton" ? ReductionMethod::CraigBampton
                                                    : ReductionMethod::None;
      });
  const auto unreduced = [](S c) {
    return c.reduction.method == ReductionMethod::None
               ? std::string("read only with reduction.method = \"modal\" or \"craig-bampton\"")
               : std::string();
  };
  b.integer("reduction", "modes", [](CaseSpec& c) { return &c.reduction.modes; });
  b.keys.back().refused = unreduced;
  b.num(
      "reduction", "cutoff", false, [](CaseSpec& c) { return &c.reduction.cutoff; }, unreduced);
}

void matrices_keys(SchemaBuilder& b, const CaseSpec& spec) {
  // the matrices' files (read as the model is read: they decide the coordinates)
  const auto required = [](const CaseSpec&) { return true; };
  b.text("rotor", "M", [](CaseSpec& c) { return &c.matrix_files.M; });
  b.keys.back().required = required;
  b.text("rotor", "C", [](CaseSpec& c) { return &c.matrix_files.C; });
  b.keys.back().required = required;
  b.text("rotor", "K", [](CaseSpec& c) { return &c.matrix_files.K; });
  b.keys.back().required = required;
  b.text("rotor", "G", [](CaseSpec& c) { return &c.matrix_files.G; });
  b.keys.back().required = required;
  b.text("rotor", "f0", [](CaseSpec& c) { return &c.matrix_files.f0; });
  b.num("rotor", "Jp", true, [](CaseSpec& c) { return &c.matrices.rotor.Jp; });
  b.text("rotor", "coordinates", [](CaseSpec& c) { return &c.matrix_files.coordinates; });
  b.text("rotor", "rotations", [](CaseSpec& c) { return &c.matrix_files.rotations; });
  // one contact node as a section [contact_node] with [stator] and [contact], or several as
  // [[contact_node]] tables, each with its own ring and law
  using S = const CaseSpec&;
  const auto single = [](S c) { return c.matrices.nodes.empty(); };
  // (never met: a [contact_node] section and [[contact_node]] tables cannot share the name)
  const auto node_moved = [](S c) {
    return c.matrices.nodes.empty()
               ? std::string()
               : fmt::format(
                     "with [[contact_node]] tables each node has its keys in its table: "
                     "contact_node.K.<key> with K = 1 to {}",
                     c.matrices.nodes.size());
  };
  b.integer("contact_node", "x", [](CaseSpec& c) { return &c.matrices.node.x; });
  b.keys.back().required = single;
  b.keys.back().refused = node_moved;
  b.integer("contact_node", "y", [](CaseSpec& c) { return &c.matrices.node.y; });
  b.keys.back().required = single;
  b.keys.back().refused = node_moved;
  b.num(
      "contact_node", "radius", false, [](CaseSpec& c) { return &c.matrices.node.radius; },
      node_moved, single);
  b.num(
      "contact_node", "gap", false, [](CaseSpec& c) { return &c.matrices.node.gap; }, node_moved,
      single);
  const auto ring_moved = [](S c) {
    return c.matrices.nodes.empty()
               ? std::string()
               : std::string(
                     "with [[contact_node]] tables each node has its own ring: stator_mass, "
                     "stator_k, stator_c (or stator_rigid = true) in each [[contact_node]]");
  };
  b.flag("stator", "rigid", [](CaseSpec& c) { return &c.matrices.stator.rigid; });
  b.keys.back().refused = ring_moved;
  const auto sprung = [](const CaseSpec& c) {
    return c.matrices.nodes.empty() && !c.matrices.stator.rigid;
  };
  const auto rigid_refuses = [ring_moved](const CaseSpec& c) {
    if (!c.matrices.nodes.empty()) return ring_moved(c);
    return c.matrices.stator.rigid
               ? std::string(
                     "a rigid stator (stator.rigid = true) is a fixed ring without "
                     "mass, spring or damper: remove this key")
               : std::string();
  };
  b.num(
      "stator", "mass", false, [](CaseSpec& c) { return &c.matrices.stator.mass; }, rigid_refuses,
      sprung);
  b.num(
      "stator", "k", false, [](CaseSpec& c) { return &c.matrices.stator.k; }, rigid_refuses,
      sprung);
  b.num(
      "stator", "c", false, [](CaseSpec& c) { return &c.matrices.stator.c; }, rigid_refuses,
      sprung);
  for (std::size_t k = 0; k < spec.matrices.nodes.size(); ++k) {
    const std::string sec = node_section(k);
    auto at = [k](CaseSpec& c) -> MatrixNode& { return c.matrices.nodes[k]; };
    const auto always = [](S) { return true; };
    b.integer(sec, "x", [at](CaseSpec& c) { return &at(c).at.x; });
    b.keys.back().required = always;
    b.integer(sec, "y", [at](CaseSpec& c) { return &at(c).at.y; });
    b.keys.back().required = always;
    b.num(sec, "radius", true, [at](CaseSpec& c) { return &at(c).at.radius; });
    b.num(sec, "gap", true, [at](CaseSpec& c) { return &at(c).at.gap; });
    b.num(sec, "mu", true, [at](CaseSpec& c) { return &at(c).law.mu; });
    b.num(sec, "e_n", false, [at](CaseSpec& c) { return &at(c).law.e_n; });
    b.num(sec, "e_t", false, [at](CaseSpec& c) { return &at(c).law.e_t; });
    b.flag(sec, "stator_rigid", [at](CaseSpec& c) { return &at(c).stator.rigid; });
    const auto node_sprung = [k](S c) { return !c.matrices.nodes[k].stator.rigid; };
    const auto node_rigid_refuses = [k](S c) {
      return c.matrices.nodes[k].stator.rigid
                 ? std::string(
                       "a rigid ring (stator_rigid = true) is fixed, without mass, spring or "
                       "damper: remove this key")
                 : std::string();
    };
    b.num(
        sec, "stator_mass", false, [at](CaseSpec& c) { return &at(c).stator.mass; },
        node_rigid_refuses, node_sprung);
    b.num(
        sec, "stator_k", false, [at](CaseSpec& c) { return &at(c).stator.k; }, node_rigid_refuses,
        node_sprung);
    b.num(
        sec, "stator_c", false, [at](CaseSpec& c) { return &at(c).stator.c; }, node_rigid_refuses,
        node_sprung);
  }
  reduction_keys(b);
}

/// The largest size n of a matrices model (its hot paths cost n^2 per solve).
constexpr int kMaxMatrixSize = 1000;

// ---- what every model has --------------------------------------------------------------------

void contact_and_load_keys(SchemaBuilder& b) {
  using S = const CaseSpec&;
  // a rigid rotor with [[plane]] tables has a law per plane
  const auto one_law = [](S c) {
    return (c.model != "rigid-rotor" || c.params.planes.empty()) &&
           (c.model != "matrices" || c.matrices.nodes.empty());
  };
  const auto law_moved = [](S c) {
    if (c.model == "matrices" && !c.matrices.nodes.empty())
      return std::string(
          "with [[contact_node]] tables each node has its own law: mu, e_n, e_t in each "
          "[[contact_node]]");
    return c.model == "rigid-rotor" && !c.params.planes.empty()
               ? std::string(
                     "with [[plane]] tables each plane has its own law: mu, e_n, e_t in "
                     "each [[plane]]")
               : std::string();
  };
  b.num(
      "contact", "mu", false, [](CaseSpec& c) { return &c.contact().mu; }, law_moved, one_law);
  b.num(
      "contact", "e_n", false, [](CaseSpec& c) { return &c.contact().e_n; }, law_moved);
  b.num(
      "contact", "e_t", false, [](CaseSpec& c) { return &c.contact().e_t; }, law_moved);
  const auto torque_driven = [](S c) { return c.loads().spin == SpinDrive::Torque; };
  const auto prescribed_refuses = [](S c) {
    return c.loads().spin == SpinDrive::Prescribed
               ? std::string(
                     "not read with loads.spin = \"prescribed\": the torque that holds "
                     "the speed is an output (timeseries.csv drive_torque)")
               : std::string();
  };
  b.num("loads", "gravity", true, [](CaseSpec& c) { return &c.loads().gravity; });
  b.choice(
      "loads", "spin", {"torque", "prescribed"},
      [](S c) { return std::string(to_string(c.loads().spin)); },
      [](CaseSpec& c, const std::string& w) {
        c.loads().spin = w == "prescribed" ? SpinDrive::Prescribed : SpinDrive::Torque;
      });
  b.num(
      "loads", "torque", false, [](CaseSpec& c) { return &c.loads().torque; }, prescribed_refuses,
      torque_driven);
  b.choice(
      "loads", "torque_law", {"constant", "linear"},
      [](S c) { return std::string(to_string(c.loads().torque_law)); },
      [](CaseSpec& c, const std::string& w) {
        c.loads().torque_law = w == "linear" ? TorqueLaw::Linear : TorqueLaw::Constant;
      },
      prescribed_refuses);
  b.num(
      "loads", "torque_free_speed", false, [](CaseSpec& c) { return &c.loads().torque_free_speed; },
      [](S c) {
        return c.loads().spin == SpinDrive::Torque && c.loads().torque_law == TorqueLaw::Linear
                   ? std::string()
                   : std::string(
                         "read only with loads.torque_law = \"linear\" (and a spin "
                         "driven by the torque)");
      },
      [](S c) {
        return c.loads().spin == SpinDrive::Torque && c.loads().torque_law == TorqueLaw::Linear;
      });
  b.num(
      "loads", "spin_accel", false, [](CaseSpec& c) { return &c.loads().spin_accel; },
      [](S c) {
        return c.loads().spin == SpinDrive::Prescribed
                   ? std::string()
                   : std::string("read only with loads.spin = \"prescribed\"");
      });
  b.num("loads", "unbalance", false, [](CaseSpec& c) { return &c.loads().unbalance; });
  b.num("loads", "unbalance_phase", false, [](CaseSpec& c) { return &c.loads().unbalance_phase; });
}

void initial_keys(SchemaBuilder& b, const CaseSpec& c) {
  // the model's coordinates and their rates (io/model_registry.hpp)
  const std::vector<Coordinate> coords = initial_coordinates(c);
  for (std::size_t i = 0; i < coords.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    b.num("initial", coords[i].name, false, [k](CaseSpec& s) { return &s.initial.q0[k]; });
  }
  for (std::size_t i = 0; i < coords.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    b.num("initial", coords[i].rate_key, false, [k](CaseSpec& s) { return &s.initial.v0[k]; });
  }
}

void run_solver_output_keys(SchemaBuilder& b) {
  b.num("run", "t_start", false, [](CaseSpec& c) { return &c.run.t_start; });
  b.num("run", "t_end", true, [](CaseSpec& c) { return &c.run.t_end; });
  b.num("run", "omega_lim", true, [](CaseSpec& c) { return &c.run.omega_lim; });
  b.num("run", "max_wall", false, [](CaseSpec& c) { return &c.run.max_wall; });
  b.text("solver", "kind", [](CaseSpec& c) { return &c.solver.kind; });
  b.num("solver", "rtol", false, [](CaseSpec& c) { return &c.solver.rtol; });
  b.num("solver", "atol", false, [](CaseSpec& c) { return &c.solver.atol; });
  b.text("solver", "method", [](CaseSpec& c) { return &c.solver.method; });
  b.text("solver", "contact_phases", [](CaseSpec& c) { return &c.solver.contact_phases; });
  b.text("solver", "contact_method", [](CaseSpec& c) { return &c.solver.contact_method; });
  b.num("solver", "max_events_per_second", false,
        [](CaseSpec& c) { return &c.solver.max_events_per_second; });
  b.num("solver", "h", false, [](CaseSpec& c) { return &c.solver.h; });
  b.integer("solver", "itmax", [](CaseSpec& c) { return &c.solver.itmax; });
  b.num("solver", "qn_tol", false, [](CaseSpec& c) { return &c.solver.qn_tol; });
  b.num("solver", "theta", false, [](CaseSpec& c) { return &c.solver.theta; });
  b.num("solver", "eta", false, [](CaseSpec& c) { return &c.solver.eta; });
  b.text("solver", "projection", [](CaseSpec& c) { return &c.solver.projection; });
  b.num("output", "dt", false, [](CaseSpec& c) { return &c.output.dt; });
  b.integer("output", "every", [](CaseSpec& c) { return &c.output.every; });
  b.text("output", "folder", [](CaseSpec& c) { return &c.output.folder; });
  b.text("output", "coordinates", [](CaseSpec& c) { return &c.output.coordinates; });
}

/// Every key of a case of c's model with c's flags (stator.rigid, loads.spin, loads.torque_law),
/// in the order of case.resolved.toml.
std::vector<KeySpec> schema(const CaseSpec& c) {
  SchemaBuilder b;
  b.text("model", "kind", [](CaseSpec& s) { return &s.model; });
  if (c.model == "jeffcott") {
    jeffcott_keys(b);
  } else if (c.model == "rigid-rotor") {
    rigid_rotor_keys(b, c);
  } else if (c.model == "matrices") {
    matrices_keys(b, c);
  }
  contact_and_load_keys(b);
  if (find_model(c.model)) initial_keys(b, c);
  run_solver_output_keys(b);
  if (c.model == "matrices") {
    // the rotor's modal amplitudes as output columns (model/matrix_model.hpp): a key of this
    // model's only, after the others of [output] (every other case's keys as they were)
    b.integer("output", "modes", [](CaseSpec& s) { return &s.matrices.output_modes; });
  }
  return b.keys;
}

/// The sections of every model, and which models have each key (for the messages about a key
/// of another model).
struct AllModels {
  std::vector<std::string> sections;
  std::map<std::string, std::vector<std::string>> owners;  // section.key -> kinds
};
const AllModels& all_models() {
  static const AllModels all = [] {
    AllModels a;
    for (const auto& e : model_registry()) {
      CaseSpec c;
      c.model = std::string(e.kind);
      for (const auto& k : schema(c)) {
        if (std::find(a.sections.begin(), a.sections.end(), k.section) == a.sections.end())
          a.sections.push_back(k.section);
        a.owners[k.full()].push_back(c.model);
      }
    }
    return a;
  }();
  return all;
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

/// Line `line` (1-based) of `text`, without its line end.
std::string_view line_of(std::string_view text, std::size_t line) {
  std::size_t pos = 0;
  for (std::size_t l = 1; l < line; ++l) {
    pos = text.find('\n', pos);
    if (pos == std::string_view::npos) return {};
    ++pos;
  }
  std::size_t end = text.find('\n', pos);
  if (end == std::string_view::npos) end = text.size();
  std::string_view s = text.substr(pos, end - pos);
  if (!s.empty() && s.back() == '\r') s.remove_suffix(1);
  return s;
}

/// The characters of a number as written from column `column` (1-based, in characters, as
/// toml++ counts them) of `line`: digits, signs, '.', '_', 'e', 'E', "inf", "nan".
std::string number_token(std::string_view line, std::size_t column) {
  std::size_t i = 0;
  for (std::size_t c = 1; c < column && i < line.size(); ++c) {
    ++i;  // over one UTF-8 character
    while (i < line.size() && (static_cast<unsigned char>(line[i]) & 0xC0) == 0x80) ++i;
  }
  std::size_t j = i;
  while (j < line.size() && (std::isalnum(static_cast<unsigned char>(line[j])) || line[j] == '.' ||
                             line[j] == '_' || line[j] == '+' || line[j] == '-'))
    ++j;
  return std::string(line.substr(i, j - i));
}

/// A decimal number written with a non-zero digit before its exponent: "1e-999" (read as 0 by
/// an underflow) is one, "0.0e-5" is not.
bool nonzero_mantissa(std::string_view token) {
  for (const char ch : token) {
    if (ch == 'e' || ch == 'E') return false;
    if (ch >= '1' && ch <= '9') return true;
  }
  return false;
}

/// What is wrong with a number token that a double cannot hold: "" when it can. `token` must
/// be a decimal number as a whole (strtod reads all of it), else "" too.
std::string out_of_double_range(std::string_view token) {
  std::string t;
  for (const char ch : token)
    if (ch != '_') t += ch;  // (TOML's digit separators)
  if (t.empty() || t.find_first_not_of("0123456789+-.eE") != std::string::npos) return "";
  errno = 0;
  char* end = nullptr;
  const double x = std::strtod(t.c_str(), &end);
  if (end != t.c_str() + t.size()) return "";
  if (std::isinf(x))
    return fmt::format("is outside the range of a double (magnitude at most {:.17g})",
                       std::numeric_limits<double>::max());
  if (x == 0.0 && nonzero_mantissa(t))
    return fmt::format(
        "is below the smallest double ({:.2g}) in magnitude and would be read as 0: write 0 if "
        "zero is meant",
        std::numeric_limits<double>::denorm_min());
  return "";
}

/// The key on line `line` of a TOML text as the case names it (section.key; the K-th table of
/// a [[plane]] or [[contact_node]] array as plane.K), or "" when the line holds no key.
std::string key_at_line(std::string_view text, std::size_t line) {
  const std::string_view l = line_of(text, line);
  const auto eq = l.find('=');
  if (eq == std::string_view::npos) return "";
  std::string key(l.substr(0, eq));
  key.erase(0, key.find_first_not_of(" \t"));
  key.erase(key.find_last_not_of(" \t") + 1);
  if (key.empty()) return "";
  std::string section;
  std::map<std::string, int> tables;  // [[name]] headers met so far
  for (std::size_t k = 1; k < line; ++k) {
    std::string h(line_of(text, k));
    h.erase(0, h.find_first_not_of(" \t"));
    if (h.rfind("[[", 0) == 0 && h.find("]]") != std::string::npos) {
      std::string name = h.substr(2, h.find("]]") - 2);
      section = name + "." + std::to_string(++tables[name]);
    } else if (h.rfind('[', 0) == 0 && h.find(']') != std::string::npos) {
      section = h.substr(1, h.find(']') - 1);
    }
  }
  return section.empty() ? key : section + "." + key;
}

class Loader {
 public:
  explicit Loader(std::string source, MatrixSnapshot* snapshot = nullptr)
      : source_(std::move(source)), snapshot_(snapshot) {}

  CaseSpec load(std::string_view text, const std::vector<std::string>& overrides) {
    toml::table doc;
    text_ = text;
    try {
      doc = toml::parse(text, source_);
    } catch (const toml::parse_error& e) {
      // a number a double cannot hold (toml++ refuses 1e999 as a syntax error): said as such,
      // with its key
      const std::size_t line = e.source().begin.line;
      const std::string_view l = line_of(text, line);
      const auto eq = l.find('=');
      const std::string key = key_at_line(text, line);
      std::string value;
      std::string why;
      if (eq != std::string_view::npos && !key.empty()) {
        std::string_view v = l.substr(eq + 1);
        while (!v.empty() && (v.front() == ' ' || v.front() == '\t')) v.remove_prefix(1);
        value = number_token(v, 1);
        why = out_of_double_range(value);
      }
      if (!why.empty()) {
        issues_.push_back({source_, static_cast<int>(line), key, value, why});
      } else {
        issues_.push_back(
            {source_, static_cast<int>(line), "(syntax)", "", std::string(e.description())});
      }
      throw CaseError(issues_);
    }
    split_planes(doc);
    apply_overrides(doc, overrides);
    CaseSpec c;
    c.source = source_;
    c.name = std::filesystem::path(source_).stem().string();
    // The model and its flags first: they decide which keys the case has (a rigid stator has
    // no stator coordinates; a prescribed spin no drive torque).
    read_model(doc, c);
    std::vector<KeySpec> keys = schema(c);
    if (!model_known_) {
      // an unknown kind has unknown keys: only the sections every model has are checked (the
      // model's own sections and [initial] would be judged by a model the case does not name)
      std::erase_if(keys, [](const KeySpec& k) { return model_specific(k.section); });
    }
    const std::size_t n = initial_coordinates_or_none(c);
    c.initial.q0 = Vec::Zero(static_cast<Eigen::Index>(n));
    c.initial.v0 = Vec::Zero(static_cast<Eigen::Index>(n));
    // a wide model writes its contacts' and spin's coordinates unless told otherwise
    c.output.coordinates = default_output_coordinates(n);
    check_structure(doc, c, keys);
    read_values(doc, c, keys);
    // Rules run even when other keys have problems, so that every problem is reported at once.
    // A key that is missing or of the wrong type keeps its (valid) default and so adds nothing.
    if (model_known_) check_rules(c);
    if (issues_.empty()) resolved_size_rule(c);
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

  /// The [[plane]] array's tables become the sections plane.1, plane.2, ... (their nodes keep
  /// their lines), so that every key of a plane is read, checked and named like any other:
  /// plane.2.mu. A [plane] table or a value that is not an array of tables is refused. The same
  /// for a matrices model's [[contact_node]] array (contact_node.1, ...), where a single
  /// [contact_node] section stays the one node.
  void split_planes(toml::table& doc) {
    planes_in_file_ =
        split_array(doc, "plane", kMaxPlanes, "planes", plane_section,
                    "must be an array of tables: one [[plane]] table per rub plane (at least one)");
    if (const toml::node* n = doc.get("contact_node"); n && n->is_table()) return;
    nodes_in_file_ =
        split_array(doc, "contact_node", kMaxContactNodes, "contact nodes", node_section,
                    "must be a section [contact_node] (one node) or an array of "
                    "tables, one [[contact_node]] per contact node");
  }
  /// The tables of the array `name` as sections section(k); their number (0: none or refused).
  std::size_t split_array(toml::table& doc, const std::string& name, int most, const char* what,
                          std::string (*section)(std::size_t), const char* shape_rule) {
    toml::node* n = doc.get(name);
    if (!n) return 0;
    toml::array* arr = n->as_array();
    if (!arr || !arr->is_array_of_tables() || arr->empty()) {
      issue(name, n, node_text(*n), shape_rule);
      doc.erase(name);
      return 0;
    }
    if (arr->size() > static_cast<std::size_t>(most)) {
      issue(name, n, fmt::format("{} [[{}]] tables", arr->size(), name),
            fmt::format("at most {} {}", most, what));
      doc.erase(name);
      return 0;
    }
    // (moved, not copied: a copied node forgets its line)
    std::vector<toml::table> tables;
    for (toml::node& t : *arr) tables.push_back(std::move(*t.as_table()));
    doc.erase(name);
    for (std::size_t k = 0; k < tables.size(); ++k) doc.insert(section(k), std::move(tables[k]));
    return tables.size();
  }

  void apply_overrides(toml::table& doc, const std::vector<std::string>& overrides) {
    for (const auto& ov : overrides) {
      const auto eq = ov.find('=');
      const std::string lhs = eq == std::string::npos ? ov : ov.substr(0, eq);
      // one override sets one key: a line end would let the TOML value carry more keys
      // ("0.3\ncontact.e_n=0.5"), which the parse below would silently drop
      if (std::any_of(ov.begin(), ov.end(), [](char ch) {
            return (static_cast<unsigned char>(ch) < 0x20 && ch != '\t') || ch == 0x7f;
          })) {
        issues_.push_back({"--set", 0, "(override)", toml_quote(ov),
                           "an override is one line: no line end or other control character"});
        continue;
      }
      // TOML text is UTF-8: a value with another encoding's bytes (a path typed in Latin-1)
      // could not be written back to case.resolved.toml; as a bare string it kept its quotes
      // (--out $'dir\xe9' wrote into a folder named "dir\xe9" with the quotes)
      if (!valid_utf8(ov)) {
        issues_.push_back({"--set", 0, "(override)", printable_text(ov),
                           "an override is UTF-8 text (a case is TOML): a byte of another "
                           "encoding, shown as \\xHH, cannot be written back"});
        continue;
      }
      const auto dot = lhs.find('.');
      if (eq == std::string::npos || dot == std::string::npos || dot == 0 ||
          dot + 1 == lhs.size()) {
        // (an empty --set '' has no key to name: the text itself is shown)
        issues_.push_back({"--set", 0, lhs.empty() ? "(override)" : lhs, "\"" + ov + "\"",
                           "an override must read section.key=value"});
        continue;
      }
      // (the last dot: a plane's keys are plane.K.key)
      const auto last = lhs.rfind('.');
      const std::string section = lhs.substr(0, last), key = lhs.substr(last + 1);
      const std::string rhs = ov.substr(eq + 1);
      // The value is read as a TOML value (numbers, booleans, quoted strings); anything that is
      // not one (solver.kind=mj) is taken as a bare string.
      toml::node_view<toml::node> parsed;
      toml::table holder;
      try {
        holder = toml::parse("v = " + rhs);
      } catch (const toml::parse_error&) {
        if (const std::string why = out_of_double_range(rhs); !why.empty()) {
          issues_.push_back({"--set", 0, lhs, rhs, why});  // (not a bare string: a number)
          continue;
        }
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
      set_text_[section + "." + key] = rhs;
    }
  }

  std::size_t initial_coordinates_or_none(const CaseSpec& c) const {
    return model_known_ ? initial_coordinates(c).size() : 0;
  }

  /// [model] kind and the flags the schema depends on (stator.rigid, loads.spin,
  /// loads.torque_law), read with the same rules as every key (read_values reads them again).
  void read_model(const toml::table& doc, CaseSpec& c) {
    const toml::node* sec = doc.get("model");
    const toml::node* kind = sec && sec->is_table() ? sec->as_table()->get("kind") : nullptr;
    if (kind) {
      if (auto s = kind->as_string()) {
        c.model = s->get();
      } else {
        model_known_ = false;  // reported by read_values ("must be a string")
        return;
      }
    }
    if (!find_model(c.model)) {
      std::vector<std::string> kinds;
      for (const auto& e : model_registry()) kinds.emplace_back(e.kind);
      issue("model.kind", kind, "\"" + c.model + "\"",
            "must be one of " + model_names(", ") + suggestion(c.model, kinds));
      model_known_ = false;
      c.model = "rigid-rotor";  // (its keys are still read, so that the rest is checked)
      return;
    }
    for (const auto& k : schema(c)) {
      const std::string full = k.full();
      if (full != "stator.rigid" && full != "loads.spin" && full != "loads.torque_law") continue;
      const toml::node* s = doc.get(k.section);
      const toml::node* n = s && s->is_table() ? s->as_table()->get(k.key) : nullptr;
      if (!n) continue;
      if (k.kind == Kind::Bool) {
        if (auto b = n->as_boolean()) *k.flag(c) = b->get();
      } else if (auto w = n->as_string()) {
        if (std::find(k.choices.begin(), k.choices.end(), w->get()) != k.choices.end())
          k.set(c, w->get());
      }
    }
    if (c.model == "matrices") {
      // the contact nodes of the file and their rings' kind (the coordinates depend on it)
      c.matrices.nodes.assign(nodes_in_file_, MatrixNode{});
      for (std::size_t k = 0; k < nodes_in_file_; ++k) {
        const toml::node* sec = doc.get(node_section(k));
        const toml::node* r =
            sec && sec->is_table() ? sec->as_table()->get("stator_rigid") : nullptr;
        if (r && r->as_boolean()) c.matrices.nodes[k].stator.rigid = r->as_boolean()->get();
      }
      read_matrices(doc, c);
      read_reduction(doc, c);
    } else if (nodes_in_file_ > 0) {
      issue("contact_node", nullptr, "",
            fmt::format("[[contact_node]] tables are read by [model] kind = \"matrices\" only "
                        "(this case's kind: \"{}\")",
                        c.model));
      nodes_in_file_ = 0;
    }
    if (c.model == "rigid-rotor") {
      // the planes of the file (an override cannot add one) and their rings' kind, which
      // decides the coordinates
      c.params.planes.assign(planes_in_file_, PlaneParams{});
      for (std::size_t k = 0; k < planes_in_file_; ++k) {
        const toml::node* sec = doc.get(plane_section(k));
        const toml::node* r =
            sec && sec->is_table() ? sec->as_table()->get("stator_rigid") : nullptr;
        if (r && r->as_boolean()) c.params.planes[k].rigid = r->as_boolean()->get();
      }
    } else if (planes_in_file_ > 0) {
      issue("plane", nullptr, "",
            fmt::format("[[plane]] tables are read by [model] kind = \"rigid-rotor\" only (this "
                        "case's kind: \"{}\")",
                        c.model));
      planes_in_file_ = 0;
    }
  }

  void check_structure(const toml::table& doc, CaseSpec& c, const std::vector<KeySpec>& keys) {
    std::vector<std::string> sections;
    for (const auto& k : keys)
      if (std::find(sections.begin(), sections.end(), k.section) == sections.end())
        sections.push_back(k.section);
    const AllModels& all = all_models();
    auto owners_text = [](const std::vector<std::string>& kinds) {
      std::string t;
      for (const auto& k : kinds) t += (t.empty() ? "'" : ", '") + k + "'";
      return t;
    };
    for (const auto& [k, node] : doc) {
      const std::string key(k.str());
      if (key == "name") {
        name_line_ = static_cast<int>(node.source().begin.line);
        if (auto s = node.as_string()) {
          c.name = s->get();
        } else {
          issue("name", &node, node_text(node), "must be a string");
        }
        continue;
      }
      if (!model_known_ && model_specific(key)) continue;  // (see load)
      if (std::find(sections.begin(), sections.end(), key) == sections.end()) {
        // a table of a [[plane]] or [[contact_node]] array: of another model's case (reported
        // by read_model), or one that an override names beyond the file's tables
        const bool plane = key.rfind("plane.", 0) == 0;
        if (plane || key.rfind("contact_node.", 0) == 0) {
          if (c.model == (plane ? "rigid-rotor" : "matrices")) {
            const std::string why =
                plane ? fmt::format(
                            "no such plane: the case has {} [[plane]] table(s), "
                            "numbered from 1",
                            planes_in_file_)
                      : fmt::format(
                            "no such contact node: the case has {} [[contact_node]] "
                            "table(s), numbered from 1",
                            nodes_in_file_);
            const bool by_override =
                std::any_of(overridden_.begin(), overridden_.end(),
                            [&](const std::string& o) { return o.rfind(key + ".", 0) == 0; });
            if (by_override) {
              issues_.push_back({"--set", 0, key, "", why});
            } else {
              issue(key, &node, "", why);
            }
          }
          continue;
        }
        if (model_known_ &&
            std::find(all.sections.begin(), all.sections.end(), key) != all.sections.end()) {
          issue(key, &node, "",
                fmt::format("not a section of model '{}' ([model] kind; a section of {})", c.model,
                            other_models_with_section(key, c.model)));
          continue;
        }
        // (a section that only an override names is the override's error, not the file's)
        std::string set_key;
        for (const auto& o : overridden_)
          if (o.rfind(key + ".", 0) == 0) set_key = o;
        const bool array = (key == "plane" && planes_in_file_ > 0) ||
                           (key == "contact_node" && nodes_in_file_ > 0);
        std::string why;
        if (array) {
          const std::size_t tables = key == "plane" ? planes_in_file_ : nodes_in_file_;
          why = fmt::format(
              "the case has {} [[{}]] table(s): name one by its number, {}.K.<key> with K = 1 to "
              "{} (e.g. {}.1.{})",
              tables, key, key, tables, key,
              set_key.empty() ? std::string("mu") : set_key.substr(key.size() + 1));
        } else {
          auto candidates = sections;
          candidates.push_back("name");
          why = "unknown section" + suggestion(key, candidates);
        }
        if (!set_key.empty() && node.source().begin.line == 0) {  // (made by an override)
          const auto v = set_text_.find(set_key);
          issues_.push_back({"--set", 0, set_key, v == set_text_.end() ? "" : v->second, why});
        } else {
          issue(key, &node, "", why);
        }
        continue;
      }
      const toml::table* sec = node.as_table();
      if (!sec) {
        issue(key, &node, node_text(node), "must be a section ([" + key + "])");
        continue;
      }
      std::vector<std::string> known;
      for (const auto& ks : keys)
        if (key == ks.section) known.push_back(ks.key);
      for (const auto& [kk, vv] : *sec) {
        const std::string name(kk.str());
        const std::string full = key + "." + name;
        const auto it = std::find_if(keys.begin(), keys.end(),
                                     [&](const KeySpec& ks) { return ks.full() == full; });
        if (it == keys.end()) {
          const auto own = all.owners.find(full);
          const bool ours =
              own != all.owners.end() &&
              std::find(own->second.begin(), own->second.end(), c.model) != own->second.end();
          if (model_known_ && own != all.owners.end() && !ours) {
            issue(full, &vv, node_text(vv),
                  fmt::format("not a key of model '{}' ([model] kind; a key of {})", c.model,
                              owners_text(own->second)));
          } else if (key == "initial" && model_known_) {
            issue(full, &vv, node_text(vv),
                  fmt::format("not a coordinate of this case's model '{}' (its coordinates: "
                              "{}){}",
                              c.model, coordinate_list(c),
                              c.model == "jeffcott" && c.jeffcott.stator.rigid
                                  ? "; a rigid stator (stator.rigid = true) has no coordinates"
                                  : ""));
          } else {
            issue(full, &vv, node_text(vv), "unknown key" + suggestion(name, known));
          }
          continue;
        }
        if (it->refused) {
          const std::string why = it->refused(c);
          if (!why.empty()) issue(full, &vv, node_text(vv), why);
        }
      }
    }
  }

  static std::string other_models_with_section(const std::string& section,
                                               const std::string& except) {
    std::string t;
    for (const auto& e : model_registry()) {
      if (e.kind == except) continue;
      CaseSpec c;
      c.model = std::string(e.kind);
      for (const auto& k : schema(c))
        if (k.section == section) {
          t += (t.empty() ? "'" : ", '") + std::string(e.kind) + "'";
          break;
        }
    }
    return t;
  }

  static std::string coordinate_list(const CaseSpec& c) {
    std::string t;
    for (const auto& x : initial_coordinates(c)) t += (t.empty() ? "" : ", ") + x.name;
    return t;
  }

  void read_values(const toml::table& doc, CaseSpec& c, const std::vector<KeySpec>& keys) {
    for (const auto& ks : keys) {
      const std::string full = ks.full();
      const toml::node* sec = doc.get(ks.section);
      const toml::node* n = sec && sec->is_table() ? sec->as_table()->get(ks.key) : nullptr;
      if (!n) {
        if (ks.required && ks.required(c) && (model_known_ || !model_section(ks.section))) {
          issues_.push_back({source_, sec ? static_cast<int>(sec->source().begin.line) : 0, full,
                             "", "required key is missing"});
        }
        continue;
      }
      present_[full] = n;
      if (ks.refused && !ks.refused(c).empty()) continue;  // reported by check_structure
      switch (ks.kind) {
        case Kind::Number: {
          double v = 0.0;
          if (auto f = n->as_floating_point()) {
            v = f->get();
            if (v == 0.0) {
              // 1e-999 reads as 0: an underflow the user did not mean (the number as written)
              const auto it = set_text_.find(full);
              const std::string token = it != set_text_.end() && overridden_.count(full)
                                            ? it->second
                                            : number_token(line_of(text_, n->source().begin.line),
                                                           n->source().begin.column);
              if (const std::string why = out_of_double_range(token); !why.empty()) {
                issue(full, n, token, why);
                break;
              }
            }
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
            // (read_model has model.kind, and the files of kind "matrices", resolved)
            if (full != "model.kind" && !read_early_.count(full)) *ks.text(c) = s->get();
          } else {
            issue(full, n, node_text(*n), "must be a string");
          }
          break;
        case Kind::Bool:
          if (auto b = n->as_boolean()) {
            *ks.flag(c) = b->get();
          } else {
            issue(full, n, node_text(*n), "must be true or false");
          }
          break;
        case Kind::Choice:
          if (auto s = n->as_string();
              s && std::find(ks.choices.begin(), ks.choices.end(), s->get()) != ks.choices.end()) {
            ks.set(c, s->get());
          } else {
            std::string words;
            for (const auto& w : ks.choices) words += (words.empty() ? "\"" : ", \"") + w + "\"";
            issue(full, n, node_text(*n), "must be one of " + words);
          }
          break;
      }
    }
  }

  /// A section that only some models have (their own, not [contact], [loads], [run], ...).
  static bool model_section(const std::string& section) {
    for (const auto& e : model_registry())
      for (auto s : e.sections)
        if (s == section) return true;
    return section == "initial";
  }

  /// A section whose keys depend on the model: its own sections, [initial], the tables of a
  /// [[plane]] or [[contact_node]] array.
  static bool model_specific(const std::string& section) {
    return model_section(section) || section.rfind("plane.", 0) == 0 ||
           section.rfind("contact_node.", 0) == 0;
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
    const std::size_t before = issues_.size();
    if (c.model == "jeffcott") {
      jeffcott_rules(c);
    } else if (c.model == "matrices") {
      matrices_rules(c);
    } else {
      rigid_rotor_rules(c);
    }
    load_rules(c);
    const bool model_valid = issues_.size() == before && buildable_;
    common_rules(c);
    // output.coordinates names coordinates of the model (io/columns.hpp)
    if (model_known_) {
      const std::string why =
          output_coordinates_problem(c.output.coordinates, initial_coordinates(c));
      if (!why.empty()) {
        const toml::node* n = at("output.coordinates");
        issue("output.coordinates", n, n ? node_text(*n) : "\"" + c.output.coordinates + "\"", why);
      }
    }
    // The initial state must not penetrate the stator (d_N >= 0 at every contact), checked on
    // the model itself once its parameters are valid. A state on the constraint written by a
    // run (17 significant digits) gives d_N within round-off of 0, of either sign: touching.
    // 64 ulps of g0 is about 3e-18 m for the reference case, six orders below the solver's
    // position tolerance.
    if (model_valid) {
      const auto model = build_model(c);
      derived_finite_rules(c, *model);
      const auto pen = model->initial_penetration(initial_state(c).q,
                                                  64.0 * std::numeric_limits<double>::epsilon());
      if (pen) {
        const auto coords = initial_coordinates(c);
        const PlaneCoordinates pc = plane_coordinates(coords, pen->contact);
        std::string key, names, values;
        for (int i : {pc.rotor_x, pc.rotor_y, pc.stator_x, pc.stator_y}) {
          if (i < 0) continue;
          const std::string k = "initial." + coords[static_cast<std::size_t>(i)].name;
          if (key.empty() && given(k)) key = k;
          names += (names.empty() ? "" : ", ") + coords[static_cast<std::size_t>(i)].name;
          values += (values.empty() ? "" : ", ") + fmt::format("{:.6g}", c.initial.q0[i]);
        }
        if (key.empty() && pc.rotor_x >= 0)
          key = "initial." + coords[static_cast<std::size_t>(pc.rotor_x)].name;
        if (key.empty()) {
          // a plane whose rotor point interpolates between B and R: the given rotor
          // coordinate, else plane K's position
          for (const char* k : {"initial.x_r", "initial.y_r", "initial.x_b", "initial.y_b"})
            if (key.empty() && given(k)) key = k;
          if (key.empty())
            key = plane_section(static_cast<std::size_t>(pen->contact)) + ".position";
          if (names.empty())
            names = "the rotor's point in plane " + std::to_string(pen->contact + 1);
          if (values.empty()) values = "interpolated between B and R";
        }
        issue(key, at(key), fmt::format("({}) = ({})", names, values),
              fmt::format("the initial state penetrates the stator: d_N = g0 - |r - s| = {:.6g} m "
                          "< 0",
                          pen->d_N));
      }
    }
  }

  /// A run writes the case back as case.resolved.toml (every default filled in, strings
  /// escaped), which `rubdyn analyze`, `run --from` and rubdyn.read read as a case file: it must
  /// be one, of at most kMaxCaseBytes. A case whose resolved form is larger (a string of 900 kB,
  /// whose escapes grow it) is refused here, before anything runs, naming its longest string.
  void resolved_size_rule(const CaseSpec& c) {
    const std::size_t size = resolved_toml(c).size();
    if (size <= kMaxCaseBytes) return;
    std::string key = "name";
    std::size_t longest = c.name.size();
    for (const CaseEntry& e : case_values(c)) {
      const std::string* text = std::get_if<std::string>(&e.value);
      if (text && text->size() > longest) {
        longest = text->size();
        key = e.full();
      }
    }
    const toml::node* n = at(key);
    const Origin o = key == "name" ? Origin{source_, name_line_} : origin(key, n);
    issues_.push_back(
        {o.file, o.line, key, fmt::format("(a string of {} bytes)", longest),
         fmt::format("case.resolved.toml, which a run writes and `rubdyn analyze`, `run --from` "
                     "and rubdyn.read read back as a case file, would hold {} bytes, above the "
                     "{} bytes a case file may have: shorten this string",
                     size, kMaxCaseBytes)});
  }

  /// Quantities derived from valid values must be finite too: the initial state's mechanical
  /// energy and its contact kinematics (gap, gap rate, slip speed R_r omega + ...). An overflow
  /// there (omega0 = 1e308, radius = 1e308) would only give non-finite numbers in the output.
  /// The key named is the given number of largest magnitude (the one that overflowed, in every
  /// case seen: a single absurd value among ordinary ones).
  void derived_finite_rules(const CaseSpec& c, const LagrangianModel& model) {
    const MechanicalState s0 = initial_state(c);
    std::string what;
    double value = 0.0;
    const double E = model.mechanical_energy(s0.t, s0.q, s0.v);
    if (!std::isfinite(E)) {
      what = "the initial mechanical energy";
      value = E;
    }
    for (int k = 0; k < model.contact_count() && what.empty(); ++k) {
      const ContactKinematics ck = model.contact(k, s0.t, s0.q, s0.v);
      for (const auto& [name, x] : {std::pair<const char*, double>{"gap d_N", ck.d_N},
                                    {"gap rate v_N", ck.v_N},
                                    {"slip speed v_t", ck.v_t}}) {
        if (std::isfinite(x)) continue;
        what = fmt::format("the initial {}", name);
        value = x;
        break;
      }
    }
    // the rim speed R_r |omega0| against the speed no solid is rigid at (run_envelope.hpp)
    const double R = model.contact_radius(0);
    const std::string radius_key =
        c.model == "matrices"
            ? (c.matrices.nodes.empty() ? "contact_node.radius" : "contact_node.1.radius")
        : c.params.planes.empty() ? "rotor.radius"
                                  : "plane.1.radius";
    const double omega0 =
        model.spin_coordinate() >= 0 ? std::abs(model.spin(s0.t, s0.q, s0.v)) : 0.0;
    const double rim = R * omega0;
    if (what.empty() && std::isfinite(E) && !(rim <= kMaxContactSpeed)) {
      const bool by_radius = std::abs(R) > omega0 || !given("initial.omega0");
      const std::string key = by_radius ? radius_key : "initial.omega0";
      const toml::node* n = at(key);
      issue(key, n, n ? node_text(*n) : "(default)",
            fmt::format("the initial rim speed {} x |initial.omega0| = {:.3g} m/s must "
                        "be <= {:.3g} m/s (no solid is rigid at that speed: elastic waves travel "
                        "at 6 km/s in steel, 13 km/s in beryllium)",
                        radius_key, rim, kMaxContactSpeed));
      return;
    }
    if (what.empty()) return;
    std::string key;
    double largest = -1.0;
    for (const CaseEntry& e : case_values(c)) {
      const double* x = std::get_if<double>(&e.value);
      if (!x || !given(e.full()) || !(std::abs(*x) > largest)) continue;
      largest = std::abs(*x);
      key = e.full();
    }
    // a matrices case's numbers are mostly in its files: an entry larger than every value
    // given names its file's key (M = 1e308 I overflows the energy)
    std::string entry;
    if (c.model == "matrices") {
      const MatrixRotorParams& r = c.matrices.rotor;
      const auto most = [](const auto& m) { return m.size() ? m.cwiseAbs().maxCoeff() : 0.0; };
      for (const auto& [k, a] : {std::pair<const char*, double>{"rotor.M", most(r.M)},
                                 {"rotor.C", most(r.C)},
                                 {"rotor.K", most(r.K)},
                                 {"rotor.G", most(r.G)},
                                 {"rotor.f0", most(r.f0)}}) {
        if (!(a > largest)) continue;
        largest = a;
        key = k;
        entry = fmt::format(" (an entry of {:g})", a);
      }
    }
    if (key.empty()) key = "initial.omega0";
    const toml::node* n = at(key);
    issue(key, n, n ? node_text(*n) : "(default)",
          fmt::format("{} is {} (an overflow): every quantity derived from the case must be "
                      "finite; this is the largest value given{}",
                      what, value, entry));
  }

  void rigid_rotor_rules(const CaseSpec& c) {
    const auto& r = c.params.rotor;
    rule(r.mass > 0, "rotor.mass", r.mass, "must be > 0 (a mass)");
    rule(r.Jd > 0, "rotor.Jd", r.Jd, "must be > 0 (a moment of inertia)");
    rule(r.Jp > 0, "rotor.Jp", r.Jp, "must be > 0 (a moment of inertia)");
    rule(r.L > 0, "rotor.L", r.L, "must be > 0 (a length)");
    rule(r.delta > 0, "rotor.delta", r.delta, "must be > 0 (a length)");
    rule(r.d > 0, "rotor.d", r.d, "must be > 0 (a length); d must lie in (0, L - delta]");
    const bool single = c.params.planes.empty();
    if (single) rule(r.radius > 0, "rotor.radius", r.radius, "must be > 0 (a length)");
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
    if (single) {
      const auto& s = c.params.stator;
      rule(s.mass > 0, "stator.mass", s.mass, "must be > 0 (a mass)");
      rule(s.k > 0, "stator.k", s.k, "must be > 0 (a stiffness)");
      rule(s.c >= 0, "stator.c", s.c, "must be >= 0 (a damping)");
      rule(s.gap > 0, "stator.gap", s.gap, "must be > 0 (the radial clearance g0)");
    }
    for (std::size_t k = 0; k < c.params.planes.size(); ++k) {
      const PlaneParams& pl = c.params.planes[k];
      const std::string sec = plane_section(k) + ".";
      rule(pl.position > 0 && pl.position <= r.L, sec + "position", pl.position,
           fmt::format("must lie in (0, L] = (0, {:.17g}] (the axial distance from the bearing B "
                       "to the plane, on the shaft)",
                       r.L));
      rule(pl.radius > 0, sec + "radius", pl.radius, "must be > 0 (the seal radius)");
      rule(pl.gap > 0, sec + "gap", pl.gap, "must be > 0 (the radial clearance g0)");
      law_rules(sec, pl.contact);
      if (!pl.rigid) {
        rule(pl.mass > 0, sec + "stator_mass", pl.mass, "must be > 0 (the ring's mass)");
        rule(pl.k > 0, sec + "stator_k", pl.k, "must be > 0 (the ring's support stiffness)");
        rule(pl.c >= 0, sec + "stator_c", pl.c, "must be >= 0 (the ring's support damping)");
      }
    }
    // M(q) is positive definite only if the spin's inertia exceeds the unbalance's share
    // (docs/models.md, 2.3): Jp > u_b^2 / m
    const double ub = c.params.loads.unbalance;
    if (r.mass > 0 && ub > 0)
      rule(r.Jp > ub * ub / r.mass, "rotor.Jp", r.Jp,
           fmt::format("must be > loads.unbalance^2 / rotor.mass = {:.6g} kg m^2 (the polar "
                       "inertia includes the unbalance's m eps^2)",
                       ub * ub / r.mass));
    // A rigid body's principal moments about its mass centre obey the triangle inequality
    // C <= A + B: for an axisymmetric rotor the polar moment about G is at most twice the
    // diametral one (equality: a thin disc). Jp above 2 Jd is no rigid body, and makes the
    // tilt dynamics degenerate (Jd = 5e-324 ran for minutes on 1 ms).
    if (r.mass > 0 && r.Jp > 0 && r.Jd > 0) {
      const double JpG = r.Jp - (ub > 0 ? ub * ub / r.mass : 0.0);
      rule(JpG <= 2.0 * r.Jd, "rotor.Jd", r.Jd,
           fmt::format("must be >= Jp_G / 2 = {:.6g} kg m^2 (a rigid body: polar moment about G "
                       "Jp - loads.unbalance^2 / rotor.mass = {:.6g} <= 2 Jd)",
                       0.5 * JpG, JpG));
    }
  }

  void jeffcott_rules(const CaseSpec& c) {
    const auto& r = c.jeffcott.rotor;
    rule(r.mass > 0, "rotor.mass", r.mass, "must be > 0 (a mass)");
    rule(r.k > 0, "rotor.k", r.k, "must be > 0 (a stiffness)");
    rule(r.c >= 0, "rotor.c", r.c, "must be >= 0 (a damping)");
    rule(r.radius > 0, "rotor.radius", r.radius, "must be > 0 (a length)");
    rule(r.Jp > 0, "rotor.Jp", r.Jp, "must be > 0 (a moment of inertia)");
    const double ub = c.jeffcott.loads.unbalance;
    if (r.mass > 0 && ub > 0 && r.Jp > 0)
      rule(r.Jp > ub * ub / r.mass, "rotor.Jp", r.Jp,
           fmt::format("must be > loads.unbalance^2 / rotor.mass = {:.6g} kg m^2 (the polar "
                       "inertia about the geometric centre includes the unbalance's m eps^2)",
                       ub * ub / r.mass));
    const auto& s = c.jeffcott.stator;
    if (!s.rigid) {
      rule(s.mass > 0, "stator.mass", s.mass, "must be > 0 (a mass)");
      rule(s.k > 0, "stator.k", s.k, "must be > 0 (a stiffness)");
      rule(s.c >= 0, "stator.c", s.c, "must be >= 0 (a damping)");
    }
    rule(s.gap > 0, "stator.gap", s.gap, "must be > 0 (the radial clearance g0)");
  }

  // ---- kind "matrices": the user's matrix files --------------------------------------------

  /// Reads the matrix files named in [rotor] (relative to the case file's folder) and the
  /// coordinates' names: they decide the model's coordinates, hence the [initial] keys. Their
  /// problems wait in matrix_issues_ for matrices_rules; the paths become absolute (so that
  /// case.resolved.toml, in another folder, names the files that were read).
  void read_matrices(const toml::table& doc, CaseSpec& c) {
    const toml::node* sec = doc.get("rotor");
    const toml::table* rot = sec ? sec->as_table() : nullptr;
    const std::filesystem::path base = std::filesystem::path(source_).parent_path();
    auto pend = [&](const std::string& key, const toml::node* n, std::string value,
                    std::string why) {
      const Origin o = origin(key, n);
      matrix_issues_.push_back({o.file, o.line, key, std::move(value), std::move(why)});
      matrices_ok_ = false;
    };
    auto load = [&](const std::string& k, std::string& path, Mat& m) -> const toml::node* {
      const std::string key = "rotor." + k;
      const toml::node* n = rot ? rot->get(k) : nullptr;
      if (!n || !n->as_string()) {
        if (k != "f0") matrices_ok_ = false;  // (missing or not a string: read_values says so)
        return nullptr;
      }
      const std::string given = n->as_string()->get();
      if (given.empty() && k == "f0") {  // (no constant load, as case.resolved.toml writes it)
        read_early_.insert(key);
        return nullptr;
      }
      std::filesystem::path p(given);
      if (p.is_relative()) p = base / p;
      std::error_code ec;
      const std::filesystem::path abs = std::filesystem::absolute(p, ec);
      path = (ec ? p : abs).lexically_normal().string();
      read_early_.insert(key);
      try {
        // a snapshot holds the file as it was when the case was first made (MatrixSnapshot)
        const auto held = snapshot_ ? snapshot_->find(path) : MatrixSnapshot::iterator();
        if (snapshot_ && held != snapshot_->end()) {
          m = held->second;
        } else {
          m = read_matrix_file(path);
          if (snapshot_) snapshot_->emplace(path, m);
        }
      } catch (const MatrixFileError& e) {
        pend(key, n, toml_quote(given), fmt::format("the file {}: {}", path, e.what()));
        return nullptr;
      }
      return n;
    };
    MatrixFiles& f = c.matrix_files;
    MatrixRotorParams& r = c.matrices.rotor;
    Mat M, C, K, G, f0;
    const toml::node* nM = load("M", f.M, M);
    const toml::node* nC = load("C", f.C, C);
    const toml::node* nK = load("K", f.K, K);
    const toml::node* nG = load("G", f.G, G);
    const toml::node* nf = load("f0", f.f0, f0);
    const auto shape = [](const Mat& a) { return fmt::format("{} x {}", a.rows(), a.cols()); };
    const auto quoted = [](const toml::node* n) { return node_text(*n); };
    long n = -1;
    if (nM) {
      if (M.rows() != M.cols() || M.rows() < 2 || M.rows() > kMaxMatrixSize) {
        pend("rotor.M", nM, quoted(nM),
             fmt::format("must be a square matrix of size n in [2, {}] (read {})", kMaxMatrixSize,
                         shape(M)));
      } else {
        n = M.rows();
      }
    }
    // the other matrices: n x n, with their symmetry
    const auto sym_error = [](const Mat& a, int sign) {
      // largest |a_ij - sign a_ji| and where, against 1e-12 of the largest entry (a file
      // written from formulas may carry round-off; the matrix is then used as (A +- A^T) / 2)
      Eigen::Index bi = 0, bj = 0;
      const double d = (a - sign * a.transpose()).cwiseAbs().maxCoeff(&bi, &bj);
      const double tol = 1e-12 * a.cwiseAbs().maxCoeff();
      return std::tuple<bool, double, Eigen::Index, Eigen::Index>{d <= tol, d, bi, bj};
    };
    const auto square = [&](const char* k, const toml::node* nd, const Mat& a) {
      if (!nd || n < 0) return false;
      if (a.rows() != n || a.cols() != n) {
        pend(std::string("rotor.") + k, nd, quoted(nd),
             fmt::format("must be {} x {} as rotor.M is (read {})", n, n, shape(a)));
        return false;
      }
      return true;
    };
    const auto symmetric = [&](const char* k, const toml::node* nd, Mat& a, int sign,
                               const char* what) {
      const auto [ok, d, i, j] = sym_error(a, sign);
      if (!ok) {
        pend(std::string("rotor.") + k, nd, quoted(nd),
             fmt::format("must be {}: entries ({}, {}) and ({}, {}) differ by {:.3g} from it, "
                         "above 1e-12 of its largest entry",
                         what, i, j, j, i, d));
        return false;
      }
      // (left as it is when it already is; halves first: a + a^T would overflow at 1e308)
      if (a != sign * Mat(a.transpose())) a = 0.5 * a + (0.5 * sign) * Mat(a.transpose());
      return true;
    };
    if (n >= 0 && symmetric("M", nM, M, 1, "symmetric (a mass matrix)")) {
      Eigen::LLT<Mat> llt(M);
      if (llt.info() != Eigen::Success) {
        pend("rotor.M", nM, quoted(nM),
             "must be positive definite (a mass matrix): its Cholesky factorisation fails");
      } else if (const Mat Minv = llt.solve(Mat::Identity(n, n)); !Minv.allFinite()) {
        // positive definite in exact arithmetic, but its inverse overflows a double (M = 5e-324
        // I): every acceleration would be infinite
        const Vec pivots = llt.matrixL().toDenseMatrix().diagonal();
        pend("rotor.M", nM, quoted(nM),
             fmt::format("must have an inverse a double can hold (a mass matrix): M^-1 overflows "
                         "(its smallest Cholesky pivot squared is {:.3g} kg)",
                         pivots.cwiseAbs2().minCoeff()));
      }
    }
    if (square("C", nC, C) &&
        symmetric("C", nC, C, 1, "symmetric (a damping matrix; docs/models.md, 5)")) {
      const double lo =
          Eigen::SelfAdjointEigenSolver<Mat>(C, Eigen::EigenvaluesOnly).eigenvalues().minCoeff();
      if (lo < -1e-12 * C.cwiseAbs().maxCoeff())
        pend("rotor.C", nC, quoted(nC),
             fmt::format("must be positive semidefinite (a damping: it dissipates); its smallest "
                         "eigenvalue is {:.6g}",
                         lo));
    }
    if (square("K", nK, K))
      symmetric("K", nK, K, 1,
                "symmetric (a stiffness with a potential; docs/models.md, 5: non-symmetric "
                "bearing stiffness is not modelled)");
    if (square("G", nG, G)) symmetric("G", nG, G, -1, "skew-symmetric (a gyroscopic matrix)");
    if (nf && n >= 0) {
      if (f0.cols() == 1 && f0.rows() == n) {
        // a column
      } else if (f0.rows() == 1 && f0.cols() == n) {
        f0.transposeInPlace();
      } else {
        pend("rotor.f0", nf, quoted(nf),
             fmt::format("must hold n = {} numbers (a row or a column; read {})", n, shape(f0)));
      }
    } else if (n >= 0) {
      f0 = Vec::Zero(n);
    }
    // the coordinates' names
    std::vector<std::string> names;
    const toml::node* nc = rot ? rot->get("coordinates") : nullptr;
    if (nc && nc->as_string()) {
      read_early_.insert("rotor.coordinates");
      f.coordinates = nc->as_string()->get();
    }
    if (!f.coordinates.empty()) {  // (empty, as case.resolved.toml writes none: q0, q1, ...)
      std::string word;
      std::stringstream in(f.coordinates);
      while (std::getline(in, word, ',')) {
        const auto a = word.find_first_not_of(" \t"), b = word.find_last_not_of(" \t");
        names.push_back(a == std::string::npos ? "" : word.substr(a, b - a + 1));
      }
      // each name a column of timeseries.csv and an [initial] key; so is "v" + name. Taken:
      // the other columns of this case's timeseries.csv (t, theta, omega, the rings' x_s, y_s
      // and rates, the contacts' d_N ... phase, numbered with several nodes: F_N_2), a
      // prescribed spin's observables (drive_torque) and [initial] omega0, whatever the rings
      std::set<std::string> taken = {"omega0"};
      {
        std::vector<MatrixNode> rings(std::max<std::size_t>(nodes_in_file_, 1));
        for (auto& r : rings) r.stator.rigid = false;  // (every ring's names reserved)
        // (a prescribed spin's observables, model/prescribed_spin.hpp: theta and omega are
        // the spin's coordinate names anyway)
        const std::vector<Observable> observables = {{"drive_torque", "N m", ""}};
        for (const auto& col : timeseries_columns(matrix_model_coordinates(0, {}, rings),
                                                  observables, static_cast<int>(rings.size())))
          taken.insert(col.name);
      }
      std::string bad;
      for (const auto& w : names) {
        const bool ident = !w.empty() &&
                           (std::isalpha(static_cast<unsigned char>(w[0])) || w[0] == '_') &&
                           std::all_of(w.begin(), w.end(), [](char ch) {
                             return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_';
                           });
        if (!ident) {
          bad = fmt::format("'{}' is not a name (letters, digits and _, not first a digit)", w);
          break;
        }
        std::string rate = "v";  // (appended: g++ 12 warns falsely about "v" + w)
        rate.append(w);
        if (!taken.insert(w).second || !taken.insert(rate).second) {
          bad = fmt::format(
              "'{}' (or its rate 'v{}') is taken by another coordinate or column of "
              "timeseries.csv (t, theta, omega, drive_torque, the rings' and the contacts' "
              "columns{})",
              w, w, nodes_in_file_ > 1 ? ", numbered per node: F_N_2" : "");
          break;
        }
      }
      if (bad.empty() && n >= 0 && static_cast<long>(names.size()) != n)
        bad = fmt::format("names {} coordinates where rotor.M has n = {}", names.size(), n);
      if (!bad.empty()) {
        pend("rotor.coordinates", nc, quoted(nc),
             "must name the n coordinates of q, separated by commas: " + bad);
        names.clear();
      }
    }
    // the rotations among them (rad: their unit and error weight): names or name* prefixes
    const toml::node* nr = rot ? rot->get("rotations") : nullptr;
    if (nr && nr->as_string()) {
      read_early_.insert("rotor.rotations");
      f.rotations = nr->as_string()->get();
    }
    r.rotation.clear();
    if (!f.rotations.empty() && n >= 2 && matrices_ok_) {
      // q's coordinates as the model names them (the first n; q0, q1, ... without names)
      std::vector<Coordinate> q = matrix_model_coordinates(static_cast<int>(n), names, {});
      q.resize(static_cast<std::size_t>(n));
      std::vector<bool> rotation(static_cast<std::size_t>(n), false);
      std::string bad;
      for (const std::string& w : comma_words(f.rotations)) {
        const bool prefix = !w.empty() && w.back() == '*';
        const std::string stem = prefix ? w.substr(0, w.size() - 1) : w;
        if (stem.empty() || stem.find('*') != std::string::npos) {
          bad = fmt::format("'{}' is neither a coordinate's name nor a prefix followed by *", w);
          break;
        }
        bool matched = false;
        for (std::size_t i = 0; i < q.size(); ++i) {
          const std::string& nm = q[i].name;
          if (prefix ? nm.rfind(stem, 0) == 0 : nm == stem) rotation[i] = matched = true;
        }
        if (!matched) {
          bad = fmt::format("'{}' matches no coordinate of q (its coordinates: {})", w,
                            brief_coordinate_list(q));
          break;
        }
      }
      if (bad.empty()) {
        r.rotation = std::move(rotation);
      } else {
        pend("rotor.rotations", nr, quoted(nr),
             "must list q's rotations (rad) by name or prefix*, separated by commas: " + bad);
      }
    }
    if (!matrices_ok_) {
      // the coordinates of what could be read (so that [initial] is still checked): rotor.M's
      // size, or without it as many as rotor.coordinates names (so that [initial] keys of
      // those names are not reported as another model's)
      if (n < 0 && !names.empty()) n = static_cast<long>(names.size());
      r.M.resize(n >= 0 ? n : 0, n >= 0 ? n : 0);
      r.names = names;
      return;
    }
    r.M = std::move(M);
    r.C = std::move(C);
    r.K = std::move(K);
    r.G = std::move(G);
    r.f0 = f0;
    r.names = std::move(names);
  }

  /// [reduction] (kind "matrices"): its keys and the contact nodes' coordinates are read before
  /// the others (read_values reads them again and reports a wrong type; the node rules report
  /// bad indices), and the reduced model is computed once here: its coordinates are the case's
  /// ([initial] keys, output columns). Its problems wait in matrix_issues_ for matrices_rules.
  void read_reduction(const toml::table& doc, CaseSpec& c) {
    const toml::node* sec = doc.get("reduction");
    const toml::table* t = sec ? sec->as_table() : nullptr;
    if (!t) return;
    ReductionParams& r = c.reduction;
    if (const toml::node* n = t->get("method"); n && n->as_string()) {
      const std::string w = n->as_string()->get();
      r.method = w == "modal"           ? ReductionMethod::Modal
                 : w == "craig-bampton" ? ReductionMethod::CraigBampton
                                        : ReductionMethod::None;
    }
    if (r.method == ReductionMethod::None) return;
    if (const toml::node* n = t->get("modes"); n && n->as_integer()) {
      const auto v = n->as_integer()->get();
      r.modes = v < 0 ? -1 : static_cast<int>(std::min<std::int64_t>(v, 1 << 30));
    }
    if (const toml::node* n = t->get("cutoff")) {
      if (auto f = n->as_floating_point()) r.cutoff = f->get();
      if (auto i = n->as_integer()) r.cutoff = static_cast<double>(i->get());
    }
    reduction_ok_ = false;  // until it is computed
    if (!matrices_ok_) return;
    // the nodes' coordinates as the file gives them (a node's other keys do not matter here)
    MatrixParams p = c.matrices;
    const auto index = [&doc](const std::string& section, const char* key, int& out) {
      const toml::node* s = doc.get(section);
      const toml::node* n = s && s->is_table() ? s->as_table()->get(key) : nullptr;
      if (!n || !n->as_integer()) return false;
      const auto v = n->as_integer()->get();
      if (v < 0 || v > std::numeric_limits<int>::max()) return false;
      out = static_cast<int>(v);
      return true;
    };
    bool nodes_read = true;
    if (p.nodes.empty()) {
      nodes_read = index("contact_node", "x", p.node.x) && index("contact_node", "y", p.node.y);
    } else {
      for (std::size_t k = 0; k < p.nodes.size(); ++k)
        nodes_read = nodes_read && index(node_section(k), "x", p.nodes[k].at.x) &&
                     index(node_section(k), "y", p.nodes[k].at.y);
    }
    if (!nodes_read) return;  // (the node's rules say why)
    try {
      c.reduced = std::make_shared<const ReducedMatrices>(reduce_matrix_model(p, r));
      reduction_ok_ = true;
    } catch (const ReductionRefused& e) {
      const std::string key = e.key();
      const toml::node* n = key.rfind("reduction.", 0) == 0 ? t->get(key.substr(10)) : nullptr;
      // (a key not given, e.g. modes with neither modes nor cutoff: where the method is)
      const Origin o = n ? origin(key, n) : origin("reduction.method", t->get("method"));
      matrix_issues_.push_back({o.file, o.line, key, n ? node_text(*n) : "", e.what()});
    }
  }

  void matrices_rules(const CaseSpec& c) {
    const std::size_t before = issues_.size();
    issues_.insert(issues_.end(), matrix_issues_.begin(), matrix_issues_.end());
    const MatrixParams& p = c.matrices;
    const int n = p.rotor.size();
    rule(p.rotor.Jp > 0, "rotor.Jp", p.rotor.Jp, "must be > 0 (a moment of inertia)");
    if (p.nodes.empty()) {
      if (n >= 2) {
        for (const auto& [key, i] : {std::pair<const char*, int>{"contact_node.x", p.node.x},
                                     {"contact_node.y", p.node.y}})
          rule(i >= 0 && i < n, key, i,
               fmt::format("must be the 0-based index of a coordinate of q, in [0, {}]", n - 1));
        rule(p.node.x != p.node.y, "contact_node.y", p.node.y,
             "must differ from contact_node.x (the node's two coordinates)");
      }
      rule(p.node.radius > 0, "contact_node.radius", p.node.radius, "must be > 0 (a length)");
      rule(p.node.gap > 0, "contact_node.gap", p.node.gap, "must be > 0 (the radial clearance g0)");
      const auto& s = p.stator;
      if (!s.rigid) {
        rule(s.mass > 0, "stator.mass", s.mass, "must be > 0 (a mass)");
        rule(s.k > 0, "stator.k", s.k, "must be > 0 (a stiffness)");
        rule(s.c >= 0, "stator.c", s.c, "must be >= 0 (a damping)");
      }
    }
    for (std::size_t k = 0; k < p.nodes.size(); ++k) {
      const MatrixNode& nd = p.nodes[k];
      const std::string sec = node_section(k) + ".";
      if (n >= 2) {
        for (const auto& [key, i] :
             {std::pair<std::string, int>{sec + "x", nd.at.x}, {sec + "y", nd.at.y}}) {
          rule(i >= 0 && i < n, key, i,
               fmt::format("must be the 0-based index of a coordinate of q, in [0, {}]", n - 1));
          // a coordinate belongs to one node
          for (std::size_t j = 0; j < k; ++j) {
            const MatrixNode& o = p.nodes[j];
            rule(i != o.at.x && i != o.at.y, key, i,
                 fmt::format("is already a coordinate of contact node {} ({}x = {}, {}y = {})",
                             j + 1, node_section(j) + ".", o.at.x, node_section(j) + ".", o.at.y));
          }
        }
        rule(nd.at.x != nd.at.y, sec + "y", nd.at.y,
             "must differ from " + sec + "x (the node's two coordinates)");
      }
      rule(nd.at.radius > 0, sec + "radius", nd.at.radius, "must be > 0 (the seal radius)");
      rule(nd.at.gap > 0, sec + "gap", nd.at.gap, "must be > 0 (the radial clearance g0)");
      law_rules(sec, nd.law);
      if (!nd.stator.rigid) {
        rule(nd.stator.mass > 0, sec + "stator_mass", nd.stator.mass,
             "must be > 0 (the ring's mass)");
        rule(nd.stator.k > 0, sec + "stator_k", nd.stator.k,
             "must be > 0 (the ring's support stiffness)");
        rule(nd.stator.c >= 0, sec + "stator_c", nd.stator.c,
             "must be >= 0 (the ring's support damping)");
      }
    }
    // a seal circle's centre is a deflection (m), never a rotation
    if (static_cast<int>(p.rotor.rotation.size()) == n) {
      const std::vector<MatrixNode> list = p.node_list();
      for (std::size_t k = 0; k < list.size(); ++k)
        for (const int i : {list[k].at.x, list[k].at.y}) {
          if (i < 0 || i >= n || !p.rotor.rotation[static_cast<std::size_t>(i)]) continue;
          const auto& nm = p.rotor.names;
          rule(false, "rotor.rotations", 0.0,
               fmt::format("must not name coordinate {} ('{}'): it is {}'s seal circle centre, "
                           "a deflection in m",
                           i,
                           static_cast<int>(nm.size()) == n ? nm[static_cast<std::size_t>(i)]
                                                            : "q" + std::to_string(i),
                           list.size() > 1 ? "contact node " + std::to_string(k + 1)
                                           : std::string("the contact node")));
        }
    }
    // ([reduction]'s own rules are reduce_matrix_model's, reported by read_reduction)
    const int modes = p.output_modes;
    rule(modes >= 0, "output.modes", modes,
         "must be >= 0 (the number of the rotor's lowest free modes whose amplitudes "
         "timeseries.csv holds; 0: none)");
    buildable_ = matrices_ok_ && reduction_ok_;
    if (!buildable_ || issues_.size() != before) return;
    if (modes > 0) {
      // the modes are those of the model integrated: the reduced rotor's with a [reduction]
      const MatrixParams mp = matrix_model_params(c);
      const int nr = mp.rotor.size();
      rule(modes <= nr, "output.modes", modes,
           c.reduced ? fmt::format("must be at most n = {} (the reduced rotor's coordinates: the "
                                   "modes are those of the model integrated)",
                                   nr)
                     : fmt::format("must be at most n = {} (the rotor's coordinates)", nr));
      rule(modes > nr || modes % 2 == 0 || !isotropic_rotor(mp), "output.modes", modes,
           "must be even: the rotor is isotropic and its modes come in (x, y) pairs of one "
           "frequency (both of a pair are written)");
      // the columns mode<k>, vmode<k> must not be a coordinate's or its rate's
      for (const Coordinate& x : initial_coordinates(c))
        for (int k = 1; k <= modes && k <= nr; ++k)
          for (const std::string& col : {fmt::format("mode{}", k), fmt::format("vmode{}", k)})
            rule(x.name != col && x.rate != col, "output.modes", modes,
                 fmt::format("would write a column {} beside the coordinate {} (its rate {}): "
                             "rename the coordinate",
                             col, x.name, x.rate));
      if (issues_.size() != before) return;
    }
    // M_full(q) = [[M, b], [b^T, Jp]] is positive definite where the Schur complement
    // Jp - b^T M^-1 b of theta is > 0 (docs/models.md, 5.3): required of the initial state
    // (of the reduced model with a [reduction]: its coordinates are the initial state's)
    const double schur = MatrixModel(matrix_model_params(c)).schur(c.initial.q0);
    rule(schur > 0, "rotor.Jp", p.rotor.Jp,
         fmt::format("must exceed b^T M^-1 b = {:.6g} kg m^2 at the initial state (b = G q / 2 "
                     "+ the unbalance's column; docs/models.md, 5.3): M_full is not positive "
                     "definite there",
                     p.rotor.Jp - schur));
  }

  void load_rules(const CaseSpec& c) {
    const LoadParams& L = c.loads();
    rule(L.gravity >= 0, "loads.gravity", L.gravity, "must be >= 0 (its direction is fixed: -Y)");
    if (L.spin == SpinDrive::Torque && L.torque_law == TorqueLaw::Linear)
      rule(L.torque_free_speed > 0, "loads.torque_free_speed", L.torque_free_speed,
           "must be > 0 (the speed at which the linear torque law gives no torque) [rad/s]");
    rule(L.unbalance >= 0, "loads.unbalance", L.unbalance,
         "must be >= 0 (m eps [kg m]; its direction is loads.unbalance_phase)");
  }

  /// The one rule of a contact law, for every key that takes one (contact.*, plane.K.*,
  /// contact_node.K.*; prefix: the section with its dot).
  void law_rules(const std::string& prefix, const ContactLaw& l) {
    rule(l.mu >= 0, prefix + "mu", l.mu, "must be >= 0 (a friction coefficient)");
    rule(l.e_n >= 0 && l.e_n <= 1, prefix + "e_n", l.e_n, "must lie in [0, 1] (a restitution)");
    rule(l.e_t >= 0 && l.e_t <= 1, prefix + "e_t", l.e_t, "must lie in [0, 1] (a restitution)");
  }

  void common_rules(const CaseSpec& c) {
    const auto& k = c.contact();
    if (c.model != "rigid-rotor" || c.params.planes.empty()) {  // (else each plane's law)
      law_rules("contact.", k);
    }
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
    if (so.method != "auto" && so.method != "bdf" && so.method != "adams") {
      issue("solver.method", at("solver.method"), "\"" + so.method + "\"",
            "must be auto, bdf or adams");
    }
    if (so.contact_phases != "auto" && so.contact_phases != "reduced" &&
        so.contact_phases != "projection") {
      issue("solver.contact_phases", at("solver.contact_phases"), "\"" + so.contact_phases + "\"",
            "must be auto, reduced or projection");
    }
    if (so.contact_method != "auto" && so.contact_method != "bdf" && so.contact_method != "adams") {
      issue("solver.contact_method", at("solver.contact_method"), "\"" + so.contact_method + "\"",
            "must be auto, bdf or adams");
    }
    if (so.projection != "mass" && so.projection != "identity") {
      issue("solver.projection", at("solver.projection"), "\"" + so.projection + "\"",
            "must be mass or identity");
    }
    // The solvers' options, through the one mapping from a case to them
    // (io/solver_options.hpp, which the run uses too): each family states its own rules.
    for (const KeyProblem& p : solver_option_problems(c)) {
      const toml::node* n = at(p.key);
      issue(p.key, n, n ? node_text(*n) : p.value + " (default)", p.rule);
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
  }

  std::string source_;
  MatrixSnapshot* snapshot_ = nullptr;  // kind "matrices": files as first read (case_io.hpp)
  int name_line_ = 0;                   // the line of the top-level `name`
  std::string_view text_;               // the case file's text (numbers as written)
  std::vector<CaseIssue> issues_;
  std::set<std::string> overridden_;
  std::map<std::string, std::string> set_text_;  // an override's value as given
  std::map<std::string, const toml::node*> present_;
  bool model_known_ = true;         // [model] kind names a model of the registry
  std::size_t planes_in_file_ = 0;  // the tables of the file's [[plane]] array
  std::size_t nodes_in_file_ = 0;   // the tables of the file's [[contact_node]] array
  // kind "matrices": the keys read_model resolved (read_values keeps them), the problems of the
  // files (reported by matrices_rules), whether every matrix was read and is valid
  std::set<std::string> read_early_;
  std::vector<CaseIssue> matrix_issues_;
  bool matrices_ok_ = true;
  bool reduction_ok_ = true;  // no [reduction], or the reduced model was computed
  bool buildable_ = true;     // the model can be built (with valid parameters)
};

}  // namespace

CaseSpec parse_case(std::string_view toml_text, const std::string& source,
                    const std::vector<std::string>& overrides, MatrixSnapshot* snapshot) {
  return Loader(source, snapshot).load(toml_text, overrides);
}

std::string read_case_file(const std::string& path) {
  auto refuse = [&path](const std::string& why) {
    throw CaseError({{path, 0, "(file)", "", why}});
  };
  // a regular file or a FIFO of at most kMaxCaseBytes is a case file (text_files.hpp)
  std::string text;
  try {
    text = read_input_file(path, kMaxCaseBytes, "case");
  } catch (const InputRefused& e) {
    refuse(e.what());
  }
  if (text.find('\0') != std::string::npos) refuse("holds NUL bytes: not a text (TOML) file");
  return text;
}

CaseSpec load_case(const std::string& path, const std::vector<std::string>& overrides) {
  return parse_case(read_case_file(path), path, overrides);
}

std::string toml_quote(std::string_view text) {
  return quoted_string(text);
}

std::vector<CaseEntry> case_values(const CaseSpec& c) {
  std::vector<CaseEntry> out;
  CaseSpec copy = c;  // schema accessors take a mutable CaseSpec
  for (const auto& ks : schema(c)) {
    if (ks.refused && !ks.refused(c).empty()) continue;  // not a key of this case
    CaseEntry e{ks.section, ks.key, {}};
    switch (ks.kind) {
      case Kind::Number: e.value = *ks.num(copy); break;
      case Kind::Integer: e.value = *ks.integer(copy); break;
      case Kind::String: e.value = *ks.text(copy); break;
      case Kind::Bool: e.value = *ks.flag(copy); break;
      case Kind::Choice: e.value = ks.get(c); break;
    }
    out.push_back(std::move(e));
  }
  return out;
}

std::string to_toml(const CaseSpec& c) {
  std::string out = fmt::format("# resolved case: every key with its value (rubdyn)\nname = {}\n",
                                toml_quote(c.name));
  std::string section;
  for (const CaseEntry& e : case_values(c)) {
    if (section != e.section) {
      section = e.section;
      // a plane's section plane.K is the K-th table of the [[plane]] array, a node's
      // contact_node.K the K-th of [[contact_node]]
      out += section.rfind("plane.", 0) == 0          ? std::string("\n[[plane]]\n")
             : section.rfind("contact_node.", 0) == 0 ? std::string("\n[[contact_node]]\n")
                                                      : fmt::format("\n[{}]\n", section);
    }
    std::string v;
    if (const double* x = std::get_if<double>(&e.value)) {
      // shortest round-trip digits, always as a TOML float: "-0" would read back as the
      // integer 0 and lose the sign of -0.0 (found by tests/fuzz)
      v = fmt::format("{}", *x);
      if (v.find_first_of(".eEn") == std::string::npos) v += ".0";
    } else if (const int* i = std::get_if<int>(&e.value)) {
      v = fmt::format("{}", *i);
    } else if (const bool* f = std::get_if<bool>(&e.value)) {
      v = *f ? "true" : "false";
    } else {
      v = toml_quote(std::get<std::string>(e.value));
    }
    out += fmt::format("{} = {}\n", e.key, v);
  }
  return out;
}

std::vector<std::string> case_keys(const CaseSpec& c) {
  std::vector<std::string> keys;
  for (const auto& k : schema(c))
    if (!k.refused || k.refused(c).empty()) keys.push_back(k.full());
  return keys;
}

std::string output_folder(const CaseSpec& c) {
  if (!c.output.folder.empty()) return c.output.folder;
  // the name becomes one folder under out/: a name that is no single folder name would write
  // elsewhere (".." is out/.. = the current folder, "a/../../x" anywhere)
  const std::string& n = c.name;
  if (n.empty() || n == "." || n == ".." || n.find('/') != std::string::npos ||
      n.find('\0') != std::string::npos)
    throw CaseError({{c.source, 0, "name", n,
                      "cannot name the output folder out/<name> (empty, '.', '..' or with a "
                      "'/'): give output.folder or --out, or another name"}});
  return "out/" + n;
}

}  // namespace rubdyn
