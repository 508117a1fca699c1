#pragma once
// A one-screen, human-readable report of a run (what `rubdyn run` prints on stdout).
#include <string>

#include "rubdyn/core/run_types.hpp"

namespace rubdyn {

/// Termination, time reached, wall time, work counters, events by kind, phase fractions,
/// invariants and the energy balance, spin statistics. Lines of at most 100 characters.
std::string brief_report(const RunSummary& s);

}  // namespace rubdyn
