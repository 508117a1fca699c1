#pragma once
// Loading, validating and writing case files (TOML). The ONLY place that knows TOML.
//
// Every problem in a case is collected and reported at once in a CaseError: each issue names the
// file, line, key (section.key), value and the rule it breaks. Unknown sections and keys are
// errors (a typo is never silently ignored); so are missing required keys, wrong types and
// non-finite numbers. Overrides "section.key=value" (CLI --set) are applied on top of the file and
// validated the same way (their issues name "--set" as the file).
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "rubdyn/io/case_spec.hpp"

namespace rubdyn {

/// Largest number of timeseries rows a case may ask for (t_end / output.dt, or the fixed-step
/// count / output.every): 1e8 rows are about 42 GB. More is refused as bad input.
inline constexpr long kMaxOutputRows = 100'000'000;

/// A case file is read up to this size (1 MiB; the reference case is 2 kB): a larger file, or
/// a device such as /dev/zero, is refused rather than read without end; a FIFO (`rubdyn check
/// <(gen-case)`) is read with a bounded wait for its writer (io/text_files.hpp).
inline constexpr std::size_t kMaxCaseBytes = 1 << 20;

/// The matrices a case of kind "matrices" read, by the path of their file as resolved
/// (absolute), as the file held them. A case parsed with a snapshot takes a file found there
/// instead of reading it again, and adds what it reads: a case made again from the same text
/// (the Python Case with more overrides) is then a snapshot of its matrix files too.
using MatrixSnapshot = std::map<std::string, Mat>;

/// Reads, overrides, validates. Throws CaseError (every problem listed) on bad input.
CaseSpec load_case(const std::string& path, const std::vector<std::string>& overrides = {});

/// The text of a case file (what load_case parses; read once, as a FIFO can be). Throws
/// CaseError naming the file: not readable, not a regular file or FIFO, too large, NUL bytes.
std::string read_case_file(const std::string& path);

/// Same, from TOML text; `source` is the name used in messages (tests, stdin) and the file whose
/// folder relative matrix paths start from. With `snapshot`, matrix files are taken from it when
/// there and added to it when read (MatrixSnapshot).
CaseSpec parse_case(std::string_view toml_text, const std::string& source,
                    const std::vector<std::string>& overrides = {},
                    MatrixSnapshot* snapshot = nullptr);

/// The case as TOML with every default and override filled in (case.resolved.toml). Reading it
/// back with parse_case gives the same CaseSpec (numbers are written with 17 significant digits).
std::string to_toml(const CaseSpec& c);

/// case.resolved.toml as a run folder holds it (output_folder.hpp): to_toml(c), with the matrix
/// files of a case of kind "matrices" named by their copies beside it (case_matrix_files), so
/// that the folder stands alone: it reads back after the folder is moved or copied and the
/// original files are gone. For other kinds it is to_toml(c).
std::string resolved_toml(const CaseSpec& c);

/// The copies of a case's matrix files that a run folder holds beside case.resolved.toml: for
/// each matrix the case read (kind "matrices": M, C, K, G, and f0 when given), its file name
/// (case_matrix_file) and the matrix as .npy bytes, which read back bit for bit. Empty for other
/// kinds. With resolved_toml, the whole identity of a run's case (what sweep --resume compares
/// and the sweep plan hash holds): a matrix file changed on disk is another case.
std::vector<std::pair<std::string, std::string>> case_matrix_files(const CaseSpec& c);
/// The name of the copy of the matrix of rotor key `key` (M, C, K, G, f0): "case.<key>.npy".
std::string case_matrix_file(std::string_view key);
/// The rotor keys whose matrices a run folder may hold copies of, in the order written.
inline constexpr const char* kCaseMatrixKeys[] = {"M", "C", "K", "G", "f0"};

/// `text` as a TOML basic string, quotes included: ", \\ and every control character escaped,
/// so that parsing it gives `text` back (case.resolved.toml, and --out / --set values that are
/// paths, never read as TOML escapes).
std::string toml_quote(std::string_view text);

/// Every key ("section.key") a case of c's model may hold with c's settings (stator.rigid,
/// loads.spin, loads.torque_law), in the order of case.resolved.toml: the schema of
/// io/case_toml.cpp, for documentation and its test.
std::vector<std::string> case_keys(const CaseSpec& c);

/// One key of a case with its value (numbers as double, integers as int, choices as their word).
struct CaseEntry {
  std::string section, key;
  std::variant<double, int, bool, std::string> value;
  std::string full() const { return section + "." + key; }
};
/// Every key of the case with its value, in the order of case.resolved.toml (to_toml writes
/// them; the Python Case reads them).
std::vector<CaseEntry> case_values(const CaseSpec& c);

/// The output folder of a case: output.folder if set, else "out/<name>". Throws CaseError when
/// the name cannot name one folder under out/ (empty, ".", ".." or with a "/").
std::string output_folder(const CaseSpec& c);

}  // namespace rubdyn
