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

bool LagrangianModel::plane_motion(int k, double /*t*/, VecIn q, VecIn v, PlaneMotion& out) const {
  const PlaneCoordinates pc = plane_coordinates(coordinates(), k);
  if (pc.rotor_x < 0 || pc.rotor_y < 0) return false;
  auto at = [](VecIn x, int i) { return i >= 0 ? x[i] : 0.0; };
  out.rotor = {q[pc.rotor_x], q[pc.rotor_y]};
  out.rotor_rate = {v[pc.rotor_x], v[pc.rotor_y]};
  out.stator = {at(q, pc.stator_x), at(q, pc.stator_y)};
  out.stator_rate = {at(v, pc.stator_x), at(v, pc.stator_y)};
  return true;
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
