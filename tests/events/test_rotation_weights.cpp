// rotor.rotations (issue 32): a matrices model's rotation (an FE shaft's slope) is resolved by the
// event solver as the displacement of equal kinetic energy, atol / l with l = sqrt(M_ii / m), m
// the median of the deflections' diagonal masses (hybrid/phase_session.cpp), and its rate as
// atol_v / l. Checked on the committed FE rotors: the lengths are computed here from M, the
// sessions' weights read back; a chart's copied coordinates carry the weight of the coordinate
// they copy, and which one that is (ChartScales::copies, RingChart::lengths) is checked against
// the chart's own values, p_k = q_copies[k]. (An equivalence of whole runs, the same rotor with
// its slopes rescaled to metres, is not bitwise: the banded LU's partial pivoting compares rows
// of different scales, and the step sequence of BDF amplifies that round-off to a few per cent
// of the steps; what the declaration gains is measured in bench/FE_SCALING.md.)
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "hybrid/phase_chart.hpp"
#include "hybrid/phase_session.hpp"
#include "rubdyn/contact/ring_chart.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/model/matrix_model.hpp"

using namespace rubdyn;
using namespace rubdyn::detail;

namespace {

const std::string kCases = std::string(RUBDYN_SOURCE_DIR) + "/cases/";

/// The run-up case with its spin free under a torque (so that it has a contact chart).
CaseSpec free_runup() {
  const std::string path = kCases + "fe-runup.toml";
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  const std::string from = "spin = \"prescribed\"\nspin_accel = 1000.0\n";
  const auto at = text.find(from);
  REQUIRE(at != std::string::npos);
  text.replace(at, from.size(), "spin = \"torque\"\ntorque = 363.0\n");
  return parse_case(text, path);
}

/// The lengths the rule gives, computed here: sqrt(M_ii / m) on the rotations, 1 elsewhere.
std::vector<double> expected_lengths(const MatrixRotorParams& r) {
  std::vector<double> defl;
  for (int i = 0; i < r.size(); ++i)
    if (!r.rotation[static_cast<std::size_t>(i)]) defl.push_back(r.M(i, i));
  std::sort(defl.begin(), defl.end());
  const double m = defl[(defl.size() - 1) / 2];
  std::vector<double> l(static_cast<std::size_t>(r.size()), 1.0);
  for (int i = 0; i < r.size(); ++i)
    if (r.rotation[static_cast<std::size_t>(i)])
      l[static_cast<std::size_t>(i)] = std::sqrt(r.M(i, i) / m);
  return l;
}

/// A state with the first contact closed (the rotor point at g0 from the ring's centre), the
/// rest small and random.
void closed_state(const LagrangianModel& m, Vec& q, Vec& v) {
  const int n = m.num_dofs();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  q = Vec::Zero(n);
  v = Vec::Zero(n);
  for (int i = 0; i < n; ++i) q[i] = 1e-6 * u(rng);
  const auto& cs = m.coordinates();
  int ix = -1, iy = -1;
  for (int i = 0; i < n; ++i) {
    const auto& c = cs[static_cast<std::size_t>(i)];
    if (c.plane == 0 && c.role == CoordinateRole::RotorX) ix = i;
    if (c.plane == 0 && c.role == CoordinateRole::RotorY) iy = i;
    if (c.plane == 0 && (c.role == CoordinateRole::StatorX || c.role == CoordinateRole::StatorY))
      q[i] = 0.0;
  }
  REQUIRE(ix >= 0);
  REQUIRE(iy >= 0);
  q[ix] = m.gap_scale(0);
  q[iy] = 0.0;
  if (m.spin_coordinate() >= 0) v[m.spin_coordinate()] = 200.0;
}

}  // namespace

TEST_CASE("Rotations: the sessions weight a rotation as atol / l, l = sqrt(M_ii / m)",
          "[events][matrices]") {
  const double atol = 1e-13, atol_v = 1e-10;
  SessionSettings s;
  s.rtol = 1e-8;
  s.atol_q = atol;
  s.atol_v = atol_v;
  s.g0 = 1.5e-4;
  s.adams = false;
  // the prescribed run-up (free flight and the projected contact phase) and the free spin
  // (free flight and the charted contact phase)
  for (const bool free_spin : {false, true}) {
    INFO((free_spin ? "free spin" : "prescribed spin"));
    const CaseSpec spec = free_spin ? free_runup() : load_case(kCases + "fe-runup.toml", {});
    const MatrixRotorParams& r = spec.matrices.rotor;
    REQUIRE(std::count(r.rotation.begin(), r.rotation.end(), true) == 26);  // dx*, dy*
    const std::vector<double> l = expected_lengths(r);
    // (the 12 elements' 0.1 m: about 0.16 of it, the lever arm of a slope in its element)
    CHECK(l[26] > 0.01);
    CHECK(l[26] < 0.03);
    const auto model = build_model(spec);
    // q's coordinates are the model's first n (the spin, the ring after them, PrescribedSpin
    // leaving out the spin)
    for (int i = 0; i < r.size(); ++i)
      CHECK(model->coordinates()[static_cast<std::size_t>(i)].length ==
            Approx(l[static_cast<std::size_t>(i)]).epsilon(1e-15));
    PhaseContext ctx(*model, s.rtol, atol, 0.0);
    for (const SessionKind kind : {SessionKind::Free, SessionKind::Projected}) {
      if (kind == SessionKind::Projected && free_spin) continue;  // (charted, below)
      ctx.modes[0] = kind == SessionKind::Free ? Phase::Free : Phase::SlipNeg;
      const PhaseSession ps(ctx, s, kind);
      const auto tol = ps.absolute_tolerances();
      const int n = model->num_dofs();
      for (int i = 0; i < r.size(); ++i) {
        INFO("coordinate " << i);
        const double li = l[static_cast<std::size_t>(i)];
        CHECK(tol[static_cast<std::size_t>(i)] == Approx(atol / li).epsilon(1e-15));
        CHECK(tol[static_cast<std::size_t>(n + i)] == Approx(atol_v / li).epsilon(1e-15));
      }
      for (int i = r.size(); i < n; ++i) {  // the spin and the ring's centre: as before
        CHECK(tol[static_cast<std::size_t>(i)] == atol);
        CHECK(tol[static_cast<std::size_t>(n + i)] == atol_v);
      }
    }
    if (!free_spin) continue;
    // the charted slip phase: each copied coordinate weighted as the one it copies
    ctx.modes[0] = Phase::SlipNeg;
    auto chart = make_phase_chart(*model);
    REQUIRE(chart);
    const int dim = chart->dim(ctx.modes);
    PhaseSession ps(ctx, s, SessionKind::Reduced, std::move(chart), dim);
    Vec q, v;
    closed_state(*model, q, v);
    ps.restart(0.0, q, v, Works{}, 1.0);
    const auto tol = ps.absolute_tolerances();
    const ChartScales sc = model->contact_chart()->scales(ChartMode::Slip);
    int rotations = 0;
    for (int k = 0; k < dim; ++k) {
      const int c = sc.copies[static_cast<std::size_t>(k)];
      if (c < 0 || c >= r.size()) continue;
      INFO("chart coordinate " << k << " copies " << c);
      const double lc = l[static_cast<std::size_t>(c)];
      rotations += r.rotation[static_cast<std::size_t>(c)] ? 1 : 0;
      CHECK(tol[static_cast<std::size_t>(k)] == Approx(atol / lc).epsilon(1e-15));
      CHECK(tol[static_cast<std::size_t>(dim + k)] == Approx(atol_v / lc).epsilon(1e-15));
    }
    CHECK(rotations == 26);
  }
}

TEST_CASE("Rotations: a chart's copies are the coordinates it copies", "[events][matrices]") {
  // one contact node (MatrixModel::Chart, slip and stick) and two (RingChart): p_k = q_c and
  // p'_k = v_c for every copy c = copies[k], each of q's coordinates but the charted ones
  // copied once, and the angles (length > 0) copy nothing
  const auto check_copies = [](const LagrangianModel& m, VecIn q, VecIn v, VecIn p, VecIn pd,
                               const std::vector<double>& len, const std::vector<int>& copies,
                               int charted) {
    std::vector<int> seen(static_cast<std::size_t>(m.num_dofs()), 0);
    for (std::size_t k = 0; k < copies.size(); ++k) {
      INFO("chart coordinate " << k);
      if (len[k] > 0.0) {
        CHECK(copies[k] == -1);
        continue;
      }
      const int c = copies[k];
      REQUIRE(c >= 0);
      REQUIRE(c < m.num_dofs());
      CHECK(p[static_cast<Eigen::Index>(k)] == q[c]);
      CHECK(pd[static_cast<Eigen::Index>(k)] == v[c]);
      ++seen[static_cast<std::size_t>(c)];
    }
    CHECK(std::count(seen.begin(), seen.end(), 1) == m.num_dofs() - charted);
    CHECK(std::count(seen.begin(), seen.end(), 0) == charted);
  };
  {
    const auto model = build_model(free_runup());
    const ContactChart* ch = model->contact_chart();
    REQUIRE(ch);
    Vec q, v;
    closed_state(*model, q, v);
    for (const ChartMode mode : {ChartMode::Slip, ChartMode::Stick}) {
      INFO((mode == ChartMode::Slip ? "slip" : "stick"));
      const int dim = ch->dim(mode);
      Vec p(dim), pd(dim);
      ChartAnchor anchor{};
      ch->chart(mode, q, v, anchor, p, pd);
      const ChartScales sc = ch->scales(mode);
      REQUIRE(sc.copies.size() == static_cast<std::size_t>(dim));
      // charted: the node's x, y (and the spin in stick)
      check_copies(*model, q, v, p, pd, sc.length, sc.copies, mode == ChartMode::Slip ? 2 : 3);
    }
  }
  {
    const auto model = build_model(load_case(kCases + "fe-two-seal.toml", {}));
    const RingChart* ch = model->ring_chart();
    REQUIRE(ch);
    Vec q, v;
    closed_state(*model, q, v);
    const std::vector<Phase> modes = {Phase::SlipNeg, Phase::Free};
    RingChart::Plan pl;
    ch->plan(modes, pl);
    const int dim = ch->dim(modes);
    Vec p(dim), pd(dim);
    RingAnchor anchor{};
    ch->chart(modes, pl, 0.0, q, v, anchor, p, pd);
    std::vector<double> len(static_cast<std::size_t>(dim));
    std::vector<int> copies(static_cast<std::size_t>(dim));
    ch->lengths(modes, pl, len, copies);
    check_copies(*model, q, v, p, pd, len, copies, 2);  // the slipping node's x, y
  }
}
