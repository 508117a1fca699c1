#pragma once
// Phase dynamics of the event-driven integrator: one object per formulation and mode, each with
// its own CVODE session (cvode_session.hpp, the only place that touches SUNDIALS) and its own
// right-hand side, so that no right-hand side branches on the phase or the formulation:
//   FreeFlight        free flight in (q, v): a = M^{-1} f (one structured solve), analytic
//                     Jacobian; Adams (fixed-point) or BDF
//   ProjectedContact  slip+-/stick as the index-reduced DAE in (q, v): BDF, CVODE's projection
//                     after every step (positions onto d_N = 0, velocities onto v_N = 0 and
//                     v_t = 0 in stick, mass-weighted)
//   ReducedContact    slip (phi free) or stick (phi tied to theta) in the model's chart
//                     (contact_chart.hpp): the constraints hold by construction
// A session state is the mechanical part (size(): (q, v) or (p, p')) followed by the kNw works
// of the applied loads, the dampers and friction, integrated with the state and
// error-controlled like it (as CVODES quadratures they cost a second Nordsieck array: measured
// 30 % of the run time in the rolling regime).
// The witnesses of the running phase are evaluated here, on the phase's own state.
// Every buffer is sized for the model when the object is built: the right-hand sides, the
// witnesses and the interpolation allocate nothing. Each callback has its own scratch (the
// right-hand side, the witnesses, the integrator's queries), so that none overwrites another's.
#include <Eigen/Cholesky>
#include <array>
#include <memory>
#include <vector>

#include "cvode_session.hpp"
#include "rubdyn/contact/contact_chart.hpp"
#include "rubdyn/hybrid/contact_problem.hpp"

namespace rubdyn::detail {

constexpr int kNw = 3;  // works: applied loads, dampers, friction
using Works = std::array<double, kNw>;

/// What ends a phase (event_driven.hpp lists them per phase).
enum class Witness { Gap, GapRate, NormalForce, SlipSpeed, ConeUpper, ConeLower, Omega };
inline constexpr std::size_t kNumWitnesses = static_cast<std::size_t>(Witness::Omega) + 1;
const char* witness_name(Witness w);

/// The witnesses of the running phase, their directions and scales. Owned by the integrator,
/// read by the root function of every session.
struct WitnessSet {
  WitnessSet() {  // room for every witness: rebuilding the set at a root allocates nothing
    list.reserve(kNumWitnesses);
    dirs.reserve(kNumWitnesses);
  }
  std::vector<Witness> list;
  std::vector<int> dirs;
  double g0 = 1.0, v_ref = 1.0, F_ref = 1.0, omega_lim = 0.0;
  double gap_offset = 0.0;  ///< the Gap witness is d_N + gap_offset (after a release)
  void clear() {
    list.clear();
    dirs.clear();
  }
  void add(Witness w, int dir) {
    list.push_back(w);
    dirs.push_back(dir);
  }
  int size() const { return static_cast<int>(list.size()); }
};

/// Tolerances and limits shared by the sessions.
struct SessionSettings {
  double rtol = 1e-10;
  double atol_q = 1e-12;  ///< positions [m]
  double atol_v = 1e-9;   ///< velocities [m/s]
  double g0 = 1.0;        ///< the gap's scale [m]
  bool adams = true;      ///< Adams (else BDF); ProjectedContact is always BDF
  bool fixed_point = true;
  long max_steps = 10'000'000;
};

/// Scratch for one evaluation of a contact phase at a full state.
struct ContactScratch {
  explicit ContactScratch(int n) : q(Vec::Zero(n)), v(Vec::Zero(n)), op(n), dyn(n) {}
  Vec q, v;
  ContactOperators op;
  PhaseDynamics dyn;
};

class PhaseSystem {
 public:
  PhaseSystem(const LagrangianModel& m, const WitnessSet& w);
  virtual ~PhaseSystem();
  PhaseSystem(const PhaseSystem&) = delete;
  PhaseSystem& operator=(const PhaseSystem&) = delete;

  /// Maps the full state (q, v) of `phase` into the session state; (q, v) becomes the state
  /// the session will start from (an embedding: equal to the input to round-off).
  void enter(Phase phase, Vec& q, Vec& v);
  /// (Re)starts the session at t from the entered state with the works w and the witnesses.
  void restart(double t, const Works& w, double t_stop);
  /// Advances the session (CvodeSession::advance) and returns the full state at t.
  CvodeSession::Status advance(double tout, double& t, Vec& q, Vec& v, bool one_step);

  Phase phase() const { return phase_; }
  CvodeSession& session() { return *session_; }
  const CvodeSession& session() const { return *session_; }
  /// Start of the last internal step (the interpolant covers [step_start, current_time]).
  double step_start() const { return session_->current_time() - session_->last_step(); }

  /// The full state interpolated at t inside the last step.
  void interpolate(double t, Vec& q, Vec& v) const;
  /// Works at the last state returned by advance, or interpolated at t in the last step.
  Works works() const;
  Works works_at(double t) const;

  /// Contact operators of a contact phase at a full state of it (q, v may be changed: the DAE
  /// formulation first projects the state onto the constraints, its interpolant between step
  /// ends is not projected; the others are on them by construction).
  virtual void contact_point(double t, Vec& q, Vec& v, ContactOperators& op) const;
  /// Contact forces of the phase at a full state of it (0 in free flight).
  void forces(double t, const Vec& q, const Vec& v, double& F_N, double& F_T) const;
  /// Value (unscaled) of a contact witness at a full state of the phase.
  double witness_value(Witness w, double t, const Vec& q, const Vec& v) const;

 protected:
  /// Session state layout; the defaults are the full coordinates (q, v).
  virtual int size() const { return 2 * n_; }
  virtual void to_full(const double* ys, Vec& q, Vec& v) const;
  virtual void chart_in(const Vec& q, const Vec& v, Vec& q0, Vec& v0);
  virtual bool projection() const { return false; }
  /// Creates the session: `size` mechanical components, then the works.
  void open(int size, CvodeMethod method, const SessionSettings& s, const ChartScales& scales,
            const CvodeCallbacks& cb);
  /// Rates of the works: applied loads, dampers, friction (friction power given), with the
  /// accelerations and contact forces a rheonomic drive's power needs.
  void powers(double t, VecIn q, VecIn v, VecIn a, double F_N, double F_T, double friction,
              double* w) const;

  const LagrangianModel& m_;
  const int n_;           ///< the model's dofs
  const bool rheonomic_;  ///< the drive's power needs the accelerations (m_.rheonomic())
  const ContactLaw law_;
  const WitnessSet& wit_;
  Phase phase_ = Phase::Free;
  std::vector<double> ys_;  ///< the session's state

 private:
  static int roots(double t, const double* y, double* g, void* user);
  std::unique_ptr<CvodeSession> session_;
  std::vector<double> rtol_, atol_;
  // scratch of the const queries (interpolate, works_at, forces, witness_value) and of roots()
  mutable std::vector<double> ys_scratch_;
  mutable ContactScratch query_, roots_;
  mutable ContactKinematics kin_;
};

class FreeFlight final : public PhaseSystem {
 public:
  FreeFlight(const LagrangianModel& m, const WitnessSet& w, const SessionSettings& s);

 private:
  static int rhs(double t, const double* y, double* yd, void* user);
  static int jac(double t, const double* y, const double* yd, double* J, void* user);
  // Jacobian workspace (BDF only)
  Mat M_, dfdq_, dfdv_, dMa_;
  Vec f_, a_;
  Eigen::LDLT<Mat> ldlt_;
};

class ProjectedContact final : public PhaseSystem {
 public:
  ProjectedContact(const LagrangianModel& m, const WitnessSet& w, const SessionSettings& s);
  void contact_point(double t, Vec& q, Vec& v, ContactOperators& op) const override;

 private:
  bool projection() const override { return true; }
  static int rhs(double t, const double* y, double* yd, void* user);
  static int proj(double t, const double* y, double* corr, void* user);
  double g0_;
  ContactScratch rhs_, proj_;
};

class ReducedContact final : public PhaseSystem {
 public:
  ReducedContact(const LagrangianModel& m, const WitnessSet& w, const SessionSettings& s,
                 const ContactChart& chart, ChartMode mode);

 private:
  int size() const override { return 2 * dim_; }
  void to_full(const double* ys, Vec& q, Vec& v) const override;
  void chart_in(const Vec& q, const Vec& v, Vec& q0, Vec& v0) override;
  static int rhs(double t, const double* y, double* yd, void* user);
  const ContactChart& chart_;
  const ChartMode mode_;
  const int dim_;
  ChartAnchor anchor_{};
  ContactScratch rhs_;
  Vec p_, pd_, pdd_;
};

}  // namespace rubdyn::detail
