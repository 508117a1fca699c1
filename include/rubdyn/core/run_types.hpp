#pragma once
// What a solver run produces, independent of the solver: samples, events, a typed summary, and the
// OutputSink interface through which solvers hand them out (solvers never see a path or a file).
//
// Three error channels are never mixed (architecture.md, section 4): bad input is rejected before a
// run (io/), a broken invariant is a bug (RUBDYN_DEMAND), and numerical trouble ends a run with a
// typed Termination and a message while what was produced so far is kept.
#include <array>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "rubdyn/core/types.hpp"

namespace rubdyn {

/// Contact phase. Slip+ means v_t > 0 (F_T = -mu F_N), Slip- means v_t < 0 (F_T = +mu F_N).
enum class Phase : int { Free = 0, SlipPos = 1, SlipNeg = 2, Stick = 3 };
inline constexpr int kNumPhases = 4;
std::string_view to_string(Phase p);

/// The largest number of contacts of a model (rub planes, contact nodes): every solver, chart
/// and case table takes up to this many (the event-driven engine keeps sets of contacts as bit
/// masks and sizes its fixed workspaces by it).
inline constexpr int kMaxContacts = 8;

/// Kinds of events logged by the solvers.
enum class EventKind : int {
  Impact = 0,  ///< contact onset with v_N < 0, impact map applied
  Contact,     ///< contact closes without impact (v_N = 0), or onset seen by a fixed-step scheme
  Liftoff,     ///< F_N reaches 0 and the contact opens
  Stick,       ///< slip -> stick (v_t reaches 0 and sticking is consistent)
  Slip,        ///< stick -> slip (|F_T| reaches mu F_N)
  Reversal,    ///< slip+ <-> slip- through v_t = 0
  Grazing,     ///< gap minimum touching zero with v_N ~ 0
  Zeno,        ///< accumulation of impacts, extrapolated
  Painleve,    ///< inconsistent or non-unique contact problem
  Release,     ///< contact opens (fixed-step schemes, seen between steps)
  Count
};
inline constexpr int kNumEventKinds = static_cast<int>(EventKind::Count);
std::string_view to_string(EventKind k);

/// Why a run ended.
enum class Termination : int {
  Completed = 0,  ///< t_end reached
  SolverFailure,  ///< the ODE/DAE solver or a Newton loop failed
  NonFinite,      ///< NaN or inf in the state
  Painleve,    ///< the contact problem has no consistent (or several) solutions and no rule applies
  Zeno,        ///< an accumulation of impacts that could not be resolved
  Chattering,  ///< too many events per unit of simulated time
  Interrupted,    ///< stopped by the user (SIGINT, SIGTERM) at an output sample
  TimeBudget,     ///< stopped at an output sample once the run's wall-time budget was spent
  OutputFailure,  ///< the output could not be written (disk full, I/O error); ends the run
  /// The integrator's steps collapsed: at the step size of its last 1000 steps the run would
  /// need more than kMaxRunSteps steps (a stiff or degenerate parameter: run_envelope.hpp)
  StepCollapse,
  /// A plausibility guard broke (run_envelope.hpp, Plausibility): a result no one should trust
  /// (the event solver's penetration beyond round-off of the gap, an energy residual as large
  /// as the energy flows)
  Implausible,
  /// The contact law broke beyond round-off at a sample or an event: a normal force below 0 or a
  /// friction force outside the Coulomb cone (the event-driven solver checks every contact at
  /// every sample and event; a reference must satisfy the law it claims)
  LawViolation,
};
/// The last Termination (every value from Completed to it has a name: to_string).
inline constexpr Termination kLastTermination = Termination::LawViolation;
std::string_view to_string(Termination t);

/// Exit codes of the CLI (README.md, "Exit codes and the output contract"; `rubdyn --help`).
inline constexpr int kExitOk = 0;           ///< complete result
inline constexpr int kExitBadInput = 2;     ///< bad input, usage, folder locked: nothing written
inline constexpr int kExitEarlyEnd = 3;     ///< numerical early end: output kept, incomplete
inline constexpr int kExitInterrupted = 4;  ///< SIGINT / SIGTERM / run.max_wall: output kept
inline constexpr int kExitOutput = 5;       ///< a write failed: the error names the file

/// Exit code of the CLI for a termination: 0 for Completed, 4 for Interrupted and TimeBudget
/// (stopped on the user's request), 5 for OutputFailure, 3 for the numerical ones (step_collapse
/// and implausible included).
inline int exit_code(Termination t) {
  switch (t) {
    case Termination::Completed: return kExitOk;
    case Termination::Interrupted:
    case Termination::TimeBudget: return kExitInterrupted;
    case Termination::OutputFailure: return kExitOutput;
    default: return kExitEarlyEnd;
  }
}

/// The state of one contact at an output sample.
struct ContactSample {
  double d_N = 0.0, v_N = 0.0, v_t = 0.0;
  double F_N = 0.0, F_T = 0.0;  ///< contact forces (impulse / h for impulse-based schemes)
  Phase phase = Phase::Free;
};

/// One output sample (dense output on the output grid, or before/after an event): the state
/// (q, v of the model's size) and each contact's quantities (one entry per contact).
struct Sample {
  Sample() = default;
  /// Sized for a model with n dofs, `contacts` contacts and `observables` observables.
  Sample(int n, int contacts, int observables = 0)
      : q(Vec::Zero(n)),
        v(Vec::Zero(n)),
        contacts(static_cast<std::size_t>(contacts)),
        observables(Vec::Zero(observables)) {}
  double t = 0.0;
  Vec q, v;
  std::vector<ContactSample> contacts;
  Vec observables;  ///< the model's observables (LagrangianModel::observables), in its order
};

/// A sample's state as one vector (q, v).
inline Vec stacked_state(const Sample& s) {
  Vec x(s.q.size() + s.v.size());
  x << s.q, s.v;
  return x;
}

/// One logged event.
struct EventRecord {
  double t = 0.0;
  EventKind kind = EventKind::Impact;
  int contact = 0;  ///< the contact the event belongs to (0-based)
  Phase phase_before = Phase::Free, phase_after = Phase::Free;
  double d_N = 0.0;
  double v_N_minus = 0.0, v_N_plus = 0.0;
  double v_t_minus = 0.0, v_t_plus = 0.0;
  double P_N = 0.0, P_T = 0.0;                                       ///< impulses
  double F_N = 0.0, F_T = 0.0;                                       ///< forces after the event
  double t_accumulation = std::numeric_limits<double>::quiet_NaN();  ///< zeno: extrapolated
  std::string witness;  ///< which witness fired, or how the event was found
  std::string note;     ///< free text (Painleve rule, Zeno truncation estimate, ...)
};

/// One broken rule of a solver's options: the option ("h", "rtol", "t_end", ...), its value as
/// text, and the rule. Each solver family states its rules once in a *_option_problems function
/// that its entry point and the case-file validation both call.
struct OptionProblem {
  std::string option, value, rule;
};

/// Counters and invariants of a run.
struct RunSummary {
  std::string solver;   ///< solver kind, e.g. "event", "mj"
  std::string options;  ///< solver options as a JSON object text, e.g. {"rtol":1e-10}
  double t_start = 0.0, t_end_requested = 0.0, t_reached = 0.0;
  double wall_seconds = 0.0;
  long steps = 0, rhs_evals = 0, jac_evals = 0, root_evals = 0, newton_iters = 0;
  /// Event-driven solver: steps CVODE rejected and retried smaller, because the local error
  /// test failed or the Newton (or fixed-point) iteration did not converge. Zero for the
  /// fixed-step schemes, which never reject a step.
  long err_test_fails = 0, conv_fails = 0;
  long suppressed_witnesses = 0;  ///< witness roots ignored at the very start of a phase
  std::array<long, kNumEventKinds> events{};
  std::array<double, kNumPhases> phase_time{};  ///< simulated seconds spent in each phase
  /// Event-driven solver: integrator steps and wall seconds spent integrating each phase (event
  /// handling and output excluded); zero for solvers that do not measure them.
  std::array<long, kNumPhases> phase_steps{};
  std::array<double, kNumPhases> phase_wall{};
  // invariants
  double max_penetration = 0.0;  ///< max(-d_N, 0) over samples and step ends [m]
  double min_F_N_in_contact = std::numeric_limits<double>::quiet_NaN();
  double max_cone_violation = 0.0;  ///< max(|F_T| - mu F_N, 0) / (largest contact force) [-]
  double max_drift_position = 0.0;  ///< max |d_N| in persistent contact [m]
  double max_drift_velocity = 0.0;  ///< max |v_N| in persistent contact [m/s]
  // energy balance: E(t) - E(0) = W_torque + W_damping + W_friction + W_impacts (+ residual)
  double energy_initial = 0.0, energy_final = 0.0;
  double work_torque = 0.0, work_damping = 0.0, work_friction = 0.0, work_impacts = 0.0;
  double energy_residual = 0.0;  ///< (E_final - E_initial) - sum of works [J]
  // spin
  double omega_max = 0.0, omega_final = 0.0;
  double t_omega_lim = std::numeric_limits<double>::quiet_NaN();  ///< NaN when never crossed
  Termination termination = Termination::Completed;
  std::string message;
  /// What the run's model is when it is not the case's as written (a reduced matrices model:
  /// ReducedMatrices::describe()); empty otherwise. Set by the driver (simulate).
  std::string model;
  bool complete() const { return termination == Termination::Completed; }
  /// energy_residual = (E_final - E_initial) - (sum of the works): the one definition.
  void close_energy_balance() {
    energy_residual = (energy_final - energy_initial) -
                      (work_torque + work_damping + work_friction + work_impacts);
  }
};

/// Receives a run's output, in time order. Solvers hand out everything through a sink.
class OutputSink {
 public:
  virtual ~OutputSink() = default;
  virtual void sample(const Sample& s) = 0;
  virtual void event(const EventRecord& e) = 0;
  virtual void end(const RunSummary& s) = 0;
};

/// Keeps everything in memory (tests, post-processing, the compare tool).
class MemorySink final : public OutputSink {
 public:
  void sample(const Sample& s) override { samples.push_back(s); }
  void event(const EventRecord& e) override { events.push_back(e); }
  void end(const RunSummary& s) override { summary = s; }
  std::vector<Sample> samples;
  std::vector<EventRecord> events;
  RunSummary summary;
};

}  // namespace rubdyn
