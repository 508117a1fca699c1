#include "rubdyn/io/json_reader.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstdlib>
#include <string>

namespace rubdyn {

const JsonValue* JsonValue::find(std::string_view key) const {
  if (kind != Kind::Object) return nullptr;
  for (const auto& [k, v] : object)
    if (k == key) return &v;
  return nullptr;
}

JsonError::JsonError(int line, int column, const std::string& what)
    : std::runtime_error(fmt::format("line {}, column {}: {}", line, column, what)),
      line_(line),
      column_(column) {}

namespace {

/// Nesting deeper than this is refused (a hostile file cannot exhaust the stack).
constexpr int kMaxDepth = 64;

class Parser {
 public:
  explicit Parser(std::string_view t) : t_(t) {}

  JsonValue document() {
    JsonValue v = value(0);
    space();
    if (i_ != t_.size()) fail("the end of the text after the value");
    return v;
  }

 private:
  [[noreturn]] void fail(const std::string& expected) const {
    int line = 1, column = 1;
    for (std::size_t k = 0; k < i_ && k < t_.size(); ++k) {
      if (t_[k] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
    throw JsonError(line, column, "expected " + expected);
  }

  void space() {
    while (i_ < t_.size() && (t_[i_] == ' ' || t_[i_] == '\t' || t_[i_] == '\n' || t_[i_] == '\r'))
      ++i_;
  }

  bool literal(std::string_view word) {
    if (t_.substr(i_, word.size()) != word) return false;
    i_ += word.size();
    return true;
  }

  JsonValue value(int depth) {
    if (depth > kMaxDepth) fail(fmt::format("at most {} nested arrays and objects", kMaxDepth));
    space();
    if (i_ >= t_.size()) fail("a value");
    JsonValue v;
    const char c = t_[i_];
    if (c == '{') {
      v.kind = JsonValue::Kind::Object;
      ++i_;
      space();
      if (i_ < t_.size() && t_[i_] == '}') {
        ++i_;
        return v;
      }
      for (;;) {
        space();
        if (i_ >= t_.size() || t_[i_] != '"') fail("a member name (a string)");
        std::string key = string();
        space();
        if (i_ >= t_.size() || t_[i_] != ':') fail("':' after a member name");
        ++i_;
        v.object.emplace_back(std::move(key), value(depth + 1));
        space();
        if (i_ < t_.size() && t_[i_] == ',') {
          ++i_;
          continue;
        }
        if (i_ < t_.size() && t_[i_] == '}') {
          ++i_;
          return v;
        }
        fail("',' or '}' in an object");
      }
    }
    if (c == '[') {
      v.kind = JsonValue::Kind::Array;
      ++i_;
      space();
      if (i_ < t_.size() && t_[i_] == ']') {
        ++i_;
        return v;
      }
      for (;;) {
        v.array.push_back(value(depth + 1));
        space();
        if (i_ < t_.size() && t_[i_] == ',') {
          ++i_;
          continue;
        }
        if (i_ < t_.size() && t_[i_] == ']') {
          ++i_;
          return v;
        }
        fail("',' or ']' in an array");
      }
    }
    if (c == '"') {
      v.kind = JsonValue::Kind::String;
      v.string = string();
      return v;
    }
    if (literal("true")) {
      v.kind = JsonValue::Kind::Bool;
      v.boolean = true;
      return v;
    }
    if (literal("false")) {
      v.kind = JsonValue::Kind::Bool;
      return v;
    }
    if (literal("null")) return v;
    v.kind = JsonValue::Kind::Number;
    v.number = number();
    return v;
  }

  /// JSON's number grammar, converted by strtod (correctly rounded).
  double number() {
    const std::size_t start = i_;
    auto digits = [&] {
      const std::size_t s = i_;
      while (i_ < t_.size() && t_[i_] >= '0' && t_[i_] <= '9') ++i_;
      return i_ > s;
    };
    if (i_ < t_.size() && t_[i_] == '-') ++i_;
    if (i_ < t_.size() && t_[i_] == '0') {
      ++i_;
    } else if (!digits()) {
      i_ = start;
      fail("a value (an object, array, string, number, true, false or null)");
    }
    if (i_ < t_.size() && t_[i_] == '.') {
      ++i_;
      if (!digits()) fail("digits after the decimal point");
    }
    if (i_ < t_.size() && (t_[i_] == 'e' || t_[i_] == 'E')) {
      ++i_;
      if (i_ < t_.size() && (t_[i_] == '+' || t_[i_] == '-')) ++i_;
      if (!digits()) fail("digits in the exponent");
    }
    const std::string s(t_.substr(start, i_ - start));
    errno = 0;
    const double x = std::strtod(s.c_str(), nullptr);
    if (errno == ERANGE && (x > 1.0 || x < -1.0)) {
      i_ = start;
      fail("a number within the range of a double");
    }
    return x;
  }

  unsigned hex4() {
    unsigned u = 0;
    for (int k = 0; k < 4; ++k, ++i_) {
      if (i_ >= t_.size()) fail("four hexadecimal digits after \\u");
      const char h = t_[i_];
      u *= 16;
      if (h >= '0' && h <= '9')
        u += static_cast<unsigned>(h - '0');
      else if (h >= 'a' && h <= 'f')
        u += static_cast<unsigned>(h - 'a' + 10);
      else if (h >= 'A' && h <= 'F')
        u += static_cast<unsigned>(h - 'A' + 10);
      else
        fail("four hexadecimal digits after \\u");
    }
    return u;
  }

  static void utf8(unsigned cp, std::string& out) {
    if (cp < 0x80) {
      out += static_cast<char>(cp);
    } else if (cp < 0x800) {
      out += static_cast<char>(0xC0 | (cp >> 6));
      out += static_cast<char>(0x80 | (cp & 0x3F));
    } else if (cp < 0x10000) {
      out += static_cast<char>(0xE0 | (cp >> 12));
      out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (cp & 0x3F));
    } else {
      out += static_cast<char>(0xF0 | (cp >> 18));
      out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
      out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (cp & 0x3F));
    }
  }

  std::string string() {
    ++i_;  // the opening quote
    std::string out;
    for (;;) {
      if (i_ >= t_.size()) fail("the closing '\"' of a string");
      const char c = t_[i_++];
      if (c == '"') return out;
      if (static_cast<unsigned char>(c) < 0x20) {
        --i_;
        fail("no control character inside a string (escape it)");
      }
      if (c != '\\') {
        out += c;
        continue;
      }
      if (i_ >= t_.size()) fail("an escape after '\\'");
      const char e = t_[i_++];
      switch (e) {
        case '"': out += '"'; break;
        case '\\': out += '\\'; break;
        case '/': out += '/'; break;
        case 'b': out += '\b'; break;
        case 'f': out += '\f'; break;
        case 'n': out += '\n'; break;
        case 'r': out += '\r'; break;
        case 't': out += '\t'; break;
        case 'u': {
          unsigned cp = hex4();
          if (cp >= 0xD800 && cp <= 0xDBFF) {  // a surrogate pair
            if (!literal("\\u")) fail("the low surrogate of a surrogate pair");
            const unsigned lo = hex4();
            if (lo < 0xDC00 || lo > 0xDFFF) fail("a low surrogate (\\uDC00 to \\uDFFF)");
            cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
          } else if (cp >= 0xDC00 && cp <= 0xDFFF) {
            fail("no lone low surrogate");
          }
          utf8(cp, out);
          break;
        }
        default: --i_; fail("one of the escapes \\\" \\\\ \\/ \\b \\f \\n \\r \\t \\uXXXX");
      }
    }
  }

  std::string_view t_;
  std::size_t i_ = 0;
};

}  // namespace

JsonValue parse_json(std::string_view text) {
  return Parser(text).document();
}

}  // namespace rubdyn
