// The JSON reader of rubdyn's own files (io/json_reader.hpp): what branch --resume / --switch
// read back. Values, escapes and the errors' positions, against texts written here by hand.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "rubdyn/io/json_reader.hpp"

using namespace rubdyn;

TEST_CASE("json reader: objects, arrays, numbers, literals and escapes", "[io][json]") {
  const JsonValue v = parse_json(
      "{\n  \"a\": [1, -2.5e-3, 0, 1E+2],\n  \"b\": {\"t\": true, \"f\": false, \"n\": null},\n"
      "  \"s\": \"q\\\" b\\\\ n\\n t\\t u\\u00e9 pair\\ud83d\\ude00 /\\/\",\n  \"e\": []\n}\n");
  REQUIRE(v.kind == JsonValue::Kind::Object);
  const JsonValue* a = v.find("a");
  REQUIRE(a);
  REQUIRE(a->array.size() == 4);
  CHECK(a->array[0].number == 1.0);
  CHECK(a->array[1].number == -2.5e-3);
  CHECK(a->array[2].number == 0.0);
  CHECK(a->array[3].number == 100.0);
  const JsonValue* b = v.find("b");
  REQUIRE(b);
  CHECK(b->find("t")->boolean);
  CHECK(b->find("f")->kind == JsonValue::Kind::Bool);
  CHECK_FALSE(b->find("f")->boolean);
  CHECK(b->find("n")->kind == JsonValue::Kind::Null);
  CHECK(b->find("missing") == nullptr);
  // U+00E9 is C3 A9 in UTF-8, the pair D83D DE00 is U+1F600: F0 9F 98 80
  CHECK(v.find("s")->string == "q\" b\\ n\n t\t u\xC3\xA9 pair\xF0\x9F\x98\x80 //");
  CHECK(v.find("e")->array.empty());
  // the 17 significant digits rubdyn writes read back to the same double
  const double x = 0.1 + 0.2;
  CHECK(parse_json("[0.30000000000000004]").array[0].number == x);
}

TEST_CASE("json reader: malformed texts are refused with their line and column", "[io][json]") {
  struct Bad {
    const char* text;
    int line, column;
  };
  for (const Bad& bad :
       {Bad{"{\"a\": 1,}", 1, 9}, Bad{"[1, 2", 1, 6}, Bad{"{\n  \"a\" 1}", 2, 7}, Bad{"[01]", 1, 3},
        Bad{"[1.]", 1, 4}, Bad{"\"ab", 1, 4}, Bad{"[\"\\x\"]", 1, 4}, Bad{"[\"\\ud800\"]", 1, 9},
        Bad{"[nul]", 1, 2}, Bad{"{} x", 1, 4}, Bad{"[1e999]", 1, 2}, Bad{"", 1, 1},
        Bad{"[\"a\nb\"]", 1, 4}}) {
    INFO(bad.text);
    try {
      parse_json(bad.text);
      FAIL("accepted");
    } catch (const JsonError& e) {
      INFO(e.what());
      CHECK(e.line() == bad.line);
      CHECK(e.column() == bad.column);
    }
  }
  // nesting beyond 64 levels is refused (a hostile file cannot exhaust the stack)
  CHECK_THROWS_AS(parse_json(std::string(100, '[') + std::string(100, ']')), JsonError);
  CHECK_NOTHROW(parse_json(std::string(60, '[') + std::string(60, ']')));
}
