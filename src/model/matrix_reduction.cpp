#include "rubdyn/model/matrix_reduction.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>

#include "rubdyn/core/demand.hpp"

namespace rubdyn {

std::string_view to_string(ReductionMethod m) {
  switch (m) {
    case ReductionMethod::None: return "none";
    case ReductionMethod::Modal: return "modal";
    case ReductionMethod::CraigBampton: return "craig-bampton";
  }
  return "?";
}

namespace {

using Index = Eigen::Index;

/// A's rows and columns at idx.
Mat sub(const Mat& A, const std::vector<int>& rows, const std::vector<int>& cols) {
  Mat S(static_cast<Index>(rows.size()), static_cast<Index>(cols.size()));
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (std::size_t j = 0; j < cols.size(); ++j)
      S(static_cast<Index>(i), static_cast<Index>(j)) = A(rows[i], cols[j]);
  return S;
}

}  // namespace

// (1e-12 of each matrix's largest entry: the reader's symmetry tolerance)
bool isotropic_rotor(const MatrixParams& p) {
  const MatrixRotorParams& r = p.rotor;
  const int n = r.size();
  if (n % 2 != 0) return false;
  for (const MatrixNode& nd : p.node_list())
    if (nd.at.x % 2 != 0 || nd.at.y != nd.at.x + 1) return false;
  for (const Mat* A : {&r.M, &r.C, &r.K}) {
    const double tol = 1e-12 * A->cwiseAbs().maxCoeff();
    for (int j = 0; j < n; j += 2)
      for (int i = 0; i < n; i += 2) {
        if (std::abs((*A)(i, j) - (*A)(i + 1, j + 1)) > tol) return false;
        if (std::abs((*A)(i + 1, j)) > tol || std::abs((*A)(i, j + 1)) > tol) return false;
      }
  }
  return true;
}

namespace {

/// Mass-normalised modes of (K, M) (symmetric, M positive definite), lowest first, each with its
/// largest entry positive (a deterministic sign). Frequencies [Hz] of negative eigenvalues (an
/// indefinite K) are NaN.
void modes_of(const Mat& K, const Mat& M, Vec& f_hz, Mat& Phi) {
  Eigen::GeneralizedSelfAdjointEigenSolver<Mat> es(K, M,
                                                   Eigen::ComputeEigenvectors | Eigen::Ax_lBx);
  RUBDYN_DEMAND(es.info() == Eigen::Success);
  Phi = es.eigenvectors();
  const Vec w2 = es.eigenvalues();
  f_hz.resize(w2.size());
  for (Index k = 0; k < w2.size(); ++k) {
    f_hz[k] = w2[k] >= 0.0 ? std::sqrt(w2[k]) / (2.0 * std::numbers::pi)
                           : std::numeric_limits<double>::quiet_NaN();
    Index at = 0;
    Phi.col(k).cwiseAbs().maxCoeff(&at);
    if (Phi(at, k) < 0.0) Phi.col(k) *= -1.0;
  }
}

/// The coordinates the modes are computed on: an isotropic rotor's x plane (its even
/// coordinates, `per` = 2), which stands for both; else all of q (`per` = 1).
std::vector<int> mode_plane(int n, int per) {
  std::vector<int> plane;
  for (int i = 0; i < n; i += per) plane.push_back(i);
  return plane;
}

/// The free modes of the rotor r on `plane` (every one, lowest first).
void free_modes(const MatrixRotorParams& r, const std::vector<int>& plane, Vec& f, Mat& Phi) {
  modes_of(sub(r.K, plane, plane), sub(r.M, plane, plane), f, Phi);
}

/// The first `kept` of the plane's modes Phi (plane x kept or wider) and their frequencies f
/// spread over the n coordinates: with `per` = 2 each becomes the (x, y) pair of columns.
void spread_modes(const std::vector<int>& plane, int per, const Mat& Phi, const Vec& f, int kept,
                  int n, Mat& modes, std::vector<double>& f_hz, std::vector<std::string>& planes) {
  modes.setZero(n, per * kept);
  for (int j = 0; j < kept; ++j) {
    for (std::size_t i = 0; i < plane.size(); ++i)
      for (int c = 0; c < per; ++c)
        modes(plane[i] + c, per * j + c) = Phi(static_cast<Index>(i), j);
    for (int c = 0; c < per; ++c) {
      f_hz.push_back(f[j]);
      planes.push_back(per == 2 ? (c == 0 ? "x" : "y") : "");
    }
  }
}

/// How many of the modes (ascending frequencies f, `per` coordinates each: 2 for isotropic
/// pairs) the parameters keep; `what` names them in messages.
int kept_count(const ReductionParams& r, const Vec& f, int per, int available, int n,
               const char* what) {
  if (r.modes > 0) {
    if (r.modes > available) {
      throw ReductionRefused(
          "reduction.modes",
          available == n
              ? fmt::format("must be at most n = {} (the rotor's coordinates)", n)
              : fmt::format("must be at most n - 2K = {} (n = {} coordinates, of which the "
                            "contact nodes' {} stay physical)",
                            available, n, n - available));
    }
    if (r.modes % per != 0) {
      throw ReductionRefused(
          "reduction.modes",
          "must be even: the rotor is isotropic and its modes come in (x, y) pairs of one "
          "frequency (keeping one of a pair would make the reduced rotor anisotropic)");
    }
    return r.modes / per;
  }
  const double first = f.size() > 0 ? f[0] : std::numeric_limits<double>::quiet_NaN();
  if (!(r.cutoff >= first)) {
    throw ReductionRefused("reduction.cutoff",
                           fmt::format("must not be below the first {} mode ({:.6g} Hz): no mode "
                                       "would be kept",
                                       what, first));
  }
  int k = 0;
  while (k < f.size() && f[k] <= r.cutoff) ++k;
  return k;
}

}  // namespace

std::string ReducedMatrices::describe() const {
  const int m = static_cast<int>(T.cols());
  const int nm = static_cast<int>(f_hz.size());
  std::string phys;
  for (int i = 0; i < m - nm; ++i)
    phys += (phys.empty() ? "" : ", ") + rotor.names[static_cast<std::size_t>(i)];
  const bool cb = params.method == ReductionMethod::CraigBampton;
  std::string modes =
      fmt::format("{} {} mode{}", nm, cb ? "fixed-interface" : "free", nm == 1 ? "" : "s");
  if (nm > 0) {
    modes += fmt::format(" ({:.6g} to {:.6g} Hz", f_hz.front(), f_hz.back());
    if (std::isfinite(f_next)) modes += fmt::format("; the next at {:.6g} Hz", f_next);
    modes += ")";
  }
  return fmt::format("{} reduction{}: {} -> {} coordinates: {} physical ({}) and {}{}",
                     cb ? "Craig-Bampton" : "modal",
                     params.modes > 0 ? fmt::format(" to {} modes", params.modes)
                                      : fmt::format(" below {:.6g} Hz", params.cutoff),
                     full_size, m, m - nm, phys, modes, isotropic ? ", in (x, y) pairs" : "");
}

RotorModes rotor_modes(const MatrixParams& p, int count) {
  const int n = p.rotor.size();
  RotorModes out;
  out.isotropic = isotropic_rotor(p);
  const int per = out.isotropic ? 2 : 1;
  RUBDYN_DEMAND(count >= 0 && count <= n && count % per == 0);
  const std::vector<int> plane = mode_plane(n, per);
  Vec f;
  Mat Phi;
  if (count > 0) free_modes(p.rotor, plane, f, Phi);
  spread_modes(plane, per, Phi, f, count / per, n, out.shapes, out.f_hz, out.planes);
  return out;
}

ReducedMatrices reduce_matrix_model(const MatrixParams& full, const ReductionParams& r) {
  RUBDYN_DEMAND(r.method != ReductionMethod::None);
  const MatrixRotorParams& fr = full.rotor;
  const int n = fr.size();
  const std::vector<MatrixNode> nodes = full.node_list();
  const int K = static_cast<int>(nodes.size());
  {
    // a rotor whose files or nodes are not valid cannot be reduced (the case validation names
    // their keys; this only keeps a half-read case from being indexed out of range)
    bool ok = n >= 2 && fr.M.cols() == n && fr.C.rows() == n && fr.C.cols() == n &&
              fr.K.rows() == n && fr.K.cols() == n && fr.G.rows() == n && fr.G.cols() == n &&
              fr.f0.size() == n && K >= 1;
    std::set<int> used;
    for (const MatrixNode& nd : nodes)
      for (int i : {nd.at.x, nd.at.y}) ok = ok && i >= 0 && i < n && used.insert(i).second;
    if (!ok)
      throw ReductionRefused("reduction.method",
                             "needs valid matrices and contact nodes (see their problems)");
  }
  if (r.modes < 0)
    throw ReductionRefused("reduction.modes", "must be >= 1 (the number of modes kept)");
  if (r.cutoff < 0.0)
    throw ReductionRefused("reduction.cutoff",
                           "must be > 0 (the frequency [Hz] below which every mode is kept)");
  if (r.modes == 0 && r.cutoff == 0.0)
    throw ReductionRefused("reduction.modes",
                           "must be >= 1, or reduction.cutoff given: the number of modes kept, or "
                           "the frequency [Hz] below which every mode is kept");
  if (r.modes > 0 && r.cutoff != 0.0)
    throw ReductionRefused("reduction.cutoff",
                           "give reduction.modes or reduction.cutoff, not both");
  const bool cb = r.method == ReductionMethod::CraigBampton;

  ReducedMatrices out;
  out.params = r;
  out.full_size = n;
  out.isotropic = isotropic_rotor(full);
  const int per = out.isotropic ? 2 : 1;  // coordinates per mode
  // the planes: isotropic, the x plane (even coordinates) stands for both; else all of q
  const std::vector<int> plane = mode_plane(n, per);
  // the boundary (contact coordinates) of that plane, in node order, and the rest
  std::vector<int> bnd, inner;
  for (const MatrixNode& nd : nodes) {
    bnd.push_back(nd.at.x);
    if (!out.isotropic) bnd.push_back(nd.at.y);
  }
  for (int i : plane)
    if (std::find(bnd.begin(), bnd.end(), i) == bnd.end()) inner.push_back(i);
  const int nb = static_cast<int>(bnd.size());  // per plane

  // the plane's basis: T_p (plane x (nb + kept)), boundary columns first
  Vec f;
  Mat Phi;
  Mat Tp;
  int kept = 0;
  if (cb) {
    const Mat Kii = sub(fr.K, inner, inner);
    Eigen::LLT<Mat> llt(Kii);
    if (llt.info() != Eigen::Success || inner.empty()) {
      throw ReductionRefused(
          "reduction.method",
          inner.empty()
              ? std::string("craig-bampton needs coordinates besides the contact nodes' (none "
                            "left to reduce)")
              : std::string("craig-bampton holds the contact nodes' coordinates, and then K is "
                            "not positive definite on the others (the rotor is not held there: "
                            "no fixed-interface modes); use method = \"modal\""));
    }
    const Mat Psi = -llt.solve(sub(fr.K, inner, bnd));
    modes_of(Kii, sub(fr.M, inner, inner), f, Phi);
    kept = kept_count(r, f, per, per * static_cast<int>(inner.size()), n, "fixed-interface");
    // T_p in (plane) coordinates: rows bnd -> [I, 0], rows inner -> [Psi, Phi]
    Tp.setZero(static_cast<Index>(plane.size()), nb + kept);
    auto pos = [&plane](int i) {
      return static_cast<Index>(std::find(plane.begin(), plane.end(), i) - plane.begin());
    };
    for (int b = 0; b < nb; ++b) Tp(pos(bnd[static_cast<std::size_t>(b)]), b) = 1.0;
    for (std::size_t i = 0; i < inner.size(); ++i) {
      const Index row = pos(inner[i]);
      Tp.row(row).head(nb) = Psi.row(static_cast<Index>(i));
      Tp.row(row).tail(kept) = Phi.row(static_cast<Index>(i)).head(kept);
    }
    // the modes' shapes in the plane's coordinates (zero at the boundary)
    Mat shapes = Mat::Zero(static_cast<Index>(plane.size()), kept);
    for (std::size_t i = 0; i < inner.size(); ++i)
      shapes.row(pos(inner[i])) = Phi.row(static_cast<Index>(i)).head(kept);
    Phi = shapes;
  } else {
    free_modes(fr, plane, f, Phi);  // (rotor_modes's)
    kept = kept_count(r, f, per, n, n, "free");
    if (kept < nb) {
      throw ReductionRefused(
          r.modes > 0 ? "reduction.modes" : "reduction.cutoff",
          fmt::format("keeps {} mode{} where the {} contact node{}' {} coordinates must stay "
                      "physical: a modal basis needs at least as many modes ({})",
                      per * kept, per * kept == 1 ? "" : "s", K, K == 1 ? "" : "s", 2 * K, 2 * K));
    }
    Phi.conservativeResize(Eigen::NoChange, kept);
    // a basis of span(Phi) whose first nb coordinates are the contact coordinates
    Mat Pb(nb, kept);
    for (int b = 0; b < nb; ++b) {
      const Index row = static_cast<Index>(
          std::find(plane.begin(), plane.end(), bnd[static_cast<std::size_t>(b)]) - plane.begin());
      Pb.row(b) = Phi.row(row);
    }
    Eigen::JacobiSVD<Mat> svd(Pb, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Vec s = svd.singularValues();
    // (the modes are mass-normalised: a singular value 1e-8 of the largest makes the basis
    // carry 1e8 of it, and the contact coordinates would be a difference of large numbers)
    if (!(s.size() == nb && s[nb - 1] > 1e-8 * s[0])) {
      throw ReductionRefused(
          r.modes > 0 ? "reduction.modes" : "reduction.cutoff",
          fmt::format("the {} kept free modes do not move the contact node{}' coordinates "
                      "independently (singular values of their rows there: {:.3g} to {:.3g}): "
                      "the reduction would eliminate a contact node; keep other modes, or use "
                      "method = \"craig-bampton\", which keeps them by construction",
                      per * kept, K == 1 ? "" : "s", s[0], s[s.size() - 1]));
    }
    Mat A(kept, kept);
    const Mat& U = svd.matrixU();
    const Mat& V = svd.matrixV();
    A.leftCols(nb) = V.leftCols(nb) * s.head(nb).cwiseInverse().asDiagonal() * U.transpose();
    A.rightCols(kept - nb) = V.rightCols(kept - nb);
    Tp = Phi * A;
    // exact unit rows at the contact coordinates (the product leaves round-off there)
    for (int b = 0; b < nb; ++b) {
      const Index row = static_cast<Index>(
          std::find(plane.begin(), plane.end(), bnd[static_cast<std::size_t>(b)]) - plane.begin());
      Tp.row(row).setZero();
      Tp(row, b) = 1.0;
    }
  }
  out.f_next = kept < f.size() ? f[kept] : std::numeric_limits<double>::quiet_NaN();

  // the full basis: isotropic, each plane column becomes an (x, y) pair of columns
  const int mp = static_cast<int>(Tp.cols());
  const int m = per * mp;
  out.T.setZero(n, m);
  for (int j = 0; j < mp; ++j)
    for (std::size_t i = 0; i < plane.size(); ++i)
      for (int c = 0; c < per; ++c) out.T(plane[i] + c, per * j + c) = Tp(static_cast<Index>(i), j);
  spread_modes(plane, per, Phi, f, kept, n, out.modes, out.f_hz, out.mode_planes);

  // the reduced model
  MatrixRotorParams& rr = out.rotor;
  rr.Jp = fr.Jp;
  const Mat& T = out.T;
  rr.M = T.transpose() * (fr.M * T);
  rr.C = T.transpose() * (fr.C * T);
  rr.K = T.transpose() * (fr.K * T);
  rr.G = T.transpose() * (fr.G * T);
  // symmetric and skew to the bit (the products' round-off; the model demands it of K and G)
  rr.M = 0.5 * (rr.M + Mat(rr.M.transpose()));
  rr.C = 0.5 * (rr.C + Mat(rr.C.transpose()));
  rr.K = 0.5 * (rr.K + Mat(rr.K.transpose()));
  rr.G = 0.5 * (rr.G - Mat(rr.G.transpose()));
  rr.f0 = T.transpose() * fr.f0;
  // names: the physical coordinates keep theirs, the others are eta<k>[x|y]
  std::vector<std::string> full_names = fr.names;
  if (static_cast<int>(full_names.size()) != n) {
    full_names.clear();
    for (int i = 0; i < n; ++i) {
      std::string name = "q";  // (appended, not "q" + string: g++ 12 warns falsely, -Wrestrict)
      full_names.push_back(name.append(std::to_string(i)));
    }
  }
  rr.names.clear();
  std::set<std::string> taken(full_names.begin(), full_names.end());
  for (int j = 0; j < mp; ++j) {
    for (int c = 0; c < per; ++c) {
      std::string nm;
      if (j < nb) {
        // boundary column j of the plane: node j's x (isotropic, c = 0) or y
        out.physical.push_back(bnd[static_cast<std::size_t>(j)] + c);
        nm = full_names[static_cast<std::size_t>(out.physical.back())];
      } else {
        nm = "eta" + std::to_string(j - nb + 1);
        if (out.isotropic) nm += c == 0 ? "x" : "y";
        while (taken.count(nm)) nm += "_";  // (a user's coordinate of that name)
      }
      rr.names.push_back(nm);
    }
  }
  // the nodes' coordinates in p: isotropic, node k is the pair (2k, 2k + 1); else the
  // boundary was listed x1, y1, x2, y2, ...: the same
  for (int k = 0; k < K; ++k) out.node_xy.emplace_back(2 * k, 2 * k + 1);
  return out;
}

MatrixParams ReducedMatrices::apply(const MatrixParams& full) const {
  RUBDYN_DEMAND(full.rotor.size() == full_size && node_xy.size() == full.node_list().size());
  MatrixParams p = full;
  const double Jp = p.rotor.Jp;
  p.rotor = rotor;
  p.rotor.Jp = Jp;
  for (std::size_t k = 0; k < node_xy.size(); ++k) {
    MatrixContactNode& at = p.nodes.empty() ? p.node : p.nodes[k].at;
    at.x = node_xy[k].first;
    at.y = node_xy[k].second;
  }
  return p;
}

}  // namespace rubdyn
