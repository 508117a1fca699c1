#pragma once
// Parametric sweeps (rubdyn sweep, rubdyn sweep-merge; the paper's section 5.2-5.3 studies).
//
// A sweep is the Cartesian product of variations of case keys ("contact.mu=0,0.1,0.2" or
// "stator.k=1e6:8e6:8", eight values from 1e6 to 8e6 evenly spaced), the last variation varying
// fastest; point i of the product is always the same point, so `--shard i/N` (points with
// index % N == i - 1) splits a sweep deterministically across the tasks of a job array, and
// sweep-merge joins their tables. Every point is validated as a case (file, key, value, rule)
// before anything runs or is written. Points run in parallel on `jobs` threads with no shared
// mutable state (each run builds its own model, solver and output folder) and are written to
// OUT/pNNNN/ with their analysis (analysis/postprocess.hpp) in OUT/pNNNN/analysis/.
//
// Certified verdicts (--certify): each point is run again with a ten times finer step (fixed-step
// schemes) or a hundred times tighter rtol and atol (event-driven) in OUT/pNNNN-tight/, and the
// verdicts (speed limited or not, backward whirl or not, whip or not) of the two runs are
// compared: "yes" when they agree, "no" when the verdict depends on the tolerance.
//
// Ensembles (--ensemble N, N >= 1): each point is also run as N perturbed members, member k = 1..N
// in OUT/pNNNN-eKK/ (k with two digits at least) with its analysis. Member k is the point's
// resolved case (every --set and --vary applied) with
//   omega0 + domega (2 (k - 1) / (N - 1) - 1)   (-domega ... +domega; N = 1: omega0 + domega)
//   x_r + offset cos(a), y_r + offset sin(a)    (a = 2 pi (k - 1) / N: released `offset` metres
//                                                off the point's own position at R)
// evaluated in double precision as written, left to right within the usual precedence (the
// exact doubles are part of the definition: anyone can recompute a member's initial state), and
// validated as a case (a member must not start inside the stator). The point itself is member 0:
// its row keeps the verdicts of the nominal run, and the ensemble columns count the N + 1 runs:
// ensemble_members = N + 1, ensemble_incomplete = runs that did not complete (ended early,
// interrupted, not run or not analysable), and over the complete runs only (empty when none is):
// p_limited, p_backward, p_whip, p_rolling = the fraction of them that is limited, has a backward
// whirl onset, has whip_fraction > 0, has stick_fraction > 0; omega_max_min and omega_max_max.
// --certify and --ensemble answer different questions: "certified" says whether the nominal
// verdicts depend on the solver's tolerance (numerics; only the nominal run is re-run tighter),
// P(...) how much they depend on an unmeasurably small change of the initial state (physics).
// Members run on the same threads as points, go with their point in a shard, and --resume skips
// the complete members of the same resolved case as it skips points; a member that ends early
// is reported as a point is (rubdyn sweep exits 3).
//
// The sweep folder is owned like a run's (io/output_folder.hpp): held open and locked for the
// sweep's life (exclusively; a shard shares the lock with the other shards of its plan), written
// into by its descriptor, and checked before the table is written (a folder removed or replaced
// meanwhile: OutputError, exit 5). The plan hash (SweepPlan::hash) names what a sweep computes:
// every point's resolved case and every option that changes a row; OUT/sweep-plan.json holds
// the hash of the sweep that last took the folder. A sweep that takes a folder whose plan
// differs removes that plan's sweep.csv, whose rows would describe point folders it is about to
// replace (that plan's shard tables stay: sweep-merge refuses them by their plan); a shard waits up
// to kShardLockWait for the first shard of its plan, and is refused (FolderError) while a sweep of
// another plan holds the folder.
#include <atomic>
#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "rubdyn/analysis/postprocess.hpp"

namespace rubdyn {

struct Variation {
  std::string key;                  ///< section.key of the case file
  std::vector<std::string> values;  ///< as TOML values (validated by the case loader)
};
/// "section.key=v1,v2,..." or "section.key=a:b:n" (n >= 2 evenly spaced values from a to b,
/// written with 15 significant digits: 0.14:0.2:7 gives 0.15, not 0.15000000000000002).
/// Throws std::invalid_argument naming the text and the rule it breaks.
Variation parse_variation(const std::string& text);

struct Shard {
  int index = 1, count = 1;  ///< 1 <= index <= count
};
/// "i/N" with 1 <= i <= N. Throws std::invalid_argument (an empty text too: an unset job-array
/// variable must not run the whole sweep in every task).
Shard parse_shard(const std::string& text);

struct SweepPoint {
  long index = 0;
  std::vector<std::string> values;  ///< one per variation
  std::vector<std::string> overrides() const;
  std::vector<std::string> keys;  ///< the variations' keys, same order
};
/// The Cartesian product, last variation fastest.
std::vector<SweepPoint> sweep_points(const std::vector<Variation>& vary);

/// The number of points of the product (as a double: it may not fit in a long).
double sweep_point_count(const std::vector<Variation>& vary);

/// A sweep larger than this many points is refused unless max_points is raised (--max-points):
/// 1e4 points of the reference case are about 1e4 x 10 ms of wall time and 1e4 output folders.
/// With an ensemble of N members, the points times N + 1 (every member is a run and a folder)
/// are counted against it.
inline constexpr long kDefaultMaxPoints = 10'000;

/// More members per point than this are refused (a typo rather than a study: 1000 members are
/// already 1000 runs and folders per point).
inline constexpr int kMaxEnsembleMembers = 1000;

/// --ensemble N, --ensemble-domega, --ensemble-offset (see the header comment).
struct EnsembleOptions {
  int members = 0;       ///< N perturbed runs per point besides the nominal one (0: off)
  double domega = 0.1;   ///< largest change of omega0 [rad/s], finite, >= 0
  double offset = 1e-7;  ///< initial offset of the rotor at R [m], finite, >= 0, < stator.gap
};

/// Every rule `e` breaks that does not depend on the case (empty: valid): members in
/// [0, kMaxEnsembleMembers], domega and offset finite and >= 0. One message each naming the
/// option, its value and the rule.
std::vector<std::string> ensemble_option_problems(const EnsembleOptions& e);

/// Member k (1 <= k <= e.members) of a point whose resolved case is `point`: omega0, x_r and y_r
/// perturbed as the header comment says, nothing else changed. Not validated (run_sweep does).
CaseSpec ensemble_member(const CaseSpec& point, int k, const EnsembleOptions& e);

/// What a sweep is about to do, once every point is validated and before the first one runs.
struct SweepPlan {
  long points = 0;  ///< in the whole sweep
  long runs = 0;    ///< in this shard, tight runs of --certify and ensemble members included
  double simulated_seconds = 0;  ///< sum of run.t_end over the runs
  double output_rows = 0;        ///< timeseries rows over the runs (estimate, events excluded)
  double output_bytes = 0;       ///< about 420 bytes a row (21 numbers with 17 digits)
  std::string hash;              ///< plan hash: 16 hex digits (FNV-1a 64 of the points and options)
};

/// How long a shard waits for the folder's lock while the first shard of its plan prepares it.
inline constexpr std::chrono::milliseconds kShardLockWait{2000};

struct SweepOptions {
  std::string case_path;
  std::vector<std::string> sets;  ///< overrides common to every point (--set)
  std::vector<Variation> vary;
  std::string out = "out/sweep";
  int jobs = 1;
  Shard shard;
  bool certify = false;
  AnalysisOptions analysis;
  EnsembleOptions ensemble;
  /// Called (from worker threads, serialised) after each point (with its tight run) and each
  /// ensemble member with (done, total) counted in those units.
  std::function<void(long, long)> progress;
  /// Skip the points whose folder holds a complete summary.json of the same resolved case
  /// (case.resolved.toml equal to this point's): their analysis is redone, not their run.
  bool resume = false;
  /// When set and true (SIGINT / SIGTERM), running points end at their next sample
  /// ("interrupted") and the points not started get termination "not_run"; the table is
  /// written with them, and --resume completes the sweep later.
  const std::atomic<bool>* stop = nullptr;
  /// More points (times N + 1 with an ensemble) are refused (std::invalid_argument).
  long max_points = kDefaultMaxPoints;
  /// Called once every option and point is checked, before the first point runs.
  std::function<void(const SweepPlan&)> plan;
};

/// One ensemble member's run (--ensemble).
struct SweepMember {
  std::string folder;       ///< OUT/pNNNN-eKK
  std::string termination;  ///< as SweepRow::termination
  std::string message;
  bool complete = false;
  RunVerdicts v;
};

struct SweepRow {
  SweepPoint point;
  std::string termination;  ///< "completed", another termination, "error" or "not_run"
  std::string message;
  bool complete = false;
  RunVerdicts v;
  double wall_seconds = 0;
  std::string folder;
  // --certify
  bool certified_run = false;  ///< the tight run was made
  std::string tight_termination;
  RunVerdicts tight;
  bool certified = false;  ///< verdicts agree (and both runs complete)
  // --ensemble N (N > 0)
  std::vector<SweepMember> members;  ///< members 1..N
  // over the nominal run and the N members
  int ensemble_members = 0;     ///< N + 1 (0: no ensemble)
  int ensemble_incomplete = 0;  ///< runs that did not complete, left out of what follows
  /// Fractions of the complete runs (NaN when none is complete).
  double p_limited = 0, p_backward = 0, p_whip = 0, p_rolling = 0;
  double omega_max_min = 0, omega_max_max = 0;  ///< over the complete runs (NaN when none)
};

/// Checks every option (analysis and ensemble options, repeated keys, the run count against
/// max_points: std::invalid_argument), every point (CaseError on the first bad one) and, with an
/// ensemble, the offset against every point's stator.gap (std::invalid_argument) and every member
/// of this shard (CaseError), all before any output; calls `plan`; runs this shard's points and
/// their members and writes OUT/sweep.csv (or OUT/sweep-shard-i-of-N.csv with a .json sidecar
/// naming the total number of points). Returns the rows in point order.
std::vector<SweepRow> run_sweep(const SweepOptions& o);

/// The sweep table: point, the varied keys, termination, verdicts, certification (certify) and
/// the ensemble columns (ensemble).
std::string sweep_csv(const std::vector<std::string>& keys, const std::vector<SweepRow>& rows,
                      bool certify, bool ensemble = false);

/// Joins OUT/sweep-shard-*-of-N.csv into OUT/sweep.csv, holding OUT's lock (FolderError while a
/// sweep runs there). Every shard must come from one plan (the plan hash of its .json sidecar),
/// be named as rubdyn names it, appear once, and hold only its own points (index % N = i - 1),
/// each once, every field valid for its column (a number, a count, yes/no, a termination, the
/// point's folder). Throws std::runtime_error naming the file and line, the column and the value
/// that break a rule, the mismatching header, plan or ensemble settings, or the missing points.
/// Returns the number of rows.
long merge_sweep_shards(const std::string& out);

}  // namespace rubdyn
