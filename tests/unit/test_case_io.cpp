// Case files: the reference deck, every bad-input rule (one check each, asserting the message
// names the key and the line), several errors at once, overrides, and the resolved-case round trip.
#include <catch2/catch.hpp>
#include <fstream>
#include <sstream>
#include <string>

#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"

using namespace rubdyn;

namespace {

// A complete valid case; line numbers matter for the tests below (1-based, noted per key).
const char* kValid = R"(name = "t"
[rotor]
mass = 5.0
Jd = 0.035
Jp = 0.06
L = 0.5
delta = 0.1
d = 0.3
radius = 0.05
[bearing]
k = 5.0e6
c = 300.0
[stator]
mass = 2.0
k = 2.0e6
c = 100.0
gap = 2.0e-4
[contact]
mu = 0.1
e_n = 0.0
e_t = 0.0
[loads]
gravity = 9.81
torque = 20.0
[initial]
omega0 = 2000.0
[run]
t_end = 0.5
omega_lim = 2110.0
)";

/// kValid with the line "key = ..." of `section` replaced by "key = value" (or removed when value
/// is empty). Returns the text and the 1-based line of that key.
std::pair<std::string, int> with_value(const std::string& section, const std::string& key,
                                       const std::string& value) {
  std::istringstream in(kValid);
  std::string line, out, current;
  int n = 0, found = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.size() > 2 && line.front() == '[') current = line.substr(1, line.size() - 2);
    if (current == section && line.rfind(key + " =", 0) == 0) {
      found = n;
      if (value.empty()) continue;
      line = key + " = " + value;
    }
    out += line + "\n";
  }
  REQUIRE(found > 0);
  return {out, found};
}

/// Parses and expects exactly one issue naming key and line; returns the issue's rule text.
std::string one_issue(const std::string& text, const std::string& key, int line) {
  try {
    parse_case(text, "case.toml");
  } catch (const CaseError& e) {
    INFO(e.what());
    REQUIRE(e.issues().size() == 1);
    const auto& i = e.issues()[0];
    REQUIRE(i.key == key);
    REQUIRE(i.file == "case.toml");
    if (line > 0) REQUIRE(i.line == line);
    // the formatted message names file:line, the key and the rule
    const std::string msg = e.what();
    REQUIRE(msg.find(key) != std::string::npos);
    if (line > 0) REQUIRE(msg.find("case.toml:" + std::to_string(line)) != std::string::npos);
    return i.rule;
  }
  FAIL("no CaseError for " << key);
  return {};
}

std::string bad(const std::string& section, const std::string& key, const std::string& value) {
  auto [text, line] = with_value(section, key, value);
  return one_issue(text, section + "." + key, line);
}

}  // namespace

TEST_CASE("The reference case file has the spec's values", "[io]") {
  const CaseSpec c = load_case(std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml");
  // the reference parameter set
  CHECK(c.name == "reference");
  CHECK(c.params.rotor.mass == 5.0);
  CHECK(c.params.rotor.Jd == 0.035);
  CHECK(c.params.rotor.Jp == 0.06);
  CHECK(c.params.rotor.L == 0.5);
  CHECK(c.params.rotor.delta == 0.1);
  CHECK(c.params.rotor.d == 0.3);
  CHECK(c.params.rotor.radius == 0.05);
  CHECK(c.params.bearing.k == 5.0e6);
  CHECK(c.params.bearing.c == 300.0);
  CHECK(c.params.stator.mass == 2.0);
  CHECK(c.params.stator.k == 2.0e6);
  CHECK(c.params.stator.c == 100.0);
  CHECK(c.params.stator.gap == 2.0e-4);
  CHECK(c.params.contact.mu == 0.1);
  CHECK(c.params.contact.e_n == 0.0);
  CHECK(c.params.contact.e_t == 0.0);
  CHECK(c.params.loads.gravity == 9.81);
  CHECK(c.params.loads.torque == 20.0);
  CHECK(c.initial.v0[4] == 2000.0);
  CHECK(c.initial.q0.isZero());
  CHECK(c.run.t_end == 0.5);
  CHECK(c.run.omega_lim == 2110.0);
  CHECK(c.solver.kind == "event");
  CHECK(output_folder(c) == "out/reference");
}

TEST_CASE("Each rule on physical parameters is enforced and named", "[io]") {
  CHECK(bad("rotor", "mass", "0.0").find("> 0") != std::string::npos);
  CHECK(bad("rotor", "mass", "-5.0").find("> 0") != std::string::npos);
  CHECK(bad("rotor", "Jd", "0.0").find("> 0") != std::string::npos);
  CHECK(bad("rotor", "Jp", "-1.0").find("> 0") != std::string::npos);
  CHECK(bad("rotor", "L", "0.0").find("> 0") != std::string::npos);
  CHECK(bad("rotor", "delta", "0.0").find("> 0") != std::string::npos);
  CHECK(bad("rotor", "radius", "0.0").find("> 0") != std::string::npos);
  CHECK(bad("bearing", "k", "0.0").find("> 0") != std::string::npos);
  CHECK(bad("stator", "k", "-2.0").find("> 0") != std::string::npos);
  CHECK(bad("stator", "mass", "0").find("> 0") != std::string::npos);
  CHECK(bad("stator", "gap", "0.0").find("> 0") != std::string::npos);
  CHECK(bad("bearing", "c", "-1.0").find(">= 0") != std::string::npos);
  CHECK(bad("stator", "c", "-0.5").find(">= 0") != std::string::npos);
  CHECK(bad("contact", "mu", "-0.1").find(">= 0") != std::string::npos);
  CHECK(bad("contact", "e_n", "1.5").find("[0, 1]") != std::string::npos);
  CHECK(bad("contact", "e_t", "-0.1").find("[0, 1]") != std::string::npos);
  CHECK(bad("loads", "gravity", "-9.81").find(">= 0") != std::string::npos);
  CHECK(bad("run", "t_end", "0.0").find("> 0") != std::string::npos);
  CHECK(bad("run", "omega_lim", "-1.0").find("> 0") != std::string::npos);
}

TEST_CASE("Geometric rules: delta < L and d in (0 - L - delta)", "[io]") {
  CHECK(bad("rotor", "delta", "0.5").find("< L") != std::string::npos);
  CHECK(bad("rotor", "delta", "0.7").find("< L") != std::string::npos);
  CHECK(bad("rotor", "d", "0.45").find("(0, L - delta]") != std::string::npos);
  CHECK(bad("rotor", "d", "0.0").find("> 0") != std::string::npos);
  // d = L - delta exactly is admissible (G at R)
  auto [text, line] = with_value("rotor", "d", "0.4");
  (void)line;
  REQUIRE_NOTHROW(parse_case(text, "case.toml"));
}

TEST_CASE("Non-finite numbers - wrong types - missing keys - unknown keys and sections", "[io]") {
  CHECK(bad("rotor", "mass", "nan").find("finite") != std::string::npos);
  CHECK(bad("stator", "k", "inf").find("finite") != std::string::npos);
  CHECK(bad("contact", "mu", "\"high\"").find("number") != std::string::npos);
  CHECK(bad("loads", "torque", "true").find("number") != std::string::npos);
  {
    auto [text, line] = with_value("stator", "gap", "");
    // a missing key is reported at the line of its section header ([stator] is line 13)
    CHECK(one_issue(text, "stator.gap", 13).find("missing") != std::string::npos);
  }
  {
    const std::string text = std::string(kValid) + "[stator2]\nk = 1.0\n";
    CHECK(one_issue(text, "stator2", 30).find("did you mean 'stator'") != std::string::npos);
  }
  {
    auto [text, line] = with_value("stator", "k", "2.0e6\nkk = 3.0");
    CHECK(one_issue(text, "stator.kk", line + 1).find("did you mean 'k'") != std::string::npos);
  }
}

TEST_CASE("An initial state that penetrates the stator is rejected", "[io]") {
  const std::string text = std::string(kValid) + "x_r = 3.0e-4\n";
  // the key is appended under [run]: move it to [initial]
  std::string t2 = kValid;
  t2.replace(t2.find("omega0 = 2000.0"), 15, "omega0 = 2000.0\nx_r = 3.0e-4");
  const std::string rule = one_issue(t2, "initial.x_r", 27);
  CHECK(rule.find("penetrates") != std::string::npos);
  // touching (d_N = 0) is admissible
  std::string t3 = kValid;
  t3.replace(t3.find("omega0 = 2000.0"), 15, "omega0 = 2000.0\ny_r = -2.0e-4");
  REQUIRE_NOTHROW(parse_case(t3, "case.toml"));
  // a state written by a run on the constraint: d_N = -2.7e-20 m is round-off (1 ulp of g0), so
  // it is touching, not penetrating
  std::string t4 = kValid;
  t4.replace(t4.find("omega0 = 2000.0"), 15, "omega0 = 2000.0\ny_r = -0.00020000000000000004");
  REQUIRE_NOTHROW(parse_case(t4, "case.toml"));
  // 1e-15 m is far beyond round-off of g0 (~3e-18 m): rejected
  std::string t5 = kValid;
  t5.replace(t5.find("omega0 = 2000.0"), 15, "omega0 = 2000.0\ny_r = -0.000200000000001");
  CHECK(one_issue(t5, "initial.y_r", 27).find("penetrates") != std::string::npos);
}

TEST_CASE("Several errors in one file are all reported", "[io]") {
  std::string t = kValid;
  t.replace(t.find("mass = 5.0"), 10, "mass = -5.0");
  t.replace(t.find("mu = 0.1"), 8, "mu = -1.0");
  t.replace(t.find("e_n = 0.0"), 9, "e_n = 2.0");
  t += "[solver]\nkind = \"implicit\"\nrtoll = 1e-8\n";
  try {
    parse_case(t, "case.toml");
    FAIL("expected a CaseError");
  } catch (const CaseError& e) {
    INFO(e.what());
    REQUIRE(e.issues().size() == 5);
    const std::string msg = e.what();
    for (const char* key :
         {"rotor.mass", "contact.mu", "contact.e_n", "solver.kind", "solver.rtoll"})
      CHECK(msg.find(key) != std::string::npos);
  }
}

TEST_CASE("Solver and output rules", "[io]") {
  auto solver = [](const std::string& kv) {
    return std::string(kValid) + "[solver]\n" + kv + "\n";
  };
  CHECK(one_issue(solver("kind = \"mjj\""), "solver.kind", 31).find("did you mean 'mj'") !=
        std::string::npos);
  CHECK(one_issue(solver("rtol = 0.0"), "solver.rtol", 31).find("> 0") != std::string::npos);
  CHECK(one_issue(solver("h = -1e-6"), "solver.h", 31).find("> 0") != std::string::npos);
  CHECK(one_issue(solver("itmax = 0"), "solver.itmax", 31).find(">= 1") != std::string::npos);
  CHECK(one_issue(solver("itmax = 2.5"), "solver.itmax", 31).find("integer") != std::string::npos);
  CHECK(one_issue(solver("theta = 0.3"), "solver.theta", 31).find("[0.5, 1]") != std::string::npos);
  CHECK(one_issue(solver("eta = 1.5"), "solver.eta", 31).find("[0, 1]") != std::string::npos);
  CHECK(one_issue(solver("projection = \"euclid\""), "solver.projection", 31)
            .find("mass or identity") != std::string::npos);
  CHECK(one_issue(solver("method = \"rk4\""), "solver.method", 31).find("bdf or adams") !=
        std::string::npos);
  CHECK(one_issue(solver("contact_phases = \"dae\""), "solver.contact_phases", 31)
            .find("reduced or projection") != std::string::npos);
  CHECK(one_issue(solver("contact_method = \"rk4\""), "solver.contact_method", 31)
            .find("bdf or adams") != std::string::npos);
  const std::string out = std::string(kValid) + "[output]\ndt = 0.0\n";
  CHECK(one_issue(out, "output.dt", 31).find("> 0") != std::string::npos);
}

TEST_CASE("A TOML syntax error names the file and line", "[io]") {
  std::string t = kValid;
  t.replace(t.find("k = 5.0e6"), 9, "k = 5.0e6 6");
  try {
    parse_case(t, "case.toml");
    FAIL("expected a CaseError");
  } catch (const CaseError& e) {
    REQUIRE(e.issues().size() == 1);
    CHECK(e.issues()[0].line == 11);
    CHECK(std::string(e.what()).find("case.toml:11") != std::string::npos);
  }
}

TEST_CASE("A missing file is reported with its path", "[io]") {
  try {
    load_case("/nonexistent/dir/case.toml");
    FAIL("expected a CaseError");
  } catch (const CaseError& e) {
    CHECK(std::string(e.what()).find("/nonexistent/dir/case.toml") != std::string::npos);
  }
}

TEST_CASE("Overrides replace or add keys and are validated the same way", "[io]") {
  const CaseSpec c = parse_case(kValid, "case.toml",
                                {"contact.mu=0.25", "solver.kind=mj", "solver.h=1e-7",
                                 "initial.x_r=1e-5", "output.folder=\"out/x\""});
  CHECK(c.params.contact.mu == 0.25);
  CHECK(c.solver.kind == "mj");
  CHECK(c.solver.h == 1e-7);
  CHECK(c.initial.q0[2] == 1e-5);
  CHECK(output_folder(c) == "out/x");
  try {
    parse_case(kValid, "case.toml", {"contact.mu=-1", "stator.kk=3", "nodot=1", "rotor.mass"});
    FAIL("expected a CaseError");
  } catch (const CaseError& e) {
    INFO(e.what());
    REQUIRE(e.issues().size() == 4);
    for (const auto& i : e.issues()) CHECK(i.file == "--set");
    CHECK(e.issues()[0].key == "nodot");
    CHECK(e.issues()[1].key == "rotor.mass");
  }
}

TEST_CASE("to_toml round-trips every key", "[io]") {
  CaseSpec c = parse_case(
      kValid, "case.toml",
      {"contact.e_n=0.3", "initial.x_b=1.25e-7", "initial.vy_s=-0.01", "solver.kind=\"carp-qn\"",
       "solver.itmax=7", "solver.theta=0.75", "output.every=10",
       "output.folder=\"out/with \\\"quote\\\"\"", "loads.torque=0.1"});
  const CaseSpec back = parse_case(to_toml(c), "resolved.toml");
  CHECK(back.name == c.name);
  CHECK(back.params.contact.e_n == c.params.contact.e_n);
  CHECK(back.params.loads.torque == c.params.loads.torque);
  CHECK(back.initial.q0 == c.initial.q0);
  CHECK(back.initial.v0 == c.initial.v0);
  CHECK(back.solver.kind == c.solver.kind);
  CHECK(back.solver.itmax == c.solver.itmax);
  CHECK(back.solver.theta == c.solver.theta);
  CHECK(back.output.every == c.output.every);
  CHECK(back.output.folder == c.output.folder);
  // and a second round trip is textually identical
  CHECK(to_toml(back) == to_toml(c));
}
