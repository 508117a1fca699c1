#pragma once
// What the tests that run the rubdyn CLI share: scratch folders, reading a file back, quoting for
// /bin/sh, and running `rubdyn ARGS` with its exit code, standard output and standard error.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace rubdyn::testing {

/// An empty path under the temporary folder, named after `tag` and this process (ctest runs
/// every test case in its own process: two test cases never share one).
inline std::filesystem::path fresh_dir(const std::string& tag) {
  const std::filesystem::path d = std::filesystem::temp_directory_path() /
                                  ("rubdyn-test-" + tag + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  return d;
}

/// A file's bytes ("" when it cannot be read).
inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Quotes one argument for /bin/sh.
inline std::string sh(const std::string& a) {
  std::string q = "'";
  for (char c : a) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

/// The fields of one CSV line as written (split at commas; rubdyn's numeric files quote nothing).
inline std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  for (std::string f; std::getline(in, f, ',');) out.push_back(f);
  return out;
}

/// A text's lines (without their line ends).
inline std::vector<std::string> text_lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

inline bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

struct CliOutcome {
  int code = -1;  ///< exit code (-1: killed by a signal)
  std::string out, err;
};

/// Runs `prefix rubdyn ARGS` through /bin/sh (ARGS already quoted with sh(); prefix: shell
/// commands before it, e.g. "ulimit -f 100; "), keeping the exit code, stdout and stderr.
inline CliOutcome cli(const std::string& args, const std::string& prefix = "") {
  const std::filesystem::path out = fresh_dir("stdout"), err = fresh_dir("stderr");
  const std::string cmd = prefix + std::string(RUBDYN_CLI) + " " + args + " > " + sh(out.string()) +
                          " 2> " + sh(err.string());
  const int st = std::system(cmd.c_str());
  CliOutcome o;
  o.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  o.out = slurp(out);
  o.err = slurp(err);
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  return o;
}

}  // namespace rubdyn::testing
