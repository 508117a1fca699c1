// Modal reduction of a matrices model ([reduction], model/matrix_reduction.hpp): the reduced
// model is the full Lagrangian restricted to q = T p (energies equal at every state, the
// gyroscopic matrix skew again, the contact coordinates physical), with every mode kept it is the
// full model in other coordinates (the same accelerations), and each bad input is refused naming
// its key and rule (exit 2 through the CLI: validation/fe/test_fe_rotor.py).
#include <Eigen/Eigenvalues>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/model/matrix_model.hpp"
#include "rubdyn/model/matrix_reduction.hpp"

using namespace rubdyn;
namespace fs = std::filesystem;

namespace {

const std::string kRunup = RUBDYN_SOURCE_DIR "/cases/fe-runup.toml";
const std::string kTwoSeal = RUBDYN_SOURCE_DIR "/cases/fe-two-seal.toml";

/// "reduction.<key>" (appended: g++ 12 warns falsely on "..." + string, -Wrestrict)
std::string set(const std::string& key, const std::string& value) {
  std::string s = "reduction.";
  s.append(key).append("=").append(value);
  return s;
}

CaseSpec reduced_case(const std::string& path, const std::string& method, const std::string& key,
                      const std::string& value) {
  return load_case(path, {set("method", method), set(key, value)});
}

/// The issues of a case that must be refused.
std::vector<CaseIssue> refused(const std::string& path, const std::vector<std::string>& sets) {
  try {
    load_case(path, sets);
  } catch (const CaseError& e) {
    return e.issues();
  }
  FAIL("the case was accepted");
  return {};
}

Vec random_vec(std::mt19937& g, Eigen::Index n, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec v(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = scale * u(g);
  return v;
}

/// The full model's state (q = T p, q' = T p', the rest copied) of a reduced model's state.
void lift(const ReducedMatrices& red, int n_full, VecIn x, Vec& full) {
  const Eigen::Index m = red.T.cols(), rest = x.size() - m;
  full.resize(n_full + rest);
  full.head(n_full) = red.T * x.head(m);
  full.tail(rest) = x.tail(rest);
}

}  // namespace

TEST_CASE("Reduction: the reduced model is the full Lagrangian on q = T p",
          "[matrices][reduction]") {
  // For any basis T (kept modes or not), T_r(p, p', theta') = T(T p, T p', theta') and
  // V_r(p) = V(T p), since M_r = T^T M T, G_r = T^T G T, K_r = T^T K T, f0_r = T^T f0 and the
  // contact coordinates (unbalance, rings) are rows of T that are unit rows: the energies of
  // random states agree to round-off (2.3e-15 relative measured at most; 1e-13 allowed: sums of
  // 22-52 products of entries spanning 1e-6 to 1e9, in another order).
  std::mt19937 g(7);
  for (const auto& [path, method, key, value] :
       {std::tuple<std::string, std::string, std::string, std::string>{kRunup, "craig-bampton",
                                                                       "modes", "20"},
        {kRunup, "modal", "modes", "20"},
        {kRunup, "craig-bampton", "cutoff", "1000"},
        {kTwoSeal, "craig-bampton", "modes", "12"},
        {kTwoSeal, "modal", "cutoff", "2000"}}) {
    INFO(path << " " << method << " " << key << " " << value);
    const CaseSpec full_case = load_case(path, {"loads.unbalance_phase=0.3"});
    const CaseSpec red_case =
        load_case(path, {set("method", method), set(key, value), "loads.unbalance_phase=0.3"});
    REQUIRE(red_case.reduced);
    const ReducedMatrices& red = *red_case.reduced;
    const int n = full_case.matrices.rotor.size();
    const auto full = build_model(full_case);
    const auto model = build_model(red_case);
    const MatrixParams rp = matrix_model_params(red_case);
    const int m = rp.rotor.size();
    CHECK(m == red.T.cols());
    CHECK(m < n);
    // G_r skew to the bit, M_r, K_r, C_r symmetric to the bit (the model demands K and G)
    CHECK(rp.rotor.G == -rp.rotor.G.transpose());
    CHECK(rp.rotor.K == rp.rotor.K.transpose());
    // the contact nodes' coordinates are physical: unit rows of T, named as in the full model
    for (std::size_t k = 0; k < rp.node_list().size(); ++k) {
      const MatrixNode a = full_case.matrices.node_list()[k];
      const MatrixNode b = rp.node_list()[k];
      for (const auto& [i, j] : {std::pair{a.at.x, b.at.x}, std::pair{a.at.y, b.at.y}}) {
        CHECK(red.T.row(i) == Vec::Unit(m, j).transpose());
        CHECK(rp.rotor.names[static_cast<std::size_t>(j)] ==
              full_case.matrices.rotor.names[static_cast<std::size_t>(i)]);
      }
    }
    const int N = model->num_dofs();
    Vec qf, vf;
    for (int trial = 0; trial < 5; ++trial) {
      Vec q = random_vec(g, N, 1e-4), v = random_vec(g, N, 1e-2);
      if (model->spin_coordinate() >= 0) v[model->spin_coordinate()] = 200.0 + 50.0 * trial;
      lift(red, n, q, qf);
      lift(red, n, v, vf);
      const double t = 0.05;
      const double T = full->kinetic_energy(t, qf, vf), Tr = model->kinetic_energy(t, q, v);
      const double V = full->potential_energy(t, qf), Vr = model->potential_energy(t, q);
      CHECK(std::abs(Tr - T) <= 1e-13 * std::abs(T));
      CHECK(std::abs(Vr - V) <= 1e-13 * std::max(std::abs(V), 1e-300));
    }
  }
}

TEST_CASE("Reduction: with every mode kept the reduced model is the full one in other coordinates",
          "[matrices][reduction]") {
  // T is then square and invertible: the accelerations of the reduced model at (p, p') are the
  // full model's at (T p, T p') mapped back, q'' = T p'' (measured 4.5e-16 of the largest; 1e-12
  // allowed: two structured solves in other coordinates), and the frequencies at rest are the
  // same (3.8e-11 relative measured over all of them, the generalised eigensolver's accuracy on
  // the lowest of a spread of 1e6 in w^2; 1e-9 allowed).
  std::mt19937 g(11);
  for (const auto& [method, modes] :
       {std::pair<std::string, int>{"craig-bampton", 50}, {"modal", 52}}) {
    INFO(method);
    const CaseSpec full_case = load_case(kRunup, {"solver.method=bdf"});
    const CaseSpec red_case = reduced_case(kRunup, method, "modes", std::to_string(modes));
    const ReducedMatrices& red = *red_case.reduced;
    const int n = full_case.matrices.rotor.size();
    REQUIRE(red.T.rows() == n);
    REQUIRE(red.T.cols() == n);
    const auto full = build_model(full_case);
    const auto model = build_model(red_case);
    const int N = model->num_dofs();  // (the prescribed spin: no theta among them)
    Vec f(N), ff(full->num_dofs()), qf, vf, a(N), af(full->num_dofs());
    for (int trial = 0; trial < 3; ++trial) {
      const Vec q = random_vec(g, N, 1e-4), v = random_vec(g, N, 1e-2);
      lift(red, n, q, qf);
      lift(red, n, v, vf);
      const double t = 0.01 * trial;
      model->smooth_forces(t, q, v, f);
      full->smooth_forces(t, qf, vf, ff);
      Mat B = f, Bf = ff;
      model->solve_mass(q, B);
      full->solve_mass(qf, Bf);
      a = B.col(0);
      af = Bf.col(0);
      Vec lifted;
      lift(red, n, a, lifted);
      const double scale = af.cwiseAbs().maxCoeff();
      CHECK((lifted - af).cwiseAbs().maxCoeff() <= 1e-12 * scale);
    }
    // the frequencies at rest
    const MatrixParams rp = matrix_model_params(red_case);
    Eigen::GeneralizedSelfAdjointEigenSolver<Mat> a_full(
        full_case.matrices.rotor.K, full_case.matrices.rotor.M, Eigen::EigenvaluesOnly);
    Eigen::GeneralizedSelfAdjointEigenSolver<Mat> a_red(rp.rotor.K, rp.rotor.M,
                                                        Eigen::EigenvaluesOnly);
    for (int k = 0; k < n; k += 7)
      CHECK(std::abs(a_red.eigenvalues()[k] / a_full.eigenvalues()[k] - 1.0) <= 1e-9);
  }
}

TEST_CASE("Reduction: bad input is refused naming the key and the rule", "[matrices][reduction]") {
  struct Bad {
    std::vector<std::string> sets;
    std::string key, says;
  };
  const std::vector<Bad> bad = {
      // modes > what there is: n - 2K for Craig-Bampton, n for modal
      {{"reduction.method=craig-bampton", "reduction.modes=52"},
       "reduction.modes",
       "must be at most n - 2K = 50"},
      {{"reduction.method=modal", "reduction.modes=54"}, "reduction.modes", "at most n = 52"},
      // one of an isotropic pair
      {{"reduction.method=modal", "reduction.modes=21"}, "reduction.modes", "must be even"},
      // a cut-off below the first mode: fixed-interface 133.07 Hz, free 35.00 Hz
      {{"reduction.method=craig-bampton", "reduction.cutoff=130"},
       "reduction.cutoff",
       "below the first fixed-interface mode (133.068 Hz)"},
      {{"reduction.method=modal", "reduction.cutoff=30"},
       "reduction.cutoff",
       "below the first free mode (35.0046 Hz)"},
      // neither, both, negative
      {{"reduction.method=modal"}, "reduction.modes", "must be >= 1, or reduction.cutoff"},
      {{"reduction.method=modal", "reduction.modes=4", "reduction.cutoff=100"},
       "reduction.cutoff",
       "not both"},
      {{"reduction.method=modal", "reduction.modes=-2"}, "reduction.modes", "must be >= 1"},
      // modes without a method, an unknown method
      {{"reduction.modes=4"}, "reduction.modes", "read only with reduction.method"},
      {{"reduction.method=guyan"}, "reduction.method", "must be one of"},
  };
  for (const Bad& b : bad) {
    INFO(b.sets.back());
    const auto is = refused(kRunup, b.sets);
    const auto it =
        std::find_if(is.begin(), is.end(), [&](const CaseIssue& i) { return i.key == b.key; });
    REQUIRE(it != is.end());
    CHECK_THAT(it->rule, Catch::Contains(b.says));
    CHECK(it->file == "--set");
  }
  // a [reduction] section in a case of another model
  const auto is = refused(RUBDYN_SOURCE_DIR "/cases/reference.toml", {"reduction.method=modal"});
  REQUIRE(!is.empty());
  CHECK_THAT(is.front().rule, Catch::Contains("not a section of model 'rigid-rotor'"));
}

TEST_CASE("Reduction: a contact node the kept modes do not move, a rotor not held by its nodes",
          "[matrices][reduction]") {
  // Three nodes (x, y each): node 0 on a soft spring, node 1 (the seal) on a stiff one, node 2
  // between; uncoupled, so the lowest free mode (node 0's, 1 rad/s) does not move the seal at all
  // and a modal basis of it would eliminate the contact node. With the seal held, node 2 has no
  // spring at all when k2 = 0: no fixed-interface modes (Craig-Bampton refused).
  std::random_device rd;
  const fs::path d =
      fs::temp_directory_path() / std::string("rubdyn-reduction-").append(std::to_string(rd()));
  fs::create_directories(d);
  const auto put = [&d](const char* name, const std::string& text) {
    std::ofstream(d / name) << text;
  };
  const auto diag = [](std::initializer_list<double> xs) {
    std::string s;
    const int n = static_cast<int>(xs.size());
    int i = 0;
    for (double x : xs) {
      for (int j = 0; j < n; ++j) {
        if (j) s.append(",");
        s.append(std::to_string(j == i ? x : 0.0));
      }
      s += "\n";
      ++i;
    }
    return s;
  };
  put("M.csv", diag({1, 1, 1, 1, 1, 1}));
  put("C.csv", diag({0, 0, 0, 0, 0, 0}));
  put("G.csv", diag({0, 0, 0, 0, 0, 0}));
  const std::string text =
      "[model]\nkind = \"matrices\"\n[rotor]\nM = \"M.csv\"\nC = \"C.csv\"\nK = \"K.csv\"\n"
      "G = \"G.csv\"\nJp = 0.06\n[contact_node]\nx = 2\ny = 3\nradius = 0.05\ngap = 2e-4\n"
      "[stator]\nmass = 2.0\nk = 2e6\nc = 100.0\n[contact]\nmu = 0.1\n[loads]\ngravity = 0.0\n"
      "torque = 1.0\n[run]\nt_end = 0.01\nomega_lim = 2000.0\n[reduction]\n";
  const fs::path src = d / "case.toml";
  const auto issues = [&](const std::string& red) {
    try {
      parse_case(text + red, src.string());
    } catch (const CaseError& e) {
      return e.issues();
    }
    return std::vector<CaseIssue>{};
  };
  put("K.csv", diag({1, 1, 100, 100, 4, 4}));
  {
    const auto is = issues("method = \"modal\"\nmodes = 2\n");
    REQUIRE(is.size() == 1);
    CHECK(is[0].key == "reduction.modes");
    CHECK(is[0].line == 28);
    CHECK_THAT(is[0].rule, Catch::Contains("would eliminate a contact node"));
    // with node 2's mode too the seal still does not move; with the seal's own mode it does
    CHECK(issues("method = \"modal\"\nmodes = 4\n").size() == 1);
    CHECK(issues("method = \"modal\"\nmodes = 6\n").empty());
    // fewer modes than the contact coordinates (an anisotropic rotor: one mode is one
    // coordinate, against the node's two)
    put("K.csv", diag({1, 2, 1.5, 3, 4, 5}));
    CHECK_THAT(issues("method = \"modal\"\nmodes = 1\n").at(0).rule,
               Catch::Contains("a modal basis needs at least as many modes (2)"));
  }
  put("K.csv", diag({1, 1, 100, 100, 0, 0}));
  {
    const auto is = issues("method = \"craig-bampton\"\nmodes = 2\n");
    REQUIRE(is.size() == 1);
    CHECK(is[0].key == "reduction.method");
    CHECK_THAT(is[0].rule, Catch::Contains("not positive definite on the others"));
  }
  fs::remove_all(d);
}
