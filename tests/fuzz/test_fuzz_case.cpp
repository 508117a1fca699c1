// Fuzzing the input parsers (issue 12, deliverable 4; issue 34: every model, [[plane]] and
// [[contact_node]] tables, matrix files): a seeded mutation driver for the case parser (seeded
// with every case file of cases/), the --set overrides and the --vary / --shard parsers, the
// matrix-file readers (.npy and CSV bytes, alone and inside a case), and the replay of the
// committed corpus of bad inputs (tests/fuzz/corpus). It runs in the default suite (a fixed seed
// and count: about 2 s per test case on a loaded 2-core machine) and therefore also in the
// sanitizer build (scripts/test.sh --sanitize, which CI runs). RUBDYN_FUZZ_SECONDS=T keeps mutating
// with fresh seeds for T seconds (a bounded CI or local campaign); RUBDYN_FUZZ_SAVE=DIR writes
// every input that breaks a property there, to be added to the corpus.
//
// Properties, for every input:
//   1. parse_case returns a CaseSpec or throws CaseError; nothing else escapes (no crash, no
//      std::out_of_range, no bad_alloc);
//   2. every CaseIssue names a file and a key and states a rule, in UTF-8 (no raw byte of a
//      damaged file in a message);
//   3. an accepted case round trips: to_toml -> parse_case -> to_toml gives the same text;
//   4. parse_variation and parse_shard return or throw std::invalid_argument;
//   5. what `rubdyn check` and `rubdyn campbell` compute from an accepted case (its model, its
//      derived quantities, its Campbell model) is computed, or refused with a CaseError;
//   6. parse_matrix returns a matrix or throws MatrixFileError with a UTF-8 message.
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "rubdyn/analysis/campbell.hpp"
#include "rubdyn/analysis/derived.hpp"
#include "rubdyn/driver/sweep.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/matrix_files.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/text_files.hpp"

namespace fs = std::filesystem;
using namespace rubdyn;

namespace {

const std::string kCorpus = std::string(RUBDYN_SOURCE_DIR) + "/tests/fuzz/corpus";

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Tokens that have broken parsers before, or are close to a rule's edge.
const std::vector<std::string> kTokens = {
    "nan", "inf", "-inf", "+nan", "1e309", "-1e309", "4294967297", "-4294967295",
    "9223372036854775807", "9223372036854775808", "-9223372036854775809", "0", "-0", "1e-320",
    "0x10", "0o7", "0b1", "1_000", "1__0", "true", "[1, 2]", "{a = 1}", "1979-05-27T07:32:00Z",
    "\"\"", "\"\\u0000\"", "\"\\uD800\"", "\"a\\qb\"", "'''x'''", "\"\"\"x\"\"\"", "\"\xc3\x28\"",
    "[x]", "[[x]]", "[a.b.c]", "a.b.c = 1", "\"k\" = 1", "= 1", "#", "\n", "\r\n", "\t", "\\", "\"",
    "'", "[", "]", "{", "}", "=", ",", ".", "\x01", "\x7f", std::string(1, '\0'), "\xef\xbb\xbf",
    "event", "mj", "carp-qn", "1e-300", "1e300", "-1", "0.5", "2.5",
    // the models, planes, nodes and matrix files
    "\"jefcott\"", "\"Matrices\"", "\"jeffcott\"", "\"matrices\"", "\"rigid-rotor\"",
    "\"prescribed\"", "[[plane]]", "[[contact_node]]", "[contact_node]", "[plane]",
    "stator_rigid = true", "rigid = true", "1e999", "-1e999", "1e-999", "\"M.csv\"",
    "\"matrices-paper/G.npy\"", "\"a, b, c, F_N_2\"", "3", "7"};

const std::vector<std::string> kKeys = {
    "rotor.mass", "rotor.L", "rotor.delta", "rotor.d", "stator.gap", "contact.mu", "contact.e_n",
    "loads.torque", "initial.omega0", "initial.x_r", "run.t_end", "run.t_start", "solver.kind",
    "solver.h", "solver.itmax", "solver.theta", "output.every", "output.dt", "output.folder",
    "name", "nosuch.key", "rotor", "solver.kind.x",
    // the models, planes, nodes and matrix files
    "model.kind", "stator.rigid", "rotor.k", "rotor.M", "rotor.G", "rotor.coordinates",
    "plane.1.mu", "plane.2.stator_rigid", "plane.2.position", "plane.mu", "plane.9.gap",
    "contact_node.x", "contact_node.1.y", "contact_node.2.stator_rigid", "loads.spin",
    "loads.spin_accel", "loads.unbalance", "initial.x_s_2"};

class Mutator {
 public:
  explicit Mutator(unsigned seed) : rng_(seed) {}
  std::size_t below(std::size_t n) {
    return n == 0 ? 0 : std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_);
  }
  const std::string& token() { return kTokens[below(kTokens.size())]; }

  /// One to four random edits of `s`.
  std::string mutate(std::string s) {
    const std::size_t edits = 1 + below(4);
    for (std::size_t e = 0; e < edits; ++e) {
      const std::size_t at = below(s.size() + 1);
      switch (below(6)) {
        case 0:  // overwrite a byte
          if (!s.empty()) s[below(s.size())] = token().empty() ? 'x' : token()[0];
          break;
        case 1: s.insert(at, token()); break;
        case 2: s.erase(at, below(40)); break;
        case 3: s.resize(at); break;  // truncate
        case 4: {                     // replace the value of a random line
          const std::size_t eq = s.find('=', at);
          if (eq != std::string::npos) {
            const std::size_t nl = s.find('\n', eq);
            s.replace(eq + 1, (nl == std::string::npos ? s.size() : nl) - eq - 1, " " + token());
          }
          break;
        }
        default: {  // duplicate a random line
          const std::size_t a = s.rfind('\n', at);
          const std::size_t b = s.find('\n', at);
          const std::size_t from = a == std::string::npos ? 0 : a + 1;
          s.insert(from, s.substr(from, (b == std::string::npos ? s.size() : b + 1) - from));
        }
      }
    }
    return s;
  }
  /// A --set override: a schema key (or a wrong one) = a token, sometimes mangled.
  std::string override_text() {
    std::string o = kKeys[below(kKeys.size())] + "=" + token();
    return below(4) == 0 ? mutate(o) : o;
  }

 private:
  std::mt19937 rng_;
};

struct Failure {
  std::string what, input;
};

/// Property 5: what check and campbell compute from an accepted case (empty: nothing broke).
std::string check_derived(const CaseSpec& c) {
  try {
    const auto model = build_model(c);
    if (c.model == "rigid-rotor") {
      (void)compute_derived_quantities(c.params, 1.0, 2.0);
    } else if (c.model == "jeffcott") {
      (void)compute_jeffcott_quantities(c.jeffcott, 1.0, 2.0);
    }
    const CampbellModel cm = campbell_model(c);
    if (cm.lm.size() <= 16) (void)CampbellSolver(cm.lm).solve(1.0);
  } catch (const CaseError& e) {
    if (e.issues().empty()) return "CaseError without issues (check/campbell)";
  } catch (const std::exception& e) {
    return std::string("unexpected exception in check/campbell: ") + e.what();
  }
  return {};
}

/// Checks properties 1-3 and 5 on one case text with its overrides; returns what broke (empty:
/// none). `source` names the file (matrix files are found relative to it).
std::string check_case(const std::string& text, const std::vector<std::string>& sets,
                       const std::string& source = "fuzz.toml") {
  try {
    const CaseSpec c = parse_case(text, source, sets);
    const std::string once = to_toml(c);
    const std::string twice = to_toml(parse_case(once, "resolved", {}));
    if (once != twice) return "round trip changed the resolved case";
    if (std::string d = check_derived(c); !d.empty()) return d;
  } catch (const CaseError& e) {
    if (e.issues().empty()) return "CaseError without issues";
    for (const auto& i : e.issues()) {
      if (i.file.empty() || i.key.empty() || i.rule.empty())
        return "issue without file, key or rule: " + format_issue(i);
      if (!valid_utf8(i.rule)) return "issue not in UTF-8: " + printable_text(format_issue(i));
    }
  } catch (const std::exception& e) {
    return std::string("unexpected exception: ") + e.what();
  }
  return {};
}

/// Property 6 on the bytes of one matrix file (empty: nothing broke).
std::string check_matrix(const std::string& bytes, bool npy) {
  try {
    const Mat m = parse_matrix(bytes, npy);
    if (m.size() == 0) return "an empty matrix was accepted";
    if (!m.allFinite()) return "a matrix with a non-finite entry was accepted";
  } catch (const MatrixFileError& e) {
    const std::string what = e.what();
    if (what.empty()) return "MatrixFileError without a message";
    if (!valid_utf8(what)) return "matrix file message not in UTF-8: " + printable_text(what);
  } catch (const std::exception& e) {
    return std::string("unexpected exception from parse_matrix: ") + e.what();
  }
  return {};
}

std::string check_parsers(const std::string& text) {
  for (const auto& f : {+[](const std::string& t) { (void)parse_variation(t); },
                        +[](const std::string& t) { (void)parse_shard(t); }}) {
    try {
      f(text);
    } catch (const std::invalid_argument&) {
    } catch (const std::exception& e) {
      return std::string("unexpected exception from --vary/--shard: ") + e.what();
    }
  }
  return {};
}

void save(const std::vector<Failure>& failures) {
  const char* dir = std::getenv("RUBDYN_FUZZ_SAVE");
  if (!dir) return;
  fs::create_directories(dir);
  for (std::size_t i = 0; i < failures.size(); ++i)
    std::ofstream(fs::path(dir) / ("found-" + std::to_string(i) + ".toml"), std::ios::binary)
        << failures[i].input;
}

}  // namespace

TEST_CASE("Fuzz: the committed corpus of bad case files is rejected cleanly", "[fuzz]") {
  int n = 0;
  for (const auto& e : fs::directory_iterator(kCorpus)) {
    if (e.path().extension() != ".toml") continue;
    ++n;
    const std::string text = slurp(e.path());
    INFO(e.path().filename().string());
    CHECK(check_case(text, {}).empty());
    // a bad input: rejected, with every issue naming a key and a rule (checked above)
    CHECK_THROWS_AS(parse_case(text, e.path().string(), {}), CaseError);
  }
  CHECK(n >= 20);  // the corpus is there (a wrong path would make this test vacuous)
}

TEST_CASE("Fuzz: mutated cases, overrides and sweep options break no property", "[fuzz]") {
  // every model, layout and loading of cases/: the paper's rotor, one with two planes (and with
  // plane 2's ring fixed), the Jeffcott rotor, matrices with one and two contact nodes
  std::vector<std::pair<std::string, std::string>> seeds;  // (path, text)
  for (const char* name :
       {"reference", "two-plane", "jeffcott", "matrices-paper", "matrices-two-plane", "paper"}) {
    const std::string path = std::string(RUBDYN_SOURCE_DIR) + "/cases/" + name + ".toml";
    seeds.emplace_back(path, slurp(path));
  }
  {
    std::string fixed = seeds[1].second;
    const std::string ring = "stator_mass  = 1.0\nstator_k     = 4.0e6\nstator_c     = 50.0\n";
    REQUIRE(fixed.find(ring) != std::string::npos);
    seeds.emplace_back(seeds[1].first,
                       fixed.replace(fixed.find(ring), ring.size(), "stator_rigid = true\n"));
  }
  for (const auto& [path, text] : seeds) {
    INFO(path);
    REQUIRE_FALSE(text.empty());
    REQUIRE(check_case(text, {}, path).empty());
  }
  double seconds = 0.0;
  if (const char* s = std::getenv("RUBDYN_FUZZ_SECONDS")) seconds = std::atof(s);
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Failure> failures;
  long runs = 0, accepted = 0;
  // fixed seeds first (reproducible in the default suite), then fresh ones while time remains
  for (unsigned seed = 1;; ++seed) {
    const bool fixed = seed <= 3000;
    if (!fixed &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >= seconds)
      break;
    Mutator m(fixed ? seed : static_cast<unsigned>(std::random_device{}()));
    // half the inputs from the reference case (the earlier driver's), the others from the
    // other models and layouts in turn
    const auto& [source, seed_text] = seeds[seed % 2 ? 0 : 1 + (seed / 2) % (seeds.size() - 1)];
    const std::string text = m.mutate(seed_text);
    std::vector<std::string> sets;
    for (std::size_t k = m.below(3); k > 0; --k) sets.push_back(m.override_text());
    ++runs;
    std::string broke = check_case(text, sets, source);
    if (broke.empty()) broke = check_parsers(m.mutate("contact.mu=0.1,0.2"));
    if (broke.empty()) broke = check_parsers(m.mutate("stator.k=1e6:3e6:5"));
    if (broke.empty()) broke = check_parsers(m.mutate("3/8"));
    if (!broke.empty()) {
      std::string input = text;
      for (const auto& s : sets) input += "\n# --set " + s;
      failures.push_back({broke, input});
    }
    try {
      (void)parse_case(text, source, sets);
      ++accepted;
    } catch (const std::exception&) {
    }
  }
  save(failures);
  for (const auto& f : failures) FAIL_CHECK(f.what << "\n--- input ---\n" << f.input);
  INFO(runs << " inputs, " << accepted << " accepted");
  CHECK(runs >= 3000);
  // the mutants must reach both outcomes, or the driver tests only one path
  CHECK(accepted > 0);
  CHECK(accepted < runs);
}

TEST_CASE("Fuzz findings stay fixed", "[fuzz]") {
  const std::string ref = slurp(std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml");
  // --set '' named no key (found by the driver)
  CHECK(check_case(ref, {""}).empty());
  // e_n = -0.0 was written as "-0", read back as the integer 0: the sign was lost and the
  // resolved case changed on a second round trip (found by the driver)
  const CaseSpec c = parse_case(ref, "ref", {"contact.e_n=-0.0"});
  REQUIRE(std::signbit(c.params.contact.e_n));
  CHECK(std::signbit(parse_case(to_toml(c), "resolved").params.contact.e_n));
  CHECK(check_case(ref, {"contact.e_n=-0.0"}).empty());
}

namespace {

// Tokens of a .npy header and of CSV fields that have broken or may break the readers.
const std::vector<std::string> kMatrixTokens = {"(4294967296, 4294967296)",
                                                "(2305843009213693953,)",
                                                "(9223372036854775807, 2)",
                                                "(-1, 4)",
                                                "(4, 4, 4)",
                                                "()",
                                                "(4,)",
                                                "(0, 4)",
                                                "'<f4'",
                                                "'>f8'",
                                                "'<i8'",
                                                "True",
                                                "False",
                                                "'shape'",
                                                "'descr'",
                                                "{",
                                                "}",
                                                "(",
                                                ")",
                                                ",",
                                                "\x93NUMPY",
                                                "\xEF\xBB\xBF",
                                                "\xB5",
                                                "\xC3",
                                                std::string(1, '\0'),
                                                "1e999",
                                                "-1e999",
                                                "1e-999",
                                                "nan",
                                                "inf",
                                                "+",
                                                "-",
                                                "0x10",
                                                "1,2",
                                                "\n",
                                                "\r\n",
                                                "#",
                                                " ",
                                                "\t",
                                                "1e308",
                                                "5e-324",
                                                std::string(8, '\xff')};

class ByteMutator {
 public:
  explicit ByteMutator(unsigned seed) : rng_(seed) {}
  std::size_t below(std::size_t n) {
    return n == 0 ? 0 : std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_);
  }
  /// One to four edits: a byte overwritten, a token inserted or put in place of a header
  /// value or a CSV field, a cut, the header's length bytes changed.
  std::string mutate(std::string s) {
    const std::size_t edits = 1 + below(4);
    for (std::size_t e = 0; e < edits; ++e) {
      const std::string& tok = kMatrixTokens[below(kMatrixTokens.size())];
      const std::size_t at = below(s.size() + 1);
      switch (below(6)) {
        case 0:
          if (!s.empty()) s[below(s.size())] = static_cast<char>(below(256));
          break;
        case 1: s.insert(at, tok); break;
        case 2: s.resize(at); break;
        case 3: {  // a header value or a field replaced (up to the next ',' '}' or line end)
          const std::size_t end = s.find_first_of(",}\n", at);
          s.replace(at, (end == std::string::npos ? s.size() : end) - at, tok);
          break;
        }
        case 4:  // the .npy header length (bytes 8 and 9 of version 1)
          if (s.size() > 9) s[8 + below(2)] = static_cast<char>(below(256));
          break;
        default: s.erase(at, below(16));
      }
    }
    return s;
  }

 private:
  std::mt19937 rng_;
};

}  // namespace

TEST_CASE("Fuzz: mutated matrix files (.npy and CSV), alone and in a case, break no property",
          "[fuzz][matrices]") {
  const fs::path src = fs::path(RUBDYN_SOURCE_DIR) / "cases";
  const fs::path dir = fs::temp_directory_path() /
                       ("rubdyn-fuzz-matrices-" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  fs::copy(src / "matrices-paper", dir / "matrices-paper", fs::copy_options::recursive);
  const std::string case_path = (dir / "case.toml").string();
  const std::string case_text = slurp(src / "matrices-paper.toml");
  std::ofstream(case_path, std::ios::binary) << case_text;
  REQUIRE(check_case(case_text, {}, case_path).empty());
  // the case's five files: M and G are .npy, C, K and f0 CSV
  const std::vector<std::string> files = {"M.npy", "G.npy", "C.csv", "K.csv", "f0.csv"};
  std::vector<std::string> originals;
  for (const auto& f : files) originals.push_back(slurp(dir / "matrices-paper" / f));
  std::vector<Failure> failures;
  long runs = 0, refused = 0;
  for (unsigned seed = 1; seed <= 600; ++seed) {
    ByteMutator m(seed);
    const std::size_t which = m.below(files.size());
    std::string bytes = m.mutate(originals[which]);
    // sometimes the bytes of one format under the other's name
    const bool npy_name = (files[which].ends_with(".npy")) != (m.below(8) == 0);
    ++runs;
    std::string broke = check_matrix(bytes, npy_name);
    try {
      (void)parse_matrix(bytes, npy_name);
    } catch (const MatrixFileError&) {
      ++refused;
    } catch (const std::exception&) {
    }
    // in the case: the file under its key, through parse_case (property 1-3 and 5)
    if (broke.empty()) {
      const std::string name = "fuzzed" + std::string(npy_name ? ".npy" : ".csv");
      std::ofstream(dir / name, std::ios::binary) << bytes;
      const std::string key = files[which].substr(0, files[which].find('.'));
      broke = check_case(case_text, {"rotor." + key + "=\"" + name + "\""}, case_path);
    }
    if (!broke.empty()) failures.push_back({broke, files[which] + ": " + printable_text(bytes)});
  }
  for (const auto& f : failures) FAIL_CHECK(f.what << "\n--- input ---\n" << f.input);
  INFO(runs << " files, " << refused << " refused");
  // both outcomes reached, or the driver tests only one path
  CHECK(refused > 0);
  CHECK(refused < runs);
  fs::remove_all(dir);
}
