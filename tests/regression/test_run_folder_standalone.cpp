// A run folder stands alone, and what describes a run is the run's (issue 34):
//  - a matrices case's folder holds copies of its matrices beside case.resolved.toml, which
//    names them relatively: `analyze`, `run --from` and the reader work after the folder is
//    moved and the original files are gone, and a matrix file changed since changes nothing
//    of what the folder says (analyze's Campbell overlay is the run's K);
//  - the matrices' content is part of a case's identity: `sweep --resume` re-runs a point whose
//    matrix file changed, and `sweep-merge` refuses shards computed with different matrices;
//  - a new run removes everything derived from the folder's earlier run, every plane's files
//    included (analysis/plane_k/, <figure>_k.png), and an earlier run's matrix copies;
//  - `compare --json` escapes a folder name with a line end; a case whose case.resolved.toml
//    would be larger than a case file may be is refused by `run` (exit 2, nothing written)
//    instead of being written and then refused by `analyze`.
#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <thread>

#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/matrix_files.hpp"
#include "rubdyn/io/output_folder.hpp"
#include "rubdyn/io/output_reader.hpp"
#include "rubdyn/io/text_files.hpp"
#include "support/cli.hpp"

using namespace rubdyn;
using namespace rubdyn::testing;
namespace fs = std::filesystem;

namespace {

/// A copy of cases/matrices-paper.toml and its matrix files under `dir` (the case file's path).
fs::path copy_matrices_case(const fs::path& dir) {
  fs::create_directories(dir);
  fs::copy(RUBDYN_SOURCE_DIR "/cases/matrices-paper", dir / "matrices-paper",
           fs::copy_options::recursive);
  fs::copy_file(RUBDYN_SOURCE_DIR "/cases/matrices-paper.toml", dir / "matrices-paper.toml");
  return dir / "matrices-paper.toml";
}

/// Scales the matrix of a CSV file by `factor` (written with round-trip digits).
void scale_csv(const fs::path& file, double factor) {
  const Mat m = read_matrix_file(file.string()) * factor;
  std::string text;
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    for (Eigen::Index j = 0; j < m.cols(); ++j) text += fmt::format("{}{}", j ? "," : "", m(i, j));
    text += "\n";
  }
  std::ofstream(file) << text;
}

}  // namespace

TEST_CASE("Run folder: a matrices run stands alone after its folder is moved",
          "[regression][matrices][folder]") {
  const fs::path root = fresh_dir("standalone");
  const fs::path src = copy_matrices_case(root / "src");
  const fs::path out = root / "out", moved = root / "elsewhere" / "out";
  CliOutcome o = cli("run " + sh(src.string()) + " --t-end 0.01 --quiet --out " + sh(out.string()));
  REQUIRE(o.code == 0);
  // the copies beside the case, named relatively; the case is valid for its own model
  const std::string resolved = slurp(out / "case.resolved.toml");
  CHECK(has(resolved, "M = \"case.M.npy\""));
  CHECK(has(resolved, "f0 = \"case.f0.npy\""));
  CHECK_FALSE(has(resolved, src.parent_path().string()));
  for (const char* key : kCaseMatrixKeys) CHECK(fs::exists(out / case_matrix_file(key)));
  const CaseSpec original = load_case(src.string());
  // the matrices read back bit for bit
  const CaseSpec back = load_case((out / "case.resolved.toml").string());
  CHECK(back.matrices.rotor.M == original.matrices.rotor.M);
  CHECK(back.matrices.rotor.C == original.matrices.rotor.C);
  CHECK(back.matrices.rotor.K == original.matrices.rotor.K);
  CHECK(back.matrices.rotor.G == original.matrices.rotor.G);
  CHECK(back.matrices.rotor.f0 == original.matrices.rotor.f0);
  CHECK(resolved_toml(back) == resolved);
  o = cli("analyze " + sh(out.string()));
  REQUIRE(o.code == 0);
  const std::string campbell = slurp(out / "analysis" / "campbell.csv");
  // the original files gone, the folder moved
  fs::remove_all(src.parent_path());
  fs::create_directories(moved.parent_path());
  fs::rename(out, moved);
  o = cli("analyze " + sh(moved.string()));
  INFO(o.err);
  CHECK(o.code == 0);
  CHECK(slurp(moved / "analysis" / "campbell.csv") == campbell);
  CHECK_NOTHROW(read_run_files(moved.string()));
  // go on from it, with its own case
  o = cli("run " + sh((moved / "case.resolved.toml").string()) + " --t-end 0.012 --quiet --from " +
          sh(moved.string()) + " --out " + sh((root / "more").string()));
  INFO(o.err);
  CHECK(o.code == 0);
  fs::remove_all(root);
}

TEST_CASE("Run folder: analyze draws the run's Campbell overlay after a matrix file changed",
          "[regression][matrices][folder]") {
  const fs::path root = fresh_dir("standalone-k");
  const fs::path src = copy_matrices_case(root / "src");
  const fs::path out = root / "out";
  REQUIRE(cli("run " + sh(src.string()) + " --t-end 0.01 --quiet --out " + sh(out.string())).code ==
          0);
  // frames of 4 ms (the default 40 ms is longer than the run: no spectrogram, no overlay)
  const std::string analyze = "analyze --window 0.004 " + sh(out.string());
  REQUIRE(cli(analyze).code == 0);
  const std::string campbell = slurp(out / "analysis" / "campbell.csv");
  REQUIRE(std::count(campbell.begin(), campbell.end(), '\n') > 3);  // frames with frequencies
  scale_csv(src.parent_path() / "matrices-paper" / "K.csv", 1.5);   // a stiffer bearing
  REQUIRE(cli(analyze).code == 0);
  CHECK(slurp(out / "analysis" / "campbell.csv") == campbell);
  fs::remove_all(root);
}

TEST_CASE("Sweeps: the matrices' content is part of a point's identity",
          "[regression][matrices][sweep]") {
  const fs::path root = fresh_dir("sweep-matrices");
  const fs::path src = copy_matrices_case(root / "src");
  const fs::path d = root / "sweep", m = root / "merge";
  const std::string sweep =
      "sweep " + sh(src.string()) + " --t-end 0.005 --jobs 1 --quiet --vary contact.mu=0.1,0.2 ";
  REQUIRE(cli(sweep + "--out " + sh(d.string())).code == 0);
  const auto written = [&] { return fs::last_write_time(d / "p0001" / "timeseries.csv"); };
  const auto t0 = written();
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // distinct write times
  // the same matrices: --resume keeps the points
  REQUIRE(cli(sweep + "--resume --out " + sh(d.string())).code == 0);
  CHECK(written() == t0);
  // a matrix file changed: the points run again
  scale_csv(src.parent_path() / "matrices-paper" / "C.csv", 2.0);
  REQUIRE(cli(sweep + "--resume --out " + sh(d.string())).code == 0);
  CHECK(written() != t0);
  // shards computed with different matrix files are not merged
  REQUIRE(cli(sweep + "--shard 1/2 --out " + sh(m.string())).code == 0);
  scale_csv(src.parent_path() / "matrices-paper" / "C.csv", 2.0);
  REQUIRE(cli(sweep + "--shard 2/2 --out " + sh(m.string())).code == 0);
  const CliOutcome o = cli("sweep-merge " + sh(m.string()));
  INFO(o.err);
  CHECK(o.code == 2);
  CHECK(has(o.err, "plan"));
  CHECK_FALSE(fs::exists(m / "sweep.csv"));
  fs::remove_all(root);
}

TEST_CASE("Run folder: a new run removes every plane's derived files and old matrix copies",
          "[regression][folder][planes]") {
  const fs::path dir = fresh_dir("derived-planes");
  // an analysed and plotted two-plane matrices run
  const std::string two = sh(RUBDYN_SOURCE_DIR "/cases/matrices-two-plane.toml");
  REQUIRE(cli("run " + two + " --t-end 0.005 --quiet --out " + sh(dir.string())).code == 0);
  REQUIRE(cli("analyze " + sh(dir.string())).code == 0);
  REQUIRE(fs::exists(dir / "analysis" / "plane_2" / "derived.csv"));
  CHECK(fs::exists(dir / "case.M.npy"));
  // the figures python3 -m rubdyn.plot draws for it (names from plot.py's write_all)
  for (const char* f : {"omega.png", "orbit_1.png", "orbit_2.png", "contact_1.png", "contact_2.png",
                        "friction_2.png", "timeline_2.png", "spectrogram_2.png"})
    std::ofstream(dir / f) << "png";
  // a one-plane rigid-rotor run into the same folder
  REQUIRE(cli("run " + sh(RUBDYN_SOURCE_DIR "/cases/reference.toml") +
              " --t-end 0.005 --quiet --out " + sh(dir.string()))
              .code == 0);
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    const std::string name = fs::relative(e.path(), dir).string();
    INFO(name);
    CHECK((name == "case.resolved.toml" || name == "timeseries.csv" || name == "events.csv" ||
           name == "summary.json"));
  }
  // every file a plane's analysis or figure has is in the list of derived files
  const auto derived = derived_files();
  for (const char* f : {"analysis/plane_8/campbell.csv", "spectrogram_8.png", "timeline_1.png"})
    CHECK(std::find(derived.begin(), derived.end(), f) != derived.end());
  fs::remove_all(dir);
}

TEST_CASE("compare --json: a folder name with a line end is escaped", "[regression][compare]") {
  const fs::path root = fresh_dir("compare-newline");
  const fs::path a = root / "run\nA", b = root / "b";
  const std::string ref = sh(RUBDYN_SOURCE_DIR "/cases/reference.toml");
  REQUIRE(cli("run " + ref + " --t-end 0.002 --quiet --out " + sh(a.string())).code == 0);
  REQUIRE(cli("run " + ref + " --t-end 0.002 --quiet --out " + sh(b.string())).code == 0);
  const CliOutcome o = cli("compare " + sh(a.string()) + " " + sh(b.string()) + " --json " +
                           sh((root / "c.json").string()));
  REQUIRE(o.code == 0);
  const std::string json = slurp(root / "c.json");
  // the name as a JSON string: its line end written \n (a raw one is invalid JSON)
  CHECK(has(json, "\"a\": " + quoted_string(a.string()) + ","));
  CHECK(has(json, "run\\nA"));
  CHECK_FALSE(has(json, "run\nA"));
  fs::remove_all(root);
}

TEST_CASE("Run and analyze agree on what a case file may hold", "[regression][case][folder]") {
  const fs::path root = fresh_dir("big-string");
  const std::string ref = slurp(RUBDYN_SOURCE_DIR "/cases/reference.toml");
  const auto with_name = [&](const std::string& toml_name) {
    std::string s = ref;
    const auto i = s.find("name = ");
    REQUIRE(i != std::string::npos);
    s.replace(i, s.find('\n', i) - i, "name = " + toml_name);
    const fs::path f = root / "big.toml";
    fs::create_directories(root);
    std::ofstream(f) << s;
    return f;
  };
  // 900 kB of plain text: run writes it, analyze reads it
  const fs::path plain = with_name("'" + std::string(900'000, 'a') + "'");
  const fs::path out = root / "out";
  CliOutcome o =
      cli("run " + sh(plain.string()) + " --t-end 0.002 --quiet --out " + sh(out.string()));
  REQUIRE(o.code == 0);
  o = cli("analyze " + sh(out.string()));
  CHECK(o.code == 0);
  // 900 kB of backslashes (a TOML literal string, written back escaped: 1.8 MB) are refused by
  // run up front, naming the key, with nothing written
  const fs::path escaped = with_name("'" + std::string(900'000, '\\') + "'");
  fs::remove_all(out);
  o = cli("run " + sh(escaped.string()) + " --t-end 0.002 --quiet --out " + sh(out.string()));
  CHECK(o.code == 2);
  CHECK(has(o.err, "name"));
  CHECK(has(o.err, "case.resolved.toml"));
  CHECK_FALSE(fs::exists(out));
  fs::remove_all(root);
}

TEST_CASE("Matrices: a case whose matrix files are gone names the files, not its [initial] keys",
          "[regression][matrices][case]") {
  // a case.resolved.toml of an older run, its absolute paths leading nowhere: the problems are
  // the files; its [initial] keys are the coordinates rotor.coordinates names (they were reported
  // as keys of another model, initial.vx_b "a key of 'rigid-rotor'")
  std::string text = slurp(RUBDYN_SOURCE_DIR "/cases/matrices-paper.toml");
  text.replace(text.find("[initial]"), 9, "[initial]\nx_b = 0.0\nvx_b = 0.0\nvy_r = 0.0");
  try {
    parse_case(text, "/nowhere/case.resolved.toml");
    FAIL("accepted");
  } catch (const CaseError& e) {
    std::set<std::string> keys;
    for (const auto& i : e.issues()) keys.insert(i.key);
    INFO(e.what());
    CHECK(keys == std::set<std::string>{"rotor.M", "rotor.C", "rotor.K", "rotor.G", "rotor.f0"});
  }
}
