#pragma once
// The reference rotor (cases/reference.toml) with its ring split into two identical half rings
// at the same plane (half the mass, spring and damper each, the same gap and law), as a case
// text: every impact hits both at the same instant and the two contacts are redundant (equal
// rows of the Delassus matrix: the motion is determinate, the split of the force is not). Every
// solver must give the one-ring run.
#include <fstream>
#include <iterator>
#include <string>

namespace rubdyn::testing {

inline std::string split_ring_case_text() {
  std::ifstream f(RUBDYN_SOURCE_DIR "/cases/reference.toml");
  std::string s{std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
  s.erase(s.find("radius = 0.05"),
          s.find('\n', s.find("radius = 0.05")) + 1 - s.find("radius = 0.05"));
  const std::string half =
      "[[plane]]\nposition = 0.4\nradius = 0.05\ngap = 2.0e-4\nmu = 0.1\nstator_mass = 1.0\n"
      "stator_k = 1.0e6\nstator_c = 50.0\n\n";
  s.replace(s.find("[stator]"), s.find("[loads]") - s.find("[stator]"), half + half);
  return s;
}

}  // namespace rubdyn::testing
