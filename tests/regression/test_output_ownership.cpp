// Output folders are owned, output paths are opened by one rule (issue 22): what rubdyn does
// with a device, a FIFO or a link given as an output path, a folder removed or replaced while a
// run writes into it, a folder that still holds the analysis of an earlier run, sweeps into one
// folder, sweep-merge's checks, and the exit codes of a file size limit and a folder that cannot
// be prepared. Every test runs the CLI as a user does (support/cli.hpp).
#include <signal.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/types.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <string>
#include <thread>

#include "support/cli.hpp"

namespace fs = std::filesystem;
using namespace rubdyn::testing;

namespace {

const std::string kRef = std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml";
const std::string kCli = RUBDYN_CLI;

/// Waits until `pred` holds, polling every 20 ms, for at most `seconds`.
template <class Pred>
bool wait_for(Pred pred, double seconds = 60.0) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!pred()) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

/// `rubdyn ARGS` started in the background: its pid, and its exit code once it has ended.
struct Background {
  fs::path dir;  // pid, rc and stderr files
  pid_t pid = -1;
  int finish() const {  // the exit code (-1 if it did not end within a minute)
    if (!wait_for([&] { return !slurp(dir / "rc").empty(); })) return -1;
    return std::stoi(slurp(dir / "rc"));
  }
  std::string err() const { return slurp(dir / "err"); }
};

Background start(const std::string& args, const std::string& tag) {
  Background b;
  b.dir = fresh_dir(tag);
  fs::create_directories(b.dir);
  const std::string p = sh((b.dir / "pid").string()), r = sh((b.dir / "rc").string());
  const std::string cmd = "( " + kCli + " " + args + " > /dev/null 2> " +
                          sh((b.dir / "err").string()) + " & echo $! > " + p + ".tmp; mv " + p +
                          ".tmp " + p + "; wait $!; echo $? > " + r + ".tmp; mv " + r + ".tmp " +
                          r + " ) &";
  REQUIRE(std::system(cmd.c_str()) == 0);
  REQUIRE(wait_for([&] { return !slurp(b.dir / "pid").empty(); }, 10.0));
  b.pid = static_cast<pid_t>(std::stol(slurp(b.dir / "pid")));
  return b;
}

bool is_fifo_path(const fs::path& p) {
  struct stat st {};
  return ::lstat(p.c_str(), &st) == 0 && S_ISFIFO(st.st_mode);
}

/// A character device of the memory driver (major 1: 3 = null, 7 = full) at dir/name: a node
/// of its own when mknod is allowed (root), else a link to /dev/null or /dev/full. Tests write to
/// these, never to the system's nodes, which a broken rule would replace by a regular file.
fs::path device_node(const fs::path& dir, const std::string& name, unsigned minor) {
  const fs::path p = dir / name;
  if (::mknod(p.c_str(), S_IFCHR | 0666, makedev(1, minor)) != 0)
    fs::create_symlink(minor == 3 ? "/dev/null" : "/dev/full", p);
  return p;
}

/// `p` is (or leads to) a character device.
bool is_char_device(const fs::path& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
}

/// A command prefix that runs the CLI as an unprivileged user (root writes through every
/// permission bit): setpriv when we are root, nothing when we are not. Empty optional when
/// neither works.
std::optional<std::string> unprivileged() {
  if (::geteuid() != 0) return std::string();
  if (std::system("command -v setpriv > /dev/null 2>&1") != 0) return std::nullopt;
  return std::string("setpriv --reuid=65534 --regid=65534 --clear-groups ");
}

}  // namespace

// --- one place opens output paths ----------------------------------------------------------

TEST_CASE("Output paths: compare --json writes through a link to the standard output",
          "[ownership][cli]") {
  const fs::path d = fresh_dir("json-stdout");
  fs::create_directories(d);
  REQUIRE(cli("run " + sh(kRef) + " --t-end 0.01 --quiet --out " + sh(d / "a")).code == 0);
  // a private link of the kind /dev/stdout is (-> /proc/self/fd/1): the test must not put the
  // system's /dev/stdout at risk when the rule is broken
  fs::create_symlink("/proc/self/fd/1", d / "stdout");
  const CliOutcome o =
      cli("compare " + sh(d / "a") + " " + sh(d / "a") + " --json " + sh(d / "stdout"));
  CHECK(o.code == 0);
  CHECK(fs::is_symlink(d / "stdout"));        // never replaced
  CHECK_FALSE(fs::exists(d / "stdout.tmp"));  // nothing left beside it
  const auto report = o.out.find("window"), json = o.out.find("\"unmatched_a\"");
  CHECK(report != std::string::npos);
  CHECK(json != std::string::npos);
  CHECK(report < json);  // after the report: the stream is written in order
  fs::remove_all(d);
}

TEST_CASE("Output paths: a link is written through, never replaced, a link to nothing refused",
          "[ownership][cli]") {
  const fs::path d = fresh_dir("json-link");
  fs::create_directories(d);
  REQUIRE(cli("run " + sh(kRef) + " --t-end 0.01 --quiet --out " + sh(d / "a")).code == 0);
  const std::string ab = "compare " + sh(d / "a") + " " + sh(d / "a") + " --json ";
  { std::ofstream(d / "target.json") << "old\n"; }
  fs::create_symlink("target.json", d / "link.json");
  CHECK(cli(ab + sh(d / "link.json")).code == 0);
  CHECK(fs::is_symlink(d / "link.json"));
  CHECK(has(slurp(d / "target.json"), "\"unmatched_a\""));
  CHECK_FALSE(has(slurp(d / "target.json"), "old"));  // truncated, rewritten in place
  // a link to nothing: refused (exit 2), neither the link nor a target made
  fs::create_symlink("missing.json", d / "dangling.json");
  CliOutcome o = cli(ab + sh(d / "dangling.json"));
  CHECK(o.code == 2);
  CHECK(has(o.err, "dangling.json"));
  CHECK(fs::is_symlink(d / "dangling.json"));
  CHECK_FALSE(fs::exists(d / "missing.json"));
  // a directory: refused before any work
  o = cli(ab + sh(d));
  CHECK(o.code == 2);
  CHECK(has(o.err, "a directory"));
  CHECK(o.out.empty());
  // a character device: written through, never replaced. Private nodes of /dev/null (1, 3)
  // and /dev/full (1, 7), made in the scratch folder when we may (root), else links to them: a
  // broken rule then replaces the test's node or link, never the system's device
  const fs::path null_dev = device_node(d, "null", 3), full_dev = device_node(d, "full", 7);
  CHECK(cli(ab + sh(null_dev)).code == 0);
  CHECK(is_char_device(null_dev));
  // a full device: a failed write, exit 5 naming it
  o = cli(ab + sh(full_dev));
  CHECK(o.code == 5);
  CHECK(has(o.err, full_dev.string()));
  CHECK(is_char_device(full_dev));
  // an empty path (an unset variable) is refused, not skipped
  CHECK(cli(ab + "''").code == 2);
  fs::remove_all(d);
}

TEST_CASE("Output paths: a FIFO is written to its reader, refused without one, never waited for",
          "[ownership][cli]") {
  const fs::path d = fresh_dir("json-fifo");
  fs::create_directories(d);
  REQUIRE(cli("run " + sh(kRef) + " --t-end 0.01 --quiet --out " + sh(d / "a")).code == 0);
  REQUIRE(::mkfifo((d / "fifo").c_str(), 0600) == 0);
  const std::string ab = "compare " + sh(d / "a") + " " + sh(d / "a") + " --json ";
  // no reader: refused at once (`timeout` only guards the test against a hang, exit 124)
  CliOutcome o = cli(ab + sh(d / "fifo"), "timeout 20 ");
  CHECK(o.code == 2);
  CHECK(has(o.err, "FIFO"));
  CHECK(is_fifo_path(d / "fifo"));
  // with a reader: written through, the FIFO left in place
  REQUIRE(std::system(
              ("timeout 20 cat " + sh(d / "fifo") + " > " + sh(d / "read.json") + " &").c_str()) ==
          0);
  // the reader opens the FIFO first; retried until it has (a writer alone is refused)
  int code = -1;
  REQUIRE(wait_for(
      [&] {
        code = cli(ab + sh(d / "fifo"), "timeout 20 ").code;
        return code != 2;
      },
      15.0));
  CHECK(code == 0);
  CHECK(wait_for([&] { return has(slurp(d / "read.json"), "\"unmatched_b\""); }, 15.0));
  CHECK(is_fifo_path(d / "fifo"));
  fs::remove_all(d);
}

TEST_CASE("Case files: a FIFO without a writer is refused with exit 2 after a bounded wait",
          "[ownership][cli]") {
  // (a FIFO with a writer is read: test_new_surfaces.cpp, test_new_surfaces_cli.cpp)
  const fs::path d = fresh_dir("case-fifo");
  fs::create_directories(d);
  REQUIRE(::mkfifo((d / "case.toml").c_str(), 0600) == 0);
  // `timeout` guards the test: a blocking open or an unbounded wait would end with 124 instead
  // of hanging it; RUBDYN_PIPE_WAIT shortens the wait (10 s by default)
  const CliOutcome o = cli("check " + sh(d / "case.toml"), "RUBDYN_PIPE_WAIT=0.5 timeout 20 ");
  CHECK(o.code == 2);
  CHECK(has(o.err, (d / "case.toml").string()));
  CHECK(has(o.err, "is a FIFO (named pipe) from which nothing arrived within 0.5 s"));
  fs::remove_all(d);
}

// --- exit codes of failed writes -------------------------------------------------------------

TEST_CASE("Exit codes: a file size limit ends a run with exit 5 and a summary, no SIGXFSZ kill",
          "[ownership][cli]") {
  // RLIMIT_FSIZE of 100 kB (prlimit, or ulimit -f in 1 kB blocks): the reference case's 1 s
  // writes about 4 MB of rows, so timeseries.csv reaches the limit and summary.json (2 kB)
  // does not. No `trap '' XFSZ`: rubdyn must ignore the signal itself.
  const fs::path g = fresh_dir("xfsz");
  const CliOutcome o =
      cli("run " + sh(kRef) + " --t-end 1 --quiet --out " + sh(g), "ulimit -f 100; ");
  CHECK(o.code == 5);
  CHECK(has(o.err, "timeseries.csv"));
  const std::string summary = slurp(g / "summary.json");
  CHECK(has(summary, "\"complete\": false"));
  CHECK(has(summary, "\"termination\": \"output_failure\""));
  CHECK(has(summary, "timeseries.csv: File too large"));
  fs::remove_all(g);
}

TEST_CASE("Exit codes: when summary.json fails too, the message names the first failed write",
          "[ownership][cli]") {
  // the file size limit fails timeseries.csv first; summary.json cannot be written either (its
  // temporary file's name is taken by a folder): the message starts with timeseries.csv
  const fs::path g = fresh_dir("first-failure");
  fs::create_directories(g / "summary.json.tmp" / "x");
  const CliOutcome o =
      cli("run " + sh(kRef) + " --t-end 1 --quiet --out " + sh(g), "ulimit -f 100; ");
  CHECK(o.code == 5);
  const auto first = o.err.find("cannot write");
  REQUIRE(first != std::string::npos);
  CHECK(o.err.compare(first, 40, "cannot write " + g.string() + "/timeseries.csv", 0, 40) == 0);
  CHECK(has(o.err, "summary.json"));  // and the summary's failure after it
  CHECK(o.err.find("timeseries.csv") < o.err.find("summary.json"));
  fs::remove_all(g);
}

// --- output folders are owned ----------------------------------------------------------------

TEST_CASE(
    "Owned folders: a run whose folder is removed and recreated exits 5 and writes nothing "
    "into the new one",
    "[ownership][cli]") {
  // 50 s of the reference case take several seconds: the folder is replaced long before the
  // run would end, and the run must notice it (at its next event or 1024th sample)
  const fs::path d = fresh_dir("replaced");
  const Background b = start("run " + sh(kRef) + " --t-end 50 --quiet --out " + sh(d), "bg-repl");
  REQUIRE(wait_for([&] { return fs::exists(d / "timeseries.csv"); }));
  fs::remove_all(d);
  fs::create_directories(d);
  const int code = b.finish();
  CHECK(code == 5);
  CHECK(has(b.err(), "removed or replaced"));
  CHECK(fs::is_empty(d));  // in particular no summary.json saying "complete": true
  fs::remove_all(d);
  fs::remove_all(b.dir);
}

TEST_CASE("Owned folders: a run whose folder is moved away marks it incomplete there, exit 5",
          "[ownership][cli]") {
  const fs::path d = fresh_dir("moved"), m = fresh_dir("moved-to");
  const Background b = start("run " + sh(kRef) + " --t-end 50 --quiet --out " + sh(d), "bg-move");
  REQUIRE(wait_for([&] { return fs::exists(d / "timeseries.csv"); }));
  fs::rename(d, m);
  CHECK(b.finish() == 5);
  CHECK_FALSE(fs::exists(d));  // not recreated at the old path
  const std::string summary = slurp(m / "summary.json");
  CHECK(has(summary, "\"complete\": false"));
  CHECK(has(summary, "\"termination\": \"output_failure\""));
  CHECK(has(summary, "removed or replaced"));
  fs::remove_all(m);
  fs::remove_all(b.dir);
}

TEST_CASE("Owned folders: a new run removes what was derived from the previous one",
          "[ownership][cli]") {
  const fs::path d = fresh_dir("rerun");
  REQUIRE(cli("run " + sh(kRef) + " --t-end 0.05 --quiet --out " + sh(d)).code == 0);
  REQUIRE(cli("analyze " + sh(d)).code == 0);
  REQUIRE(fs::exists(d / "analysis" / "analysis.json"));
  for (const char* png : {"omega.png", "orbit.png", "timeline.png"})  // as rubdyn.plot names them
    std::ofstream(d / png) << "png";
  std::ofstream(d / "notes.txt") << "mine";  // not derived by rubdyn: kept
  REQUIRE(cli("run " + sh(kRef) + " --t-end 0.01 --quiet --out " + sh(d)).code == 0);
  CHECK_FALSE(fs::exists(d / "analysis"));
  for (const char* png : {"omega.png", "orbit.png", "timeline.png"})
    CHECK_FALSE(fs::exists(d / png));
  CHECK(slurp(d / "notes.txt") == "mine");
  // a file of the user's in analysis/ keeps the folder (only rubdyn's own files go)
  REQUIRE(cli("analyze " + sh(d)).code == 0);
  std::ofstream(d / "analysis" / "mine.csv") << "x\n";
  REQUIRE(cli("run " + sh(kRef) + " --t-end 0.01 --quiet --out " + sh(d)).code == 0);
  CHECK(fs::exists(d / "analysis" / "mine.csv"));
  CHECK_FALSE(fs::exists(d / "analysis" / "analysis.json"));
  fs::remove_all(d);
}

TEST_CASE("Owned folders: a case named .. is refused instead of writing into the current folder",
          "[ownership][cli]") {
  const fs::path d = fresh_dir("dotdot");
  fs::create_directories(d / "out");
  std::string text = "name = \"..\"\n" + slurp(kRef);
  text = std::regex_replace(text, std::regex("\nname = \"[^\"]*\"\n"), "\n");
  REQUIRE(text.find("\"..\"") != std::string::npos);
  std::ofstream(d / "dotdot.toml") << text;
  const CliOutcome o = cli("run dotdot.toml --t-end 0.01 --quiet", "cd " + sh(d) + " && ");
  CHECK(o.code == 2);
  CHECK(has(o.err, "name"));
  CHECK_FALSE(fs::exists(d / "timeseries.csv"));
  CHECK(fs::is_empty(d / "out"));
  // with --out the name does not matter
  CHECK(cli("run dotdot.toml --t-end 0.01 --quiet --out r", "cd " + sh(d) + " && ").code == 0);
  fs::remove_all(d);
}

// --- sweeps: the sweep's folder, shards, merge -----------------------------------------------

TEST_CASE("Sweeps: the sweep folder is locked, a second sweep and a merge meanwhile are refused",
          "[ownership][cli]") {
  const fs::path d = fresh_dir("sweep-lock");
  const Background b = start("sweep " + sh(kRef) + " --vary contact.mu=0.1 --t-end 50 --jobs 1 " +
                                 "--quiet --out " + sh(d),
                             "bg-sweep");
  REQUIRE(wait_for([&] { return fs::exists(d / "p0000" / "timeseries.csv"); }));
  CliOutcome o =
      cli("sweep " + sh(kRef) + " --vary contact.mu=0.2 --t-end 0.01 --quiet --out " + sh(d));
  CHECK(o.code == 2);
  CHECK(has(o.err, "in use by another rubdyn sweep"));
  // a shard of another plan waits for the folder, then is refused as well
  o = cli("sweep " + sh(kRef) + " --vary contact.mu=0.2 --t-end 0.01 --shard 1/2 --quiet --out " +
          sh(d));
  CHECK(o.code == 2);
  o = cli("sweep-merge " + sh(d));
  CHECK(o.code == 2);
  CHECK(has(o.err, "running rubdyn sweep"));
  CHECK_FALSE(fs::exists(d / "sweep.csv"));
  REQUIRE(::kill(b.pid, SIGTERM) == 0);  // ends the first sweep with its table (exit 4)
  CHECK(b.finish() == 4);
  CHECK(has(slurp(d / "sweep.csv"), "p0000"));
  fs::remove_all(d);
  fs::remove_all(b.dir);
}

TEST_CASE("Sweeps: a sweep whose folder is removed meanwhile exits 5 and writes no table",
          "[ownership][cli]") {
  const fs::path d = fresh_dir("sweep-gone");
  const Background b = start("sweep " + sh(kRef) + " --vary contact.mu=0.1 --t-end 50 --jobs 1 " +
                                 "--quiet --out " + sh(d),
                             "bg-sweep-gone");
  REQUIRE(wait_for([&] { return fs::exists(d / "p0000" / "timeseries.csv"); }));
  fs::remove_all(d);
  fs::create_directories(d);
  CHECK(b.finish() == 5);
  CHECK(has(b.err(), "removed or replaced"));
  CHECK(fs::is_empty(d));
  fs::remove_all(d);
  fs::remove_all(b.dir);
}

TEST_CASE("Sweeps: --shard '' and a folder that cannot be prepared exit 2 with nothing run",
          "[ownership][cli]") {
  const fs::path d = fresh_dir("sweep-prep");
  fs::create_directories(d);
  const std::string sweep = "sweep " + sh(kRef) + " --vary contact.mu=0.1 --t-end 0.01 --quiet ";
  // an unset job-array variable: not the whole sweep in every task
  CliOutcome o = cli(sweep + "--shard '' --out " + sh(d / "s"));
  CHECK(o.code == 2);
  CHECK(has(o.err, "--shard"));
  CHECK_FALSE(fs::exists(d / "s"));
  // a path under a regular file cannot be a folder (for root as for anyone)
  std::ofstream(d / "file") << "x";
  o = cli(sweep + "--out " + sh(d / "file" / "sub"));
  CHECK(o.code == 2);
  CHECK(has(o.err, "file/sub"));
  // a read-only folder: as an unprivileged user (root writes into it regardless)
  const auto as_user = unprivileged();
  if (!as_user) {
    WARN("neither unprivileged nor setpriv available: the read-only folder is not tested");
  } else {
    fs::create_directories(d / "ro");
    fs::permissions(d, fs::perms::owner_all | fs::perms::others_read | fs::perms::others_exec);
    fs::permissions(d / "ro", fs::perms::owner_read | fs::perms::owner_exec |
                                  fs::perms::others_read | fs::perms::others_exec);
    o = cli(sweep + "--out " + sh(d / "ro"), *as_user);
    CHECK(o.code == 2);
    CHECK(has(o.err, "cannot write into"));
    CHECK(fs::is_empty(d / "ro"));  // no point prepared, no table
    o = cli("run " + sh(kRef) + " --t-end 0.01 --quiet --out " + sh(d / "ro"), *as_user);
    CHECK(o.code == 2);
    CHECK(fs::is_empty(d / "ro"));
  }
  fs::remove_all(d);
}

TEST_CASE("Sweeps: sweep-merge takes the shards of one plan, each once, every field valid",
          "[ownership][cli]") {
  const fs::path d = fresh_dir("merge-plan"), e = fresh_dir("merge-other");
  const std::string sweep = "sweep " + sh(kRef) + " --t-end 0.01 --jobs 1 --quiet ";
  REQUIRE(cli(sweep + "--vary contact.mu=0.1,0.2,0.3 --shard 1/2 --out " + sh(d)).code == 0);
  REQUIRE(cli(sweep + "--vary contact.mu=0.1,0.2,0.3 --shard 2/2 --out " + sh(d)).code == 0);
  REQUIRE(cli("sweep-merge " + sh(d)).code == 0);
  const std::string merged = slurp(d / "sweep.csv");
  // shard 2 of another sweep with as many points (mu 0.4 for 0.2), made in a folder of its own
  REQUIRE(cli(sweep + "--vary contact.mu=0.1,0.4,0.3 --shard 2/2 --out " + sh(e)).code == 0);
  const fs::path s2csv = d / "sweep-shard-2-of-2.csv", s2json = d / "sweep-shard-2-of-2.json";
  const std::string good_csv = slurp(s2csv), good_json = slurp(s2json);
  fs::copy_file(e / "sweep-shard-2-of-2.csv", s2csv, fs::copy_options::overwrite_existing);
  fs::copy_file(e / "sweep-shard-2-of-2.json", s2json, fs::copy_options::overwrite_existing);
  CliOutcome o = cli("sweep-merge " + sh(d));
  CHECK(o.code == 2);
  CHECK(has(o.err, "plan"));
  CHECK(has(o.err, "sweep-shard-2-of-2.json"));
  CHECK(slurp(d / "sweep.csv") == merged);  // nothing written
  std::ofstream(s2csv) << good_csv;
  std::ofstream(s2json) << good_json;
  REQUIRE(cli("sweep-merge " + sh(d)).code == 0);
  // two files for one shard
  fs::copy_file(d / "sweep-shard-1-of-2.csv", d / "sweep-shard-01-of-2.csv");
  o = cli("sweep-merge " + sh(d));
  CHECK(o.code == 2);
  CHECK(has(o.err, "sweep-shard-01-of-2.csv"));
  fs::remove(d / "sweep-shard-01-of-2.csv");
  // a corrupted field: file, line, column and value named
  const std::string row = good_csv.substr(good_csv.find('\n') + 1);
  const auto c1 = row.find(',', row.find(',', row.find(',') + 1) + 1);  // after point,mu,term,
  const auto c2 = row.find(',', c1 + 1);                                // the complete field
  std::string bad = good_csv;
  bad.replace(good_csv.find('\n') + 1 + c1 + 1, c2 - c1 - 1, "maybe");
  std::ofstream(s2csv) << bad;
  o = cli("sweep-merge " + sh(d));
  CHECK(o.code == 2);
  CHECK(has(o.err, "sweep-shard-2-of-2.csv:2"));
  CHECK(has(o.err, "complete"));
  CHECK(has(o.err, "maybe"));
  // a number made two (omega_max, the column after complete)
  bad = std::regex_replace(good_csv, std::regex(",(yes|no),(\\d+)\\.(\\d+),"), ",$1,$2.$3.7,",
                           std::regex_constants::format_first_only);
  REQUIRE(bad != good_csv);
  std::ofstream(s2csv) << bad;
  o = cli("sweep-merge " + sh(d));
  CHECK(o.code == 2);
  CHECK(has(o.err, "omega_max"));
  CHECK(has(o.err, "must be a number"));
  // a row of another shard's point
  bad = good_csv + "0" + row.substr(row.find(','));
  std::ofstream(s2csv) << bad;
  o = cli("sweep-merge " + sh(d));
  CHECK(o.code == 2);
  CHECK(has(o.err, "does not belong to shard 2 of 2"));
  std::ofstream(s2csv) << good_csv;
  CHECK(cli("sweep-merge " + sh(d)).code == 0);
  CHECK(slurp(d / "sweep.csv") == merged);
  fs::remove_all(d);
  fs::remove_all(e);
}

TEST_CASE("Sweeps: a sweep of another plan into a folder removes that plan's merged table",
          "[ownership][cli]") {
  const fs::path d = fresh_dir("sweep-replan");
  const std::string sweep = "sweep " + sh(kRef) + " --t-end 0.01 --jobs 1 --quiet ";
  REQUIRE(cli(sweep + "--vary contact.mu=0.1,0.2 --out " + sh(d)).code == 0);
  REQUIRE(has(slurp(d / "sweep.csv"), "p0001"));
  // shard 1 of another plan replaces p0000: the old table, which says p0000 is mu = 0.1, goes
  REQUIRE(cli(sweep + "--vary contact.mu=0.3,0.4 --shard 1/2 --out " + sh(d)).code == 0);
  CHECK_FALSE(fs::exists(d / "sweep.csv"));
  CHECK(fs::exists(d / "sweep-shard-1-of-2.csv"));
  // the same plan again keeps its tables (a later shard, or --resume)
  REQUIRE(cli(sweep + "--vary contact.mu=0.3,0.4 --shard 2/2 --out " + sh(d)).code == 0);
  CHECK(fs::exists(d / "sweep-shard-1-of-2.csv"));
  REQUIRE(cli("sweep-merge " + sh(d)).code == 0);
  REQUIRE(cli(sweep + "--vary contact.mu=0.3,0.4 --shard 2/2 --resume --out " + sh(d)).code == 0);
  CHECK(has(slurp(d / "sweep.csv"), "0.4"));
  // a shard of the first plan left beside another plan's is refused by sweep-merge
  REQUIRE(cli(sweep + "--vary contact.mu=0.1,0.2 --shard 2/2 --out " + sh(d)).code == 0);
  const CliOutcome o = cli("sweep-merge " + sh(d));
  CHECK(o.code == 2);
  CHECK(has(o.err, "plan"));
  fs::remove_all(d);
}
