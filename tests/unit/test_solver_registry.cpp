// The solver registry (io/solver_options.hpp) against the documentation and the case file: the
// documented solvers are exactly the registered ones, every key a solver reads is a documented
// [solver] key, and every entry runs a case and tightens it for sweep --certify.
#include <catch2/catch.hpp>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "rubdyn/driver/simulate.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/solver_options.hpp"

using namespace rubdyn;

namespace {

std::string read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// The backticked words of a text.
std::set<std::string> backticked(const std::string& text) {
  std::set<std::string> out;
  const std::regex re("`([^`]+)`");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), re); it != std::sregex_iterator();
       ++it)
    out.insert((*it)[1]);
  return out;
}

std::set<std::string> registered() {
  std::set<std::string> names;
  for (const auto& e : solver_registry()) names.emplace(e.name);
  return names;
}

/// The section of a Markdown text from `heading` to the next heading of the same level.
std::string section(const std::string& text, const std::string& heading) {
  const auto a = text.find(heading);
  REQUIRE(a != std::string::npos);
  const auto level = heading.substr(0, heading.find(' ') + 1);
  const auto b = text.find("\n" + level, a + heading.size());
  return text.substr(a, b == std::string::npos ? std::string::npos : b - a);
}

}  // namespace

TEST_CASE("Solver registry: the documented solvers are exactly the registered ones",
          "[registry][unit]") {
  const std::string cases = read(RUBDYN_SOURCE_DIR "/cases/README.md");
  const std::string solver_section = section(cases, "## [solver]");
  // the `kind` row lists the admissible names
  std::smatch m;
  REQUIRE(std::regex_search(solver_section, m, std::regex("\\| `kind` \\|[^|]*\\|([^|]*)\\|")));
  CHECK(backticked(m[1].str()) == registered());
  // README's "## Solvers" names each of them as a bullet **`name`**
  const std::string readme = section(read(RUBDYN_SOURCE_DIR "/README.md"), "## Solvers");
  std::set<std::string> bullets;
  const std::regex bold("\\*\\*`([a-z-]+)`\\*\\*");
  for (auto it = std::sregex_iterator(readme.begin(), readme.end(), bold);
       it != std::sregex_iterator(); ++it)
    bullets.insert((*it)[1]);
  CHECK(bullets == registered());
  // every key a solver reads is a documented [solver] key
  for (const auto& e : solver_registry()) {
    for (const auto key : e.keys) {
      INFO(e.name << " reads " << key);
      REQUIRE(key.substr(0, 7) == "solver.");
      const std::string row = "| `" + std::string(key.substr(7)) + "` |";
      CHECK(solver_section.find(row) != std::string::npos);
    }
  }
  CHECK(find_solver("no-such-solver") == nullptr);
  CHECK(solver_names(" | ").find("event | ") == 0);
}

TEST_CASE("Solver registry: every entry runs a case and tightens it", "[registry]") {
  for (const auto& e : solver_registry()) {
    INFO(e.name);
    const std::string kind = "solver.kind=\"" + std::string(e.name) + "\"";
    const CaseSpec spec =
        load_case(RUBDYN_SOURCE_DIR "/cases/reference.toml", {kind, "run.t_end=0.002"});
    MemorySink sink;
    const RunSummary s = simulate(spec, sink);
    CHECK(s.complete());
    CHECK(s.solver == e.name);
    CHECK(s.t_reached == Approx(0.002).epsilon(1e-12));
    // tighter: overrides the case file accepts, with a smaller tolerance or step
    std::vector<std::string> over = tighter_settings(spec);
    over.push_back(kind);
    const CaseSpec tight = load_case(RUBDYN_SOURCE_DIR "/cases/reference.toml", over);
    if (e.fixed_step)
      CHECK(tight.solver.h < spec.solver.h);
    else
      CHECK(tight.solver.rtol < spec.solver.rtol);
  }
}
