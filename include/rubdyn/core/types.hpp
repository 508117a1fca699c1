#pragma once
// Linear algebra of every model and solver: dynamic sizes, set by the model (num_dofs()).
//
// A model owns its size: the rigid rotor has 7 dofs, the Jeffcott rotor 5 (3 with a rigid
// stator), a user's test problem as many as it needs. Solvers size their workspaces when they
// are built and reuse them, so that no step allocates: a hot path assigns into vectors of the
// right size (Eigen then reuses their storage) and never creates one. Arguments are passed as
// Eigen::Ref views, which bind to a Vec, a column of a Mat or a fixed-size vector without a copy
// (an expression such as `q + v` would be evaluated into a temporary: hot paths never pass one).
#include <Eigen/Core>

namespace rubdyn {

using Vec = Eigen::VectorXd;
using Mat = Eigen::MatrixXd;
using Vec2 = Eigen::Vector2d;
using Mat2 = Eigen::Matrix2d;

/// A read-only view of a contiguous vector: a Vec, a fixed-size vector, a Map, a column of a Mat
/// or a Ref, without a copy and without the heap object that Eigen::Ref<const Vec> carries for
/// the copies it may make (measured: its construction and destruction cost 10 % of a fixed-step
/// run). An expression does not convert: it has no storage to view, and a hot path evaluates
/// it into a workspace first.
class VecView : public Eigen::Map<const Vec> {
 public:
  using Base = Eigen::Map<const Vec>;
  template <class D>
  VecView(const Eigen::PlainObjectBase<D>& x)  // NOLINT: implicit by design
      : Base(x.data(), x.size()) {
    static_assert(D::IsVectorAtCompileTime, "a vector is expected");
  }
  template <class D, int Level>
  VecView(const Eigen::MapBase<D, Level>& x)  // NOLINT: implicit by design
      : Base(x.data(), x.size()) {
    static_assert(D::IsVectorAtCompileTime, "a vector is expected");
    static_assert(D::InnerStrideAtCompileTime == 1, "a contiguous vector is expected");
  }
};
/// Read-only vector argument.
using VecIn = const VecView&;
/// Vector result written by the callee into storage of the right size.
using VecOut = Eigen::Ref<Vec>;
/// Read-only matrix argument.
using MatIn = const Eigen::Ref<const Mat>&;
/// Matrix result written by the callee into storage of the right size (a Mat, or a block of
/// columns of one).
using MatOut = Eigen::Ref<Mat>;

/// True when every entry of x is finite. x * 0 is (+-)0 for a finite entry and NaN for an
/// infinite or NaN one, so the sum is 0 exactly when all are finite: one pass without a branch
/// per entry. Measured with callgrind on a fixed-step run (two 7-vectors of dynamic size a
/// step): 78 instructions a step with Eigen's allFinite, 68 with Eigen's sum of x * 0; an
/// integer test of the exponent bits was slower than both. The plain loop below does the same
/// sum without Eigen's reduction set-up, which dominated on the 5- and 6-vectors of a contact
/// phase's right-hand side (callgrind, mu = 0.25 rolling regime: 22 M instructions of 3.1 G).
template <class Derived>
inline bool all_finite(const Eigen::DenseBase<Derived>& x) {
  const Derived& d = x.derived();
  double s = 0.0;
  for (Eigen::Index j = 0; j < d.cols(); ++j)
    for (Eigen::Index i = 0; i < d.rows(); ++i) s += d.coeff(i, j) * 0.0;
  return s == 0.0;
}

/// A mechanical state: positions and velocities at one time.
struct MechanicalState {
  double t = 0.0;
  Vec q, v;
  MechanicalState() = default;
  /// n dofs, at rest at the origin.
  explicit MechanicalState(int n, double t0 = 0.0) : t(t0), q(Vec::Zero(n)), v(Vec::Zero(n)) {}
};

}  // namespace rubdyn
