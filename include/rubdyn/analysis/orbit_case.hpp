#pragma once
// A periodic orbit of a case (rubdyn orbit, rubdyn.orbit): the case's model, its initial state as
// the first guess, its solver settings for the runs of the return map, and the output folder's
// files (orbit.csv, orbit.json, case.resolved.toml). The method is analysis/orbit.hpp's.
#include <atomic>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "rubdyn/analysis/continuation.hpp"
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
  /// A free spin's orbit (loads.spin = "torque"): the guess of its period [s] (required there,
  /// refused with a prescribed spin, whose period is 2 pi k / omega0).
  double period = std::numeric_limits<double>::quiet_NaN();
  OrbitOptions orbit;
  const std::atomic<bool>* stop = nullptr;  ///< raised: the running run ends (interrupted)
};

/// Every reason the case and options cannot give an orbit (empty: they can): the event solver;
/// either a prescribed spin (loads.spin = "prescribed") at a constant speed (loads.spin_accel
/// = 0) that is not zero (initial.omega0), no --period: a forced orbit; or a free spin without
/// an unbalance (loads.unbalance = 0: the spin angle is then cyclic) and a --period guess > 0:
/// an autonomous orbit; periods >= 1, settle >= 0, tol > 0, max_iterations >= 1, samples >= 1.
/// Each issue names the case file (or the command-line option) and key.
std::vector<CaseIssue> orbit_issues(const CaseSpec& spec, const CaseOrbitOptions& o);

/// A case's orbit: its model (what the result's states are states of) and the search's result.
struct CaseOrbit {
  std::unique_ptr<LagrangianModel> model;
  bool autonomous = false;  ///< a free spin's orbit, its period found
  double omega = 0.0;       ///< the prescribed spin speed, or the free spin's at the start [rad/s]
  int periods = 1;
  double tol = 0.0;  ///< Newton's tolerance
  OrbitResult result;
};

/// Searches the case's orbit (forced or autonomous) from its initial state. Throws CaseError (every
/// issue of orbit_issues) on bad input; numerical trouble is the result's outcome.
CaseOrbit find_case_orbit(const CaseSpec& spec, const CaseOrbitOptions& o);

/// orbit.json's text: the outcome and message, the period, the section (phases, coordinates),
/// Newton's history, the orbit's state at t0 (by coordinate name), the monodromy (method, error,
/// steps, matrix), the multipliers (value, |.|, error bound, condition, direction by coordinate
/// name) with the stability verdict and its reason, the events per period and their sequence,
/// runs and wall time.
std::string orbit_json(const CaseSpec& spec, const CaseOrbit& o);

/// orbit.csv's text: the final run over one period, in timeseries.csv's columns
/// (io/columns.hpp; those output.coordinates = `selection` writes: orbit.json's state holds
/// every coordinate), one row per sample (the orbit's output grid and both sides of each event).
std::string orbit_csv(const CaseOrbit& o, std::string_view selection = "all");

/// Creates, locks and prepares the output folder of an orbit (or a branch) before the search:
/// checks that it can be written, removes an earlier search's result files (`files`; they would
/// describe another search next to this one's case) and writes case.resolved.toml. Throws
/// FolderError (in use by another rubdyn command, not writable) with nothing written.
std::unique_ptr<HeldFolder> open_orbit_folder(const std::string& dir, const CaseSpec& spec,
                                              const std::vector<std::string>& files = {
                                                  "orbit.json", "orbit.csv"});

/// Writes orbit.csv and orbit.json into the folder open_orbit_folder prepared. Throws
/// OutputError naming the file that could not be written.
void write_orbit_files(const HeldFolder& folder, const CaseSpec& spec, const CaseOrbit& o);

struct CaseBranch;

/// A branch of forced orbits of a case in one of its numeric keys (rubdyn branch).
struct CaseBranchOptions {
  std::string key;  ///< the case key varied, e.g. "initial.omega0"
  double to = std::numeric_limits<double>::quiet_NaN();  ///< stop beyond this value (NaN: none)
  int points = 200;
  double ds = 0.5, ds_max = 3.0;
  double scale = 0.0;  ///< the key's unit in the arclength (0: 1 % of its value, or 1)
  int direction = +1;  ///< the first step's sign in the key
  CaseOrbitOptions orbit;
  /// Continue this earlier branch of the same case (read_case_branch) from its last point, to
  /// `points` points in all (its points kept as they are, the new ones appended; a branch that
  /// ended, by a bound or where its events change, or has its points already, is returned as
  /// it is). nullptr: a new branch.
  const CaseBranch* resume = nullptr;
  /// Branch switching: the branch of period 2k (k: this earlier branch's periods) that leaves
  /// its period doubling `special` (an index of its specials; -1: its first period doubling),
  /// from the doubling's orbit moved by `switch_eps` (scaled state) along its multiplier -1's
  /// direction, at `switch_offset` from the doubling in the key (NaN: half the distance of the
  /// two points around it), on the side where the period-1 orbit has a real multiplier below -1
  /// first, then the other; the branch goes on away from the doubling. nullptr: none.
  const CaseBranch* switch_from = nullptr;
  int special = -1;
  double switch_offset = std::numeric_limits<double>::quiet_NaN();
  double switch_eps = 0.05;
};

/// Every reason the case and options cannot give a branch (orbit_issues, a forced orbit, the key a
/// number of the case, points >= 2, ds > 0; a resumed or switched-from branch of this key and
/// model, ...).
std::vector<CaseIssue> branch_issues(const CaseSpec& spec, const CaseBranchOptions& o);

struct CaseBranch {
  std::string key;
  double lambda0 = 0.0;
  int periods = 1;                       ///< k: the orbits' period is 2 pi k / omega (forced)
  std::string monodromy;                 ///< how the points' monodromies were computed
  std::vector<std::string> state_names;  ///< the orbit state's coordinates and rates
  Branch branch;
  /// How the branch started: "" (from the case's state), or a sentence (resumed from a folder,
  /// switched at a period doubling: where, from which orbit)
  std::string started;
  /// A resumed branch that had ended (by a bound, where its events change) or has its points
  /// already: nothing was run, and it is as it was read
  bool nothing_to_resume = false;
};

/// Follows the case's forced (or autonomous) orbit in o.key from its value in the case (or
/// resumes, or switches at a period doubling: o.resume, o.switch_from), re-reading the case
/// from `text` (the file's text, `source` its name) with `overrides` and key = value at every
/// value. Throws CaseError on bad input.
CaseBranch find_case_branch(const std::string& text, const std::string& source,
                            const std::vector<std::string>& overrides, const CaseBranchOptions& o);

/// A branch as branch_json and branch_csv wrote it (`source`: their folder, named in errors):
/// the key, periods, method, outcome, specials (with a period doubling's state and direction),
/// section moves, runs, wall time; every point's row (its multipliers' values and bounds and
/// stability, without the monodromy matrix). Throws CaseError naming the file, line and key of
/// what is missing or malformed.
CaseBranch read_case_branch(std::string_view json, std::string_view csv, const std::string& source);

/// branch.csv: one row per point (the key's value, arclength, period, the orbit's amplitude and
/// normal forces, residual, stability, each multiplier's re, im, abs and error, the corrector's
/// iterations, runs, the section time, d key / ds, the state at the section by name, the event
/// signature).
std::string branch_csv(const CaseBranch& b);
/// branch.json: the key, outcome, message, special points (kind, value, between which points,
/// how located), points, runs, wall time.
std::string branch_json(const CaseBranch& b);
/// Writes branch.csv and branch.json into the folder open_orbit_folder prepared.
void write_branch_files(const HeldFolder& folder, const CaseBranch& b);
/// 0 when the branch ended as asked (its points, a bound, where its events change); 3 when a
/// step or the start failed; 4 when interrupted.
int exit_code(const CaseBranch& b);

/// The CLI's exit code of a search: 0 converged; 4 a run stopped by SIGINT or its wall budget;
/// 3 otherwise (every other outcome, kept on disk).
int exit_code(const OrbitResult& r);

}  // namespace rubdyn
