#pragma once
// cases/two-plane.toml with the ring of plane 1 and/or plane 2 replaced by a fixed ring
// (stator_rigid = true: no mass, spring, damper or coordinates), as a case text: the K-contact
// chart's fixed-ring elimination (contact/ring_chart.hpp) is exercised on it.
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

namespace rubdyn::testing {

inline std::string two_plane_fixed_rings_text(bool fixed1, bool fixed2) {
  std::ifstream f(RUBDYN_SOURCE_DIR "/cases/two-plane.toml");
  std::string s{std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
  std::size_t at = 0;
  for (const bool fixed : {fixed1, fixed2}) {
    at = s.find("\n[[plane]]", at);  // a table header (the file's comments name [[plane]] too)
    if (at == std::string::npos) throw std::logic_error("two-plane.toml: a [[plane]] is missing");
    at += 10;
    if (!fixed) continue;
    for (const char* key : {"stator_mass", "stator_k ", "stator_c "}) {
      const std::size_t b = s.find(key, at), e = s.find('\n', b);
      if (b == std::string::npos || e == std::string::npos)
        throw std::logic_error(std::string("two-plane.toml: no ") + key);
      s.erase(b, e + 1 - b);
    }
    s.insert(s.find('\n', s.find("mu ", at)) + 1, "stator_rigid = true\n");
  }
  return s;
}

}  // namespace rubdyn::testing
