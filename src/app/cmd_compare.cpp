// rubdyn compare A B: differences between two solutions (output folders or CSV files).
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <stdexcept>

#include "commands.hpp"
#include "rubdyn/analysis/compare.hpp"
#include "rubdyn/io/text_files.hpp"

namespace rubdyn::app {

namespace {

struct CompareArgs {
  std::string a, b;
  std::optional<std::string> json;  // unset when not given ('' is given, and refused)
  std::vector<double> window;
  double event_tol = 1e-3;
};

int compare_command(const CompareArgs& x) {
  if (!x.window.empty() && !(x.window.size() == 2 && x.window[1] > x.window[0])) {
    throw std::runtime_error("--window takes two times t0 < t1");
  }
  if (!(x.event_tol > 0.0)) throw std::runtime_error("--event-tol must be > 0");
  // a path that would be refused is refused before any work (PathRefused: exit 2)
  if (x.json) check_output_path(*x.json);
  const Series a = read_series(x.a), b = read_series(x.b);
  for (const auto* s : {&a, &b})
    for (const auto& w : s->warnings)
      std::fprintf(stderr, "rubdyn compare: warning: %s\n", w.c_str());
  std::optional<std::pair<double, double>> w;
  if (!x.window.empty()) w = std::make_pair(x.window[0], x.window[1]);
  const Comparison c = compare_solutions(a, b, read_events(x.a), read_events(x.b), w, x.event_tol);
  std::printf("%s", comparison_report(c, x.a, x.b).c_str());
  // by the output-path rule (text_files.hpp): --json /dev/stdout writes after the report, a
  // link or a device is written through, never replaced
  if (x.json) write_file_atomic(*x.json, comparison_json(c, x.a, x.b));
  return 0;
}

}  // namespace

void add_compare_command(CLI::App& app, Action& action) {
  auto x = std::make_shared<CompareArgs>();
  auto* sub = app.add_subcommand(
      "compare", "Differences between two solutions (output folders or CSV files with t)");
  sub->add_option("a", x->a, "first solution: output folder or CSV file")->required();
  sub->add_option("b", x->b, "second solution: output folder or CSV file")->required();
  sub->add_option("--window", x->window, "compare over [t0, t1] only")->expected(2);
  sub->add_option("--event-tol", x->event_tol, "largest time shift of matched events [s]");
  sub->add_option("--json", x->json,
                  "also write the comparison as JSON to this file (a link or a device such as "
                  "/dev/stdout is written through, never replaced)");
  sub->callback([x, &action] { action = [x] { return compare_command(*x); }; });
}

}  // namespace rubdyn::app
