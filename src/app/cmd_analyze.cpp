// rubdyn analyze FOLDER: whirl, friction torque, spectra and Campbell overlay of an output folder.
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>

#include "cli_common.hpp"
#include "commands.hpp"
#include "rubdyn/analysis/postprocess.hpp"

namespace rubdyn::app {

namespace {

struct AnalyzeArgs {
  std::string folder, out;
  std::vector<double> window_t;
  AnalysisOptions o;
};

int analyze_command(const AnalyzeArgs& a) {
  AnalysisOptions o = a.o;
  if (!a.window_t.empty()) {
    if (!(a.window_t.size() == 2 && a.window_t[1] > a.window_t[0]))
      throw std::runtime_error("--t-window takes two times t0 < t1");
    o.t0 = a.window_t[0];
    o.t1 = a.window_t[1];
  }
  const auto bad = analysis_option_problems(o);
  if (!bad.empty()) {
    std::string text = "invalid options:";
    for (const auto& b : bad) text += "\n  " + b;
    throw std::invalid_argument(text);
  }
  const RunRecord r = read_run(a.folder);
  for (const auto& w : r.warnings) std::fprintf(stderr, "rubdyn analyze: warning: %s\n", w.c_str());
  const RunVerdicts v = write_analysis(r, o, a.out);
  std::printf("%s", verdicts_json(v).c_str());
  if (!r.complete) std::fprintf(stderr, "rubdyn analyze: note: the run is incomplete\n");
  return 0;
}

}  // namespace

void add_analyze_command(CLI::App& app, Action& action) {
  auto a = std::make_shared<AnalyzeArgs>();
  auto* sub = app.add_subcommand(
      "analyze", "Whirl, friction torque, spectrum and spectrogram of an output folder");
  sub->add_option("folder", a->folder, "output folder of rubdyn run")->required();
  sub->add_option("--out", a->out, "where to write (default FOLDER/analysis)")
      ->check(non_empty_path());
  sub->add_option("--t-window", a->window_t, "analyse [t0, t1] only")->expected(2);
  sub->add_option("--window", a->o.window, "spectrogram frame length [s] (default 0.04)");
  sub->add_option("--overlap", a->o.overlap, "spectrogram frame overlap in [0, 1) (0.75)");
  sub->add_option("--pad", a->o.pad, "zero-padding factor of each frame (4)");
  sub->add_option("--fmax", a->o.f_max, "largest |f| written [Hz] (2000)");
  sub->add_option("--min-turns", a->o.min_turns,
                  "sustained whirl: orbit revolutions in one run (default 1)");
  sub->callback([a, &action] { action = [a] { return analyze_command(*a); }; });
}

}  // namespace rubdyn::app
