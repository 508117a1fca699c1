// Matrix files (CSV, NumPy .npy) of a user's linear rotor: io/matrix_files.hpp.
#include "rubdyn/io/matrix_files.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string_view>
#include <vector>

#include "rubdyn/io/text_files.hpp"

namespace rubdyn {

namespace {

[[noreturn]] void fail(const std::string& why) {
  throw MatrixFileError(why);
}

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

std::string read_bytes(const std::string& path) {
  try {
    return read_input_file(path, kMaxMatrixFileBytes, "matrix");
  } catch (const InputRefused& e) {
    fail(e.what());
  }
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

/// Why a field that std::from_chars refused is no number: its magnitude out of a double's
/// range, or not a number at all (its bytes shown printable: a Latin-1 byte as \xB5).
std::string not_a_number(std::string_view field, std::errc ec) {
  const std::string shown = printable_text(field, 60);
  if (ec == std::errc::result_out_of_range) {
    // (from_chars says out of range for an overflow and for an underflow to zero; strtod tells
    // which: +-HUGE_VAL or 0)
    const std::string copy(field);
    const double x = std::strtod(copy.c_str(), nullptr);
    if (std::isinf(x))
      return fmt::format("{} is outside the range of a double (magnitude at most {:.17g})", shown,
                         std::numeric_limits<double>::max());
    return fmt::format(
        "{} is below the smallest double ({:.2g}) in magnitude and would be read as 0: write 0 "
        "if zero is meant",
        shown, std::numeric_limits<double>::denorm_min());
  }
  if (!valid_utf8(field))
    return fmt::format(
        "'{}' is not a number, and not UTF-8 text: a byte shown as \\xHH belongs to another "
        "encoding (Latin-1?); save the file as UTF-8 or ASCII",
        shown);
  return fmt::format("'{}' is not a number (CSV: numbers separated by commas, no header)", shown);
}

Mat parse_csv(std::string_view text) {
  // a file of another format named as CSV: said, rather than 'not a number' with its bytes
  if (text.substr(0, 6) == std::string_view("\x93NUMPY", 6))
    fail(
        "holds NumPy .npy data (it starts with \\x93NUMPY) but its name does not end in .npy: "
        "rename it (the format is chosen by the file name's ending)");
  if (text.find('\0') != std::string_view::npos)
    fail(
        fmt::format("holds a NUL byte (at byte {}): a binary file, not CSV text", text.find('\0')));
  // a UTF-8 byte order mark (spreadsheets write one) carries no data: skipped
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  std::vector<std::vector<double>> rows;
  std::size_t line_no = 0, pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    const std::string_view line = trim(std::string_view(text).substr(pos, end - pos));
    pos = end + 1;
    ++line_no;
    if (line.empty() || line.front() == '#') continue;
    std::vector<double> row;
    std::size_t a = 0;
    for (int col = 1;; ++col) {
      std::size_t b = line.find(',', a);
      if (b == std::string_view::npos) b = line.size();
      std::string_view field = trim(line.substr(a, b - a));
      const std::string_view shown = field;
      if (!field.empty() && field.front() == '+') field.remove_prefix(1);
      double x = 0.0;
      const auto r = std::from_chars(field.data(), field.data() + field.size(), x);
      if (field.empty() || r.ptr != field.data() + field.size() ||
          (r.ec != std::errc() && r.ec != std::errc::result_out_of_range))
        fail(fmt::format("line {}, column {}: {}", line_no, col,
                         not_a_number(shown, std::errc::invalid_argument)));
      if (r.ec != std::errc())
        fail(fmt::format("line {}, column {}: {}", line_no, col, not_a_number(shown, r.ec)));
      if (!std::isfinite(x))
        fail(fmt::format("line {}, column {}: {} is not finite", line_no, col,
                         printable_text(shown, 60)));
      row.push_back(x);
      if (b == line.size()) break;
      a = b + 1;
    }
    if (!rows.empty() && row.size() != rows.front().size())
      fail(
          fmt::format("line {}: {} numbers, where the first row has {} (every row must have "
                      "the same count)",
                      line_no, row.size(), rows.front().size()));
    rows.push_back(std::move(row));
  }
  if (rows.empty()) fail("holds no numbers");
  Mat m(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(rows.front().size()));
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (std::size_t j = 0; j < rows[i].size(); ++j)
      m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = rows[i][j];
  // one number per row: a column
  return m;
}

/// The value of 'key': ... in a .npy header dictionary (the text up to the next ',' or '}' at
/// the same nesting level), or "" when absent.
std::string header_value(const std::string& h, const std::string& key) {
  std::size_t k = h.find("'" + key + "'");
  if (k == std::string::npos) k = h.find("\"" + key + "\"");
  if (k == std::string::npos) return "";
  std::size_t c = h.find(':', k);
  if (c == std::string::npos) return "";
  std::size_t i = c + 1, depth = 0;
  std::string v;
  for (; i < h.size(); ++i) {
    const char ch = h[i];
    if (ch == '(') ++depth;
    if (ch == ')') --depth;
    if (depth == 0 && (ch == ',' || ch == '}')) break;
    v += ch;
  }
  return std::string(trim(v));
}

Mat parse_npy(const std::string& bytes) {
  static const char magic[] = "\x93NUMPY";
  if (bytes.size() < 10 || bytes.compare(0, 6, magic, 6) != 0)
    fail("not a NumPy .npy file (no \\x93NUMPY magic string)");
  const auto u8 = [&](std::size_t i) {
    return static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i]));
  };
  const unsigned major = u8(6);
  std::size_t hlen = 0, start = 0;
  if (major == 1) {
    hlen = u8(8) | (u8(9) << 8);
    start = 10;
  } else if (major == 2 || major == 3) {
    if (bytes.size() < 12) fail("a truncated .npy header");
    hlen = u8(8) | (u8(9) << 8) | (u8(10) << 16) | (u8(11) << 24);
    start = 12;
  } else {
    fail(fmt::format(".npy format version {} (versions 1 to 3 are read)", major));
  }
  if (start + hlen > bytes.size()) fail("a truncated .npy header");
  const std::string h = bytes.substr(start, hlen);
  // the header is a Python literal in ASCII (NumPy's format): another byte is no .npy header,
  // and is never echoed raw in a message
  for (std::size_t i = 0; i < h.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(h[i]);
    if ((c < 0x20 && c != '\n' && c != '\t') || c >= 0x7f)
      fail(
          fmt::format("the .npy header holds the byte \\x{:02X} at offset {}: not ASCII text, "
                      "not a NumPy .npy header",
                      static_cast<unsigned>(c), start + i));
  }
  const std::string descr = header_value(h, "descr");
  if (descr != "'<f8'" && descr != "\"<f8\"")
    fail(
        fmt::format("dtype {} (must be float64, little-endian: '<f8'; numpy: "
                    "a.astype('<f8'))",
                    descr.empty() ? "(none)" : descr));
  const std::string order = header_value(h, "fortran_order");
  if (order != "True" && order != "False")
    fail("no fortran_order True or False in the .npy header");
  std::string shape = header_value(h, "shape");
  if (shape.size() < 2 || shape.front() != '(' || shape.back() != ')')
    fail("no shape tuple in the .npy header");
  shape = shape.substr(1, shape.size() - 2);
  std::vector<long> dims;
  std::size_t a = 0;
  while (a < shape.size()) {
    std::size_t b = shape.find(',', a);
    if (b == std::string::npos) b = shape.size();
    const std::string_view f = trim(std::string_view(shape).substr(a, b - a));
    if (!f.empty()) {
      long d = -1;
      const auto r = std::from_chars(f.data(), f.data() + f.size(), d);
      if (r.ec != std::errc() || r.ptr != f.data() + f.size() || d < 0)
        fail(fmt::format("shape ({}) in the .npy header is not a tuple of sizes", shape));
      dims.push_back(d);
    }
    a = b + 1;
  }
  if (dims.empty() || dims.size() > 2)
    fail(fmt::format("a {}-D array (a matrix file holds a 1-D or 2-D array)", dims.size()));
  const long rows = dims[0], cols = dims.size() == 2 ? dims[1] : 1;
  const std::size_t data = start + hlen;
  // the data the shape declares, in bytes, without overflow (a header may declare 2^32 x 2^32
  // entries, whose byte count wraps around to 0 in 64 bits)
  std::size_t want = 0;
  if (__builtin_mul_overflow(static_cast<std::size_t>(rows), static_cast<std::size_t>(cols),
                             &want) ||
      __builtin_mul_overflow(want, std::size_t{8}, &want))
    fail(fmt::format(
        "shape ({}) in the .npy header declares {:.3g} entries of float64, more than "
        "any file holds (this one has {} bytes of data)",
        shape, static_cast<double>(rows) * static_cast<double>(cols), bytes.size() - data));
  if (bytes.size() - data != want)
    fail(fmt::format("{} bytes of data where shape ({}) of float64 needs {}", bytes.size() - data,
                     shape, want));
  if (rows == 0 || cols == 0) fail("an empty array");
  Mat m(rows, cols);
  const bool fortran = order == "True";
  for (long k = 0; k < rows * cols; ++k) {
    std::uint64_t bits = 0;
    for (int b = 0; b < 8; ++b)
      bits |= static_cast<std::uint64_t>(u8(data + static_cast<std::size_t>(k) * 8 + b)) << (8 * b);
    double x;
    std::memcpy(&x, &bits, sizeof x);
    const long i = fortran ? k % rows : k / cols, j = fortran ? k / rows : k % cols;
    if (!std::isfinite(x)) fail(fmt::format("entry ({}, {}) is {}: not finite", i, j, x));
    m(i, j) = x;
  }
  return m;
}

}  // namespace

Mat parse_matrix(const std::string& bytes, bool npy) {
  return npy ? parse_npy(bytes) : parse_csv(bytes);
}

Mat read_matrix_file(const std::string& path) {
  return parse_matrix(read_bytes(path), ends_with(path, ".npy"));
}

std::string npy_bytes(const Mat& m, bool column) {
  const std::string shape = column && m.cols() == 1 ? fmt::format("({},)", m.rows())
                                                    : fmt::format("({}, {})", m.rows(), m.cols());
  std::string header =
      fmt::format("{{'descr': '<f8', 'fortran_order': False, 'shape': {}, }}", shape);
  // numpy pads the header with spaces and a line end so that the data start on a multiple of
  // 64 bytes (10 bytes of magic, version and length before it)
  header.append(63 - (10 + header.size()) % 64, ' ');
  header += '\n';
  std::string out("\x93NUMPY\x01\x00", 8);
  out += static_cast<char>(header.size() & 0xff);
  out += static_cast<char>((header.size() >> 8) & 0xff);
  out += header;
  out.reserve(out.size() + 8 * static_cast<std::size_t>(m.size()));
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) {
      std::uint64_t bits = 0;
      const double x = m(i, j);
      std::memcpy(&bits, &x, sizeof x);
      for (int b = 0; b < 8; ++b) out += static_cast<char>((bits >> (8 * b)) & 0xff);
    }
  return out;
}

}  // namespace rubdyn
