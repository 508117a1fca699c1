#pragma once
// Matrices given as entry lists: the Newton matrices of wide models (a finite-element rotor's
// few nonzeros per row), written by the model (LagrangianModel::newton_entries) and factored
// by the bordered band solver without an n x n matrix in between.
#include <vector>

namespace rubdyn {

/// From this many coordinates on, a model whose matrices are mostly nonzeros (a reduced rotor's)
/// multiplies and solves with dense kernels (MatrixModel's products and M^-1, the Newton blocks
/// of PhaseSession::free_jacobians): 5-10x faster there than row by row or entry by entry.
/// Below it the loops are as fast, and the small models keep their bits.
inline constexpr int kDenseKernelSize = 16;

/// One entry (i, j, value) of a matrix given as a list (LagrangianModel::newton_entries); the
/// entries at one position add up.
struct MatrixEntry {
  int i = 0, j = 0;
  double v = 0.0;
};

/// The matrices of free flight's Newton systems as entry lists (LagrangianModel::newton_entries).
struct NewtonEntries {
  std::vector<MatrixEntry> M;   ///< M(q)
  std::vector<MatrixEntry> dq;  ///< df/dq - d(M a)/dq
  std::vector<MatrixEntry> dv;  ///< df/dv
  void clear() {
    M.clear();
    dq.clear();
    dv.clear();
  }
};

}  // namespace rubdyn
