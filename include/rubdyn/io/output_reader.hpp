#pragma once
// Reading output back: the one reader of the files rubdyn writes (output_folder.hpp writes
// them). `rubdyn analyze`, `rubdyn run --from`, `rubdyn compare`, sweeps (resume, shard merge)
// and the library all read through it, with the same tolerance for what a killed run leaves:
// a last row without its line end is dropped with a warning, an empty events.csv reads as no
// events, a missing or incomplete summary.json marks the run incomplete. CRLF line ends are read
// as LF. Anything else malformed is a ReadError naming the file and the line: a binary or
// non-UTF-8 file (a NUL, a control character or an invalid UTF-8 sequence on any line), a row
// whose field count differs from the header's, a field that is not a number, a time that is not
// finite or goes back. Messages quote file content through `printable`, so they are ASCII.
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "rubdyn/core/run_types.hpp"
#include "rubdyn/io/case_spec.hpp"
#include "rubdyn/io/columns.hpp"

namespace rubdyn {

/// A file that is not what its reader expects (malformed, binary, missing). what() is
/// "file:line: problem" (line 0: the file as a whole, then "file: problem"); the CLI exits 2,
/// Python raises rubdyn.ReadError (a ValueError) with .file and .line.
class ReadError : public std::runtime_error {
 public:
  ReadError(std::string file, long line, const std::string& problem);
  const std::string& file() const { return file_; }
  long line() const { return line_; }

 private:
  std::string file_;
  long line_;
};

/// `text` (a field or line of a file) for a message: printable ASCII as is, every other byte as
/// \xNN, cut to `max` bytes of input with "..." after.
std::string printable(std::string_view text, std::size_t max = 40);

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
/// Reads `path`. Throws ReadError naming the file and line for a missing file, a line that is
/// not text, a row whose field count differs from the header's, or (unless empty_ok) a file
/// without a header. A last row without its line end is dropped with a warning.
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
                                      ///< the file lacks is an error, others are ignored): the
                                      ///< columns the case's output.coordinates writes
  SeriesTable states;                 ///< state.csv (every column) of a run that wrote a
                                      ///< selection of its coordinates; no rows otherwise
  std::vector<EventRecord> events;    ///< events.csv (none if absent or header-only)
  std::string summary_json;           ///< summary.json as written (empty: absent)
  bool complete = true;               ///< summary.json "complete" (false: ended early or absent)
  std::vector<std::string> warnings;  ///< what the reader tolerated
};
/// Throws ReadError naming the file, line, column and problem on a missing or bad file
/// (case.resolved.toml and timeseries.csv are required; events.csv and summary.json may be
/// missing after a killed run; an empty summary.json reads as absent, with a warning), and
/// CaseError for a case.resolved.toml that is not a valid case. Every time (timeseries.csv's t,
/// events.csv's t) is finite and t does not decrease; summary.json is UTF-8 text.
RunFiles read_run_files(const std::string& dir);

/// A run read back from its output folder, as samples (what the analyses read).
struct RunRecord {
  std::string dir;
  CaseSpec spec;                      ///< case.resolved.toml
  std::vector<Sample> samples;        ///< timeseries.csv, in file order (a coordinate that the
                                      ///< run did not write: NaN)
  bool every_coordinate = true;       ///< timeseries.csv holds every coordinate
  std::vector<Sample> states;         ///< state.csv's full states (when !every_coordinate)
  long events = 0;                    ///< rows of events.csv (0 if absent)
  bool complete = true;               ///< summary.json "complete" (false: ended early or absent)
  std::vector<std::string> warnings;  ///< what the reader tolerated (the CLI prints them)
};
/// Throws as read_run_files.
RunRecord read_run(const std::string& dir);

/// summary.json of `dir` says "complete": true.
bool run_complete(const std::string& dir);

}  // namespace rubdyn
