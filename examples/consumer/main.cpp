// Runs a case file through rubdyn's C++ API and prints omega at the end:
//   consumer CASE.toml [section.key=value ...]
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "rubdyn/driver/simulate.hpp"
#include "rubdyn/io/case_io.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s CASE.toml [section.key=value ...]\n", argv[0]);
    return 2;
  }
  try {
    const std::vector<std::string> overrides(argv + 2, argv + argc);
    const rubdyn::CaseSpec spec = rubdyn::load_case(argv[1], overrides);
    rubdyn::MemorySink sink;  // every sample and event in memory
    const rubdyn::RunSummary s = rubdyn::simulate(spec, sink);
    std::printf("termination %s\n", std::string(rubdyn::to_string(s.termination)).c_str());
    std::printf("t %.17g s\nomega %.17g rad/s\nevents %zu\n", s.t_reached, s.omega_final,
                sink.events.size());
    return s.complete() ? 0 : 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
}
