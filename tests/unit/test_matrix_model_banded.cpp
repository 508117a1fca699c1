// The matrices model's per-evaluation services on banded matrices (model/matrix_model.hpp: each
// matrix and the Cholesky factor kept over its envelope, u = M^-1 b by envelope solves) against
// a dense reference computed here from the matrices and the header's formulas alone: M_full
// assembled from M, G, Jp, the unbalance and the rings, solved by Eigen's LDLT, the forces,
// energies and powers written out term by term. Two models: a finite-element-like chain of
// 4-coordinate nodes (half-bandwidth 7, as scripts/make-fe-rotor.py's) with a sprung ring and
// an unbalance, and a dense random one (full envelopes: the same code must give the dense
// answers). And the prescribed-spin wrapper around the banded one (its solve is one more column
// of the inner solve, its forces one more mass product).
//
// Tolerances (relative 1e-12, normwise in the infinity norm):
// - products (forces, mass products, energies, powers): each entry is a dot product of at most
//   n + 1 <= 50 terms, whose rounding error is at most about n eps sum |a_i b_i| (eps = 1.1e-16),
//   i.e. <= 6e-15 of the scale `sum |a_i b_i|` that the checks divide by (the sums of the
//   magnitudes of the terms, not of the result: no cancellation can inflate the ratio);
// - solves (solve_mass, schur): both the envelope solves and the reference LDLT are backward
//   stable, so each has a normwise forward error of about n eps kappa(M_full); the models are
//   built with kappa(M_full) < 100 (required below; they have 2 to 4.3), so the two differ by
//   less than about 2 * 50 * 1.1e-16 * 100 = 1.1e-12 in the worst case, and by far less in
//   practice (errors do not add up in one direction: measured at most 6e-16).
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <random>

#include "rubdyn/model/matrix_model.hpp"
#include "rubdyn/model/prescribed_spin.hpp"

using namespace rubdyn;

namespace {

constexpr double kTol = 1e-12;

/// A chain of `nodes` nodes of 4 coordinates (x, y, dx, dy), each element coupling two
/// neighbouring nodes with random 8 x 8 blocks: M and K symmetric positive definite (well
/// conditioned), C symmetric, G skew; half-bandwidth 7. Contact node `node`, a sprung ring,
/// an unbalance, a linear torque law, gravity.
MatrixParams fe_chain(int nodes, int node, unsigned seed) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const int n = 4 * nodes;
  MatrixParams p;
  auto& r = p.rotor;
  r.M.setZero(n, n);
  r.C.setZero(n, n);
  r.K.setZero(n, n);
  r.G.setZero(n, n);
  r.f0.resize(n);
  for (int i = 0; i < n; ++i) r.f0[i] = U(g);
  const auto block = [&](double scale) {
    Mat A(8, 8);
    for (int i = 0; i < 8; ++i)
      for (int j = 0; j < 8; ++j) A(i, j) = scale * U(g);
    return A;
  };
  for (int e = 0; e + 1 < nodes; ++e) {
    const int o = 4 * e;
    const Mat Bm = block(0.3), Bk = block(0.3), Bc = block(1.0), Bg = block(1.0);
    r.M.block(o, o, 8, 8) += Bm * Bm.transpose() + 0.5 * Mat::Identity(8, 8);
    r.K.block(o, o, 8, 8) += 1e4 * (Bk * Bk.transpose() + 0.5 * Mat::Identity(8, 8));
    r.C.block(o, o, 8, 8) += Bc + Bc.transpose();
    r.G.block(o, o, 8, 8) += Bg - Bg.transpose();
  }
  // (exactly symmetric, as the model demands of K: a product's summation order may differ)
  r.M = Mat(0.5 * (r.M + r.M.transpose()));
  r.K = Mat(0.5 * (r.K + r.K.transpose()));
  r.Jp = 1.5;
  p.node = {4 * node, 4 * node + 1, 0.05, 2e-4};
  p.stator = {false, 2.0, 2.0e6, 100.0};
  p.loads.gravity = 9.81;
  p.loads.torque = 3.0;
  p.loads.torque_law = TorqueLaw::Linear;
  p.loads.torque_free_speed = 400.0;
  p.loads.unbalance = 2e-3;
  p.loads.unbalance_phase = 0.4;
  return p;
}

/// Dense random matrices of size n (full envelopes), the same loads.
MatrixParams dense_random(int n, unsigned seed) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const auto rnd = [&](double scale) {
    Mat A(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) A(i, j) = scale * U(g);
    return A;
  };
  MatrixParams p = fe_chain(2, 0, seed);  // (its loads and ring)
  auto& r = p.rotor;
  const Mat Bm = rnd(0.2), Bk = rnd(1.0), Bc = rnd(1.0), Bg = rnd(1.0);
  r.M = Bm * Bm.transpose() + Mat::Identity(n, n);
  r.K = 1e4 * (Bk * Bk.transpose() + Mat::Identity(n, n));
  r.C = Bc + Bc.transpose();
  r.G = Bg - Bg.transpose();
  r.M = Mat(0.5 * (r.M + r.M.transpose()));
  r.K = Mat(0.5 * (r.K + r.K.transpose()));
  r.f0 = rnd(1.0).col(0);
  // (not adjacent, not first, when there is room)
  p.node = n >= 4 ? MatrixContactNode{n - 2, 3, 0.05, 2e-4} : MatrixContactNode{0, 1, 0.05, 2e-4};
  return p;
}

/// The reference: everything from the matrices and the header's formulas.
struct Dense {
  const MatrixParams& p;
  int n, N, th, xs, ys, ix, iy;
  explicit Dense(const MatrixParams& prm)
      : p(prm),
        n(prm.rotor.size()),
        N(prm.rotor.size() + 3),
        th(prm.rotor.size()),
        xs(prm.rotor.size() + 1),
        ys(prm.rotor.size() + 2),
        ix(prm.node.x),
        iy(prm.node.y) {}
  double psi(const Vec& q) const { return q[th] + p.loads.unbalance_phase; }
  /// the theta column of M_full
  Vec b(const Vec& q) const {
    Vec bq = 0.5 * p.rotor.G * q.head(n);
    bq[ix] -= p.loads.unbalance * std::sin(psi(q));
    bq[iy] += p.loads.unbalance * std::cos(psi(q));
    return bq;
  }
  Mat mass(const Vec& q) const {
    Mat M = Mat::Zero(N, N);
    M.topLeftCorner(n, n) = p.rotor.M;
    M.col(th).head(n) = b(q);
    M.row(th).head(n) = b(q).transpose();
    M(th, th) = p.rotor.Jp;
    M(xs, xs) = M(ys, ys) = p.stator.mass;
    return M;
  }
  /// the forces and, in `scale`, the sums of the magnitudes of their terms
  Vec forces(const Vec& q, const Vec& v, Vec& scale) const {
    const auto& r = p.rotor;
    const auto& L = p.loads;
    const double om = v[th], ub = L.unbalance, c = std::cos(psi(q)), s = std::sin(psi(q));
    Vec f = Vec::Zero(N);
    f.head(n) = r.f0 - r.C * v.head(n) - r.K * q.head(n) - om * r.G * v.head(n);
    f[ix] += ub * om * om * c;
    f[iy] += ub * om * om * s;
    f[th] = L.drive_torque(om) - ub * L.gravity * c;
    f[xs] = -p.stator.c * v[xs] - p.stator.k * q[xs];
    f[ys] = -p.stator.c * v[ys] - p.stator.k * q[ys] - p.stator.mass * L.gravity;
    scale = Vec::Zero(N);
    const Vec av = v.head(n).cwiseAbs(), aq = q.head(n).cwiseAbs();
    scale.head(n) = r.f0.cwiseAbs() + r.C.cwiseAbs() * av + r.K.cwiseAbs() * aq +
                    std::abs(om) * r.G.cwiseAbs() * av;
    scale[ix] += ub * om * om;
    scale[iy] += ub * om * om;
    scale[th] = std::abs(L.drive_torque(om)) + ub * L.gravity;
    scale[xs] = std::abs(f[xs]) + 1.0;
    scale[ys] = std::abs(f[ys]) + 1.0;
    return f;
  }
  double potential(const Vec& q) const {
    const auto& L = p.loads;
    return 0.5 * q.head(n).dot(p.rotor.K * q.head(n)) - p.rotor.f0.dot(q.head(n)) +
           L.gravity * L.unbalance * std::sin(psi(q)) +
           0.5 * p.stator.k * (q[xs] * q[xs] + q[ys] * q[ys]) + L.gravity * p.stator.mass * q[ys];
  }
  double potential_scale(const Vec& q) const {
    const Vec aq = q.cwiseAbs();
    return 0.5 * aq.head(n).dot(p.rotor.K.cwiseAbs() * aq.head(n)) +
           p.rotor.f0.cwiseAbs().dot(aq.head(n)) + p.loads.gravity * p.loads.unbalance +
           0.5 * p.stator.k * (aq[xs] * aq[xs] + aq[ys] * aq[ys]) +
           p.loads.gravity * p.stator.mass * aq[ys];
  }
};

double rel(const Vec& x, const Vec& ref, const Vec& scale) {
  return (x - ref).cwiseAbs().maxCoeff() / scale.maxCoeff();
}

/// A random state of the model's coordinates (q, theta, x_s, y_s; rates likewise).
void random_state(int N, unsigned seed, Vec& q, Vec& v) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  q.resize(N);
  v.resize(N);
  for (int i = 0; i < N; ++i) q[i] = 1e-2 * U(g), v[i] = U(g);
  q[N - 3] = 0.7;   // theta
  v[N - 3] = 60.0;  // omega
}

void check_services(const MatrixParams& p, unsigned seed) {
  const MatrixModel m(p);
  const Dense d(p);
  REQUIRE(m.num_dofs() == d.N);
  Vec q, v;
  random_state(d.N, seed, q, v);
  const Mat Mf = d.mass(q);
  const Eigen::SelfAdjointEigenSolver<Mat> eig(Mf);
  const double kappa = eig.eigenvalues().maxCoeff() / eig.eigenvalues().minCoeff();
  INFO("kappa(M_full) = " << kappa);
  REQUIRE(eig.eigenvalues().minCoeff() > 0.0);
  REQUIRE(kappa < 100.0);  // (the solves' tolerance argument, top of the file)
  const Eigen::LDLT<Mat> ldlt(Mf);
  const Mat absM = Mf.cwiseAbs();

  // mass_matrix: assembled with b's rows of G over their envelopes
  Mat Mm(d.N, d.N);
  m.mass_matrix(q, Mm);
  CHECK((Mm - Mf).cwiseAbs().maxCoeff() <= kTol * absM.maxCoeff());

  // mass_product
  Vec x = v, y(d.N);
  x[d.th] = -3.0;
  m.mass_product(q, x, y);
  CHECK(rel(y, Mf * x, absM * x.cwiseAbs()) <= kTol);

  // smooth_forces
  Vec f(d.N), scale;
  m.smooth_forces(0.0, q, v, f);
  const Vec fref = d.forces(q, v, scale);
  CHECK(rel(f, fref, scale) <= kTol);

  // the Jacobian's theta column of df/dv: -G v + the centrifugal force's derivative
  Mat dq(d.N, d.N), dv(d.N, d.N);
  m.smooth_force_jacobians(0.0, q, v, dq, dv);
  Vec dvth = -p.rotor.G * v.head(d.n);
  dvth[d.ix] += 2.0 * v[d.th] * p.loads.unbalance * std::cos(d.psi(q));
  dvth[d.iy] += 2.0 * v[d.th] * p.loads.unbalance * std::sin(d.psi(q));
  const Vec dvth_scale = p.rotor.G.cwiseAbs() * v.head(d.n).cwiseAbs() +
                         Vec::Constant(d.n, 2.0 * v[d.th] * p.loads.unbalance);
  CHECK(rel(dv.col(d.th).head(d.n), dvth, dvth_scale) <= kTol);

  // solve_mass: three right-hand sides, against the dense LDLT
  Mat R(d.N, 3);
  std::mt19937 g(seed + 1);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int i = 0; i < d.N; ++i)
    for (int j = 0; j < 3; ++j) R(i, j) = U(g);
  const Mat Xref = ldlt.solve(R);
  Mat X = R;
  m.solve_mass(q, X);
  for (int j = 0; j < 3; ++j) {
    const double e =
        (X.col(j) - Xref.col(j)).cwiseAbs().maxCoeff() / Xref.col(j).cwiseAbs().maxCoeff();
    INFO("column " << j << ": relative error " << e);
    CHECK(e <= kTol);
  }

  // schur: Jp - b^T M^-1 b
  const Vec bq = d.b(q);
  const double sref = p.rotor.Jp - bq.dot(p.rotor.M.ldlt().solve(bq));
  CHECK(std::abs(m.schur(q) - sref) <= kTol * p.rotor.Jp);

  // kinetic_energy: 1/2 v^T M_full v
  const double T = m.kinetic_energy(0.0, q, v);
  CHECK(std::abs(T - 0.5 * v.dot(Mf * v)) <= kTol * 0.5 * v.cwiseAbs().dot(absM * v.cwiseAbs()));

  // potential_energy
  CHECK(std::abs(m.potential_energy(0.0, q) - d.potential(q)) <= kTol * d.potential_scale(q));

  // smooth_power: the drive's and the dampers'
  const SmoothPower pw = m.smooth_power(0.0, q, v);
  const double om = v[d.th];
  CHECK(pw.external == Approx(p.loads.drive_torque(om) * om).epsilon(kTol));
  const double dref = -v.head(d.n).dot(p.rotor.C * v.head(d.n)) -
                      p.stator.c * (v[d.xs] * v[d.xs] + v[d.ys] * v[d.ys]);
  const double dscale = v.head(d.n).cwiseAbs().dot(p.rotor.C.cwiseAbs() * v.head(d.n).cwiseAbs()) +
                        p.stator.c * (v[d.xs] * v[d.xs] + v[d.ys] * v[d.ys]);
  CHECK(std::abs(pw.damping - dref) <= kTol * dscale);

  // a state where M_full is not positive definite (|q| far beyond the linear range): NaN
  Vec qfar = q;
  qfar.head(d.n) *= 1e6;
  if (d.b(qfar).dot(p.rotor.M.ldlt().solve(d.b(qfar))) > p.rotor.Jp) {
    Mat Z = R;
    m.solve_mass(qfar, Z);
    CHECK(Z.array().isNaN().all());
  }
}

/// x without entry s; A without row and column s.
Vec drop(const Vec& x, int s) {
  Vec y(x.size() - 1);
  for (Eigen::Index i = 0, j = 0; j < x.size(); ++j)
    if (j != s) y[i++] = x[j];
  return y;
}
Mat drop(const Mat& A, int s) {
  Mat B(A.rows() - 1, A.cols() - 1);
  for (Eigen::Index c = 0, jc = 0; jc < A.cols(); ++jc) {
    if (jc == s) continue;
    for (Eigen::Index r = 0, jr = 0; jr < A.rows(); ++jr)
      if (jr != s) B(r++, c) = A(jr, jc);
    ++c;
  }
  return B;
}

}  // namespace

TEST_CASE("Matrices model, banded (finite-element chain): every service is the dense reference",
          "[matrices][banded]") {
  // 13 nodes: n = 52, the size of cases/fe-runup.toml; the seal at node 6, as there
  check_services(fe_chain(13, 6, 11), 21);
  // the seal at the first and at the last node (envelopes cut at the ends)
  check_services(fe_chain(10, 0, 12), 22);
  check_services(fe_chain(12, 11, 13), 23);
}

TEST_CASE("Matrices model, dense random matrices: every service is the dense reference",
          "[matrices][banded]") {
  check_services(dense_random(10, 31), 41);
  check_services(dense_random(2, 32), 42);  // (n = 2: the smallest model)
}

TEST_CASE("Matrices model, banded: a zero C and a banded G with holes keep the dense answers",
          "[matrices][banded]") {
  // a row of zeros (C = 0: empty envelopes) and a G coupling only every other node (zeros
  // inside the envelopes of M, K and outside G's): the envelopes are per matrix
  MatrixParams p = fe_chain(11, 5, 14);
  p.rotor.C.setZero();
  for (int e = 0; e + 1 < 11; e += 2) p.rotor.G.block(4 * e, 4 * e, 8, 8).setZero();
  check_services(p, 24);
}

TEST_CASE("Prescribed spin around a banded matrices model: forces and solves are the dense ones",
          "[matrices][banded]") {
  const MatrixParams p = fe_chain(12, 6, 15);
  const Dense d(p);
  const double t0 = 0.1, th0 = 0.3, om0 = 50.0, alpha = 400.0, t = 0.13;
  const PrescribedSpin ps(std::make_unique<MatrixModel>(p), t0, th0, om0, alpha);
  REQUIRE(ps.num_dofs() == d.N - 1);
  Vec qf, vf;
  random_state(d.N, 25, qf, vf);
  const double dt = t - t0;
  qf[d.th] = th0 + om0 * dt + 0.5 * alpha * dt * dt;
  vf[d.th] = om0 + alpha * dt;
  const Vec q = drop(qf, d.th), v = drop(vf, d.th);
  const Mat Mf = d.mass(qf);

  // forces: the full ones less M_full e_theta alpha, without theta's row
  Vec f(d.N - 1), scale;
  ps.smooth_forces(t, q, v, f);
  const Vec ff = d.forces(qf, vf, scale) - Mf.col(d.th) * alpha;
  scale += Mf.col(d.th).cwiseAbs() * alpha;
  CHECK(rel(f, drop(ff, d.th), drop(scale, d.th)) <= kTol);

  // the solve with the block of M_full without theta (kappa <= that of M_full: interlacing)
  const Mat A = drop(Mf, d.th);
  Mat R(d.N - 1, 2);
  for (int i = 0; i < d.N - 1; ++i) R(i, 0) = std::sin(1.0 + i), R(i, 1) = std::cos(2.0 * i);
  const Mat Xref = A.ldlt().solve(R);
  Mat X = R;
  ps.solve_mass(q, X);
  CHECK((X - Xref).cwiseAbs().maxCoeff() <= kTol * Xref.cwiseAbs().maxCoeff());
}

namespace {

/// An entry list summed into a dense N x N matrix, and the sums of its entries' magnitudes.
Mat scatter(const std::vector<MatrixEntry>& E, int N, bool magnitudes = false) {
  Mat A = Mat::Zero(N, N);
  for (const MatrixEntry& e : E) A(e.i, e.j) += magnitudes ? std::abs(e.v) : e.v;
  return A;
}

/// max |list - dense| / max(sum of the list's |terms|) over the entries: each position adds at
/// most n + 2 terms, here and in the dense Jacobians (the spin row of d(M a)/dq: (G^T a)_k / 2
/// a sum over n rows), so either rounds off by at most about (n + 2) eps of those magnitudes,
/// 53 * 1.1e-16 = 6e-15 at n = 52: kTol (1e-12) holds with room; a missing, doubled or
/// misplaced entry gives O(1).
double list_error(const std::vector<MatrixEntry>& E, const Mat& dense) {
  const int N = static_cast<int>(dense.rows());
  const Mat mag = scatter(E, N, true) + dense.cwiseAbs();
  return (scatter(E, N) - dense).cwiseAbs().maxCoeff() / mag.maxCoeff();
}

std::vector<std::pair<int, int>> positions(const std::vector<MatrixEntry>& E) {
  std::vector<std::pair<int, int>> p;
  for (const MatrixEntry& e : E) p.emplace_back(e.i, e.j);
  return p;
}

/// newton_entries against the dense Jacobians of the same model at (t, q, v, a).
void check_entries(const LagrangianModel& m, double t, const Vec& q, const Vec& v, const Vec& a) {
  const int N = m.num_dofs();
  NewtonEntries e;
  REQUIRE(m.newton_entries(t, q, v, a, e));
  Mat M(N, N), dq(N, N), dv(N, N), J(N, N);
  m.mass_matrix(q, M);
  m.smooth_force_jacobians(t, q, v, dq, dv);
  m.mass_matrix_product_jacobian(q, a, J);
  dq -= J;
  CHECK(list_error(e.M, M) <= kTol);
  CHECK(list_error(e.dq, dq) <= kTol);
  CHECK(list_error(e.dv, dv) <= kTol);
  // structural: the same positions at rest (zero speed, acceleration and angle), where many of
  // the values are 0, so that a band detected once holds for every state
  NewtonEntries rest;
  const Vec z = Vec::Zero(N);
  REQUIRE(m.newton_entries(t, z, z, z, rest));
  CHECK(positions(rest.M) == positions(e.M));
  CHECK(positions(rest.dq) == positions(e.dq));
  CHECK(positions(rest.dv) == positions(e.dv));
}

}  // namespace

TEST_CASE("Matrices model: the Newton matrices' entry lists are its dense Jacobians",
          "[matrices][banded]") {
  for (const auto& [p, seed] : {std::pair{fe_chain(13, 6, 16), 26u}, {dense_random(10, 33), 43u}}) {
    const MatrixModel m(p);
    const int N = m.num_dofs();
    Vec q, v;
    random_state(N, seed, q, v);
    Vec a(N);
    for (int i = 0; i < N; ++i) a[i] = std::cos(3.0 * i + seed);
    check_entries(m, 0.0, q, v, a);
    // the prescribed spin around it: the inner's lists without the spin, with its alpha
    const PrescribedSpin ps(std::make_unique<MatrixModel>(p), 0.1, 0.3, 50.0, 400.0);
    const int th = N - 3;
    check_entries(ps, 0.13, drop(q, th), drop(v, th), drop(a, th));
  }
}

TEST_CASE("Matrices model: the solve without the spin is the block's dense solve",
          "[matrices][banded]") {
  // solve_mass_without(spin): M_full without the spin's row and column, against LDLT of that
  // block assembled densely (the solves' tolerance argument at the top of the file); any other
  // coordinate is refused (the solvers then take the whole M's Schur complement)
  const MatrixParams p = fe_chain(12, 6, 17);
  const MatrixModel m(p);
  const Dense d(p);
  Vec q, v;
  random_state(d.N, 27, q, v);
  const Mat A = drop(d.mass(q), d.th);
  Mat R(d.N - 1, 3);
  for (int i = 0; i < d.N - 1; ++i)
    R(i, 0) = std::sin(1.0 + i), R(i, 1) = std::cos(2.0 * i), R(i, 2) = i == d.ix ? 1.0 : 0.0;
  const Mat Xref = A.ldlt().solve(R);
  Mat X = R;
  REQUIRE(m.solve_mass_without(d.th, q, X));
  for (int j = 0; j < 3; ++j)
    CHECK((X.col(j) - Xref.col(j)).cwiseAbs().maxCoeff() <=
          kTol * Xref.col(j).cwiseAbs().maxCoeff());
  CHECK_FALSE(m.solve_mass_without(d.ix, q, X));
}

TEST_CASE("Matrices model: the spin's rows alone are mass_product's and smooth_forces' bits",
          "[matrices][banded]") {
  // spin_row computes the same terms in the same order (its contract: the same bits, so that a
  // prescribed spin's drive torque does not change with it): compared with ==; with a rotor
  // part of zeros (a prescribed spin's M e_theta alpha) and without
  const MatrixParams p = fe_chain(12, 6, 18);
  const MatrixModel m(p);
  const int N = m.num_dofs(), th = N - 3;
  Vec q, v;
  random_state(N, 28, q, v);
  Vec a(N), y(N), f(N);
  for (int i = 0; i < N; ++i) a[i] = std::sin(0.7 * i + 0.2);
  for (const bool zero_rotor : {false, true}) {
    Vec x = a;
    if (zero_rotor) x.head(th).setZero();
    double Ma = 0.0, fth = 0.0;
    REQUIRE(m.spin_row(0.2, q, v, x, Ma, fth));
    m.mass_product(q, x, y);
    m.smooth_forces(0.2, q, v, f);
    CHECK(Ma == y[th]);
    CHECK(fth == f[th]);
  }
}
