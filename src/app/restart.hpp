#pragma once
// Starting from a sample of another run's output folder (rubdyn run --from, rubdyn orbit --from).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rubdyn/io/case_spec.hpp"

namespace rubdyn::app {

/// The overrides that start a case from a sample of the output folder `from`: run.t_start and
/// every initial.* key, in the shortest form that reads back to the same double. The sample is
/// the one at `at` (the last of the rows at that time: after an event) or the last complete one.
/// Warnings and notes go to stderr prefixed with `command`. Throws CaseError for a bad --at.
/// `plain`: the case without the restart (null when it does not validate: its own errors are
/// reported then). A restart sets every coordinate of the case from the sample: the folder's run
/// must be of the same model with the same coordinates, else refused (CaseError, exit 2), never
/// started with the case's values where the folder has none.
std::vector<std::string> restart_overrides(const std::string& from,
                                           const std::optional<std::string>& at,
                                           const CaseSpec* plain, std::string_view command);

/// The same for commands that do not integrate to run.t_end (orbit, branch): the case at `path`
/// with `sets` is the plain case, and its own run length is carried to the sample's time
/// (run.t_end = t_start + its length), so that the case stays valid with the sample's time.
std::vector<std::string> restart_overrides_keeping_length(const std::string& from,
                                                          const std::optional<std::string>& at,
                                                          const std::string& path,
                                                          const std::vector<std::string>& sets,
                                                          std::string_view command);

}  // namespace rubdyn::app
