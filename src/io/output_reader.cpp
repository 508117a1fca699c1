#include "rubdyn/io/output_reader.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
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

ReadError::ReadError(std::string file, long line, const std::string& problem)
    : std::runtime_error(line > 0 ? fmt::format("{}:{}: {}", file, line, problem)
                                  : fmt::format("{}: {}", file, problem)),
      file_(std::move(file)),
      line_(line) {}

std::string printable(std::string_view text, std::size_t max) {
  std::string out;
  for (std::size_t i = 0; i < text.size() && i < max; ++i) {
    const auto b = static_cast<unsigned char>(text[i]);
    if (b >= 0x20 && b < 0x7f)
      out += static_cast<char>(b);
    else
      out += fmt::format("\\x{:02x}", b);
  }
  if (text.size() > max) out += "...";
  return out;
}

int CsvTable::column(std::string_view name) const {
  for (std::size_t c = 0; c < header.size(); ++c)
    if (header[c] == name) return static_cast<int>(c);
  return -1;
}

namespace {

/// Throws ReadError unless `line` is text: valid UTF-8 without NUL or other control characters
/// (a tab is allowed). rubdyn writes ASCII; a binary or corrupted file stops here, before any
/// of its bytes reach a message or Python (which needs UTF-8).
void require_text(const std::string& path, long ln, const std::string& line) {
  const auto* p = reinterpret_cast<const unsigned char*>(line.data());
  const std::size_t n = line.size();
  for (std::size_t i = 0; i < n;) {
    const unsigned char b = p[i];
    std::size_t len = 0;
    if (b >= 0x20 && b < 0x7f) {
      ++i;
      continue;
    }
    if (b == '\t') {
      ++i;
      continue;
    }
    if (b >= 0xc2 && b <= 0xdf)
      len = 2;
    else if (b >= 0xe0 && b <= 0xef)
      len = 3;
    else if (b >= 0xf0 && b <= 0xf4)
      len = 4;
    bool ok = len > 0 && i + len <= n;
    for (std::size_t k = 1; ok && k < len; ++k) ok = (p[i + k] & 0xc0) == 0x80;
    if (ok && len == 3) {  // no overlong forms, no UTF-16 surrogates
      ok = !(b == 0xe0 && p[i + 1] < 0xa0) && !(b == 0xed && p[i + 1] >= 0xa0);
    } else if (ok && len == 4) {  // no overlong forms, nothing above U+10FFFF
      ok = !(b == 0xf0 && p[i + 1] < 0x90) && !(b == 0xf4 && p[i + 1] >= 0x90);
    }
    if (!ok) {
      throw ReadError(path, ln,
                      fmt::format("byte 0x{:02x} at column {}: not text (a binary or corrupted "
                                  "file; rubdyn writes UTF-8 text without control characters)",
                                  b, i + 1));
    }
    i += len;
  }
}

/// Reads `path` line by line: the header, then each row with its line number. A last row
/// without its line end is dropped with a warning (cut_row_warning); blank lines are skipped;
/// a CRLF line end is read as LF; every line read must be text (require_text).
/// Returns false for a file without a header line.
template <class OnHeader, class OnRow>
bool for_each_line(const std::string& path, std::vector<std::string>& warnings, OnHeader header,
                   OnRow row) {
  std::ifstream in(path, std::ios::binary);
  if (!in || std::filesystem::is_directory(path)) throw ReadError(path, 0, "cannot read");
  std::string line;
  auto chomp = [&line] {
    if (!line.empty() && line.back() == '\r') line.pop_back();
  };
  if (!std::getline(in, line)) return false;
  chomp();
  require_text(path, 1, line);
  header(line);
  long ln = 1;
  while (std::getline(in, line)) {
    ++ln;
    const bool cut = in.eof();  // no line end: cut short
    chomp();
    if (line.empty()) continue;
    if (cut) {
      warnings.push_back(cut_row_warning(path, ln));
      break;
    }
    require_text(path, ln, line);
    row(line, ln);
  }
  if (in.bad()) throw ReadError(path, ln, "read error");
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
          throw ReadError(
              path, ln,
              fmt::format("{} fields, the header has {}", fields.size(), t.header.size()));
        }
        t.rows.push_back(std::move(fields));
        t.line_of.push_back(ln);
        t.text.push_back(line);
      });
  if (!has_header) {
    if (!empty_ok) throw ReadError(path, 1, "empty file");
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

SeriesTable read_series(const std::string& path, std::vector<SampleColumn> columns,
                        std::vector<std::string>& warnings) {
  SeriesTable t;
  t.columns = std::move(columns);
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
            throw ReadError(
                path, 1,
                fmt::format("column '{}' missing (rubdyn output expected)", t.columns[c].name));
          }
        }
      },
      [&](const std::string& line, long ln) {
        split_plain(line, fields);
        if (fields.size() != width) {
          throw ReadError(path, ln,
                          fmt::format("{} fields, the header has {}", fields.size(), width));
        }
        for (std::size_t c = 0; c < t.columns.size(); ++c) {
          const SampleColumn& col = t.columns[c];
          const std::string_view f = fields[static_cast<std::size_t>(at[c])];
          double x = 0.0;
          if (col.field == SampleField::Phase) {
            Phase p{};
            if (!parse_phase(f, p)) {
              throw ReadError(path, ln,
                              fmt::format("column {}: '{}' is not a phase (free, slip+, slip-, "
                                          "stick)",
                                          col.name, printable(f)));
            }
            x = static_cast<double>(p);
          } else if (!field_number(f, x)) {
            throw ReadError(path, ln,
                            fmt::format("column {}: '{}' is not a number", col.name, printable(f)));
          }
          if (col.field == SampleField::Time) {
            if (!std::isfinite(x)) {
              throw ReadError(
                  path, ln,
                  fmt::format("column {}: '{}' is not a finite time", col.name, printable(f)));
            }
            if (!t.values[c].empty() && x < t.values[c].back())
              throw ReadError(path, ln, fmt::format("t = {} goes back in time", x));
          }
          t.values[c].push_back(x);
        }
      });
  if (!has_header) throw ReadError(path, 1, "empty file");
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
      throw ReadError(path, 1,
                      fmt::format("column '{}' missing (rubdyn output expected)", cols[c].name));
    }
  }
  out.reserve(ev.rows.size());
  for (std::size_t k = 0; k < ev.rows.size(); ++k) {
    EventRecord e;
    for (std::size_t c = 0; c < cols.size(); ++c) {
      try {
        set_event_field(e, cols[c], ev.rows[k][static_cast<std::size_t>(at[c])]);
      } catch (const std::invalid_argument& err) {
        throw ReadError(path, ev.line_of[k], err.what());
      }
    }
    if (!std::isfinite(e.t)) {
      throw ReadError(path, ev.line_of[k],
                      fmt::format("column t: '{}' is not a finite time",
                                  printable(ev.rows[k][static_cast<std::size_t>(at[0])])));
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
  if (!fs::is_directory(dir)) throw ReadError(dir, 0, "not an output folder (no such folder)");
  if (!fs::exists(case_path)) throw ReadError(case_path, 0, "missing");
  r.spec = load_case(case_path);
  r.model = build_model(r.spec);
  r.series = read_series((fs::path(dir) / "timeseries.csv").string(),
                         timeseries_columns(*r.model, r.spec.output.coordinates), r.warnings);
  // the full states of a run that wrote a selection of its coordinates (absent after a run
  // killed before it opened the file: then no state to restart from)
  const std::string st_path = (fs::path(dir) / "state.csv").string();
  if (!writes_every_coordinate(*r.model, r.spec.output.coordinates) && fs::exists(st_path))
    r.states = read_series(st_path, timeseries_columns(*r.model), r.warnings);
  const std::string ev_path = (fs::path(dir) / "events.csv").string();
  if (fs::exists(ev_path)) r.events = read_events(ev_path, r.model->contact_count(), r.warnings);
  const fs::path sj = fs::path(dir) / "summary.json";
  if (fs::exists(sj)) {
    std::ifstream in(sj.string(), std::ios::binary);
    if (!in || fs::is_directory(sj)) throw ReadError(sj.string(), 0, "cannot read");
    r.summary_json.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    // the writer renames a whole file into place: anything else is not its summary (CRLF line
    // ends, from an editor, are still JSON)
    std::size_t ln = 1, from = 0;
    for (;; ++ln) {
      const std::size_t nl = r.summary_json.find('\n', from);
      std::string line = r.summary_json.substr(from, nl == std::string::npos ? nl : nl - from);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      require_text(sj.string(), static_cast<long>(ln), line);
      if (nl == std::string::npos) break;
      from = nl + 1;
    }
    if (r.summary_json.empty())
      r.warnings.push_back(sj.string() + ": empty: read as absent (the run is incomplete)");
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
  r.every_coordinate = writes_every_coordinate(*f.model, r.spec.output.coordinates);
  r.samples = samples_of(*f.model, f.series);
  r.states = samples_of(*f.model, f.states);
  return r;
}

bool run_complete(const std::string& dir) {
  std::ifstream sj((std::filesystem::path(dir) / "summary.json").string());
  const std::string text((std::istreambuf_iterator<char>(sj)), std::istreambuf_iterator<char>());
  return text.find("\"complete\": true") != std::string::npos;
}

}  // namespace rubdyn
