// rubdyn compare A B: differences between two solutions (output folders or CSV files).
#include <cstdio>
#include <fstream>
#include <memory>
#include <stdexcept>

#include "commands.hpp"
#include "rubdyn/analysis/compare.hpp"
#include "rubdyn/io/text_files.hpp"

namespace rubdyn::app {

namespace {

struct CompareArgs {
  std::string a, b, json;
  std::vector<double> window;
  double event_tol = 1e-3;
};

int compare_command(const CompareArgs& x) {
  if (!x.window.empty() && !(x.window.size() == 2 && x.window[1] > x.window[0])) {
    throw std::runtime_error("--window takes two times t0 < t1");
  }
  if (!(x.event_tol > 0.0)) throw std::runtime_error("--event-tol must be > 0");
  const Series a = read_series(x.a), b = read_series(x.b);
  for (const auto* s : {&a, &b})
    for (const auto& w : s->warnings)
      std::fprintf(stderr, "rubdyn compare: warning: %s\n", w.c_str());
  std::optional<std::pair<double, double>> w;
  if (!x.window.empty()) w = std::make_pair(x.window[0], x.window[1]);
  const Comparison c = compare_solutions(a, b, read_events(x.a), read_events(x.b), w, x.event_tol);
  std::printf("%s", comparison_report(c, x.a, x.b).c_str());
  if (!x.json.empty()) write_file_atomic(x.json, comparison_json(c, x.a, x.b));  // checked
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
  sub->add_option("--json", x->json, "also write the comparison as JSON to this file");
  sub->callback([x, &action] { action = [x] { return compare_command(*x); }; });
}

}  // namespace rubdyn::app
