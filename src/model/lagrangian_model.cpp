#include "rubdyn/model/lagrangian_model.hpp"

#include <Eigen/Cholesky>
#include <cmath>

namespace rubdyn {

void LagrangianModel::solve_mass(VecIn q, MatOut B) const {
  const int n = num_dofs();
  Mat M(n, n);
  mass_matrix(q, M);
  const Eigen::LDLT<Mat> ldlt(M);
  B = ldlt.solve(B);
}

void LagrangianModel::mass_product(VecIn q, VecIn x, VecOut y) const {
  const int n = num_dofs();
  Mat M(n, n);
  mass_matrix(q, M);
  y.noalias() = M * x;
}

const std::vector<Observable>& LagrangianModel::observables() const {
  static const std::vector<Observable> none;
  return none;
}

double LagrangianModel::kinetic_energy(double /*t*/, VecIn q, VecIn v) const {
  const int n = num_dofs();
  Mat M(n, n);
  mass_matrix(q, M);
  return 0.5 * v.dot(M * v);
}

std::optional<Penetration> LagrangianModel::initial_penetration(VecIn q, double roundoff) const {
  const Vec v = Vec::Zero(num_dofs());
  ContactKinematics c(num_dofs());
  for (int k = 0; k < contact_count(); ++k) {
    compute_contact(k, 0.0, q, v, c);
    if (c.d_N < -roundoff * gap_scale(k)) return Penetration{k, c.d_N};
  }
  return std::nullopt;
}

}  // namespace rubdyn
