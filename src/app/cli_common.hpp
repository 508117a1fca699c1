#pragma once
// Command-line options shared by every subcommand that reads a case: the CASE positional and the
// repeatable override `--set section.key=value` (one override per occurrence, applied in order).
// load_case(args.path, args.sets) then reads, overrides and validates (io/case_io.hpp).
#include <CLI/CLI.hpp>
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

}  // namespace rubdyn::app
