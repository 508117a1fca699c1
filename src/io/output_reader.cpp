#include "rubdyn/io/output_reader.hpp"

#include <fmt/format.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/text_files.hpp"

namespace rubdyn {

int CsvTable::column(std::string_view name) const {
  for (std::size_t c = 0; c < header.size(); ++c)
    if (header[c] == name) return static_cast<int>(c);
  return -1;
}

CsvTable read_csv(const std::string& path, bool empty_ok) {
  CsvTable t;
  t.path = path;
  std::ifstream in(path);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot read", path));
  std::string line;
  if (!std::getline(in, line)) {
    if (!empty_ok) throw std::runtime_error(fmt::format("{}:1: empty file", path));
    t.warnings.push_back(path + ": empty (no header): read as no rows");
    return t;
  }
  t.header = split_csv_line(line);
  t.header_text = line;
  long ln = 1;
  while (std::getline(in, line)) {
    ++ln;
    if (line.empty()) continue;
    if (in.eof()) {  // no line end: cut short
      t.warnings.push_back(cut_row_warning(path, ln));
      break;
    }
    auto fields = split_csv_line(line);
    if (fields.size() != t.header.size()) {
      throw std::runtime_error(fmt::format("{}:{}: {} fields, the header has {}", path, ln,
                                           fields.size(), t.header.size()));
    }
    t.rows.push_back(std::move(fields));
    t.line_of.push_back(ln);
    t.text.push_back(line);
  }
  return t;
}

bool parse_number(const std::string& field, double& x) {
  if (field.empty()) return false;
  char* end = nullptr;
  x = std::strtod(field.c_str(), &end);
  return end && *end == '\0';
}

namespace {

Phase phase_of(const std::string& s, const std::string& file, long line) {
  for (int k = 0; k < kNumPhases; ++k) {
    if (s == to_string(static_cast<Phase>(k))) return static_cast<Phase>(k);
  }
  throw std::runtime_error(fmt::format(
      "{}:{}: column phase: '{}' is not a phase (free, slip+, slip-, stick)", file, line, s));
}

}  // namespace

RunRecord read_run(const std::string& dir) {
  namespace fs = std::filesystem;
  RunRecord r;
  r.dir = dir;
  const std::string case_path = (fs::path(dir) / "case.resolved.toml").string();
  const std::string ts_path = (fs::path(dir) / "timeseries.csv").string();
  if (!fs::is_directory(dir)) throw std::runtime_error(dir + ": not an output folder");
  if (!fs::exists(case_path)) throw std::runtime_error(case_path + ": missing");
  r.spec = load_case(case_path);
  const CsvTable ts = read_csv(ts_path);
  r.warnings = ts.warnings;
  static const char* kCols[] = {"t",    "x_b",  "y_b",  "x_r",  "y_r",  "theta", "x_s",
                                "y_s",  "vx_b", "vy_b", "vx_r", "vy_r", "omega", "vx_s",
                                "vy_s", "d_N",  "v_N",  "v_t",  "F_N",  "F_T",   "phase"};
  int at[std::size(kCols)];
  for (size_t c = 0; c < std::size(kCols); ++c) {
    at[c] = ts.column(kCols[c]);
    if (at[c] < 0) {
      throw std::runtime_error(
          fmt::format("{}:1: column '{}' missing (rubdyn output expected)", ts_path, kCols[c]));
    }
  }
  r.samples.reserve(ts.rows.size());
  for (std::size_t k = 0; k < ts.rows.size(); ++k) {
    const auto& v = ts.rows[k];
    const long ln = ts.line_of[k];
    auto num = [&](int c) {
      double x;
      if (!parse_number(v[at[c]], x))
        throw std::runtime_error(
            fmt::format("{}:{}: column {}: '{}' is not a number", ts_path, ln, kCols[c], v[at[c]]));
      return x;
    };
    Sample s;
    s.t = num(0);
    for (int i = 0; i < kNumDofs; ++i) {
      s.q[i] = num(1 + i);
      s.v[i] = num(8 + i);
    }
    s.d_N = num(15);
    s.v_N = num(16);
    s.v_t = num(17);
    s.F_N = num(18);
    s.F_T = num(19);
    s.phase = phase_of(v[at[20]], ts_path, ln);
    if (!r.samples.empty() && s.t < r.samples.back().t) {
      throw std::runtime_error(fmt::format("{}:{}: t = {} goes back in time", ts_path, ln, s.t));
    }
    r.samples.push_back(s);
  }
  const std::string ev_path = (fs::path(dir) / "events.csv").string();
  if (fs::exists(ev_path)) {
    const CsvTable ev = read_csv(ev_path, true);
    r.events = static_cast<long>(ev.rows.size());
    r.warnings.insert(r.warnings.end(), ev.warnings.begin(), ev.warnings.end());
  }
  r.complete = run_complete(dir);
  return r;
}

bool run_complete(const std::string& dir) {
  std::ifstream sj((std::filesystem::path(dir) / "summary.json").string());
  const std::string text((std::istreambuf_iterator<char>(sj)), std::istreambuf_iterator<char>());
  return text.find("\"complete\": true") != std::string::npos;
}

}  // namespace rubdyn
