#pragma once
// OutputFolder: the sink that writes a run's output folder
//   timeseries.csv   the model's columns (io/columns.hpp): t, positions, velocities, the contact
//                    quantities d_N, v_N, v_t, F_N, F_T and phase (round-trip digits)
//   events.csv       t, kind, phase_before, phase_after, d_N, v_N_minus, v_N_plus, v_t_minus,
//                    v_t_plus, P_N, P_T, F_N, F_T, t_accumulation, witness, note
//   summary.json     every field of RunSummary, plus "complete": true|false
//   case.resolved.toml  the case with every default and override filled in
// Rows are streamed (and flushed at events), so a run that ends early keeps what it wrote; its
// summary.json says "complete": false with the termination and message. The CSV headers are
// flushed at once, so even a killed run leaves files that the readers accept.
//
// The folder is locked (flock on the directory, advisory) for the life of the sink: a second run
// into it fails at once. Before anything is written the folder is checked: it must be writable,
// and a summary.json of an earlier run is removed (a folder without summary.json is a run in
// progress, killed, or failed). Every write is checked (write, flush, close): the first failure
// is kept (error()), later rows are dropped, the stop flag given to the constructor is raised so
// that the run ends at its next check, and summary.json, if it can still be written, says
// "complete": false, termination "output_failure", with the message naming the file.
#include <atomic>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "rubdyn/core/run_types.hpp"
#include "rubdyn/io/case_spec.hpp"
#include "rubdyn/io/columns.hpp"
#include "rubdyn/io/text_files.hpp"  // OutputError

namespace rubdyn {

/// The output folder cannot be prepared, or is locked by another run: nothing was written.
class FolderError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class OutputFolder final : public OutputSink {
 public:
  /// Creates `dir` (and parents), locks it, checks that it can be written, removes an old
  /// summary.json, writes case.resolved.toml, opens the CSV files with headers. Throws
  /// FolderError naming the path if it cannot (then nothing of this run was written). `stop`,
  /// when given, is set on the first failed write.
  OutputFolder(const std::string& dir, const CaseSpec& spec, std::atomic<bool>* stop = nullptr);
  ~OutputFolder() override;
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  void sample(const Sample& s) override;
  void event(const EventRecord& e) override;
  /// Closes the CSV files (checked) and writes summary.json (atomically: a temporary file
  /// renamed). Throws OutputError when summary.json cannot be written.
  void end(const RunSummary& s) override;

  const std::string& dir() const { return dir_; }
  /// The first failed write ("cannot write DIR/FILE: reason"), empty when all succeeded.
  const std::string& error() const { return error_; }

 private:
  void failed(const std::string& file);
  std::string dir_;
  std::vector<SampleColumn> columns_;       // timeseries.csv (io/columns.hpp)
  std::vector<EventColumn> event_columns_;  // events.csv
  int n_dofs_ = 0, n_contacts_ = 0, n_observables_ = 0;
  std::string buf_;  // one row
  std::FILE* ts_ = nullptr;
  std::FILE* ev_ = nullptr;
  int lock_fd_ = -1;
  std::atomic<bool>* stop_ = nullptr;
  std::string error_;
};

/// summary.json text for a summary (also used by tools that print it).
std::string summary_json(const RunSummary& s);

}  // namespace rubdyn
