// rubdyn run: placeholder until implemented.
#include "commands.hpp"

namespace rubdyn::app {
void add_run_command(CLI::App& app, Action& action) {
  auto* sub = app.add_subcommand("run", "not implemented yet");
  sub->callback([&action] { action = [] { return 2; }; });
}
}  // namespace rubdyn::app
