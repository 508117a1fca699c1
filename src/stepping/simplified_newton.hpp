#pragma once
// The simplified Newton iteration shared by the implicit fixed-step schemes (Carpenter's
// prediction, Moreau-Jean's step). The iteration matrix is kept as an explicit inverse across
// steps (a 7x7 product is cheaper than two triangular solves) and refreshed every 32 steps, or
// when the iteration contracts slowly (ratio > 0.1): the converged solution solves the step's
// equations whatever the iteration matrix. Converged when the scaled change is within tolerance
// (norm <= 1), when the estimated remaining error r / (1 - r) times the last change is (r the
// contraction ratio), or when round-off is reached (r >= 0.5 after 4 iterations).
#include <Eigen/LU>

#include "rubdyn/core/types.hpp"

namespace rubdyn::detail {

class SimplifiedNewton {
 public:
  explicit SimplifiedNewton(int max_iterations) : max_(max_iterations) {}

  /// Before the first iteration of a step.
  void begin_step() {
    fresh_ = valid_ && ++age_ < 32;
    it_ = 0;
    prev_ = 0.0;
  }
  /// True when the iteration matrix must be set before the next iteration.
  bool needs_matrix() const { return !fresh_; }
  void set_matrix(const Mat7& J) {
    inv_ = J.partialPivLu().inverse();
    valid_ = fresh_ = true;
    age_ = 0;
  }
  const Mat7& inverse() const { return inv_; }

  enum class Next { Iterate, Converged, Failed };
  /// After an iteration whose change has the scaled norm `norm` (1 = the tolerance).
  Next after(double norm) {
    ++it_;
    if (norm <= 1.0) return Next::Converged;
    if (it_ >= 2) {
      const double r = norm / prev_;
      if (r < 1.0 && r / (1.0 - r) * norm <= 1.0) return Next::Converged;
      if (r > 0.1) fresh_ = false;                       // slow contraction: refresh the matrix
      if (it_ >= 4 && r >= 0.5) return Next::Converged;  // round-off reached
    }
    prev_ = norm;
    return it_ >= max_ ? Next::Failed : Next::Iterate;
  }
  int iterations() const { return it_; }
  int max_iterations() const { return max_; }

 private:
  int max_;
  Mat7 inv_ = Mat7::Zero();
  bool valid_ = false, fresh_ = false;
  int age_ = 0, it_ = 0;
  double prev_ = 0.0;
};

}  // namespace rubdyn::detail
