#pragma once
// The fixed-step schemes as steppers, in the spirit of Siconos' OneStepIntegrator and odeint's
// steppers: a stepper owns its scheme's state and advances it by one step of the fixed size h,
// saying how it went with a typed outcome. What every scheme needs around its steps (output,
// the run monitor, the energy balance, events between steps) is the one run loop of
// run_fixed_step (fixed_step.cpp). Adding a scheme is a Stepper and a line in make_stepper.
//   Carpenter (carpenter.cpp): carp-onevc, carp-qn
//   Moreau-Jean (moreau_jean.cpp): mj, mj-proj
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "rubdyn/stepping/fixed_step.hpp"

namespace rubdyn {

enum class StepOutcome {
  Ok,
  NewtonFailed,  ///< the scheme's nonlinear iteration did not converge
  NonFinite,     ///< the new state is not finite
  Painleve       ///< the scheme's contact problem has no solution (Painleve-type)
};
std::string_view to_string(StepOutcome o);

/// One contact's quantities in a step of a model with several contacts.
struct ContactStep {
  double F_N = 0, F_T = 0;    ///< contact force (Moreau-Jean: impulse / h)
  double P_N = 0, P_T = 0;    ///< impulse of the step
  Phase phase = Phase::Free;  ///< the contact's status in the step
  double v_N_before = 0;      ///< its v_N at the start of the step
};

/// The state a step completed, with its contact quantities. Moreau-Jean's step i completes the
/// state at t_{i+1}; Carpenter's velocity at t_i is central, so its step i completes t_i.
/// One contact: the scalar fields. Several (K > 1): `contacts`, one entry each; the scalar
/// fields are then unused.
struct StepReport {
  StepReport() = default;
  explicit StepReport(int n, int contacts = 1)
      : q(Vec::Zero(n)),
        v(Vec::Zero(n)),
        a(Vec::Zero(n)),
        contacts(contacts > 1 ? static_cast<std::size_t>(contacts) : 0) {}
  /// Every field but q and v back to its default (the vectors keep their storage).
  void reset() {
    index = 0;
    F_N = F_T = P_N = P_T = v_N_before = contact_work = 0.0;
    phase = Phase::Free;
    newton_iters = 0;
    nonunique = unconverged = false;
    for (ContactStep& c : contacts) c = ContactStep{};
  }
  long index = 0;  ///< the state is at t_0 + index h
  Vec q, v;        ///< the model's size
  /// The scheme's acceleration at the state: Moreau-Jean's mean over the step (v_{i+1} - v_i)/h
  /// (an impulse included), Carpenter's central second difference. For the power of a
  /// rheonomic drive and for the model's observables.
  Vec a;
  double F_N = 0, F_T = 0;    ///< contact force (Moreau-Jean: impulse / h)
  double P_N = 0, P_T = 0;    ///< impulse of the step
  Phase phase = Phase::Free;  ///< contact status of the step
  double v_N_before = 0;      ///< v_N at the start of the step (impact or contact, event log)
  double contact_work = 0;    ///< work of the contact force or impulse over the step [J]
  long newton_iters = 0;
  bool nonunique = false;    ///< the local contact problem had several solutions (tie rule)
  bool unconverged = false;  ///< carp-qn reached itmax (the run goes on; counted)
  std::vector<ContactStep> contacts;  ///< K > 1: each contact's (empty for one contact)
};

class Stepper {
 public:
  virtual ~Stepper() = default;
  virtual std::string_view name() const = 0;
  /// The options as a JSON object text (summary.json "options").
  virtual std::string options_json() const = 0;
  /// Starts from (q0, v0) at t0.
  virtual void start(double t0, const Vec& q0, const Vec& v0) = 0;
  /// One step from t = t_0 + i h (i = 0, 1, ...): fills `r` (sized for the model: StepReport(n));
  /// on failure, `message` says why. Allocates nothing.
  virtual StepOutcome step(double t, StepReport& r, std::string& message) = 0;
};

/// The stepper of opt.scheme. Throws std::invalid_argument when h is not finite and > 0, or the
/// model has several contacts and the scheme handles one (Carpenter's; Moreau-Jean handles K).
std::unique_ptr<Stepper> make_stepper(const LagrangianModel& m, const FixedStepOptions& opt);

// The schemes (one file each).
std::unique_ptr<Stepper> make_carpenter(const LagrangianModel& m, const FixedStepOptions& opt);
std::unique_ptr<Stepper> make_moreau_jean(const LagrangianModel& m, const FixedStepOptions& opt);

}  // namespace rubdyn
