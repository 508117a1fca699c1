// The one reader of rubdyn's CSV output (io/output_reader.hpp): what a killed run leaves is
// tolerated with a warning, anything else malformed names the file and the line.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "rubdyn/io/output_reader.hpp"

using namespace rubdyn;

namespace {
std::string write(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::temp_directory_path() / "rubdyn_output_reader_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}
}  // namespace

TEST_CASE("read_csv: rows, columns, a cut last row dropped with a warning", "[io][unit]") {
  const std::string p = write("cut.csv", "t,x,kind\n0,1,\"a,b\"\n0.5,2,c\n1,3");
  const CsvTable t = read_csv(p);
  CHECK(t.header == std::vector<std::string>{"t", "x", "kind"});
  REQUIRE(t.rows.size() == 2);
  CHECK(t.rows[0][2] == "a,b");  // RFC 4180 quoting
  CHECK(t.line_of[1] == 3);
  CHECK(t.column("x") == 1);
  CHECK(t.column("y") == -1);
  REQUIRE(t.warnings.size() == 1);
  CHECK(t.warnings[0].find(p + ":4:") == 0);
  double x = 0;
  CHECK(parse_number(t.rows[1][0], x));
  CHECK(x == 0.5);
  CHECK_FALSE(parse_number("1.5e", x));
  CHECK_FALSE(parse_number("", x));
}

TEST_CASE("read_csv: a wrong field count names the line, and an empty file", "[io][unit]") {
  const std::string bad = write("bad.csv", "t,x\n0,1\n0.5,2,3\n");
  CHECK_THROWS_WITH(read_csv(bad), Catch::Contains(bad + ":3: 3 fields, the header has 2"));
  const std::string empty = write("empty.csv", "");
  CHECK_THROWS_WITH(read_csv(empty), Catch::Contains(empty + ":1: empty file"));
  const CsvTable e = read_csv(empty, true);  // a killed run's events.csv
  CHECK(e.rows.empty());
  CHECK(e.warnings.size() == 1);
  CHECK_THROWS_WITH(read_csv(empty + ".none"), Catch::Contains("cannot read"));
}
