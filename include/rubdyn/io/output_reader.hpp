#pragma once
// Reading output back: the one reader of the files rubdyn writes (output_folder.hpp writes
// them). `rubdyn analyze`, `rubdyn run --from`, `rubdyn compare`, sweeps (resume, shard merge)
// and the library all read through it, with the same tolerance for what a killed run leaves:
// a last row without its line end is dropped with a warning, an empty events.csv reads as no
// events, a missing or incomplete summary.json marks the run incomplete.
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "rubdyn/core/run_types.hpp"
#include "rubdyn/io/case_spec.hpp"
#include "rubdyn/io/columns.hpp"

namespace rubdyn {

/// One CSV file: the header and the rows as text, each with its line number.
struct CsvTable {
  std::string path;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;  ///< every row has header.size() fields
  std::vector<long> line_of;                   ///< line number of each row (1 = header)
  std::string header_text;                     ///< the header line as read
  std::vector<std::string> text;               ///< each row's line as read
  std::vector<std::string> warnings;           ///< what the reader tolerated
  /// Index of a column, or -1.
  int column(std::string_view name) const;
};
/// Reads `path`. Throws std::runtime_error naming the file and line for a missing file, a row
/// whose field count differs from the header's, or (unless empty_ok) a file without a header.
/// A last row without its line end is dropped with a warning.
CsvTable read_csv(const std::string& path, bool empty_ok = false);

/// A whole field as a number (strtod; false for an empty field or trailing text).
bool parse_number(const std::string& field, double& x);

/// An output folder read back whole: the case it ran, the samples as columns, the events, the
/// summary as written. The one reader of output folders: read_run (the analyses) and the Python
/// package (rubdyn.read) both read through it.
struct RunFiles {
  std::string dir;
  CaseSpec spec;                                 ///< case.resolved.toml
  std::shared_ptr<const LagrangianModel> model;  ///< built from spec: its column tables
  SeriesTable series;                 ///< timeseries.csv, by name (a column of the table that
                                      ///< the file lacks is an error, others are ignored)
  std::vector<EventRecord> events;    ///< events.csv (none if absent or header-only)
  std::string summary_json;           ///< summary.json as written (empty: absent)
  bool complete = true;               ///< summary.json "complete" (false: ended early or absent)
  std::vector<std::string> warnings;  ///< what the reader tolerated
};
/// Throws std::runtime_error naming the file, line, column and problem on a missing or bad
/// file (case.resolved.toml and timeseries.csv are required; events.csv and summary.json may be
/// missing after a killed run).
RunFiles read_run_files(const std::string& dir);

/// A run read back from its output folder, as samples (what the analyses read).
struct RunRecord {
  std::string dir;
  CaseSpec spec;                      ///< case.resolved.toml
  std::vector<Sample> samples;        ///< timeseries.csv, in file order
  long events = 0;                    ///< rows of events.csv (0 if absent)
  bool complete = true;               ///< summary.json "complete" (false: ended early or absent)
  std::vector<std::string> warnings;  ///< what the reader tolerated (the CLI prints them)
};
/// Throws std::runtime_error naming the file, line and problem on a missing or bad file.
RunRecord read_run(const std::string& dir);

/// summary.json of `dir` says "complete": true.
bool run_complete(const std::string& dir);

}  // namespace rubdyn
