#pragma once
// Command-line options shared by every subcommand that reads a case: the CASE positional and the
// repeatable override `--set section.key=value` (one override per occurrence, applied in order).
// load_case(args.path, args.sets) then reads, overrides and validates (io/case_io.hpp).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdlib>
#include <string>
#include <vector>

namespace rubdyn::app {

struct CaseArgs {
  std::string path;               ///< case file (TOML)
  std::vector<std::string> sets;  ///< overrides "section.key=value", in command-line order
};

/// Adds CASE (required) and --set to `sub`. `a` must outlive the parse (hold it in a shared_ptr
/// captured by the subcommand's callback, as the cmd_*.cpp files do).
inline void add_case_options(CLI::App& sub, CaseArgs& a) {
  sub.add_option("case", a.path, "case file (TOML)")->required()->type_name("CASE");
  sub.add_option("--set", a.sets, "override a case key (repeatable), e.g. --set contact.mu=0.2")
      ->type_name("SECTION.KEY=VALUE")
      ->allow_extra_args(false);
}

/// Refuses an empty path (an unset shell variable) for an option that names a folder or file,
/// instead of falling back to the default in silence: a usage error, exit 2.
inline CLI::Validator non_empty_path() {
  return CLI::Validator(
      [](std::string& v) {
        return v.empty() ? std::string("an empty path (an unset variable?)") : std::string();
      },
      "", "non-empty path");
}

/// The flag raised by SIGINT and SIGTERM (a lock-free atomic: safe to set in a handler).
inline std::atomic<bool>& stop_flag() {
  static std::atomic<bool> flag{false};
  return flag;
}

/// Seconds a run has, after SIGINT or SIGTERM, to reach its next output sample (the
/// environment variable RUBDYN_STOP_GRACE, 1 to 3600, changes it; the tests use 1).
inline unsigned& stop_grace_seconds() {
  static unsigned seconds = 10;
  return seconds;
}

/// SIGINT and SIGTERM raise stop_flag() instead of killing the process, so that a run ends at
/// its next output sample and writes its summary ("interrupted", exit 4). The handler is reset
/// on the first signal: a second one kills the process as usual, and so does SIGALRM
/// (default action) when no sample is reached within stop_grace_seconds(): a run stuck inside one
/// output interval (say, steps of 1e-15 s) is not made unkillable by `timeout` or Ctrl-C.
inline void stop_on_signals() {
  static_assert(std::atomic<bool>::is_always_lock_free);
  struct sigaction sa {};
  sa.sa_handler = [](int) {
    stop_flag().store(true);
    alarm(stop_grace_seconds());  // async-signal-safe
  };
  if (const char* g = std::getenv("RUBDYN_STOP_GRACE")) {
    const long v = std::strtol(g, nullptr, 10);
    if (v >= 1 && v <= 3600) stop_grace_seconds() = static_cast<unsigned>(v);
  }
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

}  // namespace rubdyn::app
