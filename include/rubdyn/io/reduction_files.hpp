#pragma once
// The files a reduced matrices model ([reduction], model/matrix_reduction.hpp) leaves in a run's
// output folder, beside timeseries.csv (whose columns are the reduced coordinates p):
//   reduced_M.npy, reduced_C.npy, reduced_K.npy, reduced_G.npy, reduced_f0.npy
//                     the reduced model's matrices (m x m) and load (m): a matrices case of them
//                     runs the same model
//   reduced_T.npy     the basis, n x m: the full coordinates q = T p (a row of timeseries.csv's
//                     p gives the whole rotor's state)
//   reduced_modes.npy the kept modes' shapes, n x (modes), mass-normalised (Craig-Bampton: the
//                     fixed-interface modes, zero at the contact nodes' coordinates; modal: the
//                     free modes)
//   reduction.json    what was reduced: method, n -> m, the physical coordinates kept, the
//                     reduced coordinates' names, the modes' frequencies and planes, the next
//                     mode's frequency, and the one-line description of summary.json's "model"
// and a matrices model's with output.modes = N > 0 (docs/fe-rotors.md, section 11):
//   output_modes.npy  the shapes of the N modes whose amplitudes timeseries.csv's mode<k>,
//                     vmode<k> are, n x N (n: the model integrated, the reduced one's m with
//                     a [reduction]), mass-normalised
//   output_modes.json their frequencies and planes, which model (full or reduced) and its size,
//                     the coordinates the shapes' rows are, and the columns' definition
// The .npy files are float64 little-endian, C order (io/matrix_files.hpp's npy_bytes).
#include <string>

#include "rubdyn/io/case_spec.hpp"

namespace rubdyn {

/// Every file above, relative to the output folder.
inline constexpr const char* kReductionFiles[] = {
    "reduced_M.npy",  "reduced_C.npy", "reduced_K.npy",     "reduced_G.npy",
    "reduced_f0.npy", "reduced_T.npy", "reduced_modes.npy", "reduction.json"};

/// output_modes.npy and output_modes.json, relative to the output folder.
inline constexpr const char* kOutputModesFiles[] = {"output_modes.npy", "output_modes.json"};

/// Writes the files above for a reduced case into the folder open as dir_fd (`dir` its path, for
/// messages); for any other case removes regular files of those names left by an earlier run
/// (they would describe another model). Throws std::runtime_error when a write fails.
void write_reduction_files(int dir_fd, const std::string& dir, const CaseSpec& spec);

/// The same for kOutputModesFiles: written for a matrices case with output.modes > 0, else
/// removed (left by an earlier run into the folder: they would describe columns not written).
void write_output_modes_files(int dir_fd, const std::string& dir, const CaseSpec& spec);

}  // namespace rubdyn
