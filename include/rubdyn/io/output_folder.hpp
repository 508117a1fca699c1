#pragma once
// OutputFolder: the sink that writes a run's output folder
//   timeseries.csv   the model's columns (io/columns.hpp): t, positions, velocities, the contact
//                    quantities d_N, v_N, v_t, F_N, F_T and phase (round-trip digits)
//   events.csv       t, kind, phase_before, phase_after, d_N, v_N_minus, v_N_plus, v_t_minus,
//                    v_t_plus, P_N, P_T, F_N, F_T, t_accumulation, witness, note
//   summary.json     every field of RunSummary, plus "complete": true|false
//   case.resolved.toml  the case with every default and override filled in
//   state.csv        only when output.coordinates does not write every coordinate: the full
//                    state (timeseries.csv's columns with every coordinate) at the run's first
//                    sample, the first sample after each event and its last sample (restarts)
// Rows are streamed (and flushed at events), so a run that ends early keeps what it wrote; its
// summary.json says "complete": false with the termination and message. The CSV headers are
// flushed at once, so even a killed run leaves files that the readers accept.
//
// The folder is owned for the life of the sink: it is held open and locked (flock on the
// directory, advisory), so that a second run into it fails at once, and every file is written
// relative to the folder held open (write_file_at, open_output_stream_at), so that nothing goes
// into another folder that took its path. Before anything is written the folder is checked: it
// must be writable; a summary.json of an earlier run is removed (a folder without summary.json
// is a run in progress, killed, or failed), and so is what was derived from that run
// (kDerivedFiles: `rubdyn analyze`'s analysis/ and the figures of `python3 -m rubdyn.plot`),
// which would describe another run next to ours. Every write is checked (write, flush, close):
// the first failure is kept (error()), later rows are dropped, the stop flag given to the
// constructor is raised so that the run ends at its next check, and summary.json, if it can
// still be written, says "complete": false, termination "output_failure", with the message
// naming the file. A folder removed or replaced while the run writes (its path no longer leads
// to the folder held open; checked at every event, every kCheckEverySamples samples and at the
// end) is such a failure: the summary then goes into the folder held open if it still exists
// (moved away), never into a new folder at the path.
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

/// Files derived from a run's output (relative to its folder): removed when a new run takes the
/// folder, so that they never describe another run than the one beside them. Only regular files
/// of these names are removed (a link or a folder of that name is left alone), and analysis/
/// itself when that leaves it empty. These are a one-plane run's; derived_files() adds those of
/// every contact plane of a run with several.
inline constexpr const char* kDerivedFiles[] = {"analysis/derived.csv",
                                                "analysis/spectrum.csv",
                                                "analysis/spectrogram.csv",
                                                "analysis/campbell.csv",
                                                "analysis/analysis.json",
                                                "omega.png",
                                                "orbit.png",
                                                "contact.png",
                                                "friction.png",
                                                "timeline.png",
                                                "spectrogram.png"};
/// The files of one contact plane that `rubdyn analyze` writes into analysis/plane_k/ for planes
/// k >= 2 (plane 1's are analysis/'s own).
inline constexpr const char* kPlaneAnalysisFiles[] = {"derived.csv", "spectrum.csv",
                                                      "spectrogram.csv", "campbell.csv"};
/// The figures `python3 -m rubdyn.plot` draws per contact plane k of a run with several, as
/// <name>_k.png (python/rubdyn/plot.py: write_all).
inline constexpr const char* kPlaneFigures[] = {"orbit", "contact", "friction", "timeline",
                                                "spectrogram"};
/// Every file derived from a run, for runs with up to the most contacts any model takes (8):
/// kDerivedFiles, analysis/plane_k/ (kPlaneAnalysisFiles) and <figure>_k.png (kPlaneFigures),
/// in an order that empties each analysis/plane_k/ before analysis/.
std::vector<std::string> derived_files();
/// The folders of derived_files() that are removed when that leaves them empty, innermost first.
std::vector<std::string> derived_folders();

/// A folder held open for the object's life, to be locked (flock, advisory: released when the
/// object goes) and written into by its descriptor.
class HeldFolder {
 public:
  /// Creates `dir` (with its parents) and opens it. Throws FolderError naming the path.
  explicit HeldFolder(const std::string& dir);
  ~HeldFolder();
  HeldFolder(const HeldFolder&) = delete;
  HeldFolder& operator=(const HeldFolder&) = delete;
  /// Takes the lock without waiting (exclusive, or shared); false when another holds it.
  bool try_lock(bool exclusive);
  /// Throws FolderError unless files can be created in the folder (permissions, read-only file
  /// system).
  void check_writable() const;
  /// The path still leads to the folder held open (it was not removed, moved or replaced).
  bool intact() const;
  /// "the output folder DIR was removed or replaced while ...".
  std::string lost_message() const;
  int fd() const { return fd_; }
  const std::string& path() const { return dir_; }

 private:
  std::string dir_;
  int fd_ = -1;
};

class OutputFolder final : public OutputSink {
 public:
  /// Creates `dir` (and parents), locks it, checks that it can be written, removes an old
  /// summary.json and the files derived from it (derived_files()), writes the case
  /// (case.resolved.toml as resolved_toml gives it, beside it the copies of a matrices case's
  /// matrix files, case_matrix_files, so that the folder stands alone; an earlier run's copies
  /// that this case does not have are removed), opens the CSV files with headers. Throws
  /// FolderError naming the path if it cannot (then nothing of this run was written). `stop`, when
  /// given, is set on the first failed write.
  OutputFolder(const std::string& dir, const CaseSpec& spec, std::atomic<bool>* stop = nullptr);
  ~OutputFolder() override;
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  void sample(const Sample& s) override;
  void event(const EventRecord& e) override;
  /// Closes the CSV files (checked), checks that the folder is still the one held, and writes
  /// summary.json (atomically: a temporary file renamed). Throws OutputError when summary.json
  /// cannot be written; its message starts with the first failed write.
  void end(const RunSummary& s) override;

  const std::string& dir() const { return dir_; }
  /// The first failed write ("cannot write DIR/FILE: reason", or the folder lost), empty when
  /// all succeeded.
  const std::string& error() const { return error_; }

  /// Samples between two checks that the folder is still the one held (two stat calls).
  static constexpr int kCheckEverySamples = 1024;

 private:
  void failed(const std::string& file);
  void check_folder();
  /// Formats a sample's row of these columns into buf_.
  void format_row(const Sample& s, const std::vector<SampleColumn>& columns);
  /// Writes s to state.csv (when the run writes one).
  void state_row(const Sample& s);
  std::string dir_;
  std::unique_ptr<HeldFolder> folder_;
  std::vector<SampleColumn> columns_;       // timeseries.csv (io/columns.hpp)
  std::vector<EventColumn> event_columns_;  // events.csv
  int n_dofs_ = 0, n_contacts_ = 0, n_observables_ = 0;
  std::string buf_;  // one row
  std::FILE* ts_ = nullptr;
  std::FILE* ev_ = nullptr;
  // state.csv: the full state where timeseries.csv holds a selection of the coordinates
  std::vector<SampleColumn> state_columns_;  // every coordinate (empty: no state.csv)
  std::FILE* st_ = nullptr;
  bool state_next_ = true;      // the next sample goes to state.csv (the first, after an event)
  bool last_in_state_ = false;  // the last sample received is in state.csv
  Sample last_;                 // the last sample received (written at the end)
  bool have_last_ = false;
  int since_check_ = 0;
  std::atomic<bool>* stop_ = nullptr;
  std::string error_;
};

/// summary.json text for a summary (also used by tools that print it).
std::string summary_json(const RunSummary& s);

}  // namespace rubdyn
