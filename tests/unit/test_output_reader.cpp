// The one reader of rubdyn's CSV output (io/output_reader.hpp): what a killed run leaves is
// tolerated with a warning, anything else malformed names the file and the line.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>

#include "rubdyn/driver/simulate.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/output_folder.hpp"
#include "rubdyn/io/output_reader.hpp"

using namespace rubdyn;

namespace {
std::string write(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::temp_directory_path() / "rubdyn_output_reader_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}
}  // namespace

TEST_CASE("read_csv: rows, columns, a cut last row dropped with a warning", "[io][unit]") {
  const std::string p = write("cut.csv", "t,x,kind\n0,1,\"a,b\"\n0.5,2,c\n1,3");
  const CsvTable t = read_csv(p);
  CHECK(t.header == std::vector<std::string>{"t", "x", "kind"});
  REQUIRE(t.rows.size() == 2);
  CHECK(t.rows[0][2] == "a,b");  // RFC 4180 quoting
  CHECK(t.line_of[1] == 3);
  CHECK(t.column("x") == 1);
  CHECK(t.column("y") == -1);
  REQUIRE(t.warnings.size() == 1);
  CHECK(t.warnings[0].find(p + ":4:") == 0);
  double x = 0;
  CHECK(parse_number(t.rows[1][0], x));
  CHECK(x == 0.5);
  CHECK_FALSE(parse_number("1.5e", x));
  CHECK_FALSE(parse_number("", x));
}

TEST_CASE("read_csv: a wrong field count names the line, and an empty file", "[io][unit]") {
  const std::string bad = write("bad.csv", "t,x\n0,1\n0.5,2,3\n");
  CHECK_THROWS_WITH(read_csv(bad), Catch::Contains(bad + ":3: 3 fields, the header has 2"));
  const std::string empty = write("empty.csv", "");
  CHECK_THROWS_WITH(read_csv(empty), Catch::Contains(empty + ":1: empty file"));
  const CsvTable e = read_csv(empty, true);  // a killed run's events.csv
  CHECK(e.rows.empty());
  CHECK(e.warnings.size() == 1);
  CHECK_THROWS_WITH(read_csv(empty + ".none"), Catch::Contains("cannot read"));
}

namespace {

/// Hands a run's output to two sinks: the folder writer and memory.
class Tee final : public OutputSink {
 public:
  Tee(OutputSink& a, OutputSink& b) : a_(a), b_(b) {}
  void sample(const Sample& s) override {
    a_.sample(s);
    b_.sample(s);
  }
  void event(const EventRecord& e) override {
    a_.event(e);
    b_.event(e);
  }
  void end(const RunSummary& s) override {
    a_.end(s);
    b_.end(s);
  }

 private:
  OutputSink &a_, &b_;
};

bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0 || (std::isnan(a) && std::isnan(b));
}

}  // namespace

TEST_CASE("read_run_files: what a run wrote comes back bit for bit, by the model's column table",
          "[io][unit]") {
  // the paper's rotor (event solver: impacts, slip, lift-offs, witnesses with commas in their
  // text) and the Jeffcott rotor at prescribed speed (5 coordinates, the drive_torque column)
  const std::string src = RUBDYN_SOURCE_DIR;
  auto text_of = [](const std::string& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  std::string jeffcott = text_of(src + "/cases/jeffcott.toml");
  const std::string torque = "torque    = 20.0";
  REQUIRE(jeffcott.find(torque) != std::string::npos);
  jeffcott.replace(jeffcott.find(torque), torque.size(), "spin = \"prescribed\"");
  const std::vector<std::pair<CaseSpec, std::string>> runs = {
      {load_case(src + "/cases/reference.toml", {"run.t_end=0.05"}), "reference, event"},
      {parse_case(jeffcott, "jeffcott.toml", {"run.t_end=0.05"}), "jeffcott, prescribed"},
      {load_case(src + "/cases/reference.toml",
                 {"run.t_end=0.02", "solver.kind=\"mj\"", "solver.h=1e-5"}),
       "reference, mj"}};
  for (const auto& [spec, what] : runs) {
    const auto dir = std::filesystem::temp_directory_path() / "rubdyn_read_run_files";
    std::filesystem::remove_all(dir);
    MemorySink mem;
    {
      OutputFolder folder(dir.string(), spec);
      Tee tee(folder, mem);
      simulate(spec, tee);
    }
    INFO(what);
    const RunFiles f = read_run_files(dir.string());
    CHECK(f.complete);
    CHECK(f.warnings.empty());
    CHECK(f.spec.model == spec.model);
    REQUIRE(f.series.rows() == mem.samples.size());
    REQUIRE(f.series.columns.size() == f.series.values.size());
    const auto model = build_model(spec);
    CHECK(f.series.columns.size() == timeseries_columns(*model).size());
    long differ = 0;
    for (std::size_t c = 0; c < f.series.columns.size(); ++c)
      for (std::size_t i = 0; i < mem.samples.size(); ++i)
        differ +=
            !same_bits(f.series.values[c][i], sample_value(mem.samples[i], f.series.columns[c]));
    CHECK(differ == 0);
    REQUIRE(f.events.size() == mem.events.size());
    REQUIRE_FALSE(f.events.empty());
    for (std::size_t k = 0; k < f.events.size(); ++k) {
      const EventRecord &a = f.events[k], &b = mem.events[k];
      CHECK(a.kind == b.kind);
      CHECK(a.phase_before == b.phase_before);
      CHECK(a.phase_after == b.phase_after);
      CHECK(a.witness == b.witness);
      CHECK(a.note == b.note);
      for (const EventColumn& c : event_columns())
        if (c.field == EventField::Number || c.field == EventField::Time)
          CHECK(same_bits(event_number(a, c.name), event_number(b, c.name)));
    }
    CHECK(f.summary_json.find("\"complete\": true") != std::string::npos);
    // the analyses' view of the same folder: the samples
    const RunRecord r = read_run(dir.string());
    REQUIRE(r.samples.size() == mem.samples.size());
    CHECK(r.events == static_cast<long>(mem.events.size()));
    CHECK(same_bits(r.samples.back().q[2], mem.samples.back().q[2]));
    std::filesystem::remove_all(dir);
  }
}

TEST_CASE("read_run_files: a malformed event row names the file, line and column", "[io][unit]") {
  const CaseSpec spec =
      load_case(std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml", {"run.t_end=0.01"});
  const auto dir = std::filesystem::temp_directory_path() / "rubdyn_read_run_files_bad";
  std::filesystem::remove_all(dir);
  {
    OutputFolder folder(dir.string(), spec);
    simulate(spec, folder);
  }
  std::string ev;
  {
    std::ifstream in(dir / "events.csv");
    ev.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const auto second_line = ev.find('\n') + 1;
  REQUIRE(second_line < ev.size());
  const auto comma = ev.find(',', second_line);
  // the kind of the first event replaced by a word that is none
  const auto comma2 = ev.find(',', comma + 1);
  ev.replace(comma + 1, comma2 - comma - 1, "bounce");
  std::ofstream(dir / "events.csv", std::ios::binary | std::ios::trunc) << ev;
  CHECK_THROWS_WITH(read_run_files(dir.string()),
                    Catch::Contains("events.csv:2: column kind: 'bounce' is not an event kind"));
  std::filesystem::remove_all(dir);
}

namespace {

/// A complete output folder of the reference case over `t_end` (event solver: impacts, slip).
std::filesystem::path written_run(const std::string& name, double t_end) {
  const CaseSpec spec = load_case(std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml",
                                  {"run.t_end=" + std::to_string(t_end)});
  const auto dir = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(dir);
  OutputFolder folder(dir.string(), spec);
  simulate(spec, folder);
  return dir;
}

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void put(const std::filesystem::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << text;
}

/// The text with its line `line` (1 = first) passed through `edit`.
std::string edit_line(const std::string& text, int line,
                      const std::function<void(std::string&)>& edit) {
  std::size_t from = 0;
  for (int k = 1; k < line; ++k) from = text.find('\n', from) + 1;
  const std::size_t to = text.find('\n', from);
  std::string l = text.substr(from, to - from);
  edit(l);
  return text.substr(0, from) + l + text.substr(to);
}

}  // namespace

TEST_CASE("read_csv: a line that is not text names the file - line and byte", "[io][unit]") {
  // NUL, a control character, a lone UTF-8 continuation byte, a cut UTF-8 sequence, an overlong
  // form and a surrogate are not text; the message quotes no byte of the file (ASCII only)
  const std::vector<std::pair<std::string, std::string>> bad = {
      {std::string("0,1\0", 4), "byte 0x00 at column 4"},
      {"0,\x01", "byte 0x01 at column 3"},
      {"0,\x80", "byte 0x80 at column 3"},
      {"0,\xc3", "byte 0xc3 at column 3"},
      {"0,\xc0\xaf", "byte 0xc0 at column 3"},
      {"0,\xed\xa0\x80", "byte 0xed at column 3"}};
  for (const auto& [row, what] : bad) {
    const std::string p = write("binary.csv", "t,x\n" + row + "\n1,2\n");
    INFO(printable(row));
    try {
      read_csv(p);
      FAIL("accepted");
    } catch (const ReadError& e) {
      CHECK(std::string(e.what()).find(p + ":2: " + what) == 0);
      CHECK(e.file() == p);
      CHECK(e.line() == 2);
      for (const char ch : std::string(e.what()))
        CHECK((static_cast<unsigned char>(ch) >= 0x20 && static_cast<unsigned char>(ch) < 0x7f));
    }
  }
  // UTF-8 text (an accented word, a tab) is text; CRLF reads as LF
  const std::string ok = write("utf8.csv", "t,note\r\n0,\"caf\xc3\xa9\tbar\"\r\n1,x\r\n");
  const CsvTable t = read_csv(ok);
  REQUIRE(t.rows.size() == 2);
  CHECK(t.rows[0][1] == "caf\xc3\xa9\tbar");
  CHECK(t.rows[1][1] == "x");
  CHECK(t.header == std::vector<std::string>{"t", "note"});
  CHECK(printable("a\x01\xff" + std::string(50, 'b'), 10) == "a\\x01\\xffbbbbbbb...");
}

TEST_CASE("read_run_files: CRLF line ends read as the same numbers", "[io][unit]") {
  const auto dir = written_run("rubdyn_read_crlf", 0.01);
  const RunFiles lf = read_run_files(dir.string());
  for (const char* name : {"timeseries.csv", "events.csv"}) {
    std::string text = slurp(dir / name), crlf;
    for (const char ch : text) crlf += ch == '\n' ? std::string("\r\n") : std::string(1, ch);
    REQUIRE(crlf.size() > text.size());
    put(dir / name, crlf);
  }
  const RunFiles cr = read_run_files(dir.string());
  CHECK(cr.warnings.empty());
  REQUIRE(cr.series.rows() == lf.series.rows());
  CHECK(cr.series.values == lf.series.values);  // the same text: the same doubles
  REQUIRE(cr.events.size() == lf.events.size());
  REQUIRE_FALSE(cr.events.empty());
  CHECK(cr.events.back().note == lf.events.back().note);  // no '\r' left in the last field
  std::filesystem::remove_all(dir);
}

TEST_CASE("read_run_files: a time that is not finite is refused with file and line", "[io][unit]") {
  const auto dir = written_run("rubdyn_read_nan_time", 0.01);
  const std::string ts = slurp(dir / "timeseries.csv"), ev = slurp(dir / "events.csv");
  for (const char* value : {"nan", "inf", "-inf"}) {
    INFO(value);
    // the first field of line 4 (the third sample) is its time
    put(dir / "timeseries.csv",
        edit_line(ts, 4, [&](std::string& l) { l = value + l.substr(l.find(',')); }));
    CHECK_THROWS_AS(read_run_files(dir.string()), ReadError);
    CHECK_THROWS_WITH(read_run_files(dir.string()),
                      Catch::Contains("timeseries.csv:4: column t: '" + std::string(value) +
                                      "' is not a finite time"));
    put(dir / "timeseries.csv", ts);
    put(dir / "events.csv",
        edit_line(ev, 2, [&](std::string& l) { l = value + l.substr(l.find(',')); }));
    CHECK_THROWS_WITH(read_run_files(dir.string()),
                      Catch::Contains("events.csv:2: column t: '" + std::string(value) +
                                      "' is not a finite time"));
    put(dir / "events.csv", ev);
  }
  CHECK_NOTHROW(read_run_files(dir.string()));  // restored: the edits were the only fault
  std::filesystem::remove_all(dir);
}

TEST_CASE("read_run_files: summary.json empty or binary - timeseries header only", "[io][unit]") {
  const auto dir = written_run("rubdyn_read_summary", 0.01);
  put(dir / "summary.json", "");
  RunFiles f = read_run_files(dir.string());
  CHECK_FALSE(f.complete);
  REQUIRE(f.warnings.size() == 1);
  CHECK(f.warnings[0].find("summary.json: empty") != std::string::npos);
  put(dir / "summary.json", "{\"complete\": true,\n\xff\xfe}");
  CHECK_THROWS_WITH(read_run_files(dir.string()),
                    Catch::Contains("summary.json:2: byte 0xff at column 1: not text"));
  std::filesystem::remove(dir / "summary.json");
  // a run killed before its first sample: no rows, no error (what reads it decides)
  const std::string ts = slurp(dir / "timeseries.csv");
  put(dir / "timeseries.csv", ts.substr(0, ts.find('\n') + 1));
  f = read_run_files(dir.string());
  CHECK(f.series.rows() == 0);
  CHECK_FALSE(f.complete);
  std::filesystem::remove_all(dir);
}
