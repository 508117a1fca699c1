// A case as a run folder holds it: case.resolved.toml and the copies of its matrix files
// (io/case_io.hpp: resolved_toml, case_matrix_files).
#include <fmt/format.h>

#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/matrix_files.hpp"

namespace rubdyn {

std::string case_matrix_file(std::string_view key) {
  return fmt::format("case.{}.npy", key);
}

namespace {

/// The file key of the case's matrix files (empty: not given), in kCaseMatrixKeys' order.
std::string* file_of(MatrixFiles& f, std::string_view key) {
  return key == "M"    ? &f.M
         : key == "C"  ? &f.C
         : key == "K"  ? &f.K
         : key == "G"  ? &f.G
         : key == "f0" ? &f.f0
                       : nullptr;
}

/// The matrix of a rotor key as the case holds it (f0 a column).
Mat matrix_of(const MatrixRotorParams& r, std::string_view key) {
  if (key == "f0") return r.f0;
  return key == "M" ? r.M : key == "C" ? r.C : key == "K" ? r.K : r.G;
}

}  // namespace

std::string resolved_toml(const CaseSpec& c) {
  if (c.model != "matrices") return to_toml(c);
  CaseSpec copy = c;
  for (const char* key : kCaseMatrixKeys) {
    std::string* f = file_of(copy.matrix_files, key);
    if (!f->empty()) *f = case_matrix_file(key);  // (relative: beside case.resolved.toml)
  }
  return to_toml(copy);
}

std::vector<std::pair<std::string, std::string>> case_matrix_files(const CaseSpec& c) {
  std::vector<std::pair<std::string, std::string>> out;
  if (c.model != "matrices") return out;
  MatrixFiles names = c.matrix_files;
  for (const char* key : kCaseMatrixKeys) {
    if (file_of(names, key)->empty()) continue;  // f0 not given: no constant load
    out.emplace_back(case_matrix_file(key),
                     npy_bytes(matrix_of(c.matrices.rotor, key), std::string_view(key) == "f0"));
  }
  return out;
}

}  // namespace rubdyn
