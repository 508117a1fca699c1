#include "rubdyn/io/output_reader.hpp"

#include <fmt/format.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/columns.hpp"
#include "rubdyn/io/model_registry.hpp"
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
  const std::unique_ptr<LagrangianModel> model = build_model(r.spec);
  const std::vector<SampleColumn> cols = timeseries_columns(*model);
  std::vector<int> at(cols.size());
  for (std::size_t c = 0; c < cols.size(); ++c) {
    at[c] = ts.column(cols[c].name);
    if (at[c] < 0) {
      throw std::runtime_error(
          fmt::format("{}:1: column '{}' missing (rubdyn output expected)", ts_path, cols[c].name));
    }
  }
  const int n = model->num_dofs();
  r.samples.reserve(ts.rows.size());
  for (std::size_t k = 0; k < ts.rows.size(); ++k) {
    const auto& v = ts.rows[k];
    const long ln = ts.line_of[k];
    Sample s(n, model->contact_count(), static_cast<int>(model->observables().size()));
    for (std::size_t c = 0; c < cols.size(); ++c) {
      const SampleColumn& col = cols[c];
      const std::string& field = v[static_cast<std::size_t>(at[c])];
      if (col.field == SampleField::Phase) {
        s.contacts[static_cast<std::size_t>(col.index)].phase = phase_of(field, ts_path, ln);
        continue;
      }
      double x;
      if (!parse_number(field, x))
        throw std::runtime_error(
            fmt::format("{}:{}: column {}: '{}' is not a number", ts_path, ln, col.name, field));
      ContactSample* cs = col.field == SampleField::Time || col.field == SampleField::Position ||
                                  col.field == SampleField::Velocity ||
                                  col.field == SampleField::Observable
                              ? nullptr
                              : &s.contacts[static_cast<std::size_t>(col.index)];
      switch (col.field) {
        case SampleField::Time: s.t = x; break;
        case SampleField::Position: s.q[col.index] = x; break;
        case SampleField::Velocity: s.v[col.index] = x; break;
        case SampleField::Observable: s.observables[col.index] = x; break;
        case SampleField::Gap: cs->d_N = x; break;
        case SampleField::GapRate: cs->v_N = x; break;
        case SampleField::SlipSpeed: cs->v_t = x; break;
        case SampleField::NormalForce: cs->F_N = x; break;
        case SampleField::TangentialForce: cs->F_T = x; break;
        case SampleField::Phase: break;
      }
    }
    if (!r.samples.empty() && s.t < r.samples.back().t) {
      throw std::runtime_error(fmt::format("{}:{}: t = {} goes back in time", ts_path, ln, s.t));
    }
    r.samples.push_back(std::move(s));
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
