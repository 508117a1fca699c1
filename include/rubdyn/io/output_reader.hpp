#pragma once
// Reading output back: the one reader of the files rubdyn writes (output_folder.hpp writes
// them). `rubdyn analyze`, `rubdyn run --from`, `rubdyn compare`, sweeps (resume, shard merge)
// and the library all read through it, with the same tolerance for what a killed run leaves:
// a last row without its line end is dropped with a warning, an empty events.csv reads as no
// events, a missing or incomplete summary.json marks the run incomplete.
#include <string>
#include <string_view>
#include <vector>

#include "rubdyn/core/run_types.hpp"
#include "rubdyn/io/case_spec.hpp"

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

/// A run read back from its output folder.
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
