// rubdyn check: placeholder until implemented.
#include "commands.hpp"

namespace rubdyn::app {
void add_check_command(CLI::App& app, Action& action) {
  auto* sub = app.add_subcommand("check", "not implemented yet");
  sub->callback([&action] { action = [] { return 2; }; });
}
}  // namespace rubdyn::app
