// The matrices model ([model] kind = "matrices", model/matrix_model.hpp): its file reader (CSV,
// .npy in both orders, bad files), its case rules (each bad matrix named with its key, file and
// line), its structured operations against dense and finite-difference ones, its energy
// balance, and the paper's rigid rotor written as matrices (cases/matrices-paper.toml, from
// scripts/make-paper-matrices.py) reproducing the rigid-rotor model's runs to round-off.
#include <Eigen/Cholesky>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "rubdyn/analysis/campbell.hpp"
#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/matrix_files.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/model/matrix_model.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"
#include "rubdyn/stepping/fixed_step.hpp"
#include "support/fixed_rings.hpp"

using namespace rubdyn;
namespace fs = std::filesystem;

namespace {

/// A fresh folder under the system's temporary folder.
fs::path scratch(const std::string& tag) {
  std::random_device rd;
  const fs::path d =
      fs::temp_directory_path() / ("rubdyn-matrices-" + tag + "-" + std::to_string(rd()));
  fs::create_directories(d);
  return d;
}

void write(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary) << bytes;
}

/// A .npy file (format 1.0) of `descr` with the given shape and raw data bytes.
std::string npy(const std::string& descr, bool fortran, const std::string& shape,
                const std::string& data) {
  std::string h = "{'descr': '" + descr + "', 'fortran_order': " + (fortran ? "True" : "False") +
                  ", 'shape': " + shape + ", }";
  while ((10 + h.size() + 1) % 64 != 0) h += ' ';
  h += '\n';
  std::string out = "\x93NUMPY";
  out += '\x01';
  out += '\x00';
  out += static_cast<char>(h.size() & 0xff);
  out += static_cast<char>(h.size() >> 8);
  return out + h + data;
}

/// Little-endian float64 bytes of the values.
std::string f8(std::initializer_list<double> xs) {
  std::string s;
  for (double x : xs) {
    std::uint64_t b;
    std::memcpy(&b, &x, 8);
    for (int k = 0; k < 8; ++k) s += static_cast<char>((b >> (8 * k)) & 0xff);
  }
  return s;
}

std::string case_text(const fs::path& dir, const std::string& rotor_more = "",
                      const std::string& more = "") {
  (void)dir;
  return "[model]\nkind = \"matrices\"\n[rotor]\nM = \"M.csv\"\nC = \"C.csv\"\nK = \"K.csv\"\n"
         "G = \"G.csv\"\nJp = 0.06\n" +
         rotor_more +
         "[contact_node]\nx = 0\ny = 1\nradius = 0.05\ngap = 2e-4\n[stator]\nmass = 2.0\n"
         "k = 2e6\nc = 100.0\n[contact]\nmu = 0.1\n[loads]\ngravity = 0.0\ntorque = 1.0\n"
         "[initial]\nomega0 = 100.0\n[run]\nt_end = 0.01\nomega_lim = 2000.0\n" +
         more;
}

/// The issues of a case that must be refused.
std::vector<CaseIssue> refused(const std::string& text, const fs::path& source) {
  try {
    parse_case(text, source.string());
  } catch (const CaseError& e) {
    return e.issues();
  }
  FAIL("the case was accepted");
  return {};
}

const CaseIssue* find_issue(const std::vector<CaseIssue>& is, const std::string& key) {
  for (const auto& i : is)
    if (i.key == key) return &i;
  return nullptr;
}

const std::string kPaper = RUBDYN_SOURCE_DIR "/cases/matrices-paper.toml";
const std::string kReference = RUBDYN_SOURCE_DIR "/cases/reference.toml";

}  // namespace

TEST_CASE("Matrix files: CSV and .npy in C and Fortran order read the same matrix",
          "[matrices][io]") {
  // [[1, -2.5, 3], [4e-3, 5, 6]] written four ways
  Mat want(2, 3);
  want << 1, -2.5, 3, 4e-3, 5, 6;
  const Mat csv = parse_matrix("# header\n1, -2.5 ,+3\r\n\n4e-3,5,6\n", false);
  const Mat c_order = parse_matrix(npy("<f8", false, "(2, 3)", f8({1, -2.5, 3, 4e-3, 5, 6})), true);
  const Mat f_order = parse_matrix(npy("<f8", true, "(2, 3)", f8({1, 4e-3, -2.5, 5, 3, 6})), true);
  // exact: every value is parsed or copied, never computed
  CHECK(csv == want);
  CHECK(c_order == want);
  CHECK(f_order == want);
  const Mat column = parse_matrix(npy("<f8", false, "(3,)", f8({1, 2, 3})), true);
  CHECK(column == Eigen::Vector3d(1, 2, 3));
  CHECK(parse_matrix("1\n2\n3\n", false) == Eigen::Vector3d(1, 2, 3));
}

TEST_CASE("Matrix files: a bad file is refused with what is wrong in it", "[matrices][io]") {
  const struct {
    std::string bytes;
    bool npy;
    std::string says;
  } bad[] = {
      {"1,2\n3\n", false, "line 2: 1 numbers, where the first row has 2"},
      {"1,x\n", false, "line 1, column 2: 'x' is not a number"},
      {"1,nan\n", false, "line 1, column 2: nan is not finite"},
      {"1,2,\n", false, "line 1, column 3"},
      {"# only a comment\n", false, "holds no numbers"},
      {npy("<f4", false, "(1,)", "abcd"), true, "dtype '<f4'"},
      {npy(">f8", false, "(1,)", f8({1})), true, "dtype '>f8'"},
      {npy("<f8", false, "(1, 1, 1)", f8({1})), true, "a 3-D array"},
      {npy("<f8", false, "(2, 2)", f8({1, 2, 3})), true, "24 bytes of data where shape"},
      {npy("<f8", false, "(2,)", f8({1, INFINITY})), true, "entry (1, 0) is inf"},
      {"NUMPY", true, "no \\x93NUMPY magic"},
  };
  for (const auto& b : bad) {
    INFO(b.says);
    try {
      parse_matrix(b.bytes, b.npy);
      FAIL("accepted");
    } catch (const MatrixFileError& e) {
      CHECK_THAT(e.what(), Catch::Contains(b.says));
    }
  }
  CHECK_THROWS_WITH(read_matrix_file("/nonexistent/M.csv"),
                    Catch::Contains("cannot read the matrix file: No such file"));
}

TEST_CASE("Case files of kind matrices: each bad matrix is named with its key, file and line",
          "[matrices][io]") {
  const fs::path d = scratch("case");
  const fs::path src = d / "case.toml";
  write(d / "M.csv", "2,0.5\n0.5,3\n");
  write(d / "C.csv", "1,0\n0,1\n");
  write(d / "K.csv", "1e6,0\n0,1e6\n");
  write(d / "G.csv", "0,0.2\n-0.2,0\n");
  const CaseSpec ok = parse_case(case_text(d), src.string());
  CHECK(ok.matrices.rotor.size() == 2);
  CHECK(ok.matrix_files.M == (d / "M.csv").string());  // resolved against the case's folder
  CHECK(initial_coordinates(ok).size() == 5);          // q0, q1, theta, x_s, y_s
  // case.resolved.toml names the files read, so that it reads back from any folder
  const CaseSpec back = parse_case(to_toml(ok), "/elsewhere/case.resolved.toml");
  CHECK(back.matrices.rotor.M == ok.matrices.rotor.M);

  const struct {
    std::string file, bytes, key, says;
  } bad[] = {
      {"M.csv", "2,0.5\n0.6,3\n", "rotor.M", "must be symmetric"},
      {"M.csv", "1,2\n2,1\n", "rotor.M", "positive definite"},
      {"M.csv", "1,2,3\n", "rotor.M", "must be a square matrix"},
      {"C.csv", "1,0,0\n0,1,0\n0,0,1\n", "rotor.C", "must be 2 x 2 as rotor.M is (read 3 x 3)"},
      {"C.csv", "1,0\n0,-1\n", "rotor.C", "positive semidefinite"},
      {"K.csv", "1,0.1\n0,1\n", "rotor.K", "must be symmetric"},
      {"G.csv", "0,0.2\n0.2,0\n", "rotor.G", "skew-symmetric"},
      {"G.csv", "0,inf\n-0.2,0\n", "rotor.G", "not finite"},
  };
  for (const auto& b : bad) {
    INFO(b.file << ": " << b.says);
    const fs::path good = d / (b.file + ".good");
    fs::copy_file(d / b.file, good, fs::copy_options::overwrite_existing);
    write(d / b.file, b.bytes);
    const auto is = refused(case_text(d), src);
    fs::copy_file(good, d / b.file, fs::copy_options::overwrite_existing);
    const CaseIssue* i = find_issue(is, b.key);
    REQUIRE(i);
    CHECK_THAT(i->rule, Catch::Contains(b.says));
    CHECK_THAT(i->rule, Catch::Contains((d / b.file).string()) || Catch::Contains(b.says));
    CHECK(i->file == src.string());
    CHECK(i->line == (b.key == "rotor.M"   ? 4
                      : b.key == "rotor.C" ? 5
                      : b.key == "rotor.K" ? 6
                                           : 7));
  }
  // a missing file, named
  {
    const auto is = refused(case_text(d, "f0 = \"nothere.csv\"\n"), src);
    const CaseIssue* i = find_issue(is, "rotor.f0");
    REQUIRE(i);
    CHECK(i->value == "\"nothere.csv\"");
    CHECK_THAT(i->rule,
               Catch::Contains((d / "nothere.csv").string()) && Catch::Contains("No such file"));
  }
  // the rules on the node, the names, the Schur complement and the number of nodes
  const struct {
    std::string rotor_more, replace, with, key, says;
  } rules[] = {
      {"", "x = 0\n", "x = 2\n", "contact_node.x", "in [0, 1]"},
      {"", "y = 1\n", "y = 0\n", "contact_node.y", "must differ from contact_node.x"},
      {"coordinates = \"a, b, c\"\n", "", "", "rotor.coordinates", "names 3 coordinates"},
      {"coordinates = \"a, theta\"\n", "", "", "rotor.coordinates", "'theta'"},
      {"", "gravity = 0.0\n", "gravity = 0.0\nunbalance = 1.0\n", "rotor.Jp",
       "M_full is not positive definite"},
  };
  for (const auto& r : rules) {
    INFO(r.says);
    std::string text = case_text(d, r.rotor_more);
    if (!r.replace.empty()) text.replace(text.find(r.replace), r.replace.size(), r.with);
    const auto is = refused(text, src);
    const CaseIssue* i = find_issue(is, r.key);
    REQUIRE(i);
    CHECK_THAT(i->rule, Catch::Contains(r.says));
  }
  // several nodes ([[contact_node]] tables): each has its own ring and law, so [stator] and
  // [contact] are refused saying where the keys now live; a coordinate belongs to one node; an
  // override cannot add a node
  {
    std::string text = case_text(d);
    const std::string two =
        "[[contact_node]]\nx = 0\ny = 1\nradius = 0.05\ngap = 2e-4\nmu = 0.1\nstator_mass = 2.0\n"
        "stator_k = 2e6\nstator_c = 100.0\n[[contact_node]]\nx = 1\ny = 0\nradius = 0.05\n"
        "gap = 2e-4\nmu = 0.1\nstator_rigid = true\n";
    text.replace(text.find("[contact_node]"), text.find("[loads]") - text.find("[contact_node]"),
                 "[stator]\nmass = 2.0\n[contact]\nmu = 0.1\n" + two);
    const auto is = refused(text, src);
    const CaseIssue* i = find_issue(is, "stator.mass");
    REQUIRE(i);
    CHECK_THAT(i->rule, Catch::Contains("each node has its own ring"));
    i = find_issue(is, "contact.mu");
    REQUIRE(i);
    CHECK_THAT(i->rule, Catch::Contains("each node has its own law"));
    i = find_issue(is, "contact_node.2.x");
    REQUIRE(i);
    CHECK_THAT(i->rule, Catch::Contains("already a coordinate of contact node 1"));
    CHECK(i->line > 0);
  }
  fs::remove_all(d);
}

TEST_CASE("Matrices model: structured mass operations, Jacobians, M_full positive definite",
          "[matrices][model]") {
  // the paper's rotor (4 coordinates: every product row by row over the envelopes) and the
  // two-seal FE rotor reduced by Craig-Bampton to 24 dense coordinates (the dense kernels:
  // MatrixModel::Envelope::dense and M^-1)
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {kPaper,
       {"loads.unbalance=2e-4", "loads.unbalance_phase=0.7", "loads.gravity=9.81",
        "loads.torque_law=\"linear\"", "loads.torque_free_speed=2500"}},
      {RUBDYN_SOURCE_DIR "/cases/fe-two-seal.toml",
       {"reduction.method=\"craig-bampton\"", "reduction.modes=20", "loads.unbalance_phase=0.7",
        "loads.gravity=9.81"}}};
  for (const auto& [path, sets] : cases) {
    INFO(path);
    CaseSpec c = load_case(path, sets);
    const auto model = build_model(c);
    const int n = model->num_dofs();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    Vec q(n), v(n);
    for (int i = 0; i < n; ++i) {
      q[i] = 1e-4 * U(rng);
      v[i] = 0.1 * U(rng);
    }
    const int th = model->spin_coordinate();
    q[th] = 3.0;
    v[th] = 1500.0;
    // the forces against the matrices themselves: f0 - C v - K q - Omega G v and the unbalance's
    // centrifugal force on the first node (round-off of sums of O(n) terms: 1e-13 of the
    // terms' magnitude)
    if (path != kPaper) {
      const MatrixParams mp = matrix_model_params(c);  // (the reduced matrices)
      const auto& r = mp.rotor;
      const int nr = static_cast<int>(r.f0.size());
      REQUIRE(nr >= 16);  // (the dense kernels' size)
      Vec f(n);
      model->smooth_forces(0.0, q, v, f);
      const Vec qr = q.head(nr), vr = v.head(nr);
      Vec want = r.f0 - r.C * vr - r.K * qr - v[th] * (r.G * vr);
      const double psi = q[th] + 0.7, ub = mp.loads.unbalance;
      REQUIRE(ub > 0.0);
      const int ix = mp.node_list()[0].at.x, iy = mp.node_list()[0].at.y;
      want[ix] += v[th] * v[th] * ub * std::cos(psi);
      want[iy] += v[th] * v[th] * ub * std::sin(psi);
      const Vec scale = r.f0.cwiseAbs() + r.C.cwiseAbs() * vr.cwiseAbs() +
                        r.K.cwiseAbs() * qr.cwiseAbs() + v[th] * (r.G.cwiseAbs() * vr.cwiseAbs());
      CHECK((f.head(nr) - want).cwiseAbs().maxCoeff() <= 1e-13 * scale.maxCoeff());
    }
    Mat M(n, n);
    model->mass_matrix(q, M);
    CHECK((M - M.transpose()).norm() == 0.0);
    REQUIRE(Eigen::LLT<Mat>(M).info() == Eigen::Success);
    // product and solve against the dense matrix: round-off of O(n) operations on entries of
    // O(1): 1e-13 relative
    Vec x = Vec::NullaryExpr(n, [&] { return U(rng); }), y(n);
    model->mass_product(q, x, y);
    CHECK((y - M * x).norm() <= 1e-13 * (M * x).norm());
    Mat B = Mat::NullaryExpr(n, 3, [&] { return U(rng); });
    const Mat want = M.ldlt().solve(B);
    model->solve_mass(q, B);
    CHECK((B - want).norm() <= 1e-12 * want.norm());
    // derivatives against central differences (step 1e-7 of a state of 1e-4 m and 3 rad: the
    // truncation O(h^2) and the round-off O(eps / h) are both below 1e-6 of the entries)
    const double h = 1e-7;
    Mat J(n, n), dq(n, n), dv(n, n);
    model->mass_matrix_product_jacobian(q, x, J);
    model->smooth_force_jacobians(0.0, q, v, dq, dv);
    Mat Jfd(n, n), dqfd(n, n), dvfd(n, n);
    for (int k = 0; k < n; ++k) {
      Vec qp = q, qm = q, vp = v, vm = v, a(n), b(n);
      qp[k] += h;
      qm[k] -= h;
      vp[k] += h * 1e3;
      vm[k] -= h * 1e3;
      model->mass_product(qp, x, a);
      model->mass_product(qm, x, b);
      Jfd.col(k) = (a - b) / (2 * h);
      model->smooth_forces(0.0, qp, v, a);
      model->smooth_forces(0.0, qm, v, b);
      dqfd.col(k) = (a - b) / (2 * h);
      model->smooth_forces(0.0, q, vp, a);
      model->smooth_forces(0.0, q, vm, b);
      dvfd.col(k) = (a - b) / (2 * h * 1e3);
    }
    CHECK((J - Jfd).norm() <= 1e-6 * (1.0 + J.norm()));
    CHECK((dq - dqfd).norm() <= 1e-6 * dq.norm());
    CHECK((dv - dvfd).norm() <= 1e-6 * dv.norm());
    // the kinetic energy is 1/2 v^T M v (exact to round-off)
    CHECK(std::abs(model->kinetic_energy(0.0, q, v) - 0.5 * v.dot(M * v)) <=
          1e-13 * 0.5 * v.dot(M * v));
  }
}

TEST_CASE("Matrices model: the energy balance closes on a run with impacts, unbalance, weight",
          "[matrices][model]") {
  const CaseSpec c =
      load_case(kPaper, {"loads.unbalance=1e-4", "loads.gravity=9.81", "run.t_end=0.02"});
  const auto model = build_model(c);
  MemorySink s;
  EventDrivenOptions o;
  o.rtol = 1e-11;
  o.atol = 1e-13;
  const RunSummary r = run_event_driven(*model, initial_state(c), c.run.t_end, o, s);
  INFO(r.message);
  REQUIRE(r.complete());
  REQUIRE(r.events[static_cast<int>(EventKind::Impact)] >= 1);
  const double flows = std::max({std::abs(r.work_torque), std::abs(r.work_damping),
                                 std::abs(r.work_friction), std::abs(r.work_impacts)});
  // rtol 1e-11 on the integrated works: the residual within 1e-9 of the largest flow (the
  // contract test's bound for every model)
  CHECK(std::abs(r.energy_residual) <= 1e-9 * flows);
}

TEST_CASE("Matrices model: the paper's rotor written as matrices is the rigid-rotor model",
          "[matrices][model]") {
  const CaseSpec cm = load_case(kPaper), cr = load_case(kReference);
  const auto mm = build_model(cm), mr = build_model(cr);
  REQUIRE(mm->num_dofs() == mr->num_dofs());
  for (int i = 0; i < mm->num_dofs(); ++i)
    CHECK(mm->coordinates()[static_cast<std::size_t>(i)].name ==
          mr->coordinates()[static_cast<std::size_t>(i)].name);
  // the committed files are the rigid rotor's matrices (its linearisation, the stator's rows
  // and columns dropped) and its weight: computed by the same formulas, so equal to 1 ulp
  const LinearModel lm = *mr->linearize(Linearization::Free);
  const auto& r = cm.matrices.rotor;
  const auto close = [](const Mat& a, const Mat& b) {
    return (a - b).cwiseAbs().maxCoeff() <= 2.3e-16 * b.cwiseAbs().maxCoeff();
  };
  CHECK(close(r.M, lm.M.topLeftCorner(4, 4)));
  CHECK(close(r.G, lm.G.topLeftCorner(4, 4)));
  CHECK(close(r.C, lm.D.topLeftCorner(4, 4)));
  CHECK(close(r.K, lm.K.topLeftCorner(4, 4)));
  Vec f(7), z = Vec::Zero(7);
  mr->smooth_forces(0.0, z, z, f);
  CHECK(close(r.f0, f.head(4)));

  // runs through impacts, sliding and lift-offs (first contact at about 6 ms): 30 ms with the
  // event solver (both contact formulations) and Moreau-Jean
  struct Run {
    const char* name;
    bool fixed;
    ContactFormulation phases;
  };
  for (const Run& run : {Run{"event, reduced", false, ContactFormulation::Reduced},
                         Run{"event, projection", false, ContactFormulation::Projection},
                         Run{"mj", true, ContactFormulation::Reduced}}) {
    INFO(run.name);
    MemorySink a, b;
    RunSummary ra, rb;
    const double t_end = 0.03;
    if (run.fixed) {
      FixedStepOptions o;
      o.scheme = FixedStepScheme::MoreauJean;
      o.h = 1e-6;
      ra = run_fixed_step(*mm, initial_state(cm), t_end, o, a);
      rb = run_fixed_step(*mr, initial_state(cr), t_end, o, b);
    } else {
      EventDrivenOptions o;
      o.contact_phases = run.phases;
      ra = run_event_driven(*mm, initial_state(cm), t_end, o, a);
      rb = run_event_driven(*mr, initial_state(cr), t_end, o, b);
    }
    REQUIRE(ra.complete());
    REQUIRE(rb.complete());
    REQUIRE(ra.events == rb.events);
    REQUIRE(ra.events[static_cast<int>(EventKind::Impact)] >= 1);
    // the grid samples (k x 1e-4 s; an event's own rows fall at times that differ by the
    // events' time shifts), matched by time
    std::map<long, const Sample*> grid;
    for (const auto& x : b.samples) {
      const double k = x.t / 1e-4;
      if (std::abs(k - std::round(k)) < 1e-6) grid[std::lround(k)] = &x;
    }
    double dz = 0.0, dw = 0.0;
    int matched = 0;
    for (const auto& x : a.samples) {
      const double k = x.t / 1e-4;
      if (std::abs(k - std::round(k)) >= 1e-6) continue;
      const auto it = grid.find(std::lround(k));
      REQUIRE(it != grid.end());
      ++matched;
      dz = std::max(dz, (x.q.segment(2, 2) - it->second->q.segment(2, 2)).norm());
      dw = std::max(dw, std::abs(x.v[4] - it->second->v[4]) / std::abs(it->second->v[4]));
    }
    INFO("orbit " << dz << " m, omega " << dw << " relative, " << matched << " samples");
    CHECK(matched >= 300);
    // Not bitwise: M_full is solved by another order of operations (a Cholesky factor of M
    // and u = M^-1 b by it, against the rigid rotor's closed-form 2x2 inverses), so the states
    // differ by round-off, which the integrators' error control and the event times carry along
    // without growth on this window. 1e-12 m is 5e-9 of the clearance; omega 1e-9 relative
    // is the run's rtol.
    CHECK(dz <= 1e-12);
    CHECK(dw <= 1e-9);
  }
}

TEST_CASE("Matrices model with two contact nodes: the two-plane rigid rotor written as matrices",
          "[matrices][model][multi]") {
  // cases/two-plane.toml's rotor in the coordinates q' = (x_2, y_2, x_r, y_r), with
  // z_2 = (1 - s) z_b + s z_r the rotor's point in plane 2 (s = 0.2 / 0.4): a linear change of
  // coordinates q = T q' of the rigid rotor's linear rotor matrices (M' = T^T M T, and so C, K,
  // G, f0' = T^T f0), with contact node 1 at (x_r, y_r) and node 2 at (x_2, y_2), each with its
  // plane's ring and law. The Lagrangian is the same function of the motion, so every solver
  // must give the same motion: the node's coordinates are plane 2's interpolated point. Then
  // the same with plane 2's ring fixed: the contact phases in both models' minimal coordinates
  // (ring_chart.hpp), which solve the fixed ring's equations for different coordinates (x_b,
  // y_b in the rigid rotor; the node's own x_2, y_2 here).
  for (const bool fixed2 : {false, true}) {
    INFO((fixed2 ? "plane 2 on a fixed ring" : "sprung rings"));
    const CaseSpec cr =
        fixed2
            ? parse_case(rubdyn::testing::two_plane_fixed_rings_text(false, true), "two-plane.toml")
            : load_case(RUBDYN_SOURCE_DIR "/cases/two-plane.toml");
    const auto mr = build_model(cr);
    const LinearModel lm = *mr->linearize(Linearization::Free);
    const double l = cr.params.rotor.L - cr.params.rotor.delta;
    const double s = cr.params.planes[1].position / l;
    Mat T = Mat::Zero(4, 4);  // q = T q', q = (x_b, y_b, x_r, y_r), q' = (x_2, y_2, x_r, y_r)
    T(0, 0) = T(1, 1) = 1.0 / (1.0 - s);
    T(0, 2) = T(1, 3) = -s / (1.0 - s);
    T(2, 2) = T(3, 3) = 1.0;
    Vec f(mr->num_dofs()), z = Vec::Zero(mr->num_dofs());
    mr->smooth_forces(0.0, z, z, f);
    MatrixParams p;
    p.rotor.M = T.transpose() * lm.M.topLeftCorner(4, 4) * T;
    p.rotor.C = T.transpose() * lm.D.topLeftCorner(4, 4) * T;
    p.rotor.K = T.transpose() * lm.K.topLeftCorner(4, 4) * T;
    p.rotor.G = T.transpose() * lm.G.topLeftCorner(4, 4) * T;
    // symmetric and skew to the bit, as the case reader makes them (the model demands it)
    p.rotor.M = 0.5 * (p.rotor.M + p.rotor.M.transpose()).eval();
    p.rotor.K = 0.5 * (p.rotor.K + p.rotor.K.transpose()).eval();
    p.rotor.C = 0.5 * (p.rotor.C + p.rotor.C.transpose()).eval();
    p.rotor.G = 0.5 * (p.rotor.G - p.rotor.G.transpose()).eval();
    p.rotor.f0 = T.transpose() * f.head(4);
    p.rotor.Jp = cr.params.rotor.Jp;
    p.rotor.names = {"x_2", "y_2", "x_r", "y_r"};
    // the rotor's weight is f0; the rigid rotor does not weigh its rings (their supports carry
    // them), the matrices model weighs them by loads.gravity: 0 here
    p.loads = cr.params.loads;
    p.loads.gravity = 0.0;
    for (int k : {0, 1}) {
      const PlaneParams& pl = cr.params.planes[static_cast<std::size_t>(k)];
      MatrixNode nd;
      nd.at.x = k == 0 ? 2 : 0;
      nd.at.y = k == 0 ? 3 : 1;
      nd.at.radius = pl.radius;
      nd.at.gap = pl.gap;
      nd.law = pl.contact;
      nd.stator = {pl.rigid, pl.mass, pl.k, pl.c};
      p.nodes.push_back(nd);
    }
    const MatrixModel mm(p);
    REQUIRE(mm.contact_count() == 2);
    REQUIRE(mm.num_dofs() == mr->num_dofs());
    CHECK(mm.coordinates()[5].name == "x_s_1");
    if (!fixed2) CHECK(mm.coordinates()[8].name == "y_s_2");
    CHECK(mm.contact_chart() == nullptr);
    const MechanicalState sr = initial_state(cr);
    MechanicalState sm = sr;  // at rest, centred: the same state in both coordinates
    REQUIRE(sr.q.head(4).cwiseAbs().maxCoeff() == 0.0);
    for (const bool event : {true, false}) {
      INFO((event ? "event" : "mj"));
      MemorySink a, b;
      RunSummary ra, rb;
      const double t_end = 0.03;
      if (event) {
        EventDrivenOptions o;
        o.rtol = 1e-12;
        o.atol = 1e-15;
        ra = run_event_driven(mm, sm, t_end, o, a);
        rb = run_event_driven(*mr, sr, t_end, o, b);
      } else {
        FixedStepOptions o;
        o.scheme = FixedStepScheme::MoreauJean;
        o.h = 1e-6;
        ra = run_fixed_step(mm, sm, t_end, o, a);
        rb = run_fixed_step(*mr, sr, t_end, o, b);
      }
      REQUIRE(ra.complete());
      REQUIRE(rb.complete());
      // the same impacts, lift-offs and grazings; an arrival at |v_N| below the velocity
      // tolerance (kind contact: a touch the contact problem decides) is at the edge of the
      // tolerance, and round-off can make one (measured: the rigid rotor's event run at rtol
      // 1e-12 has one that the matrices run has not, with the motions 3.6e-14 m apart)
      for (int kind = 0; kind < kNumEventKinds; ++kind)
        if (kind != static_cast<int>(EventKind::Contact))
          CHECK(ra.events[static_cast<std::size_t>(kind)] ==
                rb.events[static_cast<std::size_t>(kind)]);
      CHECK(ra.events[static_cast<int>(EventKind::Impact)] >= 4);
      std::map<long, const Sample*> grid;
      for (const auto& x : b.samples) {
        const double k = x.t / 1e-4;
        if (std::abs(k - std::round(k)) < 1e-6) grid[std::lround(k)] = &x;
      }
      double dz = 0.0, d2 = 0.0, ds = 0.0, dF = 0.0, Fmax = 0.0;
      int matched = 0;
      for (const auto& x : a.samples) {
        const double k = x.t / 1e-4;
        if (std::abs(k - std::round(k)) >= 1e-6) continue;
        const auto it = grid.find(std::lround(k));
        if (it == grid.end()) continue;
        const Sample& y = *it->second;
        ++matched;
        dz = std::max(dz, (x.q.segment(2, 2) - y.q.segment(2, 2)).cwiseAbs().maxCoeff());
        const Vec2 z2 = (1.0 - s) * y.q.segment(0, 2) + s * y.q.segment(2, 2);
        d2 = std::max(d2, (x.q.segment(0, 2) - z2).cwiseAbs().maxCoeff());
        const Eigen::Index nr = x.q.size() - 5;  // the rings' coordinates
        ds = std::max(ds, (x.q.tail(nr) - y.q.tail(nr)).cwiseAbs().maxCoeff());
        for (int c : {0, 1}) {
          dF = std::max(dF, std::abs(x.contacts[static_cast<std::size_t>(c)].F_N -
                                     y.contacts[static_cast<std::size_t>(c)].F_N));
          Fmax = std::max(Fmax, y.contacts[static_cast<std::size_t>(c)].F_N);
        }
      }
      INFO("R " << dz << " m, plane 2 " << d2 << " m, rings " << ds << " m, F_N " << dF << " N of "
                << Fmax << ", " << matched << " samples");
      CHECK(matched >= 290);
      // Not bitwise: the matrices model solves M_full through its Cholesky factor, the rigid rotor
      // through closed-form 2x2 inverses, and the coordinates differ by T; round-off of the
      // states, carried by the error control and the event times. Measured (30 ms, gravity
      // through 9 impacts, sliding and lift-offs at both planes): the event solver at rtol 1e-12
      // 3.6e-14 m on R, 2.7e-14 m on plane 2, 2.8e-14 m on the rings, F_N 6.2e-7 N of 106 N
      // (at rtol 1e-10, 1.0e-11 m: the integration error, of the size of the self-convergence of
      // validation/planes, not a model difference); mj at h = 1e-6 below 1e-12 m. With plane 2's
      // ring fixed (each model's chart on its own coordinates): 1.4e-14 m on R, 1.6e-14 m on
      // plane 2, F_N 4.3e-7 N; mj 7e-17 m. The bounds:
      // 1e-12 m (5e-9 of the clearance) and 1e-6 of the largest F_N (forces are accelerations,
      // two derivatives less accurate than the positions).
      CHECK(dz <= 1e-12);
      CHECK(d2 <= 1e-12);
      CHECK(ds <= 1e-12);
      CHECK(dF <= 1e-6 * Fmax);
    }
  }
}

TEST_CASE("Case files with [[contact_node]] tables: read, overridden, written back, run",
          "[matrices][io][multi]") {
  const std::string path = RUBDYN_SOURCE_DIR "/cases/matrices-two-plane.toml";
  const CaseSpec c = load_case(path, {"contact_node.2.mu=0.3"});
  REQUIRE(c.matrices.nodes.size() == 2);
  CHECK(c.matrices.nodes[0].at.x == 2);
  CHECK(c.matrices.nodes[1].at.y == 1);
  CHECK(c.matrices.nodes[1].law.mu == 0.3);
  CHECK(c.matrices.nodes[1].stator.k == 4e6);
  // case.resolved.toml writes the nodes back as [[contact_node]] tables, read to the same case
  const std::string text = to_toml(c);
  CHECK(text.find("[[contact_node]]") != std::string::npos);
  const CaseSpec back = parse_case(text, path, {});
  REQUIRE(back.matrices.nodes.size() == 2);
  CHECK(back.matrices.nodes[1].law.mu == 0.3);
  CHECK(back.matrices.nodes[0].stator.mass == c.matrices.nodes[0].stator.mass);
  // an override cannot add a node
  try {
    load_case(path, {"contact_node.3.mu=0.3"});
    FAIL("a third node was accepted");
  } catch (const CaseError& e) {
    bool named = false;
    for (const auto& i : e.issues())
      named = named || (i.key == "contact_node.3" &&
                        i.rule.find("no such contact node") != std::string::npos);
    CHECK(named);
  }
  // the model from the case: the two-plane rigid rotor's motion (see the test above), here with
  // mj at h = 1e-6 over 20 ms through the case files (the matrices written by
  // scripts/make-paper-matrices.py with 17 digits)
  const CaseSpec cm = load_case(path), cr = load_case(RUBDYN_SOURCE_DIR "/cases/two-plane.toml");
  const auto mm = build_model(cm), mr = build_model(cr);
  REQUIRE(mm->contact_count() == 2);
  FixedStepOptions o;
  o.scheme = FixedStepScheme::MoreauJean;
  o.h = 1e-6;
  MemorySink a, b;
  REQUIRE(run_fixed_step(*mm, initial_state(cm), 0.02, o, a).complete());
  REQUIRE(run_fixed_step(*mr, initial_state(cr), 0.02, o, b).complete());
  REQUIRE(a.samples.size() == b.samples.size());
  double dz = 0.0;
  for (std::size_t i = 0; i < a.samples.size(); ++i)
    dz = std::max(
        dz, (a.samples[i].q.segment(2, 2) - b.samples[i].q.segment(2, 2)).cwiseAbs().maxCoeff());
  // the Campbell diagram of the paper (rings tied to their nodes, undamped) is the rigid
  // rotor's: the same eigenvalues of matrices similar by T. Measured 1.4e-15 of the largest
  // frequency (round-off of two eigen solves); 1e-10 bounds it. (The Free linearisation is not
  // compared: the free rotor pivots on B without stiffness at R, a zero-frequency pair whose
  // whirl labels are not determinate, and the two diagrams label them differently.)
  for (const auto mode : {Linearization::Tied}) {
    const auto dm = compute_campbell_diagram(*mm->linearize(mode), 2110.0, 11);
    const auto dr = compute_campbell_diagram(*mr->linearize(mode), 2110.0, 11);
    REQUIRE(dm.labels == dr.labels);
    double df = 0.0, fmax = 0.0;
    for (std::size_t l = 0; l < dm.labels.size(); ++l)
      for (std::size_t i = 0; i < dm.size(); ++i) {
        df = std::max(df, std::abs(dm.f[l][i] - dr.f[l][i]));
        fmax = std::max(fmax, dr.f[l][i]);
      }
    df /= fmax;
    INFO("Campbell " << (mode == Linearization::Tied ? "tied" : "free") << ": " << df);
    CHECK(df < 1e-10);
  }
  INFO("orbit at R " << dz << " m");
  // the files hold T^T M T and the others to 17 digits, one rounding from the test above's
  // matrices (measured there 1.2e-17 m with mj): 1e-12 m as there
  CHECK(dz <= 1e-12);
  CHECK(a.events.size() == b.events.size());
}

TEST_CASE("Matrices model: rotor.rotations marks q's rotations, their unit and error length",
          "[matrices][io]") {
  // four coordinates: the node's x, y (deflections, 2 kg each) and two rotations whose diagonal
  // masses 0.08 and 0.02 kg m^2 give the lengths of equal kinetic energy sqrt(0.08 / 2) = 0.2 m
  // and sqrt(0.02 / 2) = 0.1 m (the median of the deflections' masses: 2 kg)
  const fs::path d = scratch("rotations");
  const fs::path src = d / "case.toml";
  write(d / "M.csv", "2,0,0,0\n0,2,0,0\n0,0,0.08,0\n0,0,0,0.02\n");
  write(d / "C.csv", "1,0,0,0\n0,1,0,0\n0,0,0.01,0\n0,0,0,0.01\n");
  write(d / "K.csv", "1e6,0,0,0\n0,1e6,0,0\n0,0,1e4,0\n0,0,0,1e4\n");
  write(d / "G.csv", "0,0,0,0\n0,0,0,0\n0,0,0,0.05\n0,0,-0.05,0\n");
  const std::string names = "coordinates = \"x, y, tx, ty\"\n";
  const CaseSpec plain = parse_case(case_text(d, names), src.string());
  CHECK(plain.matrices.rotor.rotation.empty());
  const MatrixModel plain_model(plain.matrices);
  for (const auto& c : plain_model.coordinates()) {
    CHECK(c.length == 1.0);
    if (c.name != "theta") CHECK(c.unit == "m");
  }
  for (const std::string spec : {"t*", "tx, ty", "tx, t*"}) {
    INFO(spec);
    const CaseSpec c =
        parse_case(case_text(d, names + "rotations = \"" + spec + "\"\n"), src.string());
    REQUIRE(c.matrices.rotor.rotation == std::vector<bool>{false, false, true, true});
    const MatrixModel m(c.matrices);
    const auto& co = m.coordinates();
    CHECK(co[0].unit == "m");
    CHECK(co[0].length == 1.0);
    CHECK(co[2].unit == "rad");
    CHECK(co[3].unit == "rad");
    // (a square root of a ratio of decimals: a few ulps)
    CHECK(co[2].length == Approx(0.2).epsilon(1e-15));
    CHECK(co[3].length == Approx(0.1).epsilon(1e-15));
    CHECK(co[4].name == "theta");
    CHECK(co[4].length == 1.0);  // the spin angle stays weighted as before
    // the case's own coordinate list says the unit too, and case.resolved.toml keeps the key
    CHECK(initial_coordinates(c)[2].unit == "rad");
    const CaseSpec back = parse_case(to_toml(c), "/elsewhere/case.resolved.toml");
    CHECK(back.matrices.rotor.rotation == c.matrices.rotor.rotation);
  }
  // no rotation among q: the lengths stay 1; every coordinate a rotation: no deflection to
  // compare with, 1 too
  CHECK(rotation_lengths(Mat::Identity(3, 3) * 2.0, {false, false, false}) ==
        std::vector<double>{1.0, 1.0, 1.0});
  CHECK(rotation_lengths(Mat::Identity(2, 2) * 2.0, {true, true}) == std::vector<double>{1.0, 1.0});
  // bad values, each naming the key
  const struct {
    std::string value, says;
  } bad[] = {
      {"tz", "'tz' matches no coordinate of q (its coordinates: x, y, tx, ty)"},
      {"*", "'*' is neither a coordinate's name nor a prefix"},
      {"tx, ", "'' is neither"},
      {"x*", "must not name coordinate 0 ('x'): it is the contact node's seal circle centre"},
      {"ty, y", "must not name coordinate 1 ('y')"},
  };
  for (const auto& b : bad) {
    INFO(b.value);
    const auto is = refused(case_text(d, names + "rotations = \"" + b.value + "\"\n"), src);
    const CaseIssue* i = find_issue(is, "rotor.rotations");
    REQUIRE(i);
    CHECK_THAT(i->rule, Catch::Contains(b.says));
    CHECK(i->file == src.string());
    CHECK(i->line == 10);  // [model], kind, [rotor], M, C, K, G, Jp, coordinates, rotations
  }
  fs::remove_all(d);
}
