// The event localiser of the event-driven integrator (src/hybrid/event_locator.hpp): the last
// time at which a witness still has the ending phase's sign, to a few ulps.
#include <catch2/catch.hpp>
#include <cmath>

#include "hybrid/event_locator.hpp"

using rubdyn::detail::last_time_with_sign;

TEST_CASE("Event localiser: the last double at which g has the sign of g(lo)", "[events][unit]") {
  struct Case {
    double lo, hi, root;
  };
  // g, for each case: 0: linear, 1: cubic through the root, 2: exp - 1 (steep on one side)
  const Case cases[] = {{0.0, 1.0, 0.3},
                        {0.1, 0.1 + 1e-6, 0.1 + 3.7e-7},
                        {10.0, 10.5, 10.123456},
                        {0.25, 0.2500001, 0.25000007},
                        {1e-3, 2e-3, 1.5e-3 + 1e-9}};
  for (const Case& c : cases) {
    for (int kind = 0; kind < 3; ++kind) {
      for (double sign : {1.0, -1.0}) {
        auto g = [&](double t) {
          const double x = (c.root - t) / (c.hi - c.lo);  // > 0 before the root
          const double f = kind == 0 ? x : (kind == 1 ? x + 4.0 * x * x * x : std::expm1(8.0 * x));
          return sign * f;
        };
        const double t = last_time_with_sign(c.lo, c.hi, g(c.lo), g(c.hi), g);
        INFO("root " << c.root << " kind " << kind << " sign " << sign);
        // the returned time still has the sign of g(lo), the next double has not: exact, so
        // the result cannot depend on where the bracket's upper end was
        CHECK(g(t) * sign > 0.0);
        CHECK(g(std::nextafter(t, c.hi)) * sign <= 0.0);
        const double t_other =
            last_time_with_sign(c.lo, 0.5 * (c.root + c.hi), g(c.lo), g(0.5 * (c.root + c.hi)), g);
        CHECK(t_other == t);
      }
    }
  }
}

TEST_CASE("Event localiser: without a sign change the root finder's time is kept",
          "[events][unit]") {
  auto g = [](double t) { return 1.0 + t; };
  CHECK(last_time_with_sign(0.0, 1.0, g(0.0), g(1.0), g) == 1.0);
  auto z = [](double) { return 0.0; };
  CHECK(last_time_with_sign(0.0, 1.0, 0.0, 0.0, z) == 1.0);
  // g(hi) exactly 0: the double before it
  auto lin = [](double t) { return 0.5 - t; };
  CHECK(last_time_with_sign(0.0, 0.5, lin(0.0), lin(0.5), lin) == std::nextafter(0.5, 0.0));
}
