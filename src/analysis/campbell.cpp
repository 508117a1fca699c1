#include "rubdyn/analysis/campbell.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>

#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_spec.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"

namespace rubdyn {

namespace {

using cplx = std::complex<double>;

// Two eigenvalues of the scaled first-order form closer than this (relative) are one double
// eigenvalue. The eigen solver's absolute error is ~1e-15 |A| with |A| = O(1) after scaling, so
// 1e-10 is far above round-off; and the relative gyroscopic split of the reference case is
// 1e-4 to 3e-4 times Omega [rad/s], so only |Omega| < ~1e-6 rad/s is merged (error < 1e-10).
constexpr double kDoubleTol = 1e-10;
// A circular (isotropic) mode has purity 1 to round-off. Below this the whirl is mixed: a bug.
constexpr double kMinPurity = 0.5;

struct Mode {
  cplx lam;       // scaled eigenvalue, Im > 0
  double ef, eb;  // forward and backward kinetic energies of the mode shape
};

}  // namespace

namespace {

const LinearModel& whirling(const LinearModel& lm) {
  const int n = lm.size();
  if (n == 0 || lm.nodes.empty())
    throw std::invalid_argument(
        "Campbell diagram: the linear model has no coordinate or no (x, y) node: nothing whirls");
  if (lm.M.rows() != n || lm.M.cols() != n || lm.K.rows() != n || lm.K.cols() != n ||
      lm.G.rows() != n || lm.G.cols() != n || lm.D.rows() != n || lm.D.cols() != n)
    throw std::invalid_argument(
        "Campbell diagram: M, G, D, K are not n x n with n its coordinates");
  for (const auto& [x, y] : lm.nodes)
    if (x < 0 || x >= n || y < 0 || y >= n)
      throw std::invalid_argument("Campbell diagram: a node's coordinate is not one of the model");
  return lm;
}

LinearModel tied_rigid_rotor(const RotorStatorParams& p) {
  std::optional<LinearModel> lm = RotorStatorModel(p).linearize(Linearization::Tied);
  if (!lm)
    throw std::invalid_argument(
        "Campbell diagram: this rotor has no tied system (a fixed ring tied to the rotor is a "
        "constraint)");
  return std::move(*lm);
}

}  // namespace

CampbellSolver::CampbellSolver(const LinearModel& lm, bool damped)
    : lm_(whirling(lm)), damped_(damped) {
  const int n = lm_.size();
  if (!damped) lm_.D.setZero(n, n);
  // the whirl energies use the mass matrix among the nodes' x coordinates (isotropy: the same
  // among the y coordinates, none between an x and a y)
  const int nn = nodes();
  Mx_.resize(nn, nn);
  for (int a = 0; a < nn; ++a)
    for (int b = 0; b < nn; ++b)
      Mx_(a, b) = lm_.M(lm_.nodes[static_cast<std::size_t>(a)].first,
                        lm_.nodes[static_cast<std::size_t>(b)].first);

  // First-order form in the scaled state s = (q, q'/w_ref): s' = w_ref A s with
  //   A = [0, I; -M^-1 K / w_ref^2, -M^-1 (Omega G + D) / w_ref],
  // whose entries are O(1): the eigenvalues of A are lambda / w_ref, found to ~1e-15 absolute.
  // w_ref^2 = trace(M^-1 K) / n is the mean of the squared natural frequencies at rest.
  const Eigen::LLT<Mat> llt(lm_.M);
  const Mat MiK = llt.solve(lm_.K);
  w_ref_ = std::sqrt(MiK.trace() / n);
  if (!(w_ref_ > 0.0)) w_ref_ = 1.0;  // no stiffness at all: any scale will do
  MiK_ = MiK / (w_ref_ * w_ref_);
  MiG_ = llt.solve(lm_.G) / w_ref_;
  MiD_ = llt.solve(lm_.D) / w_ref_;
}

CampbellSolver::CampbellSolver(const RotorStatorParams& p, bool damped)
    : CampbellSolver(tied_rigid_rotor(p), damped) {}

std::vector<std::string> CampbellSolver::labels() const {
  std::vector<std::string> l;
  for (int k = 1; k <= nodes(); ++k) {
    l.push_back(fmt::format("f{}b", k));
    l.push_back(fmt::format("f{}f", k));
  }
  return l;
}

CampbellPoint CampbellSolver::solve(double omega) const {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  const int n = lm_.size(), nn = nodes();
  CampbellPoint out;
  out.omega = omega;
  out.f_backward.assign(static_cast<std::size_t>(nn), nan);  // a missing mode stays NaN
  out.f_forward.assign(static_cast<std::size_t>(nn), nan);
  out.zeta_backward.assign(static_cast<std::size_t>(nn), nan);
  out.zeta_forward.assign(static_cast<std::size_t>(nn), nan);
  out.f1b = out.f1f = out.f2b = out.f2f = nan;
  out.zeta_1b = out.zeta_1f = out.zeta_2b = out.zeta_2f = nan;

  Mat A(2 * n, 2 * n);
  A.topLeftCorner(n, n).setZero();
  A.topRightCorner(n, n).setIdentity();
  A.bottomLeftCorner(n, n) = -MiK_;
  A.bottomRightCorner(n, n) = -(omega * MiG_ + MiD_);
  Eigen::EigenSolver<Mat> es;
  es.compute(A, /*computeEigenvectors=*/true);
  if (es.info() != Eigen::Success) {
    out.min_whirl_purity = 0.0;
    return out;
  }
  const Eigen::VectorXcd lams = es.eigenvalues();
  const Eigen::MatrixXcd V = es.eigenvectors();

  // The oscillating modes (one eigenvalue of each conjugate pair), by increasing frequency, with
  // the forward and backward kinetic energies of their shapes (see the header).
  const cplx I(0.0, 1.0);
  std::vector<Mode> modes;
  for (int k = 0; k < 2 * n; ++k) {
    if (!(lams[k].imag() > 0.0)) continue;  // conjugate, or real (overdamped, no whirl)
    Eigen::VectorXcd zf(nn), zb(nn);
    for (int a = 0; a < nn; ++a) {
      const auto& nd = lm_.nodes[static_cast<std::size_t>(a)];
      zf[a] = V(nd.first, k) + I * V(nd.second, k);
      zb[a] = V(nd.first, k) - I * V(nd.second, k);
    }
    const Mode md{lams[k], std::real(zf.dot(Mx_ * zf)), std::real(zb.dot(Mx_ * zb))};
    auto it = modes.begin();
    while (it != modes.end() && it->lam.imag() <= md.lam.imag()) ++it;
    modes.insert(it, md);
  }

  int nf = 0, nb = 0;
  const double to_hz = w_ref_ / (2.0 * std::numbers::pi);
  auto zeta = [this](cplx lam) { return damped_ ? -lam.real() / std::abs(lam) : 0.0; };
  auto add = [&](bool forward, cplx lam) {
    int& count = forward ? nf : nb;
    if (count < nn) {
      (forward ? out.f_forward : out.f_backward)[static_cast<std::size_t>(count)] =
          lam.imag() * to_hz;
      (forward ? out.zeta_forward : out.zeta_backward)[static_cast<std::size_t>(count)] = zeta(lam);
    }
    ++count;
  };
  const std::size_t nm = modes.size();
  for (std::size_t i = 0; i < nm;) {
    if (i + 1 < nm &&
        std::abs(modes[i + 1].lam - modes[i].lam) <= kDoubleTol * std::abs(modes[i].lam)) {
      // a double eigenvalue: the circular basis of its plane, one forward and one backward mode
      const cplx mean = 0.5 * (modes[i].lam + modes[i + 1].lam);
      add(false, mean);
      add(true, mean);
      i += 2;
      continue;
    }
    const Mode& md = modes[i];
    double purity = std::abs(md.ef - md.eb) / (md.ef + md.eb);
    if (!(purity >= 0.0)) purity = 0.0;  // a null or non-finite shape: no whirl to speak of
    out.min_whirl_purity = std::min(out.min_whirl_purity, purity);
    add(md.ef > md.eb, md.lam);
    ++i;
  }
  out.n_forward = nf;
  out.n_backward = nb;
  if (nn > 0) {
    out.f1b = out.f_backward[0];
    out.f1f = out.f_forward[0];
    out.zeta_1b = out.zeta_backward[0];
    out.zeta_1f = out.zeta_forward[0];
  }
  if (nn > 1) {
    out.f2b = out.f_backward[1];
    out.f2f = out.f_forward[1];
    out.zeta_2b = out.zeta_backward[1];
    out.zeta_2f = out.zeta_forward[1];
  }
  out.labels_ok = nf == nn && nb == nn && out.min_whirl_purity >= kMinPurity;
  return out;
}

CampbellPoint solve_campbell_point(const RotorStatorParams& p, double omega, bool damped) {
  return CampbellSolver(p, damped).solve(omega);
}

const std::vector<double>& CampbellDiagram::column(const std::string& label) const {
  for (std::size_t i = 0; i < labels.size(); ++i)
    if (labels[i] == label) return f[i];
  throw std::out_of_range("Campbell diagram: no mode " + label);
}

CampbellDiagram compute_campbell_diagram(const LinearModel& lm, double omega_max, int points,
                                         bool damped) {
  if (points < 2)
    throw std::invalid_argument(fmt::format("Campbell diagram: {} points < 2", points));
  if (!(std::isfinite(omega_max) && omega_max > 0.0)) {
    throw std::invalid_argument(
        fmt::format("Campbell diagram: omega_max = {} must be finite and > 0", omega_max));
  }
  const CampbellSolver solver(lm, damped);
  CampbellDiagram d;
  d.damped = damped;
  d.labels = solver.labels();
  const auto n = static_cast<std::size_t>(points);
  d.omega.reserve(n);
  d.f.assign(d.labels.size(), {});
  if (damped) d.zeta.assign(d.labels.size(), {});
  for (int i = 0; i < points; ++i) {
    const double omega =
        i == points - 1 ? omega_max : omega_max * static_cast<double>(i) / (points - 1);
    const CampbellPoint c = solver.solve(omega);
    d.omega.push_back(omega);
    for (int k = 0; k < solver.nodes(); ++k) {
      const auto ks = static_cast<std::size_t>(k);
      d.f[2 * ks].push_back(c.f_backward[ks]);
      d.f[2 * ks + 1].push_back(c.f_forward[ks]);
      if (damped) {
        d.zeta[2 * ks].push_back(c.zeta_backward[ks]);
        d.zeta[2 * ks + 1].push_back(c.zeta_forward[ks]);
      }
    }
    if (!c.labels_ok) d.unlabelled.push_back(omega);
  }
  return d;
}

CampbellDiagram compute_campbell_diagram(const RotorStatorParams& p, double omega_max, int points,
                                         bool damped) {
  return compute_campbell_diagram(tied_rigid_rotor(p), omega_max, points, damped);
}

CampbellModel campbell_model(const CaseSpec& spec) {
  const std::unique_ptr<LagrangianModel> model = build_model(spec);
  CampbellModel out;
  std::optional<LinearModel> lm = model->linearize(Linearization::Tied);
  if (!lm || lm->size() == 0) {
    lm = model->linearize(Linearization::Free);
    out.tied = false;
  }
  if (!lm || lm->size() == 0 || lm->nodes.empty()) {
    if (spec.model == "matrices" && spec.matrices.rotor.size() % 2 != 0)
      throw CaseError(
          {{spec.source, 0, "rotor.M", spec.matrix_files.M,
            fmt::format("a Campbell diagram labels each mode's whirl on (x, y) pairs of q's "
                        "coordinates, (0, 1), (2, 3), ...: n = {} is odd, so this rotor has "
                        "none (order q as pairs of x and y)",
                        spec.matrices.rotor.size())}});
    throw CaseError({{spec.source, 0, "model.kind", spec.model,
                      "this model has no linearisation for a Campbell diagram"}});
  }
  out.lm = std::move(*lm);
  return out;
}

std::string campbell_csv(const CampbellDiagram& d) {
  std::string s = "omega_rad_s,omega_rpm";
  for (const auto& l : d.labels) s += "," + l;
  if (d.damped)
    for (const auto& l : d.labels) s += ",zeta_" + l.substr(1);
  s += '\n';
  for (std::size_t i = 0; i < d.size(); ++i) {
    s += fmt::format("{:.17g},{:.17g}", d.omega[i], d.omega[i] * 30.0 / std::numbers::pi);
    for (const auto& col : d.f) s += fmt::format(",{:.17g}", col[i]);
    if (d.damped)
      for (const auto& col : d.zeta) s += fmt::format(",{:.17g}", col[i]);
    s += '\n';
  }
  return s;
}

}  // namespace rubdyn
