#include "rubdyn/model/matrix_model.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "rubdyn/core/demand.hpp"
#include "rubdyn/model/matrix_reduction.hpp"

namespace rubdyn {

namespace {

/// b and u of the spin column, one pair per thread: a model holds no mutable state and may
/// serve several runs at once. They only grow (head(n) is used), so that models of several
/// sizes on one thread do not reallocate in turn; after a thread's first call of its largest
/// model nothing is allocated.
struct SpinScratch {
  Vec b, u, z;  // (z: a right-hand side's rotor part, solve_mass)
  Vec bm;       // b(q) of mass_product and spin_row
  Vec m;        // solve_rotor_mass's right-hand side (a dense M)
};

SpinScratch& spin_scratch(int n) {
  thread_local SpinScratch s;
  if (s.b.size() < n) {
    s.b.setZero(n);
    s.u.setZero(n);
    s.z.setZero(n);
    s.bm.setZero(n);
    s.m.setZero(n);
  }
  return s;
}

}  // namespace

MatrixModel::Envelope::Envelope(const Mat& A, bool dense_products) {
  const auto n = A.rows();
  lo.assign(static_cast<std::size_t>(n), 0);
  len.assign(static_cast<std::size_t>(n), 0);
  off.assign(static_cast<std::size_t>(n), 0);
  Eigen::Index total = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::Index first = -1, last = -1;
    for (Eigen::Index j = 0; j < A.cols(); ++j) {
      if (A(i, j) == 0.0) continue;
      if (first < 0) first = j;
      last = j;
    }
    const auto k = static_cast<std::size_t>(i);
    lo[k] = first < 0 ? 0 : first;
    len[k] = first < 0 ? 0 : last - first + 1;
    off[k] = total;
    total += len[k];
  }
  val.resize(total);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    for (Eigen::Index j = 0; j < len[k]; ++j) val[off[k] + j] = A(i, lo[k] + j);
  }
  if (dense_products && n >= kDenseKernelSize && 2 * total >= n * A.cols()) dense = A;
}

void MatrixModel::Envelope::multiply_add(double alpha, const double* x, double* y) const {
  if (dense.size() > 0) {
    Eigen::Map<Vec>(y, dense.rows()).noalias() +=
        alpha * (dense * Eigen::Map<const Vec>(x, dense.cols()));
    return;
  }
  for (std::size_t k = 0; k < lo.size(); ++k) y[k] += alpha * dot(static_cast<int>(k), x);
}

double MatrixModel::Envelope::dot(int i, const double* x) const {
  // rows of a few to a few tens of entries: a plain loop with two partial sums (a fixed order,
  // the same bits every run) instead of a general dot product's set-up
  const auto k = static_cast<std::size_t>(i);
  const double* a = val.data() + off[k];
  const double* b = x + lo[k];
  const Eigen::Index m = len[k];
  double s0 = 0.0, s1 = 0.0;
  Eigen::Index j = 0;
  for (; j + 1 < m; j += 2) {
    s0 += a[j] * b[j];
    s1 += a[j + 1] * b[j + 1];
  }
  if (j < m) s0 += a[j] * b[j];
  return s0 + s1;
}

std::vector<double> rotation_lengths(const Mat& M, const std::vector<bool>& rotation) {
  const auto n = static_cast<std::size_t>(M.rows());
  std::vector<double> len(n, 1.0);
  if (rotation.size() != n) return len;
  std::vector<double> deflection;
  for (std::size_t i = 0; i < n; ++i)
    if (!rotation[i])
      deflection.push_back(M(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)));
  if (deflection.empty()) return len;
  // the median (the lower one of an even count): discs' lumped masses do not move it
  const auto mid = deflection.begin() + static_cast<std::ptrdiff_t>((deflection.size() - 1) / 2);
  std::nth_element(deflection.begin(), mid, deflection.end());
  const double m = *mid;
  for (std::size_t i = 0; i < n; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    if (rotation[i] && m > 0.0 && M(ii, ii) > 0.0) len[i] = std::sqrt(M(ii, ii) / m);
  }
  return len;
}

std::vector<Coordinate> matrix_model_coordinates(int n, const std::vector<std::string>& names,
                                                 const std::vector<MatrixNode>& nodes,
                                                 const std::vector<bool>& rotation) {
  using R = CoordinateRole;
  const bool several = nodes.size() > 1;
  std::vector<Coordinate> c;
  for (int i = 0; i < n; ++i) {
    std::string nm = "q";
    if (static_cast<int>(names.size()) == n) {
      nm = names[static_cast<std::size_t>(i)];
    } else {
      nm.append(std::to_string(i));
    }
    int node = -1;
    bool x = false;
    for (std::size_t k = 0; k < nodes.size() && node < 0; ++k) {
      if (nodes[k].at.x == i) node = static_cast<int>(k), x = true;
      if (nodes[k].at.y == i) node = static_cast<int>(k);
    }
    std::string rate = "v";  // (appended, not "v" + nm: g++ 12 warns falsely, -Wrestrict)
    rate.append(nm);
    std::string meaning = "a coordinate of the user's rotor";
    if (node >= 0) {
      // (appended: g++ 12 warns falsely on operator+ chains, -Wrestrict)
      meaning = several ? "contact node " : "the contact node's centre";
      if (several) meaning.append(std::to_string(node + 1)).append("'s centre");
      meaning.append(x ? " (seal circle), horizontal" : " (seal circle), vertical");
    }
    const bool rot =
        static_cast<int>(rotation.size()) == n && rotation[static_cast<std::size_t>(i)];
    if (rot && node < 0) meaning = "a rotation of the user's rotor";
    c.push_back({nm, rate, rate, rot ? "rad" : "m", meaning,
                 node < 0 ? R::Other
                 : x      ? R::RotorX
                          : R::RotorY,
                 node < 0 ? 0 : node});
  }
  c.push_back(
      {"theta", "omega", "omega0", "rad", "spin angle (its rate: the spin speed)", R::Spin, 0});
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    if (nodes[k].stator.rigid) continue;
    std::string sfx, of;
    if (several) {
      sfx.append("_").append(std::to_string(k + 1));
      of.append(" of node ").append(std::to_string(k + 1));
    }
    const int plane = static_cast<int>(k);
    std::string xs = "x_s", ys = "y_s", vxs = "vx_s", vys = "vy_s";
    xs.append(sfx);
    ys.append(sfx);
    vxs.append(sfx);
    vys.append(sfx);
    std::string mx = "stator centre", my = "stator centre";
    mx.append(of).append(", horizontal");
    my.append(of).append(", vertical");
    c.push_back({xs, vxs, vxs, "m", mx, R::StatorX, plane});
    c.push_back({ys, vys, vys, "m", my, R::StatorY, plane});
  }
  return c;
}

MatrixModel::MatrixModel(MatrixParams params)
    : p_(std::move(params)),
      K_(static_cast<int>(p_.node_list().size())),
      n_(p_.rotor.size()),
      N_(p_.rotor.size() + 1),
      th_(p_.rotor.size()),
      chart_(*this) {
  const MatrixParams& p = p_;
  const auto& r = p.rotor;
  const std::vector<MatrixNode> list = p.node_list();
  RUBDYN_DEMAND(K_ >= 1 && K_ <= kMaxContactNodes);
  for (const MatrixNode& mn : list) {
    Node nd;
    nd.ix = mn.at.x;
    nd.iy = mn.at.y;
    nd.radius = mn.at.radius;
    nd.gap = mn.at.gap;
    nd.law = mn.law;
    nd.stator = mn.stator;
    RUBDYN_DEMAND(nd.ix >= 0 && nd.ix < n_ && nd.iy >= 0 && nd.iy < n_ && nd.ix != nd.iy);
    for (const Node& o : nodes_)  // a coordinate belongs to one node
      RUBDYN_DEMAND(o.ix != nd.ix && o.ix != nd.iy && o.iy != nd.ix && o.iy != nd.iy);
    if (!mn.stator.rigid) {
      nd.xs = N_;
      nd.ys = N_ + 1;
      N_ += 2;
    }
    nodes_.push_back(nd);
  }
  ix_ = nodes_[0].ix;
  iy_ = nodes_[0].iy;
  xs_ = nodes_[0].xs;
  ys_ = nodes_[0].ys;
  sprung_ = nodes_[0].sprung();
  {  // the ring chart: each node's (x, y) and its ring (x_s_k, y_s_k adjacent); with one node
     // the event solver uses chart_, a prescribed spin this one
    std::vector<RingContact> rc;
    for (const Node& nd : nodes_) {
      RingContact c;
      c.ix = {nd.ix, -1};
      c.iy = {nd.iy, -1};
      c.w = {1.0, 0.0};
      c.ring = nd.sprung() ? nd.xs : -1;
      c.gap = nd.gap;
      c.radius = nd.radius;
      rc.push_back(c);
    }
    ring_chart_.emplace(N_, th_, std::move(rc));
  }
  RUBDYN_DEMAND(n_ >= 2 && r.M.cols() == n_ && r.C.rows() == n_ && r.C.cols() == n_ &&
                r.K.rows() == n_ && r.K.cols() == n_ && r.G.rows() == n_ && r.G.cols() == n_ &&
                r.f0.size() == n_);
  // the energy V = 1/2 q^T K q and the Lagrangian's G need these exactly (io symmetrises)
  RUBDYN_DEMAND(r.K == r.K.transpose() && r.G == -r.G.transpose());
  coords_ = matrix_model_coordinates(n_, r.names, list, r.rotation);
  const std::vector<double> len = rotation_lengths(r.M, r.rotation);
  for (int i = 0; i < n_; ++i)
    coords_[static_cast<std::size_t>(i)].length = len[static_cast<std::size_t>(i)];
  Eigen::LLT<Mat> llt(r.M);
  RUBDYN_DEMAND(llt.info() == Eigen::Success);
  // L's rows are read from the factor itself: the entries left of a row's first nonzero of M
  // are exact zeros of L (no fill outside the envelope), so this is M's envelope
  Le_ = Envelope(Mat(llt.matrixL()), false);
  for (int i = 0; i < n_; ++i) {  // row i ends at its (positive) diagonal
    const auto k = static_cast<std::size_t>(i);
    RUBDYN_DEMAND(Le_.len[k] >= 1 && Le_.lo[k] + Le_.len[k] - 1 == i);
  }
  Me_ = Envelope(r.M.transpose());  // (M's columns, as the products used before: M symmetric)
  if (Me_.dense.size() > 0) Minv_ = llt.solve(Mat::Identity(n_, n_));
  Ce_ = Envelope(r.C);
  Ke_ = Envelope(r.K);
  Ge_ = Envelope(r.G);
  unit_pos_.assign(static_cast<std::size_t>(n_), -1);
  unit_solves_.setZero(n_, 2 * K_);
  for (int k = 0; k < K_; ++k) {
    for (const int i : {nd(k).ix, nd(k).iy}) {
      const int c = i == nd(k).ix ? 2 * k : 2 * k + 1;
      unit_pos_[static_cast<std::size_t>(i)] = c;
      unit_solves_(i, c) = 1.0;
      solve_rotor_mass(unit_solves_.col(c).data());
    }
  }
  const int lo = std::min(ix_, iy_);
  slot_ = lo;
  for (int i = 0; i < n_; ++i)
    if (i != ix_ && i != iy_) others_.push_back(i);
  if (p.output_modes > 0) {
    // the rotor's lowest free modes as observables: eta_k = (M phi_k)^T q by M Phi, made once
    const RotorModes modes = rotor_modes(p, p.output_modes);
    Mphi_ = r.M * modes.shapes;
    const bool rotations =
        std::find(r.rotation.begin(), r.rotation.end(), true) != r.rotation.end();
    const std::string unit = "kg^0.5 m";
    const std::string mixed =
        rotations ? "; q holds rotations (rad): a sum over deflections in kg^0.5 m and rotations "
                    "in kg^0.5 rad"
                  : "";
    for (const char* rate : {"", "v"}) {
      for (int k = 0; k < p.output_modes; ++k) {
        const auto j = static_cast<std::size_t>(k);
        const std::string plane =
            modes.planes[j].empty() ? std::string() : fmt::format(", {} plane", modes.planes[j]);
        observables_.push_back(
            {fmt::format("{}mode{}", rate, k + 1), *rate ? fmt::format("{}/s", unit) : unit,
             fmt::format("{} of the rotor's free mode {} ({:.6g} Hz{}): {}phi^T M {}, phi "
                         "mass-normalised (output_modes.npy){}",
                         *rate ? "the rate of the amplitude" : "the amplitude", k + 1,
                         modes.f_hz[j], plane, *rate ? "" : "eta = ", *rate ? "q'" : "q", mixed)});
      }
    }
  }
}

void MatrixModel::compute_observables(double /*t*/, VecIn q, VecIn v, VecIn /*a*/,
                                      const ContactForce* /*F*/, VecOut out) const {
  const Eigen::Index m = Mphi_.cols();
  for (Eigen::Index k = 0; k < m; ++k) {
    out[k] = Mphi_.col(k).dot(q.head(n_));
    out[m + k] = Mphi_.col(k).dot(v.head(n_));
  }
}

void MatrixModel::unbalance_terms(VecIn q, double& ubs, double& ubc) const {
  const double ub = p_.loads.unbalance;
  if (ub == 0.0) {
    ubs = ubc = 0.0;
    return;
  }
  const double psi = q[th_] + p_.loads.unbalance_phase;
  ubs = ub * std::sin(psi);
  ubc = ub * std::cos(psi);
}

double MatrixModel::b(int i, VecIn q, double ubs, double ubc) const {
  double bi = 0.5 * Ge_.dot(i, q.data());
  if (i == ix_) bi -= ubs;
  if (i == iy_) bi += ubc;
  return bi;
}

void MatrixModel::spin_b(VecIn q, double ubs, double ubc, double* bq) const {
  std::fill_n(bq, n_, 0.0);
  Ge_.multiply_add(0.5, q.data(), bq);  // (0 + 0.5 dot: b(i)'s bits on the envelope)
  bq[ix_] -= ubs;
  bq[iy_] += ubc;
}

void MatrixModel::solve_rotor_mass(double* x) const {
  if (Minv_.size() > 0) {
    Vec& m = spin_scratch(n_).m;
    m.head(n_) = Eigen::Map<const Vec>(x, n_);
    Eigen::Map<Vec>(x, n_).noalias() = Minv_ * m.head(n_);
    return;
  }
  // L z = x by rows (z_i = (x_i - L_i,lo..i-1 . z) / L_ii), then L^T y = z by the columns of
  // L^T, i.e. the same rows of L (y_i = z_i / L_ii, then z_lo..i-1 -= y_i L_i,lo..i-1): both
  // touch the envelope only
  const Envelope& L = Le_;
  for (int i = 0; i < n_; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Eigen::Index m = L.len[k] - 1;  // (the diagonal is the row's last entry)
    const double* row = L.val.data() + L.off[k];
    const double s = Eigen::Map<const Vec>(row, m).dot(Eigen::Map<const Vec>(x + L.lo[k], m));
    x[i] = (x[i] - s) / row[m];
  }
  for (int i = n_ - 1; i >= 0; --i) {
    const auto k = static_cast<std::size_t>(i);
    const Eigen::Index m = L.len[k] - 1;
    const double* row = L.val.data() + L.off[k];
    x[i] /= row[m];
    Eigen::Map<Vec>(x + L.lo[k], m) -= x[i] * Eigen::Map<const Vec>(row, m);
  }
}

double MatrixModel::spin_column(VecIn q, double ubs, double ubc, double* bq, double* u) const {
  spin_b(q, ubs, ubc, bq);
  std::copy_n(bq, n_, u);
  solve_rotor_mass(u);
  double s = p_.rotor.Jp;
  for (int i = 0; i < n_; ++i) s -= bq[i] * u[i];
  return s;
}

double MatrixModel::schur(VecIn q) const {
  double ubs, ubc;
  unbalance_terms(q, ubs, ubc);
  SpinScratch& w = spin_scratch(n_);
  return spin_column(q, ubs, ubc, w.b.data(), w.u.data());
}

void MatrixModel::mass_matrix(VecIn q, MatOut M) const {
  double ubs, ubc;
  unbalance_terms(q, ubs, ubc);
  M.setZero();
  M.topLeftCorner(n_, n_) = p_.rotor.M;
  for (int i = 0; i < n_; ++i) M(i, th_) = M(th_, i) = b(i, q, ubs, ubc);
  M(th_, th_) = p_.rotor.Jp;
  for (const Node& nd : nodes_)
    if (nd.sprung()) M(nd.xs, nd.xs) = M(nd.ys, nd.ys) = nd.stator.mass;
}

bool MatrixModel::rotor_part_zero(const double* x) const {
  for (int i = 0; i < n_; ++i)
    if (x[i] != 0.0) return false;
  return true;
}

void MatrixModel::mass_product(VecIn q, VecIn x, VecOut y) const {
  double ubs, ubc;
  unbalance_terms(q, ubs, ubc);
  double yth = p_.rotor.Jp * x[th_];
  const bool rotor_zero = rotor_part_zero(x.data());  // (a prescribed spin's M e_theta alpha)
  double* bq = spin_scratch(n_).bm.data();
  spin_b(q, ubs, ubc, bq);
  for (int i = 0; i < n_; ++i) y[i] = 0.0;
  // (the same values: M's row times zeros adds nothing)
  if (!rotor_zero) Me_.multiply_add(1.0, x.data(), y.data());  // (0 + 1 dot: dot's bits)
  for (int i = 0; i < n_; ++i) {
    y[i] += bq[i] * x[th_];
    if (!rotor_zero) yth += bq[i] * x[i];
  }
  y[th_] = yth;
  for (const Node& nd : nodes_) {
    if (!nd.sprung()) continue;
    y[nd.xs] = nd.stator.mass * x[nd.xs];
    y[nd.ys] = nd.stator.mass * x[nd.ys];
  }
}

void MatrixModel::solve_rotor_rhs(double* x, double* tmp) const {
  // the nonzeros: all on the contact nodes' coordinates (a contact's W_N, W_T; none: a spin or
  // ring column), then their unit solves combined; else the envelope solve
  int on_nodes = 0;
  bool elsewhere = false;
  for (int i = 0; i < n_ && !elsewhere; ++i) {
    if (x[i] == 0.0) continue;
    if (unit_pos_[static_cast<std::size_t>(i)] < 0) elsewhere = true;
    ++on_nodes;
  }
  if (elsewhere) {
    solve_rotor_mass(x);
  } else if (on_nodes > 0) {
    Eigen::Map<Vec> z(x, n_), t(tmp, n_);
    t = z;
    z.setZero();
    for (int i = 0; i < n_; ++i)
      if (t[i] != 0.0) z += t[i] * unit_solves_.col(unit_pos_[static_cast<std::size_t>(i)]);
  }
}

bool MatrixModel::solve_mass_without(int s, VecIn /*q*/, MatOut B) const {
  // without the spin, M is block diagonal: the rotor's M and the rings' masses (the spin's
  // coordinate th_ = n_ comes after the rotor's, so the rings' rows move up by one)
  if (s != th_) return false;
  RUBDYN_DEMAND(B.rows() == N_ - 1);
  SpinScratch& w = spin_scratch(n_);
  for (Eigen::Index j = 0; j < B.cols(); ++j) {
    auto r = B.col(j);
    solve_rotor_rhs(r.data(), w.z.data());
    for (const Node& nd : nodes_) {
      if (!nd.sprung()) continue;
      r[nd.xs - 1] /= nd.stator.mass;
      r[nd.ys - 1] /= nd.stator.mass;
    }
  }
  return true;
}

bool MatrixModel::spin_row(double /*t*/, VecIn q, VecIn v, VecIn a, double& Ma, double& f) const {
  // mass_product's and smooth_forces' theta entries, term by term in their order
  const auto& L = p_.loads;
  double ubs, ubc;
  unbalance_terms(q, ubs, ubc);
  Ma = p_.rotor.Jp * a[th_];
  if (!rotor_part_zero(a.data())) {
    double* bq = spin_scratch(n_).bm.data();
    spin_b(q, ubs, ubc, bq);
    for (int i = 0; i < n_; ++i) Ma += bq[i] * a[i];
  }
  f = L.drive_torque(v[th_]);
  if (L.unbalance != 0.0) f -= L.gravity * ubc;
  return true;
}

bool MatrixModel::newton_entries(double /*t*/, VecIn q, VecIn v, VecIn a, NewtonEntries& e) const {
  // the dense Jacobians' entries (mass_matrix, smooth_force_jacobians,
  // mass_matrix_product_jacobian) on the envelopes only
  e.clear();
  const auto& L = p_.loads;
  const double om = v[th_], at = a[th_];
  double ubs, ubc;
  unbalance_terms(q, ubs, ubc);
  // emit(i, j, value) for each entry of an envelope (row i of the matrix it was built from)
  const auto each = [this](const Envelope& env, auto&& emit) {
    for (int i = 0; i < n_; ++i) {
      const auto k = static_cast<std::size_t>(i);
      for (Eigen::Index j = 0; j < env.len[k]; ++j)
        emit(i, static_cast<int>(env.lo[k] + j), env.val[static_cast<std::size_t>(env.off[k] + j)]);
    }
  };
  // M: the rotor's (Me_ holds M^T's rows), the spin's row and column b(q), Jp, the rings' masses
  each(Me_, [&](int i, int j, double x) { e.M.push_back({j, i, x}); });
  for (int i = 0; i < n_; ++i) {
    const double bi = b(i, q, ubs, ubc);
    e.M.push_back({i, th_, bi});
    e.M.push_back({th_, i, bi});
  }
  e.M.push_back({th_, th_, p_.rotor.Jp});
  // df/dq - d(M a)/dq: -K, the unbalance's terms, -G a_theta / 2 and the spin's row -(G^T a)/2
  each(Ke_, [&](int i, int j, double x) { e.dq.push_back({i, j, -x}); });
  const double cg = -0.5 * at;
  each(Ge_, [&](int i, int j, double x) {
    e.dq.push_back({i, j, cg * x});
    e.dq.push_back({th_, j, -0.5 * x * a[i]});
  });
  e.dq.push_back({ix_, th_, ubc * at});
  e.dq.push_back({iy_, th_, ubs * at});
  e.dq.push_back({th_, th_, ubc * a[ix_] + ubs * a[iy_]});
  // df/dv: -C - Omega G, the spin's column -G v, the torque's slope
  each(Ce_, [&](int i, int j, double x) { e.dv.push_back({i, j, -x}); });
  each(Ge_, [&](int i, int j, double x) { e.dv.push_back({i, j, -om * x}); });
  for (int i = 0; i < n_; ++i) e.dv.push_back({i, th_, -Ge_.dot(i, v.data())});
  e.dv.push_back({th_, th_, L.drive_torque_slope()});
  if (L.unbalance != 0.0) {
    e.dq.push_back({ix_, th_, -om * om * ubs});
    e.dq.push_back({iy_, th_, om * om * ubc});
    e.dq.push_back({th_, th_, L.gravity * ubs});
    e.dv.push_back({ix_, th_, 2.0 * om * ubc});
    e.dv.push_back({iy_, th_, 2.0 * om * ubs});
  }
  for (const Node& nd : nodes_) {
    if (!nd.sprung()) continue;
    for (const int i : {nd.xs, nd.ys}) {
      e.M.push_back({i, i, nd.stator.mass});
      e.dq.push_back({i, i, -nd.stator.k});
      e.dv.push_back({i, i, -nd.stator.c});
    }
  }
  return true;
}

void MatrixModel::solve_mass(VecIn q, MatOut B) const {
  // Schur complement on theta (header): b and u once per call, then per right-hand side
  // two envelope solves and two products with b and u (O(n w) each)
  double ubs, ubc;
  unbalance_terms(q, ubs, ubc);
  SpinScratch& w = spin_scratch(n_);
  const auto bq = w.b.head(n_), u = w.u.head(n_);
  const double s = spin_column(q, ubs, ubc, w.b.data(), w.u.data());
  const bool ok = s > 0.0;  // (NaN: not ok)
  for (Eigen::Index j = 0; j < B.cols(); ++j) {
    auto r = B.col(j);
    if (!ok) {  // M_full not positive definite here: no solution (the solvers end the run)
      r.setConstant(std::numeric_limits<double>::quiet_NaN());
      continue;
    }
    auto z = r.head(n_);
    solve_rotor_rhs(z.data(), w.z.data());
    const double th = (r[th_] - bq.dot(z)) / s;
    z -= th * u;
    r[th_] = th;
    for (const Node& nd : nodes_) {
      if (!nd.sprung()) continue;
      r[nd.xs] /= nd.stator.mass;
      r[nd.ys] /= nd.stator.mass;
    }
  }
}

void MatrixModel::mass_matrix_product_jacobian(VecIn q, VecIn a, MatOut J) const {
  // rows i < n: (M a)_i + b_i(q) a_theta; row theta: b(q) . a_q + Jp a_theta, with
  // db/dq = G / 2 and db/dtheta = -u_b (cos psi e_x + sin psi e_y)
  double ubs, ubc;
  unbalance_terms(q, ubs, ubc);
  J.setZero();
  const double at = a[th_];
  for (int k = 0; k < n_; ++k) {
    for (int i = 0; i < n_; ++i) J(i, k) = 0.5 * p_.rotor.G(i, k) * at;
    J(th_, k) = 0.5 * p_.rotor.G.col(k).dot(a.head(n_));  // 1/2 (G^T a)_k
  }
  J(ix_, th_) = -ubc * at;
  J(iy_, th_) = -ubs * at;
  J(th_, th_) = -ubc * a[ix_] - ubs * a[iy_];
}

void MatrixModel::smooth_forces(double /*t*/, VecIn q, VecIn v, VecOut f) const {
  const auto& L = p_.loads;
  const double om = v[th_];
  // f0 - C v - K q - Omega G v, term by term (on an envelope the bits of the row's expression:
  // y + (-1) dot = y - dot, y + (-Omega) dot = y - Omega dot)
  double* fr = f.data();
  for (int i = 0; i < n_; ++i) fr[i] = p_.rotor.f0[i];
  Ce_.multiply_add(-1.0, v.data(), fr);
  Ke_.multiply_add(-1.0, q.data(), fr);
  Ge_.multiply_add(-om, v.data(), fr);
  f[th_] = L.drive_torque(om);
  if (L.unbalance != 0.0) {
    double ubs, ubc;
    unbalance_terms(q, ubs, ubc);
    f[ix_] += om * om * ubc;  // the centrifugal force u_b Omega^2 e^{i psi}
    f[iy_] += om * om * ubs;
    f[th_] -= L.gravity * ubc;  // gravity's torque on the unbalance
  }
  for (const Node& nd : nodes_) {
    if (!nd.sprung()) continue;
    const MatrixStatorParams& st = nd.stator;
    f[nd.xs] = -st.c * v[nd.xs] - st.k * q[nd.xs];
    f[nd.ys] = -st.c * v[nd.ys] - st.k * q[nd.ys] - st.mass * L.gravity;
  }
}

void MatrixModel::smooth_force_jacobians(double /*t*/, VecIn q, VecIn v, MatOut dfdq,
                                         MatOut dfdv) const {
  const auto& L = p_.loads;
  const double om = v[th_];
  dfdq.setZero();
  dfdv.setZero();
  dfdq.topLeftCorner(n_, n_) = -p_.rotor.K;
  dfdv.topLeftCorner(n_, n_) = -p_.rotor.C - om * p_.rotor.G;
  for (int i = 0; i < n_; ++i) dfdv(i, th_) = -Ge_.dot(i, v.data());
  dfdv(th_, th_) = L.drive_torque_slope();
  if (L.unbalance != 0.0) {
    double ubs, ubc;
    unbalance_terms(q, ubs, ubc);
    dfdq(ix_, th_) = -om * om * ubs;
    dfdq(iy_, th_) = om * om * ubc;
    dfdq(th_, th_) = L.gravity * ubs;
    dfdv(ix_, th_) += 2.0 * om * ubc;
    dfdv(iy_, th_) += 2.0 * om * ubs;
  }
  for (const Node& nd : nodes_) {
    if (!nd.sprung()) continue;
    dfdq(nd.xs, nd.xs) = dfdq(nd.ys, nd.ys) = -nd.stator.k;
    dfdv(nd.xs, nd.xs) = dfdv(nd.ys, nd.ys) = -nd.stator.c;
  }
}

void MatrixModel::compute_contact(int k, double /*t*/, VecIn q, VecIn v,
                                  ContactKinematics& c) const {
  // node k's (x, y) inside its ring (x_s_k, y_s_k), or a fixed ring at the origin
  const Node& nd = this->nd(k);
  RingContact g;
  g.ix = {nd.ix, -1};
  g.iy = {nd.iy, -1};
  g.w = {1.0, 0.0};
  g.ring = nd.sprung() ? nd.xs : -1;
  g.gap = nd.gap;
  g.radius = nd.radius;
  for (int i = 0; i < N_; ++i) c.W_N[i] = c.W_T[i] = 0.0;
  ring_contact_kinematics(g, th_, q, v, c);
}

double MatrixModel::kinetic_energy(double /*t*/, VecIn q, VecIn v) const {
  double ubs, ubc;
  unbalance_terms(q, ubs, ubc);
  const double om = v[th_];
  double T = p_.rotor.Jp * om * om;
  for (int i = 0; i < n_; ++i) T += v[i] * (Me_.dot(i, v.data()) + 2.0 * om * b(i, q, ubs, ubc));
  for (const Node& nd : nodes_)
    if (nd.sprung()) T += nd.stator.mass * (v[nd.xs] * v[nd.xs] + v[nd.ys] * v[nd.ys]);
  return 0.5 * T;
}

double MatrixModel::potential_energy(double /*t*/, VecIn q) const {
  const auto& L = p_.loads;
  double V = 0.0;
  for (int i = 0; i < n_; ++i) V += q[i] * (0.5 * Ke_.dot(i, q.data()) - p_.rotor.f0[i]);
  if (L.unbalance != 0.0) V += L.gravity * L.unbalance * std::sin(q[th_] + L.unbalance_phase);
  for (const Node& nd : nodes_)
    if (nd.sprung())
      V += 0.5 * nd.stator.k * (q[nd.xs] * q[nd.xs] + q[nd.ys] * q[nd.ys]) +
           L.gravity * nd.stator.mass * q[nd.ys];
  return V;
}

SmoothPower MatrixModel::smooth_power(double /*t*/, VecIn /*q*/, VecIn v) const {
  SmoothPower p;
  p.external = p_.loads.drive_torque(v[th_]) * v[th_];
  double d = 0.0;
  for (int i = 0; i < n_; ++i) d -= v[i] * Ce_.dot(i, v.data());
  for (const Node& nd : nodes_)
    if (nd.sprung()) d -= nd.stator.c * (v[nd.xs] * v[nd.xs] + v[nd.ys] * v[nd.ys]);
  p.damping = d;
  return p;
}

std::optional<LinearModel> MatrixModel::linearize(Linearization mode) const {
  // the whirl labels of a Campbell diagram pair the coordinates (0, 1), (2, 3), ... as (x, y)
  // of an isotropic rotor: only an even n has them
  if (n_ % 2 != 0) return std::nullopt;
  const bool tied = mode == Linearization::Tied;
  int rings = 0;
  for (const Node& nd : nodes_) {
    if (tied && !nd.sprung()) return std::nullopt;  // (a rigid ring pins its node)
    rings += nd.sprung() ? 1 : 0;
  }
  const int m = n_ + (tied ? 0 : 2 * rings);
  LinearModel lm;
  // the rings' coordinates follow theta in coords_ (skipped)
  for (int i = 0; i < m; ++i)
    lm.names.push_back(coords_[static_cast<std::size_t>(i < n_ ? i : i + 1)].name);
  lm.M.setZero(m, m);
  lm.G.setZero(m, m);
  lm.D.setZero(m, m);
  lm.K.setZero(m, m);
  const auto& r = p_.rotor;
  lm.M.topLeftCorner(n_, n_) = r.M;
  lm.G.topLeftCorner(n_, n_) = r.G;
  lm.D.topLeftCorner(n_, n_) = r.C;
  lm.K.topLeftCorner(n_, n_) = r.K;
  for (int k = 0; k < n_; k += 2) lm.nodes.push_back({k, k + 1});
  int next = n_;
  for (const Node& nd : nodes_) {
    if (!nd.sprung()) continue;
    const auto& s = nd.stator;
    const int a = tied ? nd.ix : next, b = tied ? nd.iy : next + 1;
    for (int i : {a, b}) {
      lm.M(i, i) += s.mass;
      lm.D(i, i) += s.c;
      lm.K(i, i) += s.k;
    }
    if (!tied) lm.nodes.push_back({next, next + 1});
    next += 2;
  }
  return lm;
}

// ---- minimal coordinates of the contact phases ------------------------------------------------

int MatrixModel::Chart::dim(ChartMode mode) const {
  return (m_.n_ - 1) + (mode == ChartMode::Slip ? 1 : 0) + (m_.sprung_ ? 2 : 0);
}

void MatrixModel::Chart::chart(ChartMode mode, VecIn q, VecIn v, ChartAnchor& anchor, VecOut p,
                               VecOut pd) const {
  const MatrixModel& m = m_;
  const double xs = m.sprung_ ? q[m.xs_] : 0.0, ys = m.sprung_ ? q[m.ys_] : 0.0;
  const double vxs = m.sprung_ ? v[m.xs_] : 0.0, vys = m.sprung_ ? v[m.ys_] : 0.0;
  const double phi = std::atan2(q[m.iy_] - ys, q[m.ix_] - xs);
  anchor.fill(0.0);
  const int nr = m.n_ - 1;
  for (int k = 0; k < nr; ++k) {
    if (k == m.slot_) continue;
    const int i = copied(k);
    p[k] = q[i];
    pd[k] = v[i];
  }
  int k = nr;
  if (mode == ChartMode::Slip) {
    const double g0 = m.nd(0).gap;
    p[m.slot_] = phi;
    pd[m.slot_] = (-std::sin(phi) * (v[m.ix_] - vxs) + std::cos(phi) * (v[m.iy_] - vys)) / g0;
    p[k] = q[m.th_];
    pd[k++] = v[m.th_];
  } else {
    anchor[0] = phi;
    anchor[1] = q[m.th_];
    p[m.slot_] = 0.0;
    pd[m.slot_] = v[m.th_];
  }
  if (m.sprung_) {
    p[k] = xs;
    pd[k++] = vxs;
    p[k] = ys;
    pd[k] = vys;
  }
}

void MatrixModel::Chart::embed(ChartMode mode, const ChartAnchor& anchor, VecIn p, VecIn pd,
                               VecOut q, VecOut v) const {
  const MatrixModel& m = m_;
  const double g0 = m.nd(0).gap;
  const int nr = m.n_ - 1;
  for (int k = 0; k < nr; ++k) {
    if (k == m.slot_) continue;
    const int i = copied(k);
    q[i] = p[k];
    v[i] = pd[k];
  }
  double phi, phid;
  int k = nr;
  if (mode == ChartMode::Slip) {
    phi = p[m.slot_];
    phid = pd[m.slot_];
    q[m.th_] = p[k];
    v[m.th_] = pd[k++];
  } else {
    const double ratio = m.nd(0).radius / g0;
    phi = anchor[0] - ratio * p[m.slot_];
    phid = -ratio * pd[m.slot_];
    q[m.th_] = anchor[1] + p[m.slot_];
    v[m.th_] = pd[m.slot_];
  }
  double xs = 0.0, ys = 0.0, vxs = 0.0, vys = 0.0;
  if (m.sprung_) {
    xs = q[m.xs_] = p[k];
    ys = q[m.ys_] = p[k + 1];
    vxs = v[m.xs_] = pd[k];
    vys = v[m.ys_] = pd[k + 1];
  }
  const double c = std::cos(phi), s = std::sin(phi);
  q[m.ix_] = xs + g0 * c;
  q[m.iy_] = ys + g0 * s;
  v[m.ix_] = vxs - g0 * phid * s;
  v[m.iy_] = vys + g0 * phid * c;
}

void MatrixModel::Chart::reduce(ChartMode mode, const ChartAnchor& /*anchor*/, VecIn /*p*/,
                                VecIn /*pd*/, VecIn q, VecIn a, VecOut pdd) const {
  const MatrixModel& m = m_;
  const double g0 = m.nd(0).gap;
  const double xs = m.sprung_ ? q[m.xs_] : 0.0, ys = m.sprung_ ? q[m.ys_] : 0.0;
  const double axs = m.sprung_ ? a[m.xs_] : 0.0, ays = m.sprung_ ? a[m.ys_] : 0.0;
  const int nr = m.n_ - 1;
  for (int k = 0; k < nr; ++k) {
    if (k == m.slot_) continue;
    pdd[k] = a[copied(k)];
  }
  int k = nr;
  if (mode == ChartMode::Slip) {
    // phi'' = t_phi . (a_r - a_s) / g0 (the curvature term is normal to t_phi)
    const double tx = -(q[m.iy_] - ys) / g0, ty = (q[m.ix_] - xs) / g0;
    pdd[m.slot_] = (tx * (a[m.ix_] - axs) + ty * (a[m.iy_] - ays)) / g0;
    pdd[k++] = a[m.th_];
  } else {
    pdd[m.slot_] = a[m.th_];
  }
  if (m.sprung_) {
    pdd[k++] = axs;
    pdd[k] = ays;
  }
}

ChartScales MatrixModel::Chart::scales(ChartMode mode) const {
  // phi moves the contact point by g0 per radian; theta - theta0 in stick by R
  ChartScales sc;
  sc.length.assign(static_cast<std::size_t>(dim(mode)), 0.0);
  sc.length[static_cast<std::size_t>(m_.slot_)] =
      mode == ChartMode::Slip ? m_.nd(0).gap : m_.nd(0).radius;
  // the copies, in chart()'s order: q without the node's (x, y), theta in slip, the ring
  sc.copies.assign(sc.length.size(), -1);
  const int nr = m_.n_ - 1;
  for (int k = 0; k < nr; ++k)
    if (k != m_.slot_) sc.copies[static_cast<std::size_t>(k)] = copied(k);
  int k = nr;
  if (mode == ChartMode::Slip) sc.copies[static_cast<std::size_t>(k++)] = m_.th_;
  if (m_.sprung_) {
    sc.copies[static_cast<std::size_t>(k++)] = m_.xs_;
    sc.copies[static_cast<std::size_t>(k)] = m_.ys_;
  }
  return sc;
}

}  // namespace rubdyn
