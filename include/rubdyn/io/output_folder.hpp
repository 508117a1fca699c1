#pragma once
// OutputFolder: the sink that writes a run's output folder
//   timeseries.csv   t, x_b, y_b, x_r, y_r, theta, x_s, y_s, vx_b, vy_b, vx_r, vy_r, omega,
//                    vx_s, vy_s, d_N, v_N, v_t, F_N, F_T, phase        (17 significant digits)
//   events.csv       t, kind, phase_before, phase_after, d_N, v_N_minus, v_N_plus, v_t_minus,
//                    v_t_plus, P_N, P_T, F_N, F_T, witness, note
//   summary.json     every field of RunSummary, plus "complete": true|false
//   case.resolved.toml  the case with every default and override filled in
// Rows are streamed (and flushed at events), so a run that ends early keeps what it wrote; its
// summary.json says "complete": false with the termination and message.
#include <cstdio>
#include <memory>
#include <string>

#include "rubdyn/core/run_types.hpp"
#include "rubdyn/io/case_spec.hpp"

namespace rubdyn {

class OutputFolder final : public OutputSink {
 public:
  /// Creates `dir` (and parents), writes case.resolved.toml, opens the CSV files with headers.
  /// Throws std::runtime_error naming the path if it cannot.
  OutputFolder(const std::string& dir, const CaseSpec& spec);
  ~OutputFolder() override;
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  void sample(const Sample& s) override;
  void event(const EventRecord& e) override;
  void end(const RunSummary& s) override;  ///< writes summary.json and closes the files

  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
  std::FILE* ts_ = nullptr;
  std::FILE* ev_ = nullptr;
};

/// summary.json text for a summary (also used by tools that print it).
std::string summary_json(const RunSummary& s);

}  // namespace rubdyn
