#pragma once
// Small text-file helpers shared by the readers and writers of output folders.
#include <string>
#include <vector>

namespace rubdyn {

/// Splits one CSV line (RFC 4180 quoting: "a,b" is one field, "" inside quotes is a quote; a
/// trailing \r is dropped).
std::vector<std::string> split_csv_line(const std::string& line);

/// Writes `text` to path + ".tmp" and renames it to `path`, so that a reader (or a failure) never
/// sees a half-written file. Throws std::runtime_error naming the path.
void write_file_atomic(const std::string& path, const std::string& text);

}  // namespace rubdyn
