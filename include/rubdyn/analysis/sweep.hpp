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
#include <atomic>
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
/// "i/N" with 1 <= i <= N. Throws std::invalid_argument.
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
inline constexpr long kDefaultMaxPoints = 10'000;

/// What a sweep is about to do, once every point is validated and before the first one runs.
struct SweepPlan {
  long points = 0;               ///< in the whole sweep
  long runs = 0;                 ///< in this shard, tight runs of --certify included
  double simulated_seconds = 0;  ///< sum of run.t_end over the runs
  double output_rows = 0;        ///< timeseries rows over the runs (estimate, events excluded)
  double output_bytes = 0;       ///< about 420 bytes a row (21 numbers with 17 digits)
};

struct SweepOptions {
  std::string case_path;
  std::vector<std::string> sets;  ///< overrides common to every point (--set)
  std::vector<Variation> vary;
  std::string out = "out/sweep";
  int jobs = 1;
  Shard shard;
  bool certify = false;
  AnalysisOptions analysis;
  /// Called (from worker threads, serialised) after each point with (done, total).
  std::function<void(long, long)> progress;
  /// Skip the points whose folder holds a complete summary.json of the same resolved case
  /// (case.resolved.toml equal to this point's): their analysis is redone, not their run.
  bool resume = false;
  /// When set and true (SIGINT / SIGTERM), running points end at their next sample
  /// ("interrupted") and the points not started get termination "not_run"; the table is
  /// written with them, and --resume completes the sweep later.
  const std::atomic<bool>* stop = nullptr;
  long max_points = kDefaultMaxPoints;  ///< more points are refused (std::invalid_argument)
  /// Called once every option and point is checked, before the first point runs.
  std::function<void(const SweepPlan&)> plan;
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
};

/// Checks every option (analysis options, repeated keys, the point count against max_points:
/// std::invalid_argument) and every point (CaseError on the first bad one), all before any
/// output; calls `plan`; runs this
/// shard's points and writes OUT/sweep.csv (or OUT/sweep-shard-i-of-N.csv with a .json sidecar
/// naming the total number of points). Returns the rows in point order.
std::vector<SweepRow> run_sweep(const SweepOptions& o);

/// The sweep table: point, the varied keys, termination, verdicts, certification.
std::string sweep_csv(const std::vector<std::string>& keys, const std::vector<SweepRow>& rows,
                      bool certify);

/// Joins OUT/sweep-shard-*-of-N.csv into OUT/sweep.csv. Throws std::runtime_error naming the
/// missing shard, the mismatching header or the missing points. Returns the number of rows.
long merge_sweep_shards(const std::string& out);

}  // namespace rubdyn
