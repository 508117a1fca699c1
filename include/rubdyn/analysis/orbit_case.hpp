#pragma once
// A periodic orbit of a case (rubdyn orbit, rubdyn.orbit): the case's model, its initial state as
// the first guess, its solver settings for the runs of the return map, and the output folder's
// files (orbit.csv, orbit.json, case.resolved.toml). The method is analysis/orbit.hpp's.
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "rubdyn/analysis/orbit.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_spec.hpp"
#include "rubdyn/io/output_folder.hpp"

namespace rubdyn {

struct CaseOrbitOptions {
  int periods = 1;  ///< k: the orbit's period is 2 pi k / omega0 (k > 1: a subharmonic)
  /// Periods of a transient run from the case's initial state before Newton starts (the
  /// section then lies settle periods later).
  int settle = 0;
  OrbitOptions orbit;
  const std::atomic<bool>* stop = nullptr;  ///< raised: the running run ends (interrupted)
};

/// Every reason the case and options cannot give a forced orbit (empty: they can): the event
/// solver; a prescribed spin (loads.spin = "prescribed") at a constant speed (loads.spin_accel
/// = 0) that is not zero (initial.omega0); periods >= 1, settle >= 0, tol > 0, max_iterations
/// >= 1, samples >= 1. Each issue names the case file (or the command-line option) and key.
std::vector<CaseIssue> forced_orbit_issues(const CaseSpec& spec, const CaseOrbitOptions& o);

/// A case's orbit: its model (what the result's states are states of) and the search's result.
struct CaseOrbit {
  std::unique_ptr<LagrangianModel> model;
  double omega = 0.0;  ///< the prescribed spin speed [rad/s]
  int periods = 1;
  double tol = 0.0;  ///< Newton's tolerance
  OrbitResult result;
};

/// Searches the case's forced orbit from its initial state. Throws CaseError (every issue of
/// forced_orbit_issues) on bad input; numerical trouble is the result's outcome.
CaseOrbit find_case_orbit(const CaseSpec& spec, const CaseOrbitOptions& o);

/// orbit.json's text: the outcome and message, the period, the section (phases, coordinates),
/// Newton's history, the orbit's state at t0 (by coordinate name), the monodromy (method, error,
/// steps, matrix), the multipliers (value, |.|, error bound, condition, direction by coordinate
/// name) with the stability verdict and its reason, the events per period and their sequence,
/// runs and wall time.
std::string orbit_json(const CaseSpec& spec, const CaseOrbit& o);

/// orbit.csv's text: the final run over one period, in timeseries.csv's columns
/// (io/columns.hpp), one row per sample (the orbit's output grid and both sides of each event).
std::string orbit_csv(const CaseOrbit& o);

/// Creates, locks and prepares the output folder of an orbit before the search: checks that it
/// can be written, removes an earlier search's orbit.json and orbit.csv (they would describe
/// another search next to this one's case) and writes case.resolved.toml. Throws FolderError
/// (in use by another rubdyn command, not writable) with nothing written.
std::unique_ptr<HeldFolder> open_orbit_folder(const std::string& dir, const CaseSpec& spec);

/// Writes orbit.csv and orbit.json into the folder open_orbit_folder prepared. Throws
/// OutputError naming the file that could not be written.
void write_orbit_files(const HeldFolder& folder, const CaseSpec& spec, const CaseOrbit& o);

/// The CLI's exit code of a search: 0 converged; 4 a run stopped by SIGINT or its wall budget;
/// 3 otherwise (every other outcome, kept on disk).
int exit_code(const OrbitResult& r);

}  // namespace rubdyn
