#pragma once
// A strict reader of the JSON that rubdyn writes itself (branch.json, orbit.json, ...), for the
// commands that continue from an output folder (rubdyn branch --resume / --switch): objects,
// arrays, strings (with every JSON escape), numbers, true, false, null. Not a general-purpose
// JSON library: no streaming, the document is held as a tree.
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace rubdyn {

struct JsonValue {
  enum class Kind { Null, Bool, Number, String, Array, Object };
  Kind kind = Kind::Null;
  bool boolean = false;
  double number = 0.0;
  std::string string;
  std::vector<JsonValue> array;
  std::vector<std::pair<std::string, JsonValue>> object;  ///< in the file's order

  /// The member `key` of an object (nullptr: none, or not an object).
  const JsonValue* find(std::string_view key) const;
};

/// A text that is not JSON: the message says where (line and column) and what was expected.
class JsonError : public std::runtime_error {
 public:
  JsonError(int line, int column, const std::string& what);
  int line() const { return line_; }
  int column() const { return column_; }

 private:
  int line_, column_;
};

/// Parses the whole of `text` (one value, surrounded by white space only). Throws JsonError.
JsonValue parse_json(std::string_view text);

}  // namespace rubdyn
