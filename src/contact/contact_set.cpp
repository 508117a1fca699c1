#include "rubdyn/contact/contact_set.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "rubdyn/contact/min_norm.hpp"
#include "rubdyn/core/demand.hpp"

namespace rubdyn {

std::string_view to_string(SetOutcome o) {
  switch (o) {
    case SetOutcome::Unique: return "unique";
    case SetOutcome::Boundary: return "boundary";
    case SetOutcome::NonUnique: return "non-unique";
    case SetOutcome::NoSolution: return "no solution";
    case SetOutcome::Converged: return "converged";
    case SetOutcome::NotConverged: return "not converged";
    case SetOutcome::NonFinite: return "non-finite data";
  }
  return "?";
}

SetBand contact_set_band(MatIn W, VecIn u0, double rel_band) {
  SetBand b;
  b.tol_u = rel_band * u0.cwiseAbs().sum() + 1e-300;
  double w_min = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; 2 * i < W.rows(); ++i) w_min = std::min(w_min, W(2 * i, 2 * i));
  if (W.rows() == 0) w_min = 1.0;  // no contact: any positive band
  b.tol_r = b.tol_u / std::max(w_min, 1e-300);
  return b;
}

void impulse_free_velocity(VecIn v_minus, std::span<const ContactLaw> laws, VecOut u0) {
  RUBDYN_DEMAND(v_minus.size() == 2 * static_cast<Eigen::Index>(laws.size()));
  RUBDYN_DEMAND(u0.size() == v_minus.size());
  for (std::size_t i = 0; i < laws.size(); ++i) {
    u0(2 * i) = (1.0 + laws[i].e_n) * v_minus(2 * i);
    u0(2 * i + 1) = (1.0 + laws[i].e_t) * v_minus(2 * i + 1);
  }
}

namespace {

constexpr int kCapK = kMaxEnumContacts;
constexpr int kCapRows = 2 * kCapK;
constexpr int kCapModes = 1 << (2 * kCapK);  // 4^kCapK

enum class Level : int { Violated = 0, Boundary = 1, Strict = 2 };

/// The rank of a mode in the one-contact order free, stick, slip+, slip-.
int rank_of(Phase p) {
  switch (p) {
    case Phase::Free: return 0;
    case Phase::Stick: return 1;
    case Phase::SlipPos: return 2;
    case Phase::SlipNeg: return 3;
  }
  return 0;
}

/// Solves A x = b (m x m, row-major in a[], m <= kCapRows) by Gaussian elimination with full
/// pivoting. False when a pivot falls below kSingularPivot times the largest entry of A; else
/// kappa = largest / smallest pivot (>= 1), the estimate of A's condition the margins use.
/// M: the size known at compile time (the loops unrolled; solve_full_pivot dispatches), the same
/// operations in the same order for every M.
template <int M>
bool solve_full_pivot_m(double (&a)[kCapRows][kCapRows], double (&b)[kCapRows],
                        double (&x)[kCapRows], double& kappa) {
  constexpr int m = M;
  kappa = 1.0;
  int col[kCapRows];
  double scale = 0.0;
  for (int i = 0; i < m; ++i) {
    col[i] = i;
    for (int j = 0; j < m; ++j) scale = std::max(scale, std::abs(a[i][j]));
  }
  if (m > 0 && !(scale > 0.0)) return false;
  for (int k = 0; k < m; ++k) {
    int pr = k, pc = k;
    double best = -1.0;
    for (int i = k; i < m; ++i)
      for (int j = k; j < m; ++j)
        if (std::abs(a[i][j]) > best) {
          best = std::abs(a[i][j]);
          pr = i;
          pc = j;
        }
    if (!(best > kSingularPivot * scale)) return false;
    if (pr != k) {
      for (int j = 0; j < m; ++j) std::swap(a[k][j], a[pr][j]);
      std::swap(b[k], b[pr]);
    }
    if (pc != k) {
      for (int i = 0; i < m; ++i) std::swap(a[i][k], a[i][pc]);
      std::swap(col[k], col[pc]);
    }
    for (int i = k + 1; i < m; ++i) {
      const double f = a[i][k] / a[k][k];
      if (f == 0.0) continue;
      for (int j = k + 1; j < m; ++j) a[i][j] -= f * a[k][j];
      b[i] -= f * b[k];
    }
  }
  for (int k = 0; k < m; ++k) kappa = std::max(kappa, std::abs(a[0][0] / a[k][k]));
  for (int k = m - 1; k >= 0; --k) {
    double s = b[k];
    for (int j = k + 1; j < m; ++j) s -= a[k][j] * x[col[j]];
    x[col[k]] = s / a[k][k];
  }
  return true;
}

bool solve_full_pivot(double (&a)[kCapRows][kCapRows], double (&b)[kCapRows], int m,
                      double (&x)[kCapRows], double& kappa) {
  static_assert(kCapRows == 8);
  switch (m) {
    case 0: return solve_full_pivot_m<0>(a, b, x, kappa);
    case 1: return solve_full_pivot_m<1>(a, b, x, kappa);
    case 2: return solve_full_pivot_m<2>(a, b, x, kappa);
    case 3: return solve_full_pivot_m<3>(a, b, x, kappa);
    case 4: return solve_full_pivot_m<4>(a, b, x, kappa);
    case 5: return solve_full_pivot_m<5>(a, b, x, kappa);
    case 6: return solve_full_pivot_m<6>(a, b, x, kappa);
    case 7: return solve_full_pivot_m<7>(a, b, x, kappa);
    default: return solve_full_pivot_m<8>(a, b, x, kappa);
  }
}

Level level_of(double margin, double tol) {
  return margin > tol ? Level::Strict : (margin >= -tol ? Level::Boundary : Level::Violated);
}

/// |u0|_inf and |W|_inf (row sums) of the data: the scale of the round-off bands.
struct DataScale {
  double u0_max = 0.0, W_max = 0.0;
};
DataScale data_scale(MatIn W, VecIn u0, int K) {
  DataScale d;
  for (int e = 0; e < 2 * K; ++e) {
    d.u0_max = std::max(d.u0_max, std::abs(u0(e)));
    double row_sum = 0.0;
    for (int j = 0; j < 2 * K; ++j) row_sum += std::abs(W(e, j));
    d.W_max = std::max(d.W_max, row_sum);
  }
  return d;
}

/// One combination of modes solved and judged: its r, u, its weakest margin's level, the
/// contacts that fail or sit in the band, and its place in tie rule 2's order.
struct ModeEval {
  double r[kCapRows], u[kCapRows];
  Level level = Level::Strict;
  int failing = 0, n_closed = 0, n_slip = 0, lex = 0;
  double violation = 0.0;      // sum over the failing contacts, in units of the band
  std::uint8_t fail_mask = 0;  // bit i: contact i violates the law
  std::uint8_t band_mask = 0;  // bit i: contact i has a margin within the band
};

/// Solves combination `mode` (one mode per contact) and judges it; false when its system is
/// singular and inconsistent (ill-posed: not a candidate). The enumeration and the first-guess
/// path (solve_guess) both call this, so that a guess taken is the enumeration's answer to the bit.
/// KC: K known at compile time (1 to kCapK, the loops over the contacts unrolled: a Moreau-Jean
/// step with two contacts evaluates its guess at every Newton iterate), or 0 (K = c.size()). The
/// same operations in the same order either way, so the same bits.
template <int KC>
bool eval_mode_k(MatIn W, VecIn u0, std::span<const SetContact> c, const Phase* mode, SetBand band,
                 const DataScale& scale, ModeEval& ev) {
  const int K = KC > 0 ? KC : static_cast<int>(c.size());
  double a[kCapRows][kCapRows], rhs[kCapRows], x[kCapRows];
  int row[kCapRows];
  int n_closed = 0, n_slip = 0, lex = 0;
  for (int i = 0; i < K; ++i) {
    n_closed += mode[i] != Phase::Free;
    n_slip += (mode[i] == Phase::SlipPos || mode[i] == Phase::SlipNeg) && c[i].mu > 0.0;
    lex = lex * 4 + rank_of(mode[i]);
  }
  // unknowns: r_N of each closed contact (with r_T = ct r_N on a slip), r_T of each stick;
  // equations: u_N = 0 of each closed contact, u_T = 0 of each stick
  int unk_col[kCapRows];  // the column of W of the unknown
  double unk_ct[kCapRows];
  int unk_contact[kCapRows];
  int m = 0;
  for (int i = 0; i < K; ++i) {
    if (mode[i] == Phase::Free) continue;
    double ct = 0.0;
    if (mode[i] == Phase::SlipPos || mode[i] == Phase::SlipNeg) {
      const double s = mode[i] == Phase::SlipPos ? 1.0 : -1.0;
      ct = -c[i].mu * s;
    }
    row[m] = 2 * i;
    unk_col[m] = 2 * i;
    unk_ct[m] = ct;
    unk_contact[m] = i;
    ++m;
    if (mode[i] == Phase::Stick) {
      row[m] = 2 * i + 1;
      unk_col[m] = 2 * i + 1;
      unk_ct[m] = 0.0;
      unk_contact[m] = -1;  // r_T of a stick
      ++m;
    }
  }
  // entry (e, k) of the mode's system: a slip's column is W_{., N} + ct W_{., T} (exactly
  // A_NN - mu s A_NT for K = 1)
  const auto entry = [&](int e, int k) {
    const int j = unk_col[k];
    return unk_contact[k] >= 0 && unk_ct[k] != 0.0 ? W(row[e], j) + unk_ct[k] * W(row[e], j + 1)
                                                   : W(row[e], j);
  };
  for (int e = 0; e < m; ++e) {
    for (int k = 0; k < m; ++k) a[e][k] = entry(e, k);
    rhs[e] = -u0(row[e]);
  }
  double kappa = 1.0;
  if (!solve_full_pivot(a, rhs, m, x, kappa)) {
    // singular: redundant contacts (their forces indeterminate) are a candidate with the
    // minimum-norm forces when the system is consistent; otherwise ill-posed, no candidate.
    // (The elimination overwrote the system: it is built again, only here.)
    CapMat<kCapRows> A0(m, m);
    CapVec<kCapRows> b0(m), xm;
    for (int e = 0; e < m; ++e) {
      for (int k = 0; k < m; ++k) A0(e, k) = entry(e, k);
      b0[e] = -u0(row[e]);
    }
    const MinNormResult mn = min_norm_solve<kCapRows>(A0, b0, xm, kSingularPivot);
    if (!mn.consistent) return false;
    for (int k = 0; k < m; ++k) x[k] = xm[k];
    kappa = mn.kappa;
  }
  double(&r)[kCapRows] = ev.r;
  double(&u)[kCapRows] = ev.u;
  std::fill_n(r, kCapRows, 0.0);
  for (int k = 0; k < m; ++k) {
    r[unk_col[k]] = x[k];
    if (unk_contact[k] >= 0 && mode[unk_contact[k]] != Phase::Stick)
      r[unk_col[k] + 1] = unk_ct[k] * x[k];
  }
  for (int e = 0; e < 2 * K; ++e) {
    double s = u0(e);
    for (int j = 0; j < 2 * K; ++j) s += W(e, j) * r[j];
    u[e] = s;
  }
  // the margins of each contact, each with its band: the data's (tol_u, tol_r) or, when larger,
  // the round-off of this mode's solve, m kappa eps times the size of the terms (|u0| + |W| |r|
  // for u, |r| for r): a margin that is zero in exact arithmetic (redundant contacts) is then
  // not decided by the noise of an ill-conditioned solve
  double r_max = 0.0;
  for (int e = 0; e < 2 * K; ++e) r_max = std::max(r_max, std::abs(r[e]));
  const double solve_err = m * kappa * std::numeric_limits<double>::epsilon();
  const double tol_u = std::max(band.tol_u, solve_err * (scale.u0_max + scale.W_max * r_max));
  const double tol_r = std::max(band.tol_r, solve_err * r_max);
  Level lv = Level::Strict;
  int failing = 0;
  double violation = 0.0;
  std::uint8_t fail_mask = 0, band_mask = 0;
  for (int i = 0; i < K; ++i) {
    const double rN = r[2 * i], rT = r[2 * i + 1], uN = u[2 * i], uT = u[2 * i + 1];
    Level li = Level::Strict;
    double vi = 0.0;  // violation in units of the band
    auto margin = [&](double value, double tol) {
      li = std::min(li, level_of(value, tol));
      vi = std::max(vi, -value / tol);
    };
    switch (mode[i]) {
      case Phase::Free: margin(uN, tol_u); break;
      case Phase::Stick:
        margin(rN, tol_r);
        margin(c[i].mu * rN - std::abs(rT), c[i].mu * tol_r);
        break;
      case Phase::SlipPos:
      case Phase::SlipNeg:
        margin(rN, tol_r);
        if (c[i].sliding == 0 && c[i].mu > 0.0)
          margin((mode[i] == Phase::SlipPos ? 1.0 : -1.0) * uT, tol_u);
        break;
    }
    lv = std::min(lv, li);
    if (li == Level::Violated) {
      ++failing;
      violation += vi;
      fail_mask |= static_cast<std::uint8_t>(1u << i);
    } else if (li == Level::Boundary) {
      band_mask |= static_cast<std::uint8_t>(1u << i);
    }
  }
  ev.level = lv;
  ev.failing = failing;
  ev.violation = violation;
  ev.fail_mask = fail_mask;
  ev.band_mask = band_mask;
  ev.n_closed = n_closed;
  ev.n_slip = n_slip;
  ev.lex = lex;
  return true;
}

bool eval_mode(MatIn W, VecIn u0, std::span<const SetContact> c, const Phase* mode, SetBand band,
               const DataScale& scale, ModeEval& ev) {
  switch (c.size()) {
    case 1: return eval_mode_k<1>(W, u0, c, mode, band, scale, ev);
    case 2: return eval_mode_k<2>(W, u0, c, mode, band, scale, ev);
    case 3: return eval_mode_k<3>(W, u0, c, mode, band, scale, ev);
    case 4: return eval_mode_k<4>(W, u0, c, mode, band, scale, ev);
    default: return eval_mode_k<0>(W, u0, c, mode, band, scale, ev);
  }
}

/// The enumeration's result (K <= kCapK).
struct EnumResult {
  SetOutcome outcome = SetOutcome::NoSolution;
  Phase mode[kCapK]{};
  double r[kCapRows]{}, u[kCapRows]{};
  std::uint8_t involved = 0;  // bit i: contact i
  int n_candidates = 0, n_strict = 0, n_consistent = 0;
  double r_spread = 0.0, u_spread = 0.0;
  Phase other_mode[kCapK]{};
  double other_r[kCapRows]{};
};

}  // namespace

/// The consistent combinations of one enumeration, and the scratch of the mode solves.
struct ContactSetSolver::EnumWork {
  struct Candidate {
    Phase mode[kCapK];
    double r[kCapRows], u[kCapRows];
    Level level;
    int key;
    bool alive;            // not dropped by tie rule 1
    std::uint8_t in_band;  // bit i: contact i has a margin within the band
  };
  Candidate cand[kCapModes];
  int n = 0;

  EnumResult run(MatIn W, VecIn u0, std::span<const SetContact> contacts, SetBand band);
};

EnumResult ContactSetSolver::EnumWork::run(MatIn W, VecIn u0, std::span<const SetContact> c,
                                           SetBand band) {
  const int K = static_cast<int>(c.size());
  // each contact's candidates, in the one-contact order
  Phase list[kCapK][4];
  int n_list[kCapK];
  int total = 1;
  for (int i = 0; i < K; ++i) {
    int n_i = 0;
    list[i][n_i++] = Phase::Free;
    if (c[i].mu == 0.0) {
      list[i][n_i++] = Phase::SlipPos;  // frictionless contact
    } else if (c[i].sliding != 0) {
      list[i][n_i++] = c[i].sliding > 0 ? Phase::SlipPos : Phase::SlipNeg;
    } else {
      list[i][n_i++] = Phase::Stick;
      list[i][n_i++] = Phase::SlipPos;
      list[i][n_i++] = Phase::SlipNeg;
    }
    n_list[i] = n_i;
    total *= n_i;
  }
  EnumResult out;
  n = 0;
  const DataScale scale = data_scale(W, u0, K);
  // the least violated combination (NoSolution's contacts involved)
  int lv_failing = K + 1, lv_key = 0;
  double lv_total = std::numeric_limits<double>::infinity();
  std::uint8_t lv_mask = 0;

  int idx[kCapK] = {};
  Phase mode[kCapK];
  for (int comb = 0; comb < total; ++comb) {
    if (comb > 0) {  // odometer, the last contact fastest
      for (int i = K - 1; i >= 0; --i) {
        if (++idx[i] < n_list[i]) break;
        idx[i] = 0;
      }
    }
    for (int i = 0; i < K; ++i) mode[i] = list[i][idx[i]];
    ModeEval ev;
    if (!eval_mode(W, u0, c, mode, band, scale, ev)) continue;
    ++out.n_candidates;
    const double(&r)[kCapRows] = ev.r;
    const double(&u)[kCapRows] = ev.u;
    const Level lv = ev.level;
    const int failing = ev.failing, n_closed = ev.n_closed, n_slip = ev.n_slip, lex = ev.lex;
    const double violation = ev.violation;
    const std::uint8_t fail_mask = ev.fail_mask, band_mask = ev.band_mask;
    const int key = (n_closed * (kCapK + 1) + n_slip) * kCapModes + lex;
    if (lv == Level::Violated) {
      if (failing < lv_failing ||
          (failing == lv_failing &&
           (violation < lv_total || (violation == lv_total && key < lv_key)))) {
        lv_failing = failing;
        lv_total = violation;
        lv_key = key;
        lv_mask = fail_mask;
      }
      continue;
    }
    Candidate& cd = cand[n++];
    std::copy_n(mode, K, cd.mode);
    std::copy_n(r, 2 * K, cd.r);
    std::copy_n(u, 2 * K, cd.u);
    cd.level = lv;
    cd.key = key;
    cd.alive = true;
    cd.in_band = band_mask;
  }
  // tie rule 1, contact by contact in index order: contact i's excluded mode is dropped while a
  // consistent combination with contact i in another mode remains
  auto drop = [&](int i, Phase ex) {
    bool other = false;
    for (int k = 0; k < n; ++k) other |= cand[k].alive && cand[k].mode[i] != ex;
    if (other)
      for (int k = 0; k < n; ++k) cand[k].alive &= cand[k].mode[i] != ex;
  };
  for (int i = 0; i < K; ++i) {
    if (c[i].excluded) drop(i, *c[i].excluded);
    for (int p = 0; p < kNumPhases; ++p)
      if (c[i].excluded_modes & (1u << p)) drop(i, static_cast<Phase>(p));
  }
  // tie rules 2-3
  int pick_strict = -1, pick_boundary = -1;
  for (int k = 0; k < n; ++k) {
    if (!cand[k].alive) continue;
    ++out.n_consistent;
    if (cand[k].level == Level::Strict) {
      ++out.n_strict;
      if (pick_strict < 0 || cand[k].key < cand[pick_strict].key) pick_strict = k;
    } else if (pick_boundary < 0 || cand[k].key < cand[pick_boundary].key) {
      pick_boundary = k;
    }
  }
  const int pick = pick_strict >= 0 ? pick_strict : pick_boundary;
  if (pick < 0) {
    out.outcome = SetOutcome::NoSolution;
    for (int i = 0; i < K; ++i) out.mode[i] = Phase::Free;
    for (int e = 0; e < 2 * K; ++e) out.u[e] = u0(e);
    out.involved = lv_mask;
    return out;
  }
  const Candidate& p = cand[pick];
  std::copy_n(p.mode, K, out.mode);
  std::copy_n(p.r, 2 * K, out.r);
  std::copy_n(p.u, 2 * K, out.u);
  out.outcome = out.n_strict > 1    ? SetOutcome::NonUnique
                : out.n_strict == 1 ? SetOutcome::Unique
                                    : SetOutcome::Boundary;
  int other_pick = -1;
  for (int k = 0; k < n; ++k) {
    const Candidate& q = cand[k];
    if (!q.alive) continue;
    for (int e = 0; e < 2 * K; ++e) {
      out.r_spread = std::max(out.r_spread, std::abs(q.r[e] - p.r[e]));
      out.u_spread = std::max(out.u_spread, std::abs(q.u[e] - p.u[e]));
    }
    const bool counts = out.outcome == SetOutcome::NonUnique ? q.level == Level::Strict
                                                             : out.outcome == SetOutcome::Boundary;
    if (counts)
      for (int i = 0; i < K; ++i)
        if (q.mode[i] != p.mode[i]) out.involved |= static_cast<std::uint8_t>(1u << i);
    if (out.outcome == SetOutcome::NonUnique && k != pick && q.level == Level::Strict &&
        (other_pick < 0 || q.key < cand[other_pick].key))
      other_pick = k;
  }
  if (out.outcome == SetOutcome::Boundary) out.involved |= p.in_band;
  if (other_pick >= 0) {
    std::copy_n(cand[other_pick].mode, K, out.other_mode);
    std::copy_n(cand[other_pick].r, 2 * K, out.other_r);
  }
  return out;
}

namespace {

/// unique_by_monotonicity for K contacts known at compile time (the loops unrolled: a
/// Moreau-Jean step calls it once per Delassus matrix; measured 105 ns for K = 2 with K a
/// run-time value)
template <int K>
bool certify_unique(MatIn W, std::span<const SetContact> c) {
  constexpr int n = 2 * K;
  // W copied once into plain arrays (a Moreau-Jean step calls this once per Delassus matrix)
  double w[n][n], S[n][n], wT[K];
  bool finite = true;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      w[i][j] = W(i, j);
      finite = finite && std::isfinite(w[i][j]);
    }
  if (!finite) return false;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) S[i][j] = 0.5 * (w[i][j] + w[j][i]);
  for (int k = 0; k < K; ++k) {
    double s2 = 0.0;
    for (int j = 0; j < n; ++j) s2 += w[2 * k + 1][j] * w[2 * k + 1][j];
    wT[k] = std::sqrt(s2);
  }
  for (const double t : {1.0, 0.5, 2.0, 0.25, 4.0}) {
    double A[n][n];
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) A[i][j] = S[i][j];
    for (int k = 0; k < K; ++k) {
      if (c[k].mu == 0.0 || wT[k] == 0.0) continue;  // no friction term for this contact
      // a_k = t / |w_Tk|: (mu/2) a_k w_Tk w_Tk^T and (mu/2) / a_k on the normal diagonal
      const double f = 0.5 * c[k].mu * t / wT[k];
      const double* wr = w[2 * k + 1];
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) A[i][j] -= f * wr[i] * wr[j];
      A[2 * k][2 * k] -= 0.5 * c[k].mu * wT[k] / t;
    }
    double amax = 0.0;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) amax = std::max(amax, std::abs(A[i][j]));
    const double shift = 1e-10 * n * amax;
    // Gershgorin first (no division): every row's diagonal above the sum of its other entries'
    // magnitudes, by more than the shift, puts every eigenvalue of the symmetric A above it
    bool dominant = amax > 0.0;
    for (int i = 0; i < n && dominant; ++i) {
      double off = 0.0;
      for (int j = 0; j < n; ++j)
        if (j != i) off += std::abs(A[i][j]);
      dominant = A[i][i] - off > shift;
    }
    if (dominant) return true;
    // A - shift I = L D L^T (unit lower L in the lower triangle, D on the diagonal): positive
    // definite when every d_j > 0; one reciprocal per column and no square root (this is a
    // chain of dependent divisions: its latency is the cost)
    bool pd = amax > 0.0;
    for (int j = 0; j < n && pd; ++j) {
      double d = A[j][j] - shift;
      for (int k = 0; k < j; ++k) d -= A[j][k] * A[j][k] * A[k][k];
      if (!(d > 0.0)) {
        pd = false;
        break;
      }
      A[j][j] = d;
      const double inv = 1.0 / d;
      for (int i = j + 1; i < n; ++i) {
        double s = A[i][j];
        for (int k = 0; k < j; ++k) s -= A[i][k] * A[j][k] * A[k][k];
        A[i][j] = s * inv;
      }
    }
    if (pd) return true;
  }
  return false;
}

}  // namespace

bool unique_by_monotonicity(MatIn W, std::span<const SetContact> c) {
  const int K = static_cast<int>(c.size());
  if (K > kCapK || W.rows() != 2 * K || W.cols() != 2 * K) return false;
  for (const SetContact& ci : c)
    if (ci.sliding != 0) return false;
  switch (K) {
    case 0: return true;  // no contact: the empty solution
    case 1: return certify_unique<1>(W, c);
    case 2: return certify_unique<2>(W, c);
    case 3: return certify_unique<3>(W, c);
    default: return certify_unique<kCapK>(W, c);
  }
}

ContactSetSolver::ContactSetSolver(int max_contacts, PgsOptions pgs)
    : max_contacts_(max_contacts),
      pgs_(pgs),
      r_(Vec::Zero(2 * max_contacts)),
      u_(Vec::Zero(2 * max_contacts)),
      other_r_(Vec::Zero(2 * max_contacts)),
      mode_(max_contacts, Phase::Free),
      other_mode_(max_contacts, Phase::Free),
      involved_(max_contacts, 0),
      work_(std::make_unique<EnumWork>()),
      dr_(Vec::Zero(max_contacts)),
      local_W_(Mat::Zero(2, 2)),
      local_u0_(Vec::Zero(2)) {
  RUBDYN_DEMAND(max_contacts >= 0);
  RUBDYN_DEMAND(pgs.rel_tol > 0.0 && pgs.max_sweeps > 0);
}

ContactSetSolver::~ContactSetSolver() = default;
ContactSetSolver::ContactSetSolver(ContactSetSolver&&) noexcept = default;
ContactSetSolver& ContactSetSolver::operator=(ContactSetSolver&&) noexcept = default;

int ContactSetSolver::n_involved() const {
  int n = 0;
  for (int i = 0; i < K_; ++i) n += involved_[i] != 0;
  return n;
}

void ContactSetSolver::all_free(VecIn u0) {
  for (int i = 0; i < K_; ++i) {
    mode_[i] = Phase::Free;
    other_mode_[i] = Phase::Free;
    involved_[i] = 0;
  }
  r_.head(2 * K_).setZero();
  other_r_.head(2 * K_).setZero();
  u_.head(2 * K_) = u0;
  n_candidates_ = n_strict_ = n_consistent_ = 0;
  r_spread_ = u_spread_ = 0.0;
  sweeps_ = 0;
  last_change_ = 0.0;
}

SetOutcome ContactSetSolver::solve(MatIn W, VecIn u0, std::span<const SetContact> contacts,
                                   SetBand band, SetMethod method) {
  const int K = static_cast<int>(contacts.size());
  RUBDYN_DEMAND(K <= max_contacts_);
  RUBDYN_DEMAND(W.rows() == 2 * K && W.cols() == 2 * K && u0.size() == 2 * K);
  RUBDYN_DEMAND(band.tol_u > 0.0 && band.tol_r > 0.0);
  for (const SetContact& c : contacts) RUBDYN_DEMAND(c.mu >= 0.0);
  K_ = K;
  if (method == SetMethod::Auto)
    method = K <= kMaxEnumContacts ? SetMethod::Enumeration : SetMethod::Pgs;
  RUBDYN_DEMAND(method == SetMethod::Pgs || K <= kMaxEnumContacts);
  method_ = method;
  if (!all_finite(W) || !all_finite(u0)) {
    all_free(u0);
    outcome_ = SetOutcome::NonFinite;
    return outcome_;
  }
  outcome_ = method == SetMethod::Enumeration ? enumerate(W, u0, contacts, band)
                                              : gauss_seidel(W, u0, contacts, band);
  return outcome_;
}

SetOutcome ContactSetSolver::solve_guess(MatIn W, VecIn u0, std::span<const SetContact> contacts,
                                         SetBand band, std::span<const Phase> guess,
                                         std::optional<bool> known_unique) {
  const int K = static_cast<int>(contacts.size());
  guess_taken_ = false;
  bool eligible = K <= kMaxEnumContacts && K <= max_contacts_ && guess.size() == contacts.size() &&
                  W.rows() == 2 * K && W.cols() == 2 * K && u0.size() == 2 * K &&
                  band.tol_u > 0.0 && band.tol_r > 0.0 && all_finite(u0);
  for (int i = 0; i < K && eligible; ++i) {
    const SetContact& ci = contacts[static_cast<std::size_t>(i)];
    const Phase g = guess[static_cast<std::size_t>(i)];
    // the guess must be one of the contact's candidates (contact_set.hpp, ENUMERATION)
    eligible = !ci.excludes_any() && ci.mu >= 0.0 &&
               (g == Phase::Free || (ci.mu == 0.0 ? g == Phase::SlipPos : true));
  }
  if (eligible && (known_unique ? *known_unique : unique_by_monotonicity(W, contacts))) {
    ModeEval ev;
    if (eval_mode(W, u0, contacts, guess.data(), band, data_scale(W, u0, K), ev) &&
        ev.level == Level::Strict) {
      K_ = K;
      method_ = SetMethod::Enumeration;
      all_free(u0);
      for (int i = 0; i < K; ++i) mode_[i] = guess[static_cast<std::size_t>(i)];
      for (int k = 0; k < 2 * K; ++k) {
        r_(k) = ev.r[k];
        u_(k) = ev.u[k];
      }
      n_candidates_ = n_strict_ = n_consistent_ = 1;
      guess_taken_ = true;
      outcome_ = SetOutcome::Unique;
      return outcome_;
    }
  }
  return solve(W, u0, contacts, band);
}

SetOutcome ContactSetSolver::enumerate(MatIn W, VecIn u0, std::span<const SetContact> contacts,
                                       SetBand band) {
  const EnumResult e = work_->run(W, u0, contacts, band);
  all_free(u0);
  for (int i = 0; i < K_; ++i) {
    mode_[i] = e.mode[i];
    other_mode_[i] = e.other_mode[i];
    involved_[i] = (e.involved >> i) & 1u;
  }
  for (int k = 0; k < 2 * K_; ++k) {
    r_(k) = e.r[k];
    u_(k) = e.u[k];
    other_r_(k) = e.other_r[k];
  }
  n_candidates_ = e.n_candidates;
  n_strict_ = e.n_strict;
  n_consistent_ = e.n_consistent;
  r_spread_ = e.r_spread;
  u_spread_ = e.u_spread;
  return e.outcome;
}

SetOutcome ContactSetSolver::gauss_seidel(MatIn W, VecIn u0, std::span<const SetContact> contacts,
                                          SetBand band) {
  all_free(u0);
  const int K = K_;
  dr_.head(K).setZero();
  bool stalled = false;
  double threshold = 0.0;
  for (sweeps_ = 1; sweeps_ <= pgs_.max_sweeps; ++sweeps_) {
    double change = 0.0;
    stalled = false;
    for (int i = 0; i < K; ++i) {
      // contact i's own problem: u_i = (u0_i + sum_{j != i} W_ij r_j) + W_ii r_i
      for (int a = 0; a < 2; ++a) {
        double s = u0(2 * i + a);
        for (int j = 0; j < 2 * K; ++j)
          if (j / 2 != i) s += W(2 * i + a, j) * r_(j);
        local_u0_(a) = s;
        for (int b = 0; b < 2; ++b) local_W_(a, b) = W(2 * i + a, 2 * i + b);
      }
      const EnumResult e = work_->run(local_W_, local_u0_, contacts.subspan(i, 1), band);
      if (!has_solution(e.outcome)) {
        stalled = true;  // this contact cannot obey the law given the others: keep its r
        involved_[i] = 1;
        continue;
      }
      involved_[i] = 0;
      dr_(i) = std::max(std::abs(e.r[0] - r_(2 * i)), std::abs(e.r[1] - r_(2 * i + 1)));
      change = std::max(change, dr_(i));
      r_(2 * i) = e.r[0];
      r_(2 * i + 1) = e.r[1];
      mode_[i] = e.mode[0];
    }
    last_change_ = change;
    double r_max = 0.0;
    for (int k = 0; k < 2 * K; ++k) r_max = std::max(r_max, std::abs(r_(k)));
    threshold = pgs_.rel_tol * std::max(r_max, band.tol_r);
    if (!stalled && change <= threshold) break;
  }
  for (int e = 0; e < 2 * K; ++e) {
    double s = u0(e);
    for (int j = 0; j < 2 * K; ++j) s += W(e, j) * r_(j);
    u_(e) = s;
  }
  if (sweeps_ > pgs_.max_sweeps || stalled) {
    sweeps_ = std::min(sweeps_, pgs_.max_sweeps);
    // involved: the contacts without a local solution, and those whose r still moved by more
    // than the tolerance in the last sweep
    for (int i = 0; i < K; ++i) involved_[i] |= dr_(i) > threshold;
    return SetOutcome::NotConverged;
  }
  return SetOutcome::Converged;
}

}  // namespace rubdyn
