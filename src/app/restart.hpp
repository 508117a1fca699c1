#pragma once
// Starting from a sample of another run's output folder (rubdyn run --from, rubdyn orbit --from).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rubdyn::app {

/// The overrides that start a case from a sample of the output folder `from`: run.t_start and
/// every initial.* key, in the shortest form that reads back to the same double. The sample is
/// the one at `at` (the last of the rows at that time: after an event) or the last complete one.
/// Warnings and notes go to stderr prefixed with `command`. Throws CaseError for a bad --at.
std::vector<std::string> restart_overrides(const std::string& from,
                                           const std::optional<std::string>& at,
                                           std::string_view command);

}  // namespace rubdyn::app
