#pragma once
// Matrix files that a user's own code writes (case files of [model] kind = "matrices"):
//   - CSV: n rows of numbers separated by commas, no header; blank lines and lines starting
//     with '#' (numpy.savetxt's header) are skipped; every row has the same count;
//   - NumPy .npy (format versions 1-3): float64, little-endian ('<f8'), C or Fortran order,
//     1-D (a column) or 2-D.
// The format is chosen by the file name's ending (.npy; anything else is read as CSV). Only a
// regular file of at most kMaxMatrixFileBytes is read. Every entry must be finite.
#include <cstddef>
#include <stdexcept>
#include <string>

#include "rubdyn/core/types.hpp"

namespace rubdyn {

/// A matrix file is read up to this size (64 MiB, a 2000 x 2000 .npy).
inline constexpr std::size_t kMaxMatrixFileBytes = std::size_t{64} << 20;

/// Why a matrix file cannot be read (the message names the problem, not the file: the caller
/// names it with its case key).
class MatrixFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The matrix in `path` (a 1-D .npy, or a CSV of one number per row, is an n x 1 column).
/// Throws MatrixFileError.
Mat read_matrix_file(const std::string& path);

/// The same from the bytes of a file (`npy`: the NumPy format, else CSV).
Mat parse_matrix(const std::string& bytes, bool npy);

/// `m` as the bytes of a NumPy .npy file (format 1.0, '<f8', C order): shape (rows, cols), or
/// (rows,) for a column when `column` (a load vector). read_matrix_file gives `m` back bit for
/// bit (a run folder keeps the matrices its case read so, output_folder.hpp).
std::string npy_bytes(const Mat& m, bool column = false);

}  // namespace rubdyn
