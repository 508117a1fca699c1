#pragma once
// Continuation of a forced periodic orbit in a parameter (issue 33; docs/orbits.md, section 10):
// pseudo-arclength on the section's coordinates xi and the parameter lambda, the orbits and
// their multipliers by analysis/orbit.hpp, folds (a real multiplier through +1), period
// doublings (through -1) and Neimark-Sacker points (a complex pair through the unit circle)
// detected between points and located.
//
// Unknowns u = (xi, lambda / s_lambda), xi in the chart of the last point (SectionChart, based
// on its orbit), s_lambda the parameter's unit in the arclength. The branch G(u) =
// coords(P_lambda(embed_lambda(xi))) - xi = 0 is followed with
//   predictor  u_p = u_i + ds t_i (t_i the unit tangent: the null vector of [Phi - I, G_lambda]),
//   corrector  Newton on (G(u), t_i . (u - u_p)) = 0 from the Jacobian of point i, with
//              Broyden's updates,
// then the new point's monodromy (finite differences with their error, or the options'
// provider: the flow's sensitivities) and G_lambda (central
// differences in lambda) give its tangent, oriented along the secant from the previous point.
// The step ds grows by 1.3 when the corrector converges in 4 iterations or fewer (from a
// finite-difference Jacobian whose error is ~1e-3, Broyden's iteration gains about two digits
// an iteration: 4 take a predictor's 1e-1 residual to the tolerance 1e-8), shrinks by 0.7 when
// it needs 7 or more, is halved when it fails.
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "rubdyn/analysis/orbit.hpp"

namespace rubdyn {

/// The model at one value of the parameter, with what the search needs of it.
struct ParameterModel {
  std::unique_ptr<LagrangianModel> model;
  double t0 = 0.0;      ///< the section time
  double period = 0.0;  ///< T(lambda)
  double omega = 0.0;   ///< the state scale's frequency (the spin speed)
  EventDrivenOptions options;
  /// An autonomous orbit (a free spin under a torque law): its period is an unknown of the
  /// branch (`period`: the first point's guess), the section a hyperplane through each point
  /// across the flow (the phase condition), the components `pinned` (the cyclic spin angle)
  /// held; the state's velocities scaled by 2 pi / T instead of omega.
  bool autonomous = false;
  std::vector<int> pinned;
};
/// lambda -> the model there; throws (e.g. CaseError) for a value the model refuses.
using ModelFamily = std::function<ParameterModel(double lambda)>;

struct ContinuationOptions {
  double ds = 0.5;            ///< first arclength step (scaled units)
  double ds_min = 1e-3;       ///< a step that fails below this ends the branch
  double ds_max = 2.0;        ///< largest step
  double lambda_scale = 1.0;  ///< s_lambda: the parameter's unit in the arclength
  int max_points = 200;       ///< points on the branch, the first included
  double lambda_min = -std::numeric_limits<double>::infinity();
  double lambda_max = std::numeric_limits<double>::infinity();
  int direction = +1;     ///< the sign of the first step in lambda
  int max_corrector = 8;  ///< corrector iterations per step
  OrbitOptions orbit;     ///< tol, the monodromy's steps, samples of each point's orbit
  /// The first point's section time (NaN: the family's t0) and, for an autonomous orbit, the
  /// guess of its period (NaN: the family's): a branch continued from a point of another run.
  double t0 = std::numeric_limits<double>::quiet_NaN();
  double period = std::numeric_limits<double>::quiet_NaN();
  /// A point before the first one on the same branch (its state at the section t0, its period
  /// and parameter): the first tangent is oriented along the secant from it instead of by
  /// `direction` (a resumed branch goes on the way it went, through a fold too). Empty: none.
  Vec previous_x;
  double previous_period = 0.0, previous_lambda = 0.0;
};

/// One point of a branch.
struct BranchPoint {
  double lambda = 0.0;
  double arclength = 0.0;  ///< along the branch from the first point (scaled)
  double period = 0.0;
  Vec x0;  ///< the orbit's state at the section
  double residual = 0.0;
  int corrector_iterations = 0;  ///< 0 for the first point (Newton at fixed lambda)
  double tangent_lambda = 0.0;   ///< d lambda / ds / s_lambda: its sign changes at a fold
  Monodromy monodromy;
  FloquetAnalysis floquet;
  std::string signature;                ///< the orbit's event signature
  double amplitude = 0.0;               ///< max over the period of |rotor point| of contact 1 [m]
  double F_N_max = 0.0, F_N_min = 0.0;  ///< contact 1's normal force over the period [N]
  /// contact 1's smallest gap over the period [m]: the smallest sample's, refined by the parabola
  /// through it and its two neighbours where it is a strict local minimum
  double d_N_min = 0.0;
  double free_time = 0.0;  ///< the time of the period in which every contact is free [s]
  /// contact 1's smallest gap minimum in free flight over the period, away from its contacts
  /// (a strict local minimum of the sampled gap, refined by the parabola through it and its
  /// neighbours): where it reaches 0 a new contact appears (grazing) [m]; NaN: none
  double d_N_dip = std::numeric_limits<double>::quiet_NaN();
  /// contact 1's smallest friction cone margin mu F_N - |F_T| over the samples where it sticks
  /// [N]: where it reaches 0 the stick breaks into slip; NaN: it never sticks
  double cone_min = std::numeric_limits<double>::quiet_NaN();
  /// the slowest impact's closing speed over the period, |v_N-| [m/s]; NaN: no impact
  double impact_speed_min = std::numeric_limits<double>::quiet_NaN();
  long runs = 0;  ///< runs of the return map for this point
  double t0 =
      0.0;  ///< the section's time (moved away from the orbit's events: Branch::section_moves)
};

/// A special point between two points of the branch.
struct BranchSpecial {
  std::string kind;     ///< "fold", "period_doubling", "neimark_sacker", "events_change", "end"
  int after = 0;        ///< between points `after` and `after + 1` (or beyond the last, `after`)
  double lambda = 0.0;  ///< located
  /// The located value's spread between two estimates (a lift-off's secant and parabola, see
  /// `how`); 0: no such estimate
  double spread = 0.0;
  std::string how;  ///< how it was detected and located
  /// A period doubling: the orbit nearest it (the locating evaluation with the smallest
  /// det(Phi + I)) as its state at the section time t0, and the direction of its multiplier
  /// near -1 (full state, unit in the scaled state). The period-2 branch starts from
  /// x +- eps direction with the period doubled (branch switching, docs/orbits.md section 10).
  Vec x, direction;
  double t0 = std::numeric_limits<double>::quiet_NaN();
};

struct Branch {
  std::vector<BranchPoint> points;
  std::vector<BranchSpecial> specials;
  std::string outcome;  ///< "max_points", "lambda_bound", "events_change", "step_failed",
                        ///< "start_failed"
  std::string message;
  long runs = 0;
  double wall_seconds = 0.0;
  /// Where the section was moved, because an event of the orbit came within 10 % of a period of
  /// it: after point `after` (the same orbit, from there on at the section time t0).
  struct SectionMove {
    int after = 0;
    double t0 = 0.0;
  };
  std::vector<SectionMove> section_moves;
};

/// The real multipliers below -1 (their count changes by an odd number at a period doubling).
int real_multipliers_below_minus_one(const FloquetAnalysis& f);

/// Follows the orbit from the guess x_guess at lambda0 (Newton there first): a forced orbit, or an
/// autonomous one where the family says so (ParameterModel::autonomous: its period an unknown).
Branch continue_forced_orbit(const ModelFamily& family, double lambda0, VecIn x_guess,
                             const ContinuationOptions& opt);

}  // namespace rubdyn
