// rubdyn: command-line entry point. Nothing but dispatch and the mapping of errors to exit codes.
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "commands.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/output_folder.hpp"

int main(int argc, char** argv) {
  // A file size limit (RLIMIT_FSIZE) would kill the process by SIGXFSZ with no summary: ignored,
  // the write fails with EFBIG instead, and a failed write is exit 5 naming the file.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"rubdyn: reference solutions for rotor-stator rub with Coulomb friction"};
  app.require_subcommand(1);
  app.footer(
      "Exit codes: 0 complete result; 2 bad input or usage, output folder in use or not "
      "preparable, an output path refused (nothing written); 3 run ended early for a numerical "
      "reason; 4 interrupted by "
      "SIGINT/SIGTERM or by the wall-time budget run.max_wall; 5 a write failed (the message names "
      "the file). In 3, 4 and 5 the output so "
      "far is kept and summary.json says \"complete\": false with the reason (README.md).");
  rubdyn::app::Action action;
  rubdyn::app::add_check_command(app, action);
  rubdyn::app::add_campbell_command(app, action);
  rubdyn::app::add_run_command(app, action);
  rubdyn::app::add_compare_command(app, action);
  rubdyn::app::add_analyze_command(app, action);
  rubdyn::app::add_sweep_commands(app, action);
  rubdyn::app::add_orbit_command(app, action);
  rubdyn::app::add_branch_command(app, action);
  // The first word that is no option names the subcommand: an unknown one is an error naming
  // it, whatever follows (CLI11 would answer `rubdyn orbit --help` with the general help and
  // exit 0, as if the command existed).
  if (argc > 1 && argv[1][0] != '-') {
    std::string names;
    bool known = false;
    for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
      known = known || sub->check_name(argv[1]);
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      std::fprintf(stderr,
                   "rubdyn: error: '%s' is not a subcommand (subcommands: %s; rubdyn --help)\n",
                   argv[1], names.c_str());
      return rubdyn::kExitBadInput;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);  // prints help (rc 0) or the usage error
    return rc == 0 ? 0 : 2;
  }
  // Results on stdout are output like any file: a failed write there (a full disk behind a
  // redirection) is exit 5, never a silent exit 0.
  auto checked_stdout = [](int rc) {
    errno = 0;
    if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
      std::fprintf(stderr, "rubdyn: error: cannot write the standard output: %s\n",
                   errno ? std::strerror(errno) : "write failed");
      return rc == 0 ? rubdyn::kExitOutput : rc;
    }
    return rc;
  };
  try {
    return checked_stdout(action ? action() : 2);
  } catch (const rubdyn::CaseError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return rubdyn::kExitBadInput;
  } catch (const rubdyn::FolderError& e) {
    std::fprintf(stderr, "rubdyn: error: %s (the run did not start)\n", e.what());
    return rubdyn::kExitBadInput;
  } catch (const rubdyn::PathRefused& e) {
    std::fprintf(stderr, "rubdyn: error: %s (nothing written)\n", e.what());
    return rubdyn::kExitBadInput;
  } catch (const rubdyn::OutputError& e) {
    std::fprintf(stderr, "rubdyn: error: %s\n", e.what());
    return rubdyn::kExitOutput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rubdyn: error: %s\n", e.what());
    return 2;
  }
}
