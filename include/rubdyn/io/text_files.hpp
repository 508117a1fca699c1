#pragma once
// Small text-file helpers shared by the readers and writers of output folders.
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rubdyn {

/// A file could not be written (the message names it): the CLI exits 5.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Splits one CSV line (RFC 4180 quoting: "a,b" is one field, "" inside quotes is a quote; a
/// trailing \r is dropped).
std::vector<std::string> split_csv_line(const std::string& line);

/// `text` as a double-quoted string that is both a TOML basic string and a JSON string: quote,
/// backslash, newline, tab and carriage return escaped with a backslash, every other control
/// character (and DEL) as a \u00XX escape, any other byte as is.
std::string quoted_string(std::string_view text);

/// rubdyn ends every row it writes with a line end: a last row without one was cut by a kill
/// (or a full disk) and may hold a truncated number. Readers drop it with this warning.
std::string cut_row_warning(const std::string& file, long line);

/// Writes `text` to path + ".tmp" and renames it to `path`, so that a reader (or a failure) never
/// sees a half-written file. Every step is checked (open, write, flush, close, rename). Throws
/// OutputError naming the path.
void write_file_atomic(const std::string& path, const std::string& text);

}  // namespace rubdyn
