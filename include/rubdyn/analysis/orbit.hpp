#pragma once
// Periodic orbits of the event-driven flow and their Floquet multipliers (issue 33;
// docs/orbits.md has the method, the coordinates used at contact and the checks).
//
// The flow is a black box: one call of run_event_driven (hybrid/event_driven.hpp) from a state
// at the section time t0 over one period T is the return map P. A forced orbit (a prescribed,
// constant spin speed Omega: the model is T-periodic in time with T = 2 pi k / Omega) is a fixed
// point P(x0) = x0, found by Newton's method on the section's own coordinates:
//
//  - The section. When the orbit is in a contact phase at t0 (the full annular rub slides
//    permanently), its state lies on the phase's constraint manifold: d_N = 0, v_N = 0 for every
//    closed contact (and v_t = 0 for a sticking one). A state off it is refused (penetration) or
//    starts another phase (free flight into the gap), so every iterate and every perturbation
//    must stay on it. SectionChart parametrises the manifold near a base state x_b by the
//    coordinates xi of the tangent space: in the scaled state s = D^-1 (x - x_b) (positions per
//    gap scale L, velocities per L Omega), B spans the null space of the scaled constraint
//    Jacobian G and N its orthogonal complement; embed(xi) is the point x_b + D (B xi + N eta)
//    of the manifold (eta by Newton on the constraints), coords(y) = B^T D^-1 (y - x_b) its
//    inverse. The coordinates are exact: coords(embed(xi)) = xi to round-off, for any xi for
//    which the manifold is a graph over the tangent plane. In free flight the chart is the
//    identity (no constraint). A coordinate that the return map need not close (an autonomous
//    orbit's cyclic spin angle) is pinned: held at its base value and left out of xi.
//  - Newton on r(xi) = coords(P(embed(xi))) - xi, the Jacobian Phi - I with Phi the monodromy in
//    the chart's coordinates: a finite-difference one first, Broyden's updates after, a halved
//    step while the residual does not fall. Converged when the full-state residual
//    |D^-1 (P(x) - x)|_inf <= tol.
//  - The monodromy comes from a MonodromyProvider. FiniteDifferenceMonodromy differentiates the
//    return map by central differences at several step sizes and measures its own truncation
//    error (below). A provider from the flow's sensitivities (variational equations per phase
//    and saltation matrices at events) computes the full-state derivative DP (2n x 2n) and
//    returns coords_jacobian() DP tangent(xi): the same matrix in the same coordinates.
//  - The multipliers are the eigenvalues of Phi, each with an error bound from the monodromy's
//    error (its condition number times the error's norm, and at least the spread between the
//    finite-difference estimates). An orbit is stable when every multiplier plus its error is
//    inside the unit circle, unstable when one minus its error is outside; otherwise the verdict
//    is "undecided" and says which multiplier is too close to the circle. The directions off the
//    manifold (into the gap, or a tangential slip out of stick) are not multipliers of the
//    section: a state perturbed into the gap returns to the constraint within the period by a
//    plastic impact (e_n = 0) or an accumulation of bounces, so they map to zero (docs/orbits.md).
#include <array>
#include <atomic>
#include <complex>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rubdyn/core/run_types.hpp"
#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn {

/// One run of the return map: the samples, the events and the summary.
struct FlowRun {
  RunSummary summary;
  std::vector<Sample> samples;
  std::vector<EventRecord> events;
  bool complete() const { return summary.complete() && !samples.empty(); }
};

/// The return map of a model's event-driven flow from the section time t0 over a time T.
/// A model holds no mutable state, so one map may serve several threads.
class PeriodMap {
 public:
  /// `opt`: the integrator's options (tolerances, formulation); its output grid and progress
  /// callback are replaced per run.
  PeriodMap(const LagrangianModel& model, double t0, EventDrivenOptions opt);
  const LagrangianModel& model() const { return model_; }
  double t0() const { return t0_; }
  const EventDrivenOptions& options() const { return opt_; }
  int state_size() const { return 2 * model_.num_dofs(); }
  /// Runs from the state x = (q, v) at t0 to t0 + T. output_dt = 0: the samples at the ends and
  /// at events only.
  FlowRun run(VecIn x, double T, double output_dt = 0.0) const;
  /// Runs made so far (all threads).
  long runs() const { return runs_.load(); }

 private:
  const LagrangianModel& model_;
  double t0_;
  EventDrivenOptions opt_;
  mutable std::atomic<long> runs_{0};
};

/// The phase of every contact at the start of a run (the phase the integrator chose there).
std::vector<Phase> start_phases(const FlowRun& r);
/// ... and at its end.
std::vector<Phase> end_phases(const FlowRun& r);

/// What a run did after its start, as text: the phases at the start, then every event
/// (kind, contact) after t0; the initial decision on the constraint is the start, not an event.
/// Two runs with the same signature crossed the same switching surfaces in the same order.
std::string event_signature(const FlowRun& r, double t0);

/// Coordinates of the section's manifold near a base state (see the header comment).
class SectionChart {
 public:
  /// The manifold of the contact phases `phases` (one per contact: free adds nothing, slip adds
  /// d_N = 0 and v_N = 0, stick also v_t = 0) at time t through the base state x_b = (q, v),
  /// which must lie on it. `scale` (size 2n) is D: the unit of each state component. `pinned`
  /// lists state components held at their base value (e.g. a cyclic spin angle).
  SectionChart(const LagrangianModel& model, double t, VecIn x_b, const std::vector<Phase>& phases,
               VecIn scale, const std::vector<int>& pinned = {});

  int dim() const { return static_cast<int>(B_.cols()); }  ///< d: coordinates xi
  int state_size() const { return static_cast<int>(xb_.size()); }
  int constraint_count() const { return static_cast<int>(rows_.size()); }
  const Vec& base() const { return xb_; }
  const Vec& scale() const { return D_; }
  double time() const { return t_; }

  /// The manifold's point with coordinates xi, into x; false when the projection onto the
  /// constraints does not converge (xi too far from the base for the chart).
  bool embed(VecIn xi, Vec& x) const;
  /// The same onto the constraints of another model of the same coordinates (a continuation's
  /// model at another parameter value, whose constraints may differ: a gap, a radius): the
  /// chart's base, basis and time, that model's d_N, v_N, v_t.
  bool embed_on(const LagrangianModel& model, VecIn xi, Vec& x) const;
  /// xi of a state on the manifold: B^T D^-1 (x - x_b).
  Vec coords(VecIn x) const;
  /// The largest scaled constraint value at x (0 on the manifold): |d_N| / L, |v_N| / (L Omega),
  /// |v_t| / (L Omega) over the section's constraints.
  double constraint_defect(VecIn x) const;
  /// d(coords)/dx = B^T D^-1 (d x 2n).
  Mat coords_jacobian() const;
  /// d(embed)/dxi at xi (2n x d): the full-state directions of the coordinates. At xi = 0 it is
  /// D B (the tangent space), elsewhere by differences of embed.
  Mat tangent(VecIn xi) const;
  /// |D^-1 (y - x)|_inf over the unpinned components: the scaled distance of two states.
  double scaled_distance(VecIn x, VecIn y) const;
  /// The contact phases the chart was made for.
  const std::vector<Phase>& phases() const { return phases_; }

 private:
  struct Row {
    int contact;
    int kind;  // 0: d_N, 1: v_N, 2: v_t, 3: pinned component
    int index;
  };
  // scaled constraint values of model m (size m) and their derivative in the scaled state s
  Vec values(const LagrangianModel& m, VecIn x) const;
  Mat jacobian(const LagrangianModel& m, VecIn x) const;
  const LagrangianModel& m_;
  double t_;
  Vec xb_, D_;
  double len_ = 1.0, speed_ = 1.0;  // L, L Omega
  std::vector<Row> rows_;
  std::vector<int> pinned_;
  std::vector<Phase> phases_;
  Mat B_, N_;  // scaled tangent and normal bases (2n x d, 2n x m)
};

/// A contact that the section's chart holds open (free at the section) whose stator the state
/// x = (q, v) penetrates (d_N below -64 ulps of its gap scale): a state beyond a grazing of the
/// free orbit, on the other side of the contact surface. (A closed contact's d_N is 0 to
/// round-off on the chart and is not checked.)
std::optional<Penetration> penetrates_open_contact(const LagrangianModel& model,
                                                   const SectionChart& chart, double t, VecIn x);

/// A monodromy matrix in a chart's coordinates with its error estimate.
struct Monodromy {
  Mat M;                ///< d x d
  double error = 0.0;   ///< estimated error of M (2-norm)
  std::string method;   ///< how it was computed (text for the report)
  bool ok = false;      ///< false: see failure
  std::string failure;  ///< why it could not be computed (a run failed, a chart projection)
  /// Finite differences: the steps tried (scaled units, decreasing), each step's estimate, and
  /// |Phi_k - Phi_k+1|_2 between neighbours; `chosen` is k of the pair used. A
  /// truncation-dominated pair's difference falls by the square of the step ratio (16 for a
  /// ratio 4) from one pair to the next; a noise-dominated one grows as the step falls.
  std::vector<double> steps, differences;
  std::vector<Mat> estimates;
  int chosen = -1;
  long runs = 0;
  /// A perturbed run crossed other switching surfaces than the base run (grazing, or an event
  /// at the section): the map is not differentiable there, and M is not its derivative.
  bool sequence_changed = false;
  std::string sequence_note;
  /// The multipliers of each step's estimate (diagnostics of the step-size control).
  std::vector<std::vector<std::complex<double>>> step_multipliers;
};

/// Where the monodromy comes from: finite differences of the return map today, the flow's
/// sensitivities with saltation matrices at events later (docs/orbits.md, "Plugging in
/// sensitivities").
class MonodromyProvider {
 public:
  virtual ~MonodromyProvider() = default;
  virtual std::string_view name() const = 0;
  /// The derivative of xi -> coords(P(embed(xi), T)) at xi, in the chart's coordinates. `at` is
  /// the map's run from embed(xi) (its events and end state; a provider may ignore it).
  virtual Monodromy compute(const PeriodMap& map, double T, const SectionChart& chart, VecIn xi,
                            const FlowRun& at) const = 0;
};

/// Central differences of the return map at several step sizes h_k (scaled units: a fraction
/// of the gap scale L in position, of L Omega in velocity). The pair (h_k, h_k+1) whose
/// estimates differ least gives M = Richardson's extrapolation of the two (the h^2 term
/// eliminated) and error = twice their difference (in the truncation regime the difference is
/// the coarser estimate's error, far above the extrapolation's; in the noise regime it is about
/// the extrapolation's own error, hence the factor). With one step: that step's estimate, error
/// unknown (NaN).
/// refine() adds one step where the differences say the error falls: a quarter of the smallest
/// when the finest pair is the best (truncation dominates), four times the largest when the
/// coarsest is (noise dominates); none when the best pair lies inside (the error is at its
/// minimum).
class FiniteDifferenceMonodromy final : public MonodromyProvider {
 public:
  explicit FiniteDifferenceMonodromy(std::vector<double> steps = {1e-3, 2.5e-4})
      : steps_(std::move(steps)) {}
  std::string_view name() const override { return "finite differences"; }
  Monodromy compute(const PeriodMap& map, double T, const SectionChart& chart, VecIn xi,
                    const FlowRun& at) const override;
  /// compute(), with the estimate at the step h_known already known (Phi_known, in this chart's
  /// coordinates at xi): Newton's last finite-difference Jacobian, when the orbit is that
  /// close to where it was taken (find_forced_orbit). Its runs are not repeated.
  Monodromy compute_seeded(const PeriodMap& map, double T, const SectionChart& chart, VecIn xi,
                           const FlowRun& at, double h_known, const Mat& Phi_known) const;
  /// One more step (see above) into m, recombined; false when no step would help or m failed.
  bool refine(const PeriodMap& map, double T, const SectionChart& chart, VecIn xi,
              const FlowRun& at, Monodromy& m) const;
  const std::vector<double>& steps() const { return steps_; }

 private:
  /// Phi at one step into m (its estimate, multipliers, sequence check); false on failure.
  bool estimate(const PeriodMap& map, double T, const SectionChart& chart, VecIn xi,
                const std::string& sig0, double h, Monodromy& m, Mat& Phi) const;
  static void combine(Monodromy& m);
  Monodromy compute_impl(const PeriodMap& map, double T, const SectionChart& chart, VecIn xi,
                         const FlowRun& at, double h_known, const Mat* Phi_known) const;
  std::vector<double> steps_;
};

/// The monodromy from the flow's sensitivities (docs/orbits.md section 7): the variational
/// equations V' = f_x(t, x) V of every phase, integrated along the orbit's run in the full state
/// x = (q, v) with the phase's constrained vector field f (the acceleration-level contact problem
/// of its modes: a tangent V stays tangent to the constraints), multiplied at every event by the
/// saltation matrix S = R_x P + f+ g_x^T / g', P = I - f- g_x^T / g': g the witness that fired
/// (d_N at an onset, F_N at a lift-off, v_t at a stick or reversal, the cone margin at a slip),
/// g' its rate along the flow before the event, f- and f+ the vector fields on both sides, R_x
/// the reset's Jacobian along the event surface: the engine's own impact decision
/// (ContactDecider::arrive: impulses, Zeno truncation, cascade collapse) by central differences
/// of that algebraic map at impacts, the identity at every other switch. f_x V by central
/// differences of the vector field along each column of V (step kVariationalStep of the
/// column's scaled size: truncation and round-off both ~1e-11 relative). The augmented system
/// (x, V) is integrated by CVODE-BDF under the map's tolerances (V's rows weighted as x's), its
/// Newton systems block-diagonal with one factorisation of I - gamma f_x; done twice, at rtol
/// and at rtol / 100 (rtol x 100 below 1e-11), M the finer, its error their difference (2-norm:
/// the coarser's error, above the finer's). Not smooth, so a failure naming the event: an event
/// whose witness crosses with zero rate (grazing), two triggering events at one instant, an
/// impact whose decision changes within the difference step, a grazing or Painleve record.
class SensitivityMonodromy final : public MonodromyProvider {
 public:
  std::string_view name() const override { return "sensitivities"; }
  Monodromy compute(const PeriodMap& map, double T, const SectionChart& chart, VecIn xi,
                    const FlowRun& at) const override;
};

/// One Floquet multiplier with its error bound and its direction.
struct FloquetMultiplier {
  std::complex<double> value;
  double error = 0.0;          ///< bound on |value - exact| from the monodromy's error
  double condition = 1.0;      ///< 1 / |y^H x| (unit left and right eigenvectors)
  Eigen::VectorXcd direction;  ///< the eigenvector in full-state coordinates (q, v), unit 2-norm
                               ///< in the scaled state
};

enum class Stability { Stable, Unstable, Undecided };
std::string_view to_string(Stability s);

/// The multipliers of a monodromy (sorted by decreasing modulus) and the verdict.
struct FloquetAnalysis {
  std::vector<FloquetMultiplier> multipliers;
  Stability stability = Stability::Undecided;
  std::string reason;  ///< one line: why this verdict
  /// An autonomous orbit's trivial multiplier (along the flow: exactly 1), the real one nearest
  /// 1: its index in `multipliers` (-1: a forced orbit), left out of the verdict; and whether it
  /// is 1 within its error bound (a check of the monodromy).
  int trivial = -1;
  bool trivial_ok = false;
};
/// `tangent`: the chart's tangent(xi) at the orbit (to express the eigenvectors as states).
/// `autonomous`: the orbit of an autonomous flow, whose trivial multiplier is set apart.
FloquetAnalysis floquet_analysis(const Monodromy& m, MatIn tangent, VecIn scale,
                                 bool autonomous = false);

/// How a search for an orbit ended. Everything but Converged is exit 3 in the CLI (a run
/// stopped by SIGINT or the wall budget: exit 4).
enum class OrbitOutcome {
  Converged,
  NoConvergence,    ///< max_iterations without reaching tol (the history says how it went)
  RunFailed,        ///< a run of the return map ended early (its termination and message)
  ChartFailed,      ///< an iterate could not be put on the section's constraint manifold
  SequenceChanged,  ///< converged, but the events change within the differences' steps
  NotIsolated,      ///< Phi - I singular: a multiplier at +1 (a fold, or a family of orbits)
};
std::string_view to_string(OrbitOutcome o);

/// One Newton iterate.
struct NewtonRecord {
  int iteration = 0;
  double residual = 0.0;  ///< |D^-1 (P(x) - x)|_inf at the iterate
  double step = 0.0;      ///< |D^-1 (x_next - x)|_inf of the step taken from it (0: none)
  double damping = 1.0;   ///< the step's factor (1: a full Newton step)
  std::string jacobian;   ///< "finite differences", "broyden", "" (none: converged)
  std::string signature;  ///< the run's event_signature
  long runs = 0;          ///< runs of the return map up to this iterate
};

/// The settings of a search.
struct OrbitOptions {
  double tol = 1e-8;        ///< on |D^-1 (P(x) - x)|_inf (scaled: per gap scale)
  int max_iterations = 20;  ///< Newton iterations
  /// Steps of the final monodromy: FiniteDifferenceMonodromy's default.
  std::vector<double> fd_steps = {1e-3, 2.5e-4};
  /// Steps added (FiniteDifferenceMonodromy::refine) while the verdict is undecided.
  int fd_refinements = 2;
  /// The step of Newton's finite-difference Jacobian. When it is one of fd_steps and the orbit
  /// lies within 1e-5 (scaled) of the iterate where the last such Jacobian was taken, that
  /// Jacobian is the final monodromy's estimate at this step (its runs are not repeated).
  double newton_step = 1e-3;
  /// Samples of the orbit's final run per period (orbit.csv); 0: no sampled run (the run of the
  /// last iterate, its ends and events, stands for it)
  int samples = 200;
  /// A provider of the final monodromy instead of finite differences (nullptr: them); a forced
  /// orbit's Newton takes its Jacobians from it too (Broyden's updates between them as before).
  const MonodromyProvider* provider = nullptr;
};

/// One event of the orbit, its time from the section time t0.
struct OrbitEvent {
  double t = 0.0;  ///< from t0
  EventKind kind = EventKind::Contact;
  int contact = 0;
  Phase before = Phase::Free, after = Phase::Free;
};

/// What a search found.
struct OrbitResult {
  OrbitOutcome outcome = OrbitOutcome::NoConvergence;
  std::string message;
  double t0 = 0.0, period = 0.0;
  Vec x0;  ///< the orbit's state at t0 (q, v); the last iterate when not converged
  double residual = 0.0;
  std::vector<NewtonRecord> history;
  std::vector<Phase> section_phases;  ///< every contact's phase at t0
  int chart_dim = 0, constraints = 0;
  Monodromy monodromy;
  FloquetAnalysis floquet;
  FlowRun orbit;  ///< the final run over one period, sampled
  std::vector<OrbitEvent> events;
  std::array<long, kNumEventKinds> event_counts{};
  std::array<double, kNumPhases> phase_time{};
  long runs = 0;
  double wall_seconds = 0.0;
  Termination run_termination = Termination::Completed;  ///< of the run that failed, if any
  bool converged() const { return outcome == OrbitOutcome::Converged; }
};

/// The state scale D of a model: positions per the gap scale L, velocities per L omega_ref.
Vec state_scale(const LagrangianModel& model, double omega_ref);

/// An autonomous orbit (a free spin under a torque law: the flow does not depend on time) of
/// unknown period, from the guess x and the period guess T0. The components `pinned` (the spin
/// angle, cyclic without an unbalance) are left out of the section's coordinates and need not
/// close. Unknowns: the section's coordinates but one, fixed by the phase condition xi_j = 0
/// (j the coordinate along which the flow moves fastest at the guess: the section is the
/// hyperplane through the base state across the flow), and T. The monodromy then has the
/// trivial multiplier 1, set apart from the verdict and checked against 1.
OrbitResult find_autonomous_orbit(const PeriodMap& map, VecIn guess, double T0, double omega_ref,
                                  const std::vector<int>& pinned, const OrbitOptions& opt);

/// A forced orbit of period T (a T-periodic model: a prescribed constant spin with T = 2 pi k /
/// Omega) by Newton from the guess x = (q, v) at t0. Never throws for numerical trouble: the
/// outcome says it.
OrbitResult find_forced_orbit(const PeriodMap& map, VecIn guess, double T, double omega_ref,
                              const OrbitOptions& opt);

}  // namespace rubdyn
