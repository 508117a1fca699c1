#pragma once
// Every tolerance with which the event-driven integrator decides something, stated once: which
// event a root is, whether a closing contact is an impact or an arrival, whether a gap minimum
// grazes, when mode switching loops. They derive from the user's tolerances (rtol, atol) and the
// gap's scale g0 = LagrangianModel::gap_scale(k); none is a free number of its own. The rest of
// src/hybrid reads them from here (docs/architecture.md, "Decision tolerances").
#include <algorithm>
#include <limits>

namespace rubdyn::detail {

/// Velocities are resolved to atol_v = kVelocityPerPosition * atol [m/s] (atol: positions [m]).
/// 1e3 s^-1 is the order of the fastest free frequency of a rotor-stator pair (the reference
/// case's stator: ~160 Hz, 1e3 rad/s), so a position error atol moves the rate by ~1e3 atol.
inline constexpr double kVelocityPerPosition = 1e3;
/// A closing speed below kArrivalFactor * atol_v is an arrival (the contact problem decides),
/// not an impact: ten times what the integrator resolves.
inline constexpr double kArrivalFactor = 10.0;
/// The integrator resolves positions to about atol + rtol g0 near contact; a gap within ten
/// times that is the constraint (bounce heights, the grazing test).
inline constexpr double kGrazeFactor = 10.0;
/// A gap minimum within max(graze_tol, kGrazeBandRel g0) of 0 is logged as grazing. Wider than
/// the local tolerance because the global error of the orbit is (measured: 1e-8 on a unit
/// amplitude at rtol 1e-10); logging a near-miss changes nothing in the motion, since at a
/// minimum of free flight d_N'' >= 0.
inline constexpr double kGrazeBandRel = 1e-6;
/// The reference speed of the witnesses (v_ref = kRefSpeedPerGap g0, floored at 1e-300): the
/// speed at which the gap's scale is crossed in a millisecond.
inline constexpr double kRefSpeedPerGap = 1e3;
/// The witnesses' force reference grows with the largest |F_N| seen, from this floor [N].
inline constexpr double kForceRefFloor = 1e-6;
/// A witness that fired is zero to the accuracy of the root location on the interpolant: the
/// contact problem at its event decides with this relative band, so a margin that small is a
/// zero, not a sign.
inline constexpr double kWitnessBandRel = 1e-7;
/// The contact problem at a state the integrator did not locate (an arrival, a release on the
/// constraint, the initial state, a graze) decides with this relative band.
inline constexpr double kDecisionBandRel = 1e-9;
/// The next order of a degenerate decision (contact_decisions.hpp) is taken by central
/// differences over +-kNextOrderRel h along the chosen modes' flow, h the integrator's last step
/// (the scale on which it resolves the motion): a thousandth of it keeps the differences'
/// truncation six orders below their value, and at the steps of these runs (1e-7 to 1e-5 s) it is
/// 1e6 ulps of t and more.
inline constexpr double kNextOrderRel = 1e-3;
/// Position projections onto d_N = 0 stop at kProjectionRel g0 (a few ulps of the gap scale).
inline constexpr double kProjectionRel = 1e-14;
/// A gap minimum within kPhaseStartRel max(1, |t|) of the phase's start is the phase's own start
/// (a release on the constraint whose rate dips by round-off), not a new minimum.
inline constexpr double kPhaseStartRel = 1e-12;
/// Events within kSameInstantRel max(1, |t|) of each other are at one instant; more than
/// kMaxSameInstant of them mean that mode switching loops.
inline constexpr double kSameInstantRel = 1e-14;
inline constexpr int kMaxSameInstant = 20;
/// Chattering: the rate of events over the last kChatterWindow events is compared with
/// max_events_per_second.
inline constexpr int kChatterWindow = 64;
/// Horizon [s] from which CVODE estimates the first step after a restart (cvode_session.cpp,
/// advance): a fixed time, so that neither the output grid nor the end time changes the steps
/// taken. CVODE starts its estimate from a tenth of it, and replaces it by the distance to the
/// stop time when that is shorter: only a phase that starts within 1 ms of the end of the run
/// depends on the end time. 1 ms is 30x the free-flight steps of the reference case at rtol
/// 1e-10.
inline constexpr double kFirstStepHorizon = 1e-3;

/// The error weight of a component y_i of a CVODE state is 1 / tol_i with tol_i >= kRoundoffFloor
/// eps |y_i| (cvode_session.cpp): a tolerance below the component's own round-off cannot be met
/// and CVODE stops with CV_TOO_MUCH_ACC once eps ||y||_wrms > 1. It binds only on the chart
/// angles of contact phases, whose weights are absolute ((rtol g0 + atol) / L: a chart angle
/// that turns through a long roll grows without bound: at rtol 1e-10, g0 = 2e-4 m, R = 0.05 m
/// from |theta - theta_a| = 19 rad on, where 100 eps |theta - theta_a| reaches that weight).
/// 100: CVODE's error estimates carry a few eps |y| of noise; a hundred keeps them far below
/// the test, and the demand (2e-14 relative) is still far beyond any measurement of a roll.
inline constexpr double kRoundoffFloor = 100.0;
inline constexpr double kEps = std::numeric_limits<double>::epsilon();

/// The tolerances of one run, derived from the user's rtol, atol and the gap's scale g0.
struct SwitchTolerances {
  double v_tol = 0;       ///< velocity below which a closing contact is an arrival, not an impact
  double graze_tol = 0;   ///< position resolution of the integrator (bounce heights, grazing)
  double graze_band = 0;  ///< a gap minimum within this band of 0 is logged as grazing
  double g0 = 1;          ///< the gap's scale (position projections stop at kProjectionRel g0)
  double atol_v = 0;      ///< absolute tolerance on velocities [m/s]
  double v_ref = 0;       ///< the witnesses' reference speed [m/s]
  /// A flight lower than this is not integrated (contact_decisions.hpp): a bounce is truncated
  /// by a plastic impact, a contact pushed off in a cascade is kept on the constraint by the
  /// cascade's collapse. The integrator's position resolution graze_tol: a lower flight starts
  /// and ends inside the first step after the restart (order 1, its interpolant linear), which
  /// cannot resolve it (measured: a rotor bouncing with e_n = 0.5 chatters at the default
  /// tolerances with a cut at kGrazeFactor rtol g0, 50 times lower). Both collapses are of
  /// second order in the speed they remove (their error is of the order of the flight's
  /// height), so the cut's share of the error falls with the tolerances.
  double collapse_height = 0;

  static SwitchTolerances derive(double rtol, double atol, double g0) {
    SwitchTolerances s;
    s.atol_v = atol * kVelocityPerPosition;
    s.v_tol = kArrivalFactor * s.atol_v;
    s.graze_tol = kGrazeFactor * (atol + rtol * g0);
    s.graze_band = std::max(s.graze_tol, kGrazeBandRel * g0);
    s.g0 = g0;
    s.v_ref = std::max(kRefSpeedPerGap * g0, 1e-300);
    s.collapse_height = s.graze_tol;
    return s;
  }
};

}  // namespace rubdyn::detail
