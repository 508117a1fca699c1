// An override sets one key: a line end (or another control character) in its text would let
// the TOML value carry more keys ("contact.mu=0.3\ncontact.e_n=0.5"), which the loader read as
// mu = 0.3 and silently dropped the rest. It is refused for the CLI's --set and Python alike.
#include <catch2/catch.hpp>
#include <string>
#include <vector>

#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"

using namespace rubdyn;

namespace {
const std::string kRef = std::string(RUBDYN_SOURCE_DIR) + "/cases/reference.toml";
}

TEST_CASE("Overrides: a line end or control character in --set is refused", "[case][unit]") {
  for (const std::string& ov :
       {std::string("contact.mu=0.3\ncontact.e_n=0.5"), std::string("contact.mu=0.3\r"),
        std::string("contact.mu=0.3\x1b"), std::string("contact.mu=0.3\x7f"),
        std::string("contact.mu=0.3\0", 15)}) {
    INFO(ov.size());
    try {
      load_case(kRef, {ov});
      FAIL("accepted");
    } catch (const CaseError& e) {
      REQUIRE(e.issues().size() == 1);
      const CaseIssue& i = e.issues()[0];
      CHECK(i.file == "--set");
      CHECK(i.rule == "an override is one line: no line end or other control character");
      CHECK(i.value == toml_quote(ov));  // escaped: the message itself is one line per issue
    }
  }
  // the same override on one line is accepted, and a tab is whitespace
  CHECK(load_case(kRef, {"contact.mu=0.3"}).contact().mu == 0.3);
  CHECK(load_case(kRef, {"contact.mu=\t0.3"}).contact().mu == 0.3);
}
