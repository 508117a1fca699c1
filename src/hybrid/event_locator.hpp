#pragma once
// The one event localiser of the event-driven integrator.
//
// CVODE reports a root just past a sign change (to about 100 ulps of t). Every event is then
// moved to the LAST time (the last double) at which its witness still has the sign of the ending
// phase, on the interpolant of the step that found it: the contact onset (d_N > 0 before), a gap
// that closed and reopened inside one step (the first crossing of d_N, bracketed by the step's
// start and the gap minimum), a lift-off (F_N > 0 before), a stick -> slip switch
// (|F_T| < mu F_N before) and the end of a slip (v_t of its sign before). The state logged before
// an event is then a valid state of the ending phase, and the next phase starts where the
// witness is zero to round-off.
#include <algorithm>
#include <cmath>

namespace rubdyn::detail {

/// g(lo) != 0 and g(hi) of the other sign or zero: returns the LAST DOUBLE t in [lo, hi) at
/// which g has the sign of g(lo), i.e. g(nextafter(t, hi)) has not (for a g with one sign change
/// in the bracket). Being unique, the result does not depend on hi, so not on where the root
/// finder stopped (which depends on the output times inside the step). Illinois regula falsi
/// (the retained end's value halved when it is kept twice), with a bisection step whenever two
/// iterations have not halved the bracket, until lo and hi are adjacent doubles. Without a sign
/// change in [lo, hi] (g(lo) = 0 or same signs), returns hi: the root finder's time is kept.
template <class G>
double last_time_with_sign(double lo, double hi, double g_lo, double g_hi, G&& g) {
  if (g_lo == 0.0 || g_lo * g_hi > 0.0) return hi;
  const double sign = g_lo > 0.0 ? 1.0 : -1.0;
  double f_lo = g_lo, f_hi = g_hi;                // Illinois: the retained end's value is halved
  int moved = 0;                                  // +1: lo moved last, -1: hi moved last
  double width[3] = {hi - lo, hi - lo, hi - lo};  // the bracket now, 1 and 2 iterations ago
  for (int it = 0; it < 400 && std::nextafter(lo, hi) < hi; ++it) {
    // bisect when two iterations have not halved the bracket
    double t = width[0] > 0.5 * width[2] && it >= 2 ? 0.5 * (lo + hi)
                                                    : lo + (hi - lo) * f_lo / (f_lo - f_hi);
    if (!(t > lo && t < hi)) t = 0.5 * (lo + hi);
    if (!(t > lo && t < hi)) t = std::nextafter(lo, hi);
    const double gt = g(t);
    if (gt * sign > 0.0) {
      lo = t;
      f_lo = gt;
      if (moved == 1) f_hi *= 0.5;
      moved = 1;
    } else {
      hi = t;
      f_hi = gt;
      if (moved == -1) f_lo *= 0.5;
      moved = -1;
    }
    width[2] = width[1];
    width[1] = width[0];
    width[0] = hi - lo;
  }
  return lo;
}

}  // namespace rubdyn::detail
