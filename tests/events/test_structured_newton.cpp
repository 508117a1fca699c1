// Free flight's Newton systems by BDF (hybrid/phase_session.*): the structured solve, one n x n
// factorisation of S = M - gamma df/dv - gamma^2 (df/dq - d(M a)/dq), against the dense system
// I - gamma J of the analytic Jacobian on the whole state (2n + 3 components).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "hybrid/phase_chart.hpp"
#include "hybrid/phase_session.hpp"
#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/solver_options.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"

using namespace rubdyn;
using namespace rubdyn::detail;

namespace {

/// The Jacobian [A_q, A_v] (n x 2n) of the constrained acceleration of one closed contact in
/// `mode` at (t, q, v), dense: the bordered system [M -W_f; H 0] solved for the derivatives with
/// W_f, H and wdot held (what the projected and the reduced sessions' Newton systems claim).
Mat constrained_jacobian(const LagrangianModel& m, const PhaseContext& ctx, Phase mode, double t,
                         const Vec& q, const Vec& v) {
  const int n = m.num_dofs();
  PhaseEval e(m, ctx.K);
  REQUIRE(e.dynamics(t, q, v, ctx.modes, ctx.laws));
  const Vec a = e.a();
  Mat M(n, n), dfdq(n, n), dfdv(n, n), dMa(n, n);
  m.mass_matrix(q, M);
  m.smooth_force_jacobians(t, q, v, dfdq, dfdv);
  m.mass_matrix_product_jacobian(q, a, dMa);
  const ContactKinematics& c = e.c(0);
  const int mc = mode == Phase::Stick ? 2 : 1;
  Mat Wf(n, mc), H(mc, n);
  H.row(0) = c.W_N.transpose();
  Wf.col(0) = c.W_N;
  if (mode == Phase::Stick) {
    H.row(1) = c.W_T.transpose();
    Wf.col(1) = c.W_T;
  } else {
    Wf.col(0) -= ctx.law(0).mu * slip_sign(mode) * c.W_T;
  }
  Mat Sad = Mat::Zero(n + mc, n + mc);
  Sad.topLeftCorner(n, n) = M;
  Sad.topRightCorner(n, mc) = -Wf;
  Sad.bottomLeftCorner(mc, n) = H;
  Mat rhs = Mat::Zero(n + mc, 2 * n);
  rhs.topLeftCorner(n, n) = dfdq - dMa;
  rhs.topRightCorner(n, n) = dfdv;
  return Sad.fullPivLu().solve(rhs).topRows(n);
}

}  // namespace

namespace {

/// The residual of the structured solve in the dense system, relative: |A x - b| / (|A| |x|)
/// (infinity norms), for states and right-hand sides drawn at the model's scales.
double relative_residual(const LagrangianModel& m, double gamma, unsigned seed) {
  const PhaseContext ctx(m, 1e-8, 1e-13, 0.0);
  SessionSettings s;
  s.adams = false;  // BDF: the Newton systems
  PhaseSession ps(ctx, s, SessionKind::Free);
  const int n = m.num_dofs(), N = 2 * n + kNw;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> y(static_cast<std::size_t>(N)), b(y.size()), x(y.size());
  for (int i = 0; i < n; ++i) {
    y[static_cast<std::size_t>(i)] = 1e-4 * u(rng);      // positions: a tenth of a mm
    y[static_cast<std::size_t>(n + i)] = 1e-1 * u(rng);  // velocities
  }
  if (m.spin_coordinate() >= 0) y[static_cast<std::size_t>(n + m.spin_coordinate())] = 300.0;
  for (double& v : b) v = u(rng);
  int jcur = 0;
  REQUIRE(PhaseSession::lsys_free(0.01, y.data(), gamma, 0, &jcur, &ps) == 0);
  CHECK(jcur == 1);
  REQUIRE(PhaseSession::lsolve_free(b.data(), x.data(), &ps) == 0);
  Mat J(N, N);
  REQUIRE(PhaseSession::jac_free(0.01, y.data(), nullptr, J.data(), &ps) == 0);
  const Mat A = Mat::Identity(N, N) - gamma * J;
  const Eigen::Map<const Vec> xv(x.data(), N), bv(b.data(), N);
  const double r = (A * xv - bv).lpNorm<Eigen::Infinity>();
  const double scale = A.cwiseAbs().rowwise().sum().maxCoeff() * xv.lpNorm<Eigen::Infinity>();
  return r / scale;
}

}  // namespace

TEST_CASE(
    "Structured Newton solve of free flight equals the dense system's, FE rotor and rigid rotor",
    "[events][newton]") {
  // cases/fe-runup.toml: a 52-coordinate finite-element shaft with the spin, the ring's two and
  // gyroscopic, unbalance and bearing terms; gamma from the BDF steps it takes (1e-6 .. 1e-4 s)
  // up to far beyond them, where S is dominated by gamma^2 K.
  const CaseSpec fe = load_case(std::string(RUBDYN_SOURCE_DIR) + "/cases/fe-runup.toml", {});
  const auto fe_model = build_model(fe);
  // the rigid rotor of the paper: M depends on q, so d(M a)/dq enters
  const RotorStatorModel rigid(RotorStatorParams{});
  // the two-seal FE rotor reduced by Craig-Bampton to 24 dense coordinates: S factored densely,
  // the model's entry lists gathered into dense blocks (PhaseSession::free_jacobians)
  const CaseSpec cb = load_case(std::string(RUBDYN_SOURCE_DIR) + "/cases/fe-two-seal.toml",
                                {"reduction.method=\"craig-bampton\"", "reduction.modes=20"});
  const auto cb_model = build_model(cb);
  for (const double gamma : {1e-6, 1e-5, 1e-4, 1e-2}) {
    const std::vector<const LagrangianModel*> models = {fe_model.get(), &rigid, cb_model.get()};
    for (const LagrangianModel* m : models) {
      INFO(m->name() << ", gamma " << gamma);
      // The exact Newton step, computed two ways: LU with partial pivoting of S is backward
      // stable (a residual of a few n eps |S| |x|), and forming the right-hand side and the
      // back substitution x_q = b_q + gamma x_v add a few eps more; n eps = 1.2e-14 at n = 55.
      // Measured: 4e-22 .. 6e-17. 1e-12 leaves two orders for the growth of the elimination
      // and is far below what a wrong block leaves (measured with the gamma^2 term dropped:
      // 4e-8 at gamma = 1e-6 to 1e-2 at gamma = 1e-2).
      CHECK(relative_residual(*m, gamma, 7u) <= 1e-12);
    }
  }
}

namespace {

/// A state of model m in contact with its first ring: every coordinate drawn small, then the
/// first contact node put on the ring's circle (d_N = 0) and its velocity relative to the ring
/// made tangential, whirling at `whirl` rad/s about the ring's centre.
void contact_state(const LagrangianModel& m, unsigned seed, Vec& q, Vec& v) {
  const int n = m.num_dofs();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  q.resize(n);
  v.resize(n);
  for (int i = 0; i < n; ++i) q[i] = 2e-5 * u(rng), v[i] = 1e-2 * u(rng);
  if (m.spin_coordinate() >= 0) v[m.spin_coordinate()] = 300.0;
  int ix = -1, iy = -1, xs = -1, ys = -1;
  const auto& cs = m.coordinates();
  for (int i = 0; i < n; ++i) {
    const auto r = cs[static_cast<std::size_t>(i)].role;
    if (cs[static_cast<std::size_t>(i)].plane != 0) continue;
    if (r == CoordinateRole::RotorX) ix = i;
    if (r == CoordinateRole::RotorY) iy = i;
    if (r == CoordinateRole::StatorX) xs = i;
    if (r == CoordinateRole::StatorY) ys = i;
  }
  REQUIRE(ix >= 0);
  REQUIRE(iy >= 0);
  // the node's offset from the ring's centre that closes the gap, by bisection on its length
  // (the gap's definition is the model's: a rigid rotor's seal point is not its coordinates')
  const double phi = 0.7, whirl = 400.0;
  const double cx = xs >= 0 ? q[xs] : 0.0, cy = ys >= 0 ? q[ys] : 0.0;
  double lo = 0.0, hi = 10.0 * m.gap_scale(0);
  for (int it = 0; it < 200; ++it) {
    const double r = 0.5 * (lo + hi);
    q[ix] = cx + r * std::cos(phi);
    q[iy] = cy + r * std::sin(phi);
    (m.contact(0, 0.01, q, v).d_N > 0.0 ? lo : hi) = r;
  }
  const double r = 0.5 * (lo + hi);
  const double vcx = xs >= 0 ? v[xs] : 0.0, vcy = ys >= 0 ? v[ys] : 0.0;
  v[ix] = vcx - r * whirl * std::sin(phi);
  v[iy] = vcy + r * whirl * std::cos(phi);
}

struct ProjectedErrors {
  double model = 0.0;  ///< residual in the Jacobian it claims (W_f, H, wdot held fixed)
  double exact = 0.0;  ///< difference from the Newton step of the exact Jacobian
  double bound = 0.0;  ///< its bound gamma |N_c^-1| |(J_e - J_c) x_e| / |x_e|
  /// the largest column of J_e - J_c outside the contact's coordinates, relative to J_e's
  double elsewhere = 0.0;
};

/// The Projected session's structured Newton step against dense systems built here from the
/// model's matrices and a PhaseEval: (1) the claimed Jacobian J_c = [[0, I], [A_q, A_v]] with
/// A_x the first block of [[M, -W_f], [H, 0]]^-1 [F_x; 0] (F_q = df/dq - d(M a)/dq at the
/// constrained a, F_v = df/dv): relative residual of the structured x in I - gamma J_c;
/// (2) the exact Jacobian by central differences of the constrained acceleration: relative
/// difference of the Newton steps.
ProjectedErrors projected_errors(const LagrangianModel& m, Phase mode, double gamma,
                                 unsigned seed) {
  PhaseContext ctx(m, 1e-8, 1e-13, 0.0);
  ctx.modes[0] = mode;
  SessionSettings s;
  s.adams = false;
  PhaseSession ps(ctx, s, SessionKind::Projected);
  const int n = m.num_dofs(), N = 2 * n + kNw;
  Vec q, v;
  contact_state(m, seed, q, v);
  std::vector<double> y(static_cast<std::size_t>(N), 0.0), b(y.size()), x(y.size());
  std::copy(q.data(), q.data() + n, y.begin());
  std::copy(v.data(), v.data() + n, y.begin() + n);
  std::mt19937 rng(seed + 1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (double& e : b) e = u(rng);
  const double t = 0.01;
  int jcur = 0;
  REQUIRE(PhaseSession::lsys_projected(t, y.data(), gamma, 0, &jcur, &ps) == 0);
  REQUIRE(PhaseSession::lsolve_projected(b.data(), x.data(), &ps) == 0);
  const Eigen::Map<const Vec> xv(x.data(), 2 * n), bv(b.data(), 2 * n);

  // (1) the claimed Jacobian, dense
  const Mat A = constrained_jacobian(m, ctx, mode, t, q, v);
  PhaseEval e(m, ctx.K);  // (the exact Jacobian's differences below)
  REQUIRE(e.dynamics(t, q, v, ctx.modes, ctx.laws));
  const ContactKinematics c = e.c(0);  // (a copy: e moves on)
  Mat Jc = Mat::Zero(2 * n, 2 * n);
  Jc.topRightCorner(n, n).setIdentity();
  Jc.bottomRows(n) = A;
  const Mat Nc = Mat::Identity(2 * n, 2 * n) - gamma * Jc;
  ProjectedErrors err;
  err.model = (Nc * xv - bv).lpNorm<Eigen::Infinity>() /
              (Nc.cwiseAbs().rowwise().sum().maxCoeff() * xv.lpNorm<Eigen::Infinity>());

  // (2) the exact Jacobian of the constrained acceleration, central differences
  Mat Je = Mat::Zero(2 * n, 2 * n);
  Je.topRightCorner(n, n).setIdentity();
  for (int j = 0; j < 2 * n; ++j) {
    Vec qp = q, vp = v, qm = q, vm = v;
    const double h = j < n ? 1e-9 : 1e-6 * std::max(1.0, std::abs(v[j - n]));
    (j < n ? qp[j] : vp[j - n]) += h;
    (j < n ? qm[j] : vm[j - n]) -= h;
    REQUIRE(e.dynamics(t, qp, vp, ctx.modes, ctx.laws));
    const Vec ap = e.a();
    REQUIRE(e.dynamics(t, qm, vm, ctx.modes, ctx.laws));
    Je.block(n, j, n, 1) = (ap - e.a()) / (2.0 * h);
  }
  const Vec xe = (Mat::Identity(2 * n, 2 * n) - gamma * Je).partialPivLu().solve(bv);
  err.exact = (xv - xe).lpNorm<Eigen::Infinity>() / xe.lpNorm<Eigen::Infinity>();
  // N_c (x - x_e) = gamma (J_e - J_c) x_e exactly: the step's error is bounded by what the held
  // terms are worth on the exact step
  const Mat dJ = Je - Jc;
  err.bound = gamma * Nc.inverse().lpNorm<Eigen::Infinity>() * (dJ * xe).lpNorm<Eigen::Infinity>() /
              xe.lpNorm<Eigen::Infinity>();
  // the held terms act on the contact's coordinates only: the support of W_N, W_T
  for (int j = 0; j < 2 * n; ++j) {
    const int i = j % n;
    if (c.W_N[i] != 0.0 || c.W_T[i] != 0.0) continue;
    err.elsewhere = std::max(
        err.elsewhere, dJ.col(j).lpNorm<Eigen::Infinity>() / Je.col(j).lpNorm<Eigen::Infinity>());
  }
  return err;
}

}  // namespace

TEST_CASE("Structured Newton solve of a projected contact phase: free flight's S bordered",
          "[events][newton]") {
  const CaseSpec fe = load_case(std::string(RUBDYN_SOURCE_DIR) + "/cases/fe-runup.toml", {});
  const auto fe_model = build_model(fe);  // prescribed spin: no spin coordinate, banded S
  const RotorStatorModel rigid(RotorStatorParams{});  // the spin as S's border, dense
  const std::vector<const LagrangianModel*> models = {fe_model.get(), &rigid};
  for (const LagrangianModel* m : models) {
    for (const Phase mode : {Phase::SlipNeg, Phase::SlipPos, Phase::Stick}) {
      for (const double gamma : {1e-6, 1e-5, 1e-4}) {
        INFO(m->name() << ", " << to_string(mode) << ", gamma " << gamma);
        const ProjectedErrors e = projected_errors(*m, mode, gamma, 3u);
        // (1) exact algebra of the claimed system: LU and Schur complement backward stable,
        // as in the free-flight case above (1e-12).
        CHECK(e.model <= 1e-12);
        // (2) what holding W_f, H and wdot fixed costs. The exact Jacobian differs from the
        // claimed one in the contact coordinates' columns only: elsewhere the difference is the
        // central differences' error (h^2 terms and eps |a| / h: below 1e-6 of the columns,
        // measured up to 7e-8); and the step's difference from the exact Newton step obeys its
        // exact bound (1 % above it for the round-off of forming the bound). How large it is
        // depends on the contact force: this test's states are drawn without equilibrium (the
        // shaft's random deflections give forces of 1e4 .. 1e5 N) and see 6e-7 (FE, stick) .. 0.7
        // (FE, slip, gamma 1e-4); CVODE's Newton iteration converges on the exact residual whatever
        // the Jacobian, and on the FE run-ups it takes 1.1 to 1.4 iterations per step
        // (summary.json newton_iters).
        CHECK(e.elsewhere <= 1e-6);
        CHECK(e.exact <= 1.01 * e.bound);
      }
    }
  }
}

namespace {

struct ReducedErrors {
  double tangent = 0.0;  ///< the chart's tangent map against central differences of its embed
  double inverse = 0.0;  ///< |L T - I|: reduce_linear a left inverse of the tangent map
  double model = 0.0;    ///< residual in the Jacobian it claims, [[0, I], [L A_q T, L A_v T]]
  double exact = 0.0;    ///< difference from the Newton step of the exact reduced Jacobian
  double bound = 0.0;    ///< its bound gamma |N_c^-1| |(J_e - J_c) x_e| / |x_e|
  /// the largest column of J_e - J_c outside the angles and the contact's coordinates,
  /// relative to J_e's
  double elsewhere = 0.0;
};

/// A Reduced session's structured Newton step (lsys_reduced, lsolve_reduced) against dense
/// systems built here: (0) the chart's tangent map T against central differences of its
/// positions, and L T = I; (1) the claimed Jacobian J_c = [[0, I], [L A_q T, L A_v T]] on
/// (p, p'), A_x from the dense bordered system of the constrained acceleration as in
/// projected_errors: relative residual of the structured x in I - gamma J_c; (2) the exact
/// Jacobian of the reduced right-hand side (embed, the constrained acceleration, reduce) by
/// central differences, i.e. what CVODE's dense difference quotients approximate: relative
/// difference of the Newton steps.
ReducedErrors reduced_errors(const LagrangianModel& m, Phase mode, double gamma, unsigned seed) {
  PhaseContext ctx(m, 1e-8, 1e-13, 0.0);
  ctx.modes[0] = mode;
  const auto chart = make_phase_chart(m);
  REQUIRE(chart != nullptr);
  REQUIRE(chart->applies(ctx.modes));
  const int n = m.num_dofs(), d = chart->dim(ctx.modes), N = 2 * d + kNw;
  SessionSettings s;
  s.adams = false;
  PhaseSession ps(ctx, s, SessionKind::Reduced, chart->clone(), d);
  Vec q, v;
  contact_state(m, seed, q, v);
  const double t = 0.01;
  // the reduced state: this chart entered at (q, v) as the session's own is by restart()
  Vec p(d), pd(d);
  std::vector<double> lengths(static_cast<std::size_t>(d));
  std::vector<int> copies(static_cast<std::size_t>(d));
  chart->enter(ctx.modes, t, q, v, p, pd, lengths, copies);
  {
    Vec qs = q, vs = v;
    ps.restart(t, qs, vs, Works{}, 1.0);
  }
  std::vector<double> y(static_cast<std::size_t>(N), 0.0), b(y.size()), x(y.size());
  std::copy(p.data(), p.data() + d, y.begin());
  std::copy(pd.data(), pd.data() + d, y.begin() + d);
  std::mt19937 rng(seed + 1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (double& e : b) e = u(rng);
  int jcur = 0;
  REQUIRE(PhaseSession::lsys_reduced(t, y.data(), gamma, 0, &jcur, &ps) == 0);
  CHECK(jcur == 1);
  REQUIRE(PhaseSession::lsolve_reduced(b.data(), x.data(), &ps) == 0);
  for (int i = 2 * d; i < N; ++i)
    CHECK(x[static_cast<std::size_t>(i)] == b[static_cast<std::size_t>(i)]);
  const Eigen::Map<const Vec> xv(x.data(), 2 * d), bv(b.data(), 2 * d);
  ReducedErrors err;

  // (0) the tangent map: T's columns from the chart, and dQ/dp by central differences of the
  // positions embed gives (h: 1e-9 m of contact-point motion for an angle, 1e-9 m otherwise)
  Vec qe(n), ve(n), qp(n), vp(n), qm(n), vm(n), col(n);
  Mat T(n, d), Tfd(n, d), L(d, n);
  const auto step = [&](int j) {
    const double l = lengths[static_cast<std::size_t>(j)];
    return l > 0.0 ? 1e-8 / l : 1e-8;
  };
  for (int j = 0; j < d; ++j) {
    const Vec ej = Vec::Unit(d, j);
    chart->tangent(t, p, ej, qe, col);
    T.col(j) = col;
    const double h = step(j);
    const Vec pp = p + h * ej, pm = p - h * ej;
    chart->embed(t, pp, pd, qp, vp);
    chart->embed(t, pm, pd, qm, vm);
    Tfd.col(j) = (qp - qm) / (2.0 * h);
  }
  err.tangent = (T - Tfd).cwiseAbs().maxCoeff() / Tfd.cwiseAbs().maxCoeff();
  Vec rowd(d);
  chart->embed(t, p, pd, qe, ve);
  for (int i = 0; i < n; ++i) {
    const Vec ei = Vec::Unit(n, i);
    chart->reduce_linear(p, pd, qe, ei, rowd);
    L.col(i) = rowd;
  }
  err.inverse = (L * T - Mat::Identity(d, d)).cwiseAbs().maxCoeff();

  // (1) the claimed Jacobian, dense, at the embedded state
  const Mat A = constrained_jacobian(m, ctx, mode, t, qe, ve);
  PhaseEval e(m, ctx.K);  // (the exact Jacobian's differences below)
  REQUIRE(e.dynamics(t, qe, ve, ctx.modes, ctx.laws));
  const ContactKinematics c = e.c(0);  // (a copy: e moves on)
  Mat Jc = Mat::Zero(2 * d, 2 * d);
  Jc.topRightCorner(d, d).setIdentity();
  Jc.bottomLeftCorner(d, d) = L * A.leftCols(n) * T;
  Jc.bottomRightCorner(d, d) = L * A.rightCols(n) * T;
  const Mat Nc = Mat::Identity(2 * d, 2 * d) - gamma * Jc;
  err.model = (Nc * xv - bv).lpNorm<Eigen::Infinity>() /
              (Nc.cwiseAbs().rowwise().sum().maxCoeff() * xv.lpNorm<Eigen::Infinity>());

  // (2) the exact Jacobian of the reduced right-hand side, central differences
  Vec pdd(d);
  const auto accel = [&](const Vec& pp, const Vec& ppd) {
    chart->embed(t, pp, ppd, qp, vp);
    REQUIRE(e.dynamics(t, qp, vp, ctx.modes, ctx.laws));
    chart->reduce(pp, ppd, qp, e.a(), pdd);
    return Vec(pdd);
  };
  Mat Je = Mat::Zero(2 * d, 2 * d);
  Je.topRightCorner(d, d).setIdentity();
  for (int j = 0; j < 2 * d; ++j) {
    const int k = j % d;
    const double h = j < d ? step(k) : 1e-5 * std::max(1.0, std::abs(pd[k]));
    const Vec ek = Vec::Unit(d, k);
    const Vec ap = j < d ? accel(p + h * ek, pd) : accel(p, pd + h * ek);
    const Vec am = j < d ? accel(p - h * ek, pd) : accel(p, pd - h * ek);
    Je.block(d, j, d, 1) = (ap - am) / (2.0 * h);
  }
  const Vec xe = (Mat::Identity(2 * d, 2 * d) - gamma * Je).partialPivLu().solve(bv);
  err.exact = (xv - xe).lpNorm<Eigen::Infinity>() / xe.lpNorm<Eigen::Infinity>();
  const Mat dJ = Je - Jc;
  err.bound = gamma * Nc.inverse().lpNorm<Eigen::Infinity>() * (dJ * xe).lpNorm<Eigen::Infinity>() /
              xe.lpNorm<Eigen::Infinity>();
  // the terms held fixed (T's and L's derivatives, W_f's, H's and wdot's) act on the angles and
  // on the reduced coordinates that move the contact's coordinates (the support of W_N, W_T)
  for (int j = 0; j < 2 * d; ++j) {
    const int k = j % d;
    bool contact = lengths[static_cast<std::size_t>(k)] > 0.0;
    for (int i = 0; i < n; ++i)
      if (T(i, k) != 0.0 && (c.W_N[i] != 0.0 || c.W_T[i] != 0.0)) contact = true;
    if (contact) continue;
    err.elsewhere = std::max(
        err.elsewhere, dJ.col(j).lpNorm<Eigen::Infinity>() / Je.col(j).lpNorm<Eigen::Infinity>());
  }
  return err;
}

}  // namespace

TEST_CASE("Structured Newton solve of a reduced contact phase: the chart's lift of the bordered S",
          "[events][newton]") {
  // the FE run-up (prescribed spin: the ring chart, stick rheonomic, banded S), the paper's
  // rotor in matrices (spin coordinate: the one-contact chart that eliminates the rotor node,
  // S dense with the spin's border) and the rigid rotor (its chart's reduce has a curvature
  // term c(p, p'), the left inverse taken without it)
  const CaseSpec fe = load_case(std::string(RUBDYN_SOURCE_DIR) + "/cases/fe-runup.toml", {});
  const auto fe_model = build_model(fe);
  const CaseSpec mp = load_case(std::string(RUBDYN_SOURCE_DIR) + "/cases/matrices-paper.toml", {});
  const auto mp_model = build_model(mp);
  const RotorStatorModel rigid(RotorStatorParams{});
  const std::vector<const LagrangianModel*> models = {fe_model.get(), mp_model.get(), &rigid};
  for (const LagrangianModel* m : models) {
    for (const Phase mode : {Phase::SlipNeg, Phase::SlipPos, Phase::Stick}) {
      for (const double gamma : {1e-6, 1e-5, 1e-4}) {
        INFO(m->name() << ", " << to_string(mode) << ", gamma " << gamma);
        const ReducedErrors e = reduced_errors(*m, mode, gamma, 3u);
        INFO("tangent " << e.tangent << ", inverse " << e.inverse << ", model " << e.model
                        << ", exact " << e.exact << ", bound " << e.bound << ", elsewhere "
                        << e.elsewhere);
        // (0) T against central differences of the chart's positions: the copies' columns are
        // exact (linear), an angle's has the differences' h^2 / 6 (h 5e-5 rad) and round-off
        // eps |q| / h: measured 5e-13 .. 1.6e-11 of T's largest entry; a column without a ring's
        // rows, or the rheonomic rate of stick at a prescribed spin counted in T, is off by O(1).
        CHECK(e.tangent <= 1e-6);
        // L T = I: the copies exactly, an angle's row up to the round-off of cos^2 + sin^2
        // (measured 0)
        CHECK(e.inverse <= 1e-12);
        // (1) exact algebra of the claimed system: the lift, LU and Schur complement of the
        // Projected session's and the reduction are backward stable, as in the cases above
        // (measured 2e-24 .. 3e-17)
        CHECK(e.model <= 1e-12);
        // (2) what holding T, L, W_f, H and wdot fixed costs: the exact Jacobian differs from
        // the claimed one in the angles' and the contact coordinates' columns only; elsewhere
        // by the central differences' round-off eps |a| / h (measured up to 1.2e-7; it scales
        // with 1 / h: 9.7e-7 with h ten times smaller); and the step's difference from the exact
        // Newton step obeys its exact bound (1 % above it for the round-off of forming the
        // bound). How large it is depends on the contact force and, in stick with a spin
        // coordinate, on the rolling whirl (R / g0) omega that T's derivative carries: this
        // test's states (forces of 1e4 .. 1e5 N, omega 300 rad/s) see 3e-10 (FE, stick) .. 10
        // (FE, slip, gamma 1e-4), and 1.1 (the paper's rotor, stick). CVODE's Newton iteration
        // converges on the exact residual whatever the matrix; on the run-up it takes as many
        // iterations per step as with the dense difference quotients (the next test).
        CHECK(e.elsewhere <= 1e-6);
        CHECK(e.exact <= 1.01 * e.bound);
      }
    }
  }
}

TEST_CASE("Reduced contact phases: the structured Newton solve integrates the dense solve's run",
          "[events][newton]") {
  // cases/fe-runup.toml (n = 57, its seal slides from about 0.1 s) in minimal coordinates,
  // the contact phases' Newton systems structured and dense (CVODE's difference quotients),
  // at the case's rtol 1e-8 and, as the reference for both, structured at rtol 1e-10
  const CaseSpec fe = load_case(std::string(RUBDYN_SOURCE_DIR) + "/cases/fe-runup.toml", {});
  const auto model = build_model(fe);
  EventDrivenOptions o = event_driven_options(fe);
  o.contact_phases = ContactFormulation::Reduced;
  const auto run = [&](bool dense, double rtol, MemorySink& sink) {
    EventDrivenOptions oo = o;
    oo.dense_reduced_newton = dense;
    oo.rtol = rtol;
    const RunSummary r = run_event_driven(*model, initial_state(fe), fe.run.t_end, oo, sink);
    REQUIRE(r.complete());
    return r;
  };
  MemorySink a, b, ref;
  const RunSummary ra = run(false, o.rtol, a);
  const RunSummary rb = run(true, o.rtol, b);
  run(false, 1e-10, ref);
  // the same events, in order, at the same phases
  REQUIRE(a.events.size() == b.events.size());
  REQUIRE(a.events.size() >= 2);
  for (std::size_t i = 0; i < a.events.size(); ++i) {
    REQUIRE(a.events[i].kind == b.events[i].kind);
    REQUIRE(a.events[i].phase_after == b.events[i].phase_after);
  }
  REQUIRE(ra.phase_steps[static_cast<std::size_t>(Phase::SlipNeg)] +
              ra.phase_steps[static_cast<std::size_t>(Phase::SlipPos)] >
          1000);  // the contact phases are integrated (thousands of steps)
  // the seal's distance from the reference on the output grid (k x 0.1 ms)
  int ix = -1, iy = -1;
  const auto& cs = model->coordinates();
  for (int i = 0; i < model->num_dofs(); ++i) {
    const auto& c = cs[static_cast<std::size_t>(i)];
    if (c.plane == 0 && c.role == CoordinateRole::RotorX) ix = i;
    if (c.plane == 0 && c.role == CoordinateRole::RotorY) iy = i;
  }
  REQUIRE(ix >= 0);
  REQUIRE(iy >= 0);
  const auto seal_error = [&](const MemorySink& s) {
    std::map<long, const Sample*> grid;
    for (const auto& x : ref.samples) {
      const double k = x.t / 1e-4;
      if (std::abs(k - std::round(k)) < 1e-6) grid[std::lround(k)] = &x;
    }
    double e = 0.0;
    int matched = 0;
    for (const auto& x : s.samples) {
      const double k = x.t / 1e-4;
      if (std::abs(k - std::round(k)) >= 1e-6) continue;
      const auto it = grid.find(std::lround(k));
      if (it == grid.end()) continue;
      ++matched;
      e = std::max(e, std::hypot(x.q[ix] - it->second->q[ix], x.q[iy] - it->second->q[iy]));
    }
    CHECK(matched >= 1900);  // 0.2 s at 0.1 ms
    return e;
  };
  const double ea = seal_error(a), eb = seal_error(b);
  INFO("seal from the rtol 1e-10 run: structured "
       << ea << " m, dense " << eb << " m; steps " << ra.steps << " vs " << rb.steps
       << ", Newton iterations " << ra.newton_iters << " vs " << rb.newton_iters);
  // Not the same bits: the Newton iterates differ (CVODE converges on the exact residual to a
  // fraction of the local error test), so the two runs differ by what the error control lets
  // through, and both are as accurate as rtol 1e-8 makes them: measured 2.4e-11 m (structured)
  // and 8.8e-12 m (dense) from the reference, 1e-7 of the 2e-4 m clearance (the projected DAE's:
  // 1.8e-11 m, docs/fe-rotors.md section 10). 1e-10 m (5e-7 of the clearance) is 4x above the
  // larger; a run whose Newton solve is wrong either fails (CVODE's convergence failures) or
  // takes more iterations (below).
  CHECK(ea <= 1e-10);
  CHECK(eb <= 1e-10);
  // CVODE's Newton iterations per step: the structured matrix is as good a Newton matrix on
  // the run's states as the dense difference quotients (measured 1.109 and 1.109); 10 % more
  // would be a worse matrix on the states that matter.
  const double ita = static_cast<double>(ra.newton_iters) / static_cast<double>(ra.steps);
  const double itb = static_cast<double>(rb.newton_iters) / static_cast<double>(rb.steps);
  CHECK(ita <= 1.1 * itb);
}
