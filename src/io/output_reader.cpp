#include "rubdyn/io/output_reader.hpp"

#include <fmt/format.h>

#include <charconv>
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

namespace {

/// Reads `path` line by line: the header, then each row with its line number. A last row
/// without its line end is dropped with a warning (cut_row_warning); blank lines are skipped.
/// Returns false for a file without a header line.
template <class OnHeader, class OnRow>
bool for_each_line(const std::string& path, std::vector<std::string>& warnings, OnHeader header,
                   OnRow row) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot read", path));
  std::string line;
  if (!std::getline(in, line)) return false;
  header(line);
  long ln = 1;
  while (std::getline(in, line)) {
    ++ln;
    if (line.empty()) continue;
    if (in.eof()) {  // no line end: cut short
      warnings.push_back(cut_row_warning(path, ln));
      break;
    }
    row(line, ln);
  }
  return true;
}

}  // namespace

CsvTable read_csv(const std::string& path, bool empty_ok) {
  CsvTable t;
  t.path = path;
  const bool has_header = for_each_line(
      path, t.warnings,
      [&](const std::string& line) {
        t.header = split_csv_line(line);
        t.header_text = line;
      },
      [&](const std::string& line, long ln) {
        auto fields = split_csv_line(line);
        if (fields.size() != t.header.size()) {
          throw std::runtime_error(fmt::format("{}:{}: {} fields, the header has {}", path, ln,
                                               fields.size(), t.header.size()));
        }
        t.rows.push_back(std::move(fields));
        t.line_of.push_back(ln);
        t.text.push_back(line);
      });
  if (!has_header) {
    if (!empty_ok) throw std::runtime_error(fmt::format("{}:1: empty file", path));
    t.warnings.push_back(path + ": empty (no header): read as no rows");
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

/// A field of a timeseries row as a number: std::from_chars (exact, the writer's shortest
/// round-trip text comes back bit for bit), else parse_number's rules (strtod).
bool field_number(std::string_view f, double& x) {
  if (f.empty()) return false;
  const auto [ptr, ec] = std::from_chars(f.data(), f.data() + f.size(), x);
  if (ec == std::errc() && ptr == f.data() + f.size()) return true;
  return parse_number(std::string(f), x);
}

/// Splits a row without quotes (timeseries.csv) into views of its fields.
void split_plain(const std::string& line, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    std::size_t end = comma == std::string::npos ? line.size() : comma;
    std::size_t e = end;
    if (comma == std::string::npos && e > start && line[e - 1] == '\r') --e;
    out.emplace_back(line.data() + start, e - start);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
}

SeriesTable read_series(const std::string& path, const LagrangianModel& model,
                        std::vector<std::string>& warnings) {
  SeriesTable t;
  t.columns = timeseries_columns(model);
  t.values.assign(t.columns.size(), {});
  std::vector<int> at(t.columns.size(), -1);
  std::size_t width = 0;
  std::vector<std::string_view> fields;
  const bool has_header = for_each_line(
      path, warnings,
      [&](const std::string& line) {
        const std::vector<std::string> header = split_csv_line(line);
        width = header.size();
        for (std::size_t c = 0; c < t.columns.size(); ++c) {
          for (std::size_t h = 0; h < header.size(); ++h)
            if (header[h] == t.columns[c].name) at[c] = static_cast<int>(h);
          if (at[c] < 0) {
            throw std::runtime_error(fmt::format(
                "{}:1: column '{}' missing (rubdyn output expected)", path, t.columns[c].name));
          }
        }
      },
      [&](const std::string& line, long ln) {
        split_plain(line, fields);
        if (fields.size() != width) {
          throw std::runtime_error(
              fmt::format("{}:{}: {} fields, the header has {}", path, ln, fields.size(), width));
        }
        for (std::size_t c = 0; c < t.columns.size(); ++c) {
          const SampleColumn& col = t.columns[c];
          const std::string_view f = fields[static_cast<std::size_t>(at[c])];
          double x = 0.0;
          if (col.field == SampleField::Phase) {
            Phase p{};
            if (!parse_phase(f, p)) {
              throw std::runtime_error(
                  fmt::format("{}:{}: column {}: '{}' is not a phase (free, slip+, slip-, stick)",
                              path, ln, col.name, f));
            }
            x = static_cast<double>(p);
          } else if (!field_number(f, x)) {
            throw std::runtime_error(
                fmt::format("{}:{}: column {}: '{}' is not a number", path, ln, col.name, f));
          }
          if (col.field == SampleField::Time && !t.values[c].empty() && x < t.values[c].back())
            throw std::runtime_error(fmt::format("{}:{}: t = {} goes back in time", path, ln, x));
          t.values[c].push_back(x);
        }
      });
  if (!has_header) throw std::runtime_error(fmt::format("{}:1: empty file", path));
  return t;
}

std::vector<EventRecord> read_events(const std::string& path, int contacts,
                                     std::vector<std::string>& warnings) {
  const CsvTable ev = read_csv(path, true);
  warnings.insert(warnings.end(), ev.warnings.begin(), ev.warnings.end());
  std::vector<EventRecord> out;
  if (ev.header.empty()) return out;
  const std::vector<EventColumn> cols = event_columns(contacts);
  std::vector<int> at(cols.size());
  for (std::size_t c = 0; c < cols.size(); ++c) {
    at[c] = ev.column(cols[c].name);
    if (at[c] < 0) {
      throw std::runtime_error(
          fmt::format("{}:1: column '{}' missing (rubdyn output expected)", path, cols[c].name));
    }
  }
  out.reserve(ev.rows.size());
  for (std::size_t k = 0; k < ev.rows.size(); ++k) {
    EventRecord e;
    for (std::size_t c = 0; c < cols.size(); ++c) {
      try {
        set_event_field(e, cols[c], ev.rows[k][static_cast<std::size_t>(at[c])]);
      } catch (const std::invalid_argument& err) {
        throw std::runtime_error(fmt::format("{}:{}: {}", path, ev.line_of[k], err.what()));
      }
    }
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace

RunFiles read_run_files(const std::string& dir) {
  namespace fs = std::filesystem;
  RunFiles r;
  r.dir = dir;
  const std::string case_path = (fs::path(dir) / "case.resolved.toml").string();
  if (!fs::is_directory(dir)) throw std::runtime_error(dir + ": not an output folder");
  if (!fs::exists(case_path)) throw std::runtime_error(case_path + ": missing");
  r.spec = load_case(case_path);
  r.model = build_model(r.spec);
  r.series = read_series((fs::path(dir) / "timeseries.csv").string(), *r.model, r.warnings);
  const std::string ev_path = (fs::path(dir) / "events.csv").string();
  if (fs::exists(ev_path)) r.events = read_events(ev_path, r.model->contact_count(), r.warnings);
  const fs::path sj = fs::path(dir) / "summary.json";
  if (fs::exists(sj)) {
    std::ifstream in(sj.string());
    r.summary_json.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  r.complete = r.summary_json.find("\"complete\": true") != std::string::npos;
  return r;
}

RunRecord read_run(const std::string& dir) {
  RunFiles f = read_run_files(dir);
  RunRecord r;
  r.dir = std::move(f.dir);
  r.spec = std::move(f.spec);
  r.events = static_cast<long>(f.events.size());
  r.complete = f.complete;
  r.warnings = std::move(f.warnings);
  const LagrangianModel* model = f.model.get();
  const SeriesTable& t = f.series;
  const std::size_t n = t.rows();
  r.samples.assign(n, Sample(model->num_dofs(), model->contact_count(),
                             static_cast<int>(model->observables().size())));
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    for (std::size_t i = 0; i < n; ++i)
      set_sample_value(r.samples[i], t.columns[c], t.values[c][i]);
  return r;
}

bool run_complete(const std::string& dir) {
  std::ifstream sj((std::filesystem::path(dir) / "summary.json").string());
  const std::string text((std::istreambuf_iterator<char>(sj)), std::istreambuf_iterator<char>());
  return text.find("\"complete\": true") != std::string::npos;
}

}  // namespace rubdyn
