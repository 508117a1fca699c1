#include "rubdyn/hybrid/method_choice.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <vector>

#include "rubdyn/core/bordered_band.hpp"

namespace rubdyn {

std::string NewtonStructure::reason() const {
  return fmt::format("Newton systems of {} coordinates, half-bandwidths {}/{} besides the spin: {}",
                     n, kl, ku, banded ? "banded" : "dense");
}

NewtonStructure assess_newton_structure(const LagrangianModel& model, double t, const Vec& q,
                                        const Vec& v) {
  const int n = model.num_dofs();
  Mat M(n, n), dfdq(n, n), dfdv(n, n), dMa(n, n);
  model.mass_matrix(q, M);
  model.smooth_force_jacobians(t, q, v, dfdq, dfdv);
  // d(M a)/dq's pattern for a generic a (every entry of a nonzero)
  const Vec ones = Vec::Ones(n);
  model.mass_matrix_product_jacobian(q, ones, dMa);
  detail::BorderedBand band(n, model.spin_coordinate());
  band.reset_pattern();
  for (const Mat* A : {&M, &dfdq, &dfdv, &dMa}) band.detect(*A);
  band.finish_pattern();
  NewtonStructure s;
  s.n = n;
  s.kl = band.kl();
  s.ku = band.ku();
  s.banded = band.banded();
  return s;
}

std::string StiffnessAssessment::reason() const {
  if (omega_min <= 0.0)
    return fmt::format(
        "no stiffness in the free flight (largest damping rate {:.4g} 1/s): not stiff", decay_max);
  return fmt::format(
      "fastest time scale {:.4g} 1/s (omega_max {:.4g} rad/s, damping rate {:.4g} 1/s) against "
      "the slowest frequency {:.4g} rad/s: ratio {:.4g} {} {:.4g}",
      std::max(omega_max, decay_max), omega_max, decay_max, omega_min, ratio,
      stiff ? ">" : "<=", kStiffRatio);
}

namespace {

/// The eigenvalues of the symmetric part of A against the SPD matrix M, in absolute value,
/// ascending.
Vec generalised_magnitudes(const Mat& A, const Mat& M) {
  const Mat As = 0.5 * (A + A.transpose());
  Eigen::GeneralizedSelfAdjointEigenSolver<Mat> es(As, M, Eigen::EigenvaluesOnly);
  if (es.info() != Eigen::Success) return Vec();
  Vec lam = es.eigenvalues().cwiseAbs();
  std::sort(lam.data(), lam.data() + lam.size());
  return lam;
}

}  // namespace

StiffnessAssessment assess_stiffness(const LagrangianModel& model, double t, const Vec& q,
                                     const Vec& v) {
  int n = model.num_dofs();
  Mat M(n, n), dfdq(n, n), dfdv(n, n);
  model.mass_matrix(q, M);
  model.smooth_force_jacobians(t, q, v, dfdq, dfdv);
  // the spin is not a vibration: its row and column are left out (with them, the unbalance's
  // weight under gravity gave the Jeffcott rotor's spin angle a "frequency" of 0.29 rad/s)
  const int spin = model.spin_coordinate();
  std::vector<int> keep;
  for (int i = 0; i < n; ++i)
    if (i != spin) keep.push_back(i);
  const auto sub = [&keep](const Mat& A) { return Mat(A(keep, keep)); };
  const Mat Ms = sub(M);
  StiffnessAssessment a;
  const Vec k2 = generalised_magnitudes(-sub(dfdq), Ms);
  const Vec d = generalised_magnitudes(-sub(dfdv), Ms);
  n = static_cast<int>(keep.size());
  if (n > 0 && k2.size() == n) {
    a.omega_max = std::sqrt(k2[n - 1]);
    // frequencies below 1e-6 of the largest are a coordinate without stiffness (the spin, a free
    // ring angle) seen through round-off, not a time scale
    for (int i = 0; i < n; ++i)
      if (k2[i] > 1e-12 * k2[n - 1] && k2[i] > 0.0) {
        a.omega_min = std::sqrt(k2[i]);
        break;
      }
  }
  if (n > 0 && d.size() == n) a.decay_max = d[n - 1];
  if (a.omega_min > 0.0) a.ratio = std::max(a.omega_max, a.decay_max) / a.omega_min;
  a.stiff = a.ratio > kStiffRatio;
  return a;
}

}  // namespace rubdyn
