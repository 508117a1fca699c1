// Issue 34 (first half), in the library: no crash and no silent nonsense on the models, rub planes
// and matrix files. Each test case here failed before its fix (the fix is named in each).
// The same problems through the CLI and its exit codes: test_new_surfaces_cli.cpp.
#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "rubdyn/analysis/campbell.hpp"
#include "rubdyn/analysis/derived.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/matrix_files.hpp"
#include "rubdyn/io/text_files.hpp"
#include "support/cli.hpp"

using namespace rubdyn;
using rubdyn::testing::fresh_dir;
using rubdyn::testing::has;
using rubdyn::testing::slurp;
namespace fs = std::filesystem;

namespace {

const std::string kCases = std::string(RUBDYN_SOURCE_DIR) + "/cases/";

/// The issues of a case that must be refused (fails the test if it is accepted).
std::vector<CaseIssue> issues_of(const std::string& text, const std::string& source,
                                 const std::vector<std::string>& sets = {}) {
  try {
    parse_case(text, source, sets);
  } catch (const CaseError& e) {
    return e.issues();
  }
  FAIL("the case was accepted");
  return {};
}

const CaseIssue* find_issue(const std::vector<CaseIssue>& is, const std::string& key) {
  for (const auto& i : is)
    if (i.key == key) return &i;
  return nullptr;
}

/// cases/two-plane.toml with plane 2's ring fixed (stator_rigid = true).
std::string two_plane_fixed_ring() {
  std::string t = slurp(kCases + "two-plane.toml");
  const std::string ring = "stator_mass  = 1.0\nstator_k     = 4.0e6\nstator_c     = 50.0\n";
  const auto at = t.find(ring);
  REQUIRE(at != std::string::npos);
  return t.replace(at, ring.size(), "stator_rigid = true\n");
}

/// A .npy file (format 1.0, '<f8', C order) with this shape text and these data bytes.
std::string npy(const std::string& shape, const std::string& data) {
  std::string h = "{'descr': '<f8', 'fortran_order': False, 'shape': " + shape + ", }";
  while ((10 + h.size() + 1) % 64 != 0) h += ' ';
  h += '\n';
  std::string out = "\x93NUMPY";
  out += '\x01';
  out += '\x00';
  out += static_cast<char>(h.size() & 0xff);
  out += static_cast<char>(h.size() >> 8);
  return out + h + data;
}

std::string matrix_error(const std::string& bytes, bool is_npy) {
  try {
    (void)parse_matrix(bytes, is_npy);
  } catch (const MatrixFileError& e) {
    return e.what();
  }
  FAIL("the matrix file was accepted");
  return {};
}

}  // namespace

// Fix: an unknown [model] kind leaves its keys unchecked (src/io/case_toml.cpp, Loader::load);
// before, the fallback model's [initial] keys were written into an empty initial state: SIGSEGV.
TEST_CASE("Issue 34: an unknown [model] kind is one issue naming it, never a crash",
          "[issue34][models][io]") {
  const std::string ref = slurp(kCases + "reference.toml");
  const std::string jef = slurp(kCases + "jeffcott.toml");
  REQUIRE(has(ref, "[initial]"));  // (the crash needed an [initial] section)
  for (const char* kind : {"jefcott", "Matrices", "nope", "rigid_rotor"}) {
    INFO(kind);
    for (const std::string* text : {&ref, &jef}) {
      const auto is = issues_of(*text, "case.toml", {std::string("model.kind=") + kind});
      const CaseIssue* i = find_issue(is, "model.kind");
      REQUIRE(i);
      CHECK(i->file == "--set");
      CHECK(has(i->rule, "must be one of rigid-rotor, jeffcott, matrices"));
      // the model's own keys are not judged by a model the case does not name
      CHECK(is.size() == 1);
    }
  }
  // a typo in the file, with the suggestion and the line
  std::string typo = jef;
  typo.replace(typo.find("kind = \"jeffcott\""), 17, "kind = \"jefcott\"");
  const auto is = issues_of(typo, "j.toml");
  REQUIRE(is.size() == 1);
  CHECK(is[0].key == "model.kind");
  CHECK(is[0].line > 0);
  CHECK(has(is[0].rule, "did you mean 'jeffcott'"));
  // a kind that is no string, and an unknown kind with [[plane]] tables: no crash either
  CHECK(find_issue(issues_of(ref, "case.toml", {"model.kind=3"}), "model.kind"));
  CHECK(find_issue(issues_of(slurp(kCases + "two-plane.toml"), "case.toml", {"model.kind=x"}),
                   "model.kind"));
  // the common sections are still checked
  CHECK(find_issue(issues_of(ref, "case.toml", {"model.kind=x", "contact.mu=-1"}), "model.kind"));
}

// Fix: compute_derived_quantities computes the tied frequencies only when the tied system
// exists (src/analysis/derived.cpp); before, it dereferenced the empty linearisation of a case
// with a fixed ring: std::bad_alloc, and UBSan's null reference inside Eigen.
TEST_CASE("Issue 34: the derived quantities of planes with a fixed ring, and Campbell's refusals",
          "[issue34][planes][campbell]") {
  const CaseSpec c = parse_case(two_plane_fixed_ring(), kCases + "two-plane-fixed.toml");
  REQUIRE(c.params.planes.size() == 2);
  REQUIRE(c.params.planes[1].rigid);
  const DerivedQuantities d = compute_derived_quantities(c.params, 2000.0, 2110.0);
  CHECK(std::isnan(d.f1));  // no tied system: no tied frequency
  CHECK(std::isnan(d.f2));
  CHECK(d.l == Approx(0.4).epsilon(1e-15));  // (the geometry is still there)
  // the rigid-rotor helpers refuse instead of dereferencing nothing
  CHECK_THROWS_AS(CampbellSolver(c.params), std::invalid_argument);
  CHECK_THROWS_AS(compute_campbell_diagram(c.params, 2110.0, 5), std::invalid_argument);
  CHECK_THROWS_AS(CampbellSolver(LinearModel{}), std::invalid_argument);
  // the case's diagram: its free modes (the CLI's and Python's one choice)
  const CampbellModel cm = campbell_model(c);
  CHECK_FALSE(cm.tied);
  CHECK(cm.lm.size() == 6);  // x_b, y_b, x_r, y_r and ring 1's x_s_1, y_s_1
}

// Fix: campbell_model falls back to the free modes (src/analysis/campbell.cpp); before, Python's
// rubdyn.campbell took the tied linearisation of a rigid-stator Jeffcott rotor, of size 0, and
// the eigen solver died (SIGSEGV; python/tests/test_models.py checks the Python side).
TEST_CASE("Issue 34: a Jeffcott rotor in a rigid stator has a Campbell diagram of its free modes",
          "[issue34][campbell][models]") {
  std::string t = slurp(kCases + "jeffcott.toml");
  const std::string ring =
      "mass = 2.0        # m_s [kg]\nk    = 2.0e7      # k_s [N/m]\n"
      "c    = 2500.0     # c_s [N s/m]\n";
  REQUIRE(has(t, ring));
  t.replace(t.find(ring), ring.size(), "rigid = true\n");
  const CaseSpec c = parse_case(t, kCases + "jeffcott-rigid.toml");
  REQUIRE(c.jeffcott.stator.rigid);
  const CampbellModel cm = campbell_model(c);
  CHECK_FALSE(cm.tied);
  REQUIRE(cm.lm.size() == 2);  // the rotor's x_r, y_r: the rotor alone, sqrt(k_r / m_r)
  const CampbellDiagram d = compute_campbell_diagram(cm.lm, 2000.0, 3);
  // no gyroscopic effect: forward = backward = sqrt(k_r / m_r) / 2 pi at every speed, to the
  // eigen solver's round-off (1e-12 relative is far above it: w_ref scaling, campbell.cpp)
  const double f = std::sqrt(c.jeffcott.rotor.k / c.jeffcott.rotor.mass) / (2.0 * std::numbers::pi);
  CHECK(d.column("f1f").back() == Approx(f).epsilon(1e-12));
  CHECK(d.column("f1b").front() == Approx(f).epsilon(1e-12));
}

// Fix: campbell_model names the reason (src/analysis/campbell.cpp); before, an odd n gave "this
// model has no linearisation for a Campbell diagram", which does not say why.
TEST_CASE(
    "Issue 34: a matrices rotor of odd size has no Campbell diagram, and the word odd says why",
    "[issue34][campbell][matrices]") {
  const fs::path d = fresh_dir("odd-n");
  fs::create_directories(d);
  std::ofstream(d / "M.csv") << "2,0,0\n0,2,0\n0,0,2\n";
  std::ofstream(d / "Z.csv") << "0,0,0\n0,0,0\n0,0,0\n";
  std::ofstream(d / "K.csv") << "1e6,0,0\n0,1e6,0\n0,0,1e6\n";
  const std::string text =
      "[model]\nkind = \"matrices\"\n[rotor]\nM = \"M.csv\"\nC = \"Z.csv\"\nK = \"K.csv\"\n"
      "G = \"Z.csv\"\nJp = 0.06\n[contact_node]\nx = 0\ny = 1\nradius = 0.05\ngap = 2e-4\n"
      "[stator]\nrigid = true\n[contact]\nmu = 0.1\n[loads]\ngravity = 0.0\ntorque = "
      "1.0\n[run]\nt_end = 0.01\nomega_lim = 100.0\n";
  const CaseSpec c = parse_case(text, (d / "odd.toml").string());
  REQUIRE(c.matrices.rotor.size() == 3);
  try {
    (void)campbell_model(c);
    FAIL("an odd n was given a Campbell diagram");
  } catch (const CaseError& e) {
    REQUIRE(e.issues().size() == 1);
    CHECK(e.issues()[0].key == "rotor.M");
    CHECK(has(e.issues()[0].rule, "n = 3 is odd"));
  }
  fs::remove_all(d);
}

// Fix: parse_npy computes the declared byte count with overflow checks (src/io/matrix_files.cpp);
// before, 2^32 x 2^32 x 8 bytes wrapped to 0 (and (2^61 + 1) x 8 to 8), the header passed
// and allocating the matrix threw std::bad_alloc (Python: MemoryError), naming no file or key.
TEST_CASE("Issue 34: .npy headers declaring absurd shapes are refused, naming file and key",
          "[issue34][matrices][io]") {
  CHECK(has(matrix_error(npy("(4294967296, 4294967296)", ""), true),
            "shape (4294967296, 4294967296) in the .npy header declares 1.84e+19 entries"));
  CHECK(has(matrix_error(npy("(2305843009213693953,)", std::string(8, '\0')), true),
            "declares 2.31e+18 entries"));
  CHECK(has(matrix_error(npy("(9223372036854775807, 2)", ""), true), "declares"));
  // through a case: the key, the value and the file
  const fs::path d = fresh_dir("npy-shape");
  fs::create_directories(d);
  fs::copy(kCases + "matrices-paper", d / "matrices-paper", fs::copy_options::recursive);
  fs::copy(kCases + "matrices-paper.toml", d / "case.toml");
  std::ofstream(d / "huge.npy", std::ios::binary) << npy("(4294967296, 4294967296)", "");
  const auto is =
      issues_of(slurp(d / "case.toml"), (d / "case.toml").string(), {"rotor.M=\"huge.npy\""});
  const CaseIssue* i = find_issue(is, "rotor.M");
  REQUIRE(i);
  CHECK(i->file == "--set");
  CHECK(has(i->rule, (d / "huge.npy").string()));
  CHECK(has(i->rule, "declares"));
  fs::remove_all(d);
}

// Fix: parse_csv says what a refused field is (src/io/matrix_files.cpp, not_a_number): a UTF-8
// byte order mark is skipped, a byte of another encoding shown as \xHH, .npy bytes and NUL
// bytes named, numbers out of a double's range said to be so. Before, each was "'<raw bytes>'
// is not a number", the raw bytes in the message.
TEST_CASE("Issue 34: CSV matrix files: a BOM, a Latin-1 byte, .npy bytes, 1e999 and 1e-999",
          "[issue34][matrices][io]") {
  // a UTF-8 BOM (as spreadsheets write it) carries no data: the same matrix
  const Mat plain = parse_matrix("1,2\n3,4\n", false);
  const Mat bom = parse_matrix(
      "\xEF\xBB\xBF"
      "1,2\n3,4\n",
      false);
  CHECK(bom == plain);
  // a Latin-1 byte: shown escaped, the encoding named
  const std::string latin = matrix_error(
      "\xB5"
      "1,2\n3,4\n",
      false);
  CHECK(has(latin, "'\\xB51'"));
  CHECK(has(latin, "not UTF-8"));
  CHECK(latin.find('\xB5') == std::string::npos);
  CHECK(valid_utf8(latin));
  // .npy bytes in a file read as CSV
  const std::string npy_bytes = matrix_error(npy("(2,)", std::string(16, '\0')), false);
  CHECK(has(npy_bytes, "holds NumPy .npy data"));
  CHECK(has(npy_bytes, "rename"));
  CHECK(valid_utf8(npy_bytes));
  CHECK(has(matrix_error(std::string("1,2\n3,\0\n", 7), false), "NUL byte (at byte 6)"));
  // out of a double's range, either way
  CHECK(has(matrix_error("1e999,2\n3,4\n", false),
            "line 1, column 1: 1e999 is outside the range of a double"));
  CHECK(has(matrix_error("1,-1e999\n3,4\n", false),
            "line 1, column 2: -1e999 is outside the range of a double"));
  CHECK(has(matrix_error("1,2\n3,1e-999\n", false),
            "line 2, column 2: 1e-999 is below the smallest double"));
  // (a subnormal is a double: kept)
  CHECK(parse_matrix("1e-310\n", false)(0, 0) == 1e-310);
  // a .npy header byte that is not ASCII is not echoed raw either (found by tests/fuzz)
  std::string bad_header = npy("(2,)", std::string(16, '\0'));
  bad_header.replace(bad_header.find("'<f8'"), 5, "'\xC3\xC3\xC3'");
  const std::string header_error = matrix_error(bad_header, true);
  CHECK(has(header_error, "the .npy header holds the byte \\xC3"));
  CHECK(valid_utf8(header_error));
  // a long field is cut in the message
  CHECK(matrix_error(std::string(5000, 'x') + "\n", false).size() < 400);
}

// Fix: read_matrices symmetrises without overflow and requires a finite M^-1, and
// derived_finite_rules names a matrix file when one of its entries is the largest number of the
// case (src/io/case_toml.cpp); before, M = 1e308 I became inf on its diagonal and was reported as
// stator.k = 2000000 ("the largest value given"), and M = 5e-324 I as rotor.Jp with a NaN.
TEST_CASE("Issue 34: M = 1e308 I and M = 5e-324 I are named by rotor.M", "[issue34][matrices]") {
  const fs::path d = fresh_dir("absurd-m");
  fs::create_directories(d);
  fs::copy(kCases + "matrices-paper", d / "matrices-paper", fs::copy_options::recursive);
  const std::string text = slurp(kCases + "matrices-paper.toml");
  const std::string source = (d / "case.toml").string();
  std::ofstream(d / "big.csv") << "1e308,0,0,0\n0,1e308,0,0\n0,0,1e308,0\n0,0,0,1e308\n";
  std::ofstream(d / "tiny.csv") << "5e-324,0,0,0\n0,5e-324,0,0\n0,0,5e-324,0\n0,0,0,5e-324\n";
  // a rotor of 1e308 kg at rest is a valid case (symmetrising M no longer overflows it to inf)
  const CaseSpec big = parse_case(text, source, {"rotor.M=\"big.csv\""});
  CHECK(big.matrices.rotor.M(0, 0) == 1e308);
  // moving at 10 m/s its kinetic energy overflows: named by the matrix, not by stator.k
  auto is = issues_of(text, source, {"rotor.M=\"big.csv\"", "initial.vx_b=10"});
  REQUIRE(is.size() == 1);
  CHECK(is[0].key == "rotor.M");
  CHECK(is[0].value == "\"big.csv\"");
  CHECK(has(is[0].rule, "the initial mechanical energy is inf"));
  CHECK(has(is[0].rule, "an entry of 1e+308"));
  // positive definite, but its inverse overflows
  is = issues_of(text, source, {"rotor.M=\"tiny.csv\""});
  REQUIRE(is.size() == 1);
  CHECK(is[0].key == "rotor.M");
  CHECK(is[0].value == "\"tiny.csv\"");
  CHECK(has(is[0].rule, "M^-1 overflows"));
  fs::remove_all(d);
}

// Fix: numbers a double cannot hold are named as such, in the file and in --set
// (src/io/case_toml.cpp, out_of_double_range); before, -1e999 was a "(syntax)" error without its
// key in a file and "must be a number" in --set, and 1e-999 was read as 0 without a word.
TEST_CASE("Issue 34: -1e999 and 1e-999 in a case file and in --set", "[issue34][io]") {
  const std::string ref = slurp(kCases + "reference.toml");
  REQUIRE(has(ref, "mu  = 0.1"));
  auto with_mu = [&](const std::string& v) {
    std::string t = ref;
    return t.replace(t.find("mu  = 0.1"), 9, "mu  = " + v);
  };
  for (const std::string v : {"-1e999", "1e999", "+1e999"}) {
    INFO(v);
    auto is = issues_of(with_mu(v), "r.toml");
    REQUIRE(is.size() == 1);
    CHECK(is[0].key == "contact.mu");
    CHECK(is[0].value == v);
    CHECK(is[0].line > 0);
    CHECK(has(is[0].rule, "outside the range of a double"));
    is = issues_of(ref, "r.toml", {"contact.mu=" + v});
    REQUIRE(is.size() == 1);
    CHECK(is[0].file == "--set");
    CHECK(is[0].key == "contact.mu");
    CHECK(has(is[0].rule, "outside the range of a double"));
  }
  for (const std::string v : {"1e-999", "-2.5e-400", "1_0e-999"}) {
    INFO(v);
    auto is = issues_of(with_mu(v), "r.toml");
    REQUIRE(is.size() == 1);
    CHECK(is[0].key == "contact.mu");
    CHECK(is[0].value == v);
    CHECK(has(is[0].rule, "below the smallest double"));
    is = issues_of(ref, "r.toml", {"contact.mu=" + v});
    REQUIRE(is.size() == 1);
    CHECK(is[0].file == "--set");
    CHECK(has(is[0].rule, "below the smallest double"));
  }
  // a key in a [[plane]] table is named with its table's number
  std::string planes = slurp(kCases + "two-plane.toml");
  const auto second = planes.find("mu           = 0.1", planes.find("mu           = 0.1") + 1);
  planes.replace(second, 18, "mu           = -1e999");
  const auto is = issues_of(planes, "p.toml");
  REQUIRE(is.size() == 1);
  CHECK(is[0].key == "plane.2.mu");
  // zeros and subnormals stay accepted
  CHECK(parse_case(with_mu("0.0e-999"), "r.toml").params.contact.mu == 0.0);
  CHECK(parse_case(ref, "r.toml", {"contact.mu=1e-310"}).params.contact.mu == 1e-310);
  CHECK(parse_case(ref, "r.toml", {"contact.mu=-0.0"}).params.contact.mu == 0.0);
}

// Fix: an unknown section made by an override is the override's error (src/io/case_toml.cpp,
// check_structure); before, --set plane.mu=0.3 was reported against the case file.
TEST_CASE("Issue 34: --set plane.mu (no table number) is an error of --set, with the rule",
          "[issue34][planes][io]") {
  const std::string two = slurp(kCases + "two-plane.toml");
  auto is = issues_of(two, kCases + "two-plane.toml", {"plane.mu=0.3"});
  REQUIRE(is.size() == 1);
  CHECK(is[0].file == "--set");
  CHECK(is[0].key == "plane.mu");
  CHECK(is[0].value == "0.3");
  CHECK(has(is[0].rule, "plane.K.<key> with K = 1 to 2 (e.g. plane.1.mu)"));
  is = issues_of(slurp(kCases + "matrices-two-plane.toml"), kCases + "matrices-two-plane.toml",
                 {"contact_node.gap=1e-4"});
  REQUIRE(is.size() == 1);
  CHECK(is[0].file == "--set");
  CHECK(has(is[0].rule, "contact_node.K.<key> with K = 1 to 2"));
  // any section an override invents is the override's
  is = issues_of(slurp(kCases + "reference.toml"), "r.toml", {"contakt.mu=0.3"});
  REQUIRE(is.size() == 1);
  CHECK(is[0].file == "--set");
  CHECK(has(is[0].rule, "did you mean 'contact'"));
}

// Fix: the names a matrices rotor's coordinates may not take are the case's other columns
// (src/io/case_toml.cpp, read_matrices); before, the per-node columns of several nodes (F_N_2,
// x_s_1, ...) were missing from the list, and the CSV had two columns of one name.
TEST_CASE("Issue 34: matrices coordinates named like another output column are refused",
          "[issue34][matrices][io]") {
  const std::string two = slurp(kCases + "matrices-two-plane.toml");
  for (const char* name : {"F_N_2", "x_s_1", "vy_s_2", "phase_1", "drive_torque", "omega0"}) {
    INFO(name);
    const auto is = issues_of(two, kCases + "matrices-two-plane.toml",
                              {std::string("rotor.coordinates=\"a, b, c, ") + name + "\""});
    REQUIRE(is.size() == 1);
    CHECK(is[0].key == "rotor.coordinates");
    CHECK(has(is[0].rule, std::string("'") + name));
    CHECK(has(is[0].rule, "is taken by another coordinate or column"));
  }
  // with one node the contact columns are unnumbered: F_N_2 is a free name there, F_N is not
  const std::string one = slurp(kCases + "matrices-paper.toml");
  CHECK(parse_case(one, kCases + "matrices-paper.toml", {"rotor.coordinates=\"a, b, c, F_N_2\""})
            .matrices.rotor.names.back() == "F_N_2");
  CHECK(issues_of(one, kCases + "matrices-paper.toml", {"rotor.coordinates=\"a, b, c, F_N\""})
            .size() == 1);
}

// Fix: read_input_file sizes its buffer by the file (src/io/text_files.cpp); before, it
// zero-filled max_bytes + 1 (64 MiB for a matrix file) whatever the file held. The bound on a
// growing file stays.
TEST_CASE("Issue 34: input files are read as large as they are, up to the bound", "[issue34][io]") {
  const fs::path d = fresh_dir("read-size");
  fs::create_directories(d);
  std::ofstream(d / "small") << "abc";
  CHECK(read_input_file((d / "small").string(), 10, "test") == "abc");
  std::ofstream(d / "exact") << std::string(10, 'x');
  CHECK(read_input_file((d / "exact").string(), 10, "test") == std::string(10, 'x'));
  std::ofstream(d / "large") << std::string(11, 'x');
  CHECK_THROWS_WITH(read_input_file((d / "large").string(), 10, "test"),
                    Catch::Contains("larger than 10 bytes"));
  std::ofstream(d / "empty");
  CHECK(read_input_file((d / "empty").string(), 10, "test").empty());
  // a file whose size the system does not know beforehand (/proc: st_size 0) is read whole
  CHECK(has(read_input_file("/proc/self/status", 1 << 20, "test"), "Name:"));
  // a bound far above any memory (4 TiB): what the file holds is read, no buffer of the bound
  // is made (before: std::string(max_bytes + 1, '\0'), std::bad_alloc here, and 64 MiB
  // zero-filled for every matrix file)
  const std::size_t huge = std::size_t{1} << 42;
  CHECK(read_input_file((d / "small").string(), huge, "test") == "abc");
  CHECK(has(read_input_file("/proc/self/status", huge, "test"), "Name:"));
  fs::remove_all(d);
}

// Fix: a FIFO is read with a bounded wait (src/io/text_files.cpp, read_fifo); before, every
// FIFO was refused, `rubdyn check <(cat case.toml)` included.
TEST_CASE("Issue 34: a case file in a FIFO is read when its writer comes, refused after the wait",
          "[issue34][io]") {
  const fs::path d = fresh_dir("fifo-read");
  fs::create_directories(d);
  const fs::path f = d / "case.toml";
  REQUIRE(::mkfifo(f.c_str(), 0600) == 0);
  const std::string ref = slurp(kCases + "reference.toml");
  // a writer that comes after the reader opened the FIFO, and writes in two parts
  std::thread writer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    std::ofstream out(f);
    out << ref.substr(0, 100) << std::flush;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    out << ref.substr(100);
  });
  const CaseSpec c = load_case(f.string());
  writer.join();
  CHECK(c.params.contact.mu == 0.1);
  fs::remove_all(d);
}
