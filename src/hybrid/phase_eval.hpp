#pragma once
// The contacts' mechanics at one state, for any number K of contacts: every contact's
// kinematics, the Delassus operator of the K contacts, the contact forces and the constrained
// acceleration of a mode tuple, and the projections onto the closed contacts' constraints.
// One contact is the smallest case; it keeps the one-contact kernels of contact_problem.hpp on
// its hot path (the contact phases' right-hand sides: one structured solve for f, W_N, W_T and
// the closed-form 2x2 mode solve), which compute the same quantities.
// Every workspace is sized when built: nothing here allocates.
#include <array>
#include <span>
#include <vector>

#include "contact_modes.hpp"
#include "rubdyn/contact/contact_law.hpp"
#include "rubdyn/hybrid/contact_problem.hpp"
#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn::detail {

// The small dense systems of the closed contacts: at most 2K unknowns.
using SmallMat =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 2 * kMaxContacts, 2 * kMaxContacts>;
using SmallVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 2 * kMaxContacts, 1>;

/// Solves G x = b in place: the minimum-norm solution when G is singular (redundant contacts:
/// their forces indeterminate, the motion not; contact/min_norm.hpp). False when the system is
/// inconsistent (a Painleve slip, or constraints that cannot all hold).
bool solve_small(const SmallMat& G, SmallVec& b);

/// Every contact's kinematics and the Delassus operator of all K contacts at one state:
/// B = M^{-1} (f, W_N0, W_T0, W_N1, ...), W = H B(:, 1:), b = H M^{-1} f + wdot (H: rows W_N,k,
/// W_T,k). Row i of H is contact i / 2's normal (i even) or tangential (i odd) row.
struct MultiOps {
  MultiOps(int n, int K);
  int K;
  std::vector<ContactKinematics> c;
  Mat B, W;
  Vec b;
  const ContactKinematics& at(int k) const { return c[static_cast<std::size_t>(k)]; }
  const Vec& row(int i) const { return i % 2 == 0 ? at(i / 2).W_N : at(i / 2).W_T; }
  /// The speed (v_N or v_t) of row i.
  double speed(int i) const { return i % 2 == 0 ? at(i / 2).v_N : at(i / 2).v_t; }
  void compute(const LagrangianModel& m, double t, VecIn q, VecIn v);
  /// Only the contacts' kinematics (no solve with M).
  void kinematics(const LagrangianModel& m, double t, VecIn q, VecIn v);
};

/// The contact forces and the acceleration of a mode tuple at an evaluated state: r (2K, 0 for
/// open contacts), a (n). False: the closed set's equations are singular (Painleve).
struct ModeSolve {
  ModeSolve(int n, int K);
  Vec r, a;
  SmallMat G;
  SmallVec x;
  std::array<int, 2 * kMaxContacts> rows{}, cols{};
  bool solve(const MultiOps& op, const Modes& modes, std::span<const ContactLaw> laws);
};

/// How a velocity projection treats one contact of its set.
enum class RowKind : std::uint8_t {
  Normal,  ///< v_N = 0 by a normal impulse
  Stick,   ///< v_N = 0 and v_t = 0 (both rows)
  Sliding  ///< v_N = 0 by an impulse with the slip friction, P_T = -mu s P_N (s = sign v_t)
};

/// Projects (q, v) onto the constraints of a set of contacts: positions by joint Gauss-Newton
/// steps along the W_N,k (to kProjectionRel g0,k), velocities mass-weighted (RowKind per
/// contact); leaves `op` evaluated at the projected state.
struct Projector {
  Projector(int n, int K);
  MultiOps op;
  Mat J;
  Vec d;
  SmallMat G;
  SmallVec x;
  std::array<int, 2 * kMaxContacts> rows{}, cols{};
  std::array<RowKind, kMaxContacts> kind{};
  /// Positions of the contacts in `set` onto d_N = 0 (op evaluated there, v unchanged).
  void positions(const LagrangianModel& m, double t, Vec& q, VecIn v, ContactSet set,
                 std::span<const SwitchTolerances> tol);
  /// Velocities of the contacts in `set` (kind[k] each) onto the constraints at the state op
  /// was evaluated at; op evaluated at the result. False: the projection is singular and
  /// inconsistent (nothing changed).
  bool velocities(const LagrangianModel& m, double t, VecIn q, Vec& v, ContactSet set,
                  std::span<const ContactLaw> laws);
};

/// The phase of a mode tuple at one state: the contacts' kinematics, forces and the
/// constrained acceleration. K = 1 runs the one-contact kernels (contact_problem.hpp).
class PhaseEval {
 public:
  PhaseEval(const LagrangianModel& m, int K);
  /// The contacts' kinematics only (free flight's witnesses; forces 0, acceleration not set).
  void kinematics(double t, VecIn q, VecIn v);
  /// The phase of `modes` at (q, v). False: its equations are singular (a Painleve slip).
  bool dynamics(double t, VecIn q, VecIn v, const Modes& modes, std::span<const ContactLaw> laws);
  /// Projects (q, v) onto the constraints of the closed contacts of `modes` (positions onto
  /// d_N = 0, velocities mass-weighted onto v_N = 0, and v_t = 0 in stick), then dynamics().
  bool place(double t, Vec& q, Vec& v, const Modes& modes, std::span<const ContactLaw> laws,
             std::span<const SwitchTolerances> tol);

  const ContactKinematics& c(int k) const { return K_ == 1 ? op1_.c : cur_->at(k); }
  double F_N(int k) const { return K_ == 1 ? dyn1_.F_N : ms_.r(2 * k); }
  double F_T(int k) const { return K_ == 1 ? dyn1_.F_T : ms_.r(2 * k + 1); }
  /// The acceleration after dynamics() or place().
  const Vec& a() const { return K_ == 1 ? dyn1_.a : ms_.a; }
  int contacts() const { return K_; }

 private:
  void zero_forces();
  const LagrangianModel& m_;
  const int K_;
  // K = 1
  ContactOperators op1_;
  PhaseDynamics dyn1_;
  // K > 1
  MultiOps ops_;
  ModeSolve ms_;
  Projector pr_;
  const MultiOps* cur_ = &ops_;  // the operators of the last evaluation (pr_.op after place())
};

}  // namespace rubdyn::detail
