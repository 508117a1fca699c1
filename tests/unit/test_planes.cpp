// The rigid rotor with several rub planes ([[plane]] tables; rotor_stator_model.hpp,
// docs/models.md section 6): its structure against its own definition (M, the structured solve
// and product, the contact Jacobians and rates by finite differences, the energy balance of free
// flight), one [[plane]] at R against the paper's model (the same numbers), and the case file's
// rules, each with the key, line and reason it names.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <random>
#include <string>

#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/model/rotor_stator_model.hpp"

using namespace rubdyn;

namespace {

std::string reference_text() {
  std::ifstream f(RUBDYN_SOURCE_DIR "/cases/reference.toml");
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

/// cases/reference.toml with its seal, ring and law written as one [[plane]] (or the tables
/// given instead of it).
std::string planes_text(const std::string& planes = "") {
  std::string s = reference_text();
  const auto erase_line = [&](const std::string& start) {
    const auto i = s.find(start);
    REQUIRE(i != std::string::npos);
    s.erase(i, s.find('\n', i) + 1 - i);
  };
  erase_line("radius = 0.05");
  const auto a = s.find("[stator]"), b = s.find("[loads]");
  s.replace(a, b - a,
            planes.empty() ? "[[plane]]\nposition = 0.4\nradius = 0.05\ngap = 2e-4\nmu = 0.1\n"
                             "stator_mass = 2.0\nstator_k = 2e6\nstator_c = 100.0\n\n"
                           : planes);
  if (!planes.empty()) {
    // several planes run with Moreau-Jean here (a fixed-step case)
    erase_line("rtol = ");
    erase_line("atol = ");
    const auto k = s.find("kind = \"event\"");
    REQUIRE(k != std::string::npos);
    s.replace(k, std::string("kind = \"event\"").size(), "kind = \"mj\"\nh = 1e-6");
  }
  return s;
}

const char* kTwo =
    "[[plane]]\nposition = 0.4\nradius = 0.05\ngap = 2e-4\nmu = 0.1\nstator_mass = 2.0\n"
    "stator_k = 2e6\nstator_c = 100.0\n\n"
    "[[plane]]\nposition = 0.2\nradius = 0.025\ngap = 1e-4\nmu = 0.3\ne_n = 0.2\n"
    "stator_mass = 1.0\nstator_k = 4e6\nstator_c = 50.0\n\n"
    "[[plane]]\nposition = 0.47\nradius = 0.03\ngap = 3e-4\nmu = 0.2\nstator_rigid = true\n\n";

/// The issues of a case text that must fail; each must name `key` and contain `says`.
void refused(const std::string& text, const std::string& key, const std::string& says,
             const std::vector<std::string>& overrides = {}) {
  try {
    parse_case(text, "case.toml", overrides);
  } catch (const CaseError& e) {
    for (const auto& i : e.issues())
      if (i.key == key && i.rule.find(says) != std::string::npos) {
        // the line of the file (a key of the file) or --set (an override)
        CHECK((i.line > 0 || i.file == "--set" || key == "plane"));
        return;
      }
    FAIL("no issue on " << key << " saying '" << says << "': " << e.what());
  }
  FAIL("accepted: expected an issue on " << key);
}

Vec random_vec(std::mt19937& rng, int n, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec x(n);
  for (int i = 0; i < n; ++i) x[i] = scale * u(rng);
  return x;
}

}  // namespace

TEST_CASE("Planes: one [[plane]] at R is the paper's model, the same numbers", "[unit][planes]") {
  const CaseSpec a = parse_case(reference_text(), "reference.toml");
  const CaseSpec b = parse_case(planes_text(), "one-plane.toml");
  const auto ma = build_model(a), mb = build_model(b);
  REQUIRE(ma->num_dofs() == 7);
  REQUIRE(mb->num_dofs() == 7);
  REQUIRE(mb->contact_count() == 1);
  REQUIRE(mb->contact_chart() != nullptr);  // the same model: its chart applies
  CHECK(mb->coordinates()[5].name == "x_s_1");
  std::mt19937 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    const Vec q = random_vec(rng, 7, 2e-4), v = random_vec(rng, 7, 0.5);
    Mat A(7, 7), B(7, 7);
    ma->mass_matrix(q, A);
    mb->mass_matrix(q, B);
    CHECK(A == B);
    Vec fa(7), fb(7);
    ma->smooth_forces(0.0, q, v, fa);
    mb->smooth_forces(0.0, q, v, fb);
    CHECK(fa == fb);
    const ContactKinematics ca = ma->contact(0, 0.0, q, v), cb = mb->contact(0, 0.0, q, v);
    CHECK(ca.d_N == cb.d_N);
    CHECK(ca.W_N == cb.W_N);
    CHECK(ca.W_T == cb.W_T);
    CHECK(ca.v_t == cb.v_t);
    CHECK(ca.wdot_N == cb.wdot_N);
    CHECK(ma->mechanical_energy(0.0, q, v) == mb->mechanical_energy(0.0, q, v));
  }
  const auto la = ma->linearize(Linearization::Tied), lb = mb->linearize(Linearization::Tied);
  REQUIRE(la);
  REQUIRE(lb);
  CHECK(la->M == lb->M);
  CHECK(la->K == lb->K);
}

TEST_CASE("Planes: three planes (two sprung rings, one fixed): M, solves, contacts, energy",
          "[unit][planes]") {
  const CaseSpec c = parse_case(planes_text(kTwo), "three.toml");
  const auto m = build_model(c);
  const int n = m->num_dofs();
  REQUIRE(n == 9);  // 5 rotor dofs, two sprung rings
  REQUIRE(m->contact_count() == 3);
  REQUIRE(m->contact_chart() == nullptr);
  CHECK(m->contact_law(1).mu == 0.3);
  CHECK(m->contact_law(1).e_n == 0.2);
  CHECK(m->gap_scale(2) == 3e-4);
  CHECK(m->contact_radius(1) == 0.025);
  std::mt19937 rng(11);
  for (int trial = 0; trial < 30; ++trial) {
    const Vec q = random_vec(rng, n, 2e-4), v = random_vec(rng, n, 0.5);
    Mat M(n, n);
    m->mass_matrix(q, M);
    CHECK((M - M.transpose()).norm() == 0.0);
    // the structured solve and product against the dense M: entries of M are O(1-10) kg, its
    // condition about 1e2: 1e-12 is 1e4 eps times that
    Mat X = Mat::Identity(n, n);
    m->solve_mass(q, X);
    CHECK((M * X - Mat::Identity(n, n)).cwiseAbs().maxCoeff() < 1e-12);
    Vec y(n);
    m->mass_product(q, v, y);
    CHECK((y - M * v).cwiseAbs().maxCoeff() < 1e-14);
    CHECK(m->kinetic_energy(0.0, q, v) == Approx(0.5 * v.dot(M * v)).epsilon(1e-14));
    for (int k = 0; k < 3; ++k) {
      const ContactKinematics ck = m->contact(k, 0.0, q, v);
      // W_N = grad d_N: central differences of a smooth function of O(1e-4) m positions with
      // h = 1e-9 m: truncation O(h^2 / |sr|) ~ 1e-14, round-off eps g0 / h ~ 1e-11
      const double h = 1e-9;
      for (int i = 0; i < n; ++i) {
        Vec qp = q, qm = q;
        qp[i] += h;
        qm[i] -= h;
        const double dd = (m->contact(k, 0.0, qp, v).d_N - m->contact(k, 0.0, qm, v).d_N) / (2 * h);
        CHECK(dd == Approx(ck.W_N[i]).margin(1e-6));
      }
      CHECK(ck.v_N == Approx(ck.W_N.dot(v)).margin(1e-15));
      CHECK(ck.v_t == Approx(ck.W_T.dot(v)).margin(1e-15));
      // wdot = d(W^T v)/dt at fixed v: same difference along q' = v, h in time 1e-9 s
      const Vec qp = q + h * v, qm = q - h * v;
      const ContactKinematics cp = m->contact(k, 0.0, qp, v), cm = m->contact(k, 0.0, qm, v);
      const double scale = v.squaredNorm() / 1e-4;  // |v|^2 / |sr|: the rates' scale
      CHECK((cp.W_N.dot(v) - cm.W_N.dot(v)) / (2 * h) == Approx(ck.wdot_N).margin(1e-5 * scale));
      CHECK((cp.W_T.dot(v) - cm.W_T.dot(v)) / (2 * h) == Approx(ck.wdot_T).margin(1e-5 * scale));
      // the plane's centres: d_N = g0 - |rotor point - ring centre|
      PlaneMotion pm;
      REQUIRE(m->plane_motion(k, 0.0, q, v, pm));
      CHECK(m->gap_scale(k) - (pm.rotor - pm.stator).norm() == Approx(ck.d_N).margin(1e-18));
    }
    // free flight's energy balance: d(T + V)/dt = drive + dampers along a = M^-1 f, by a
    // central difference in time (h = 1e-7 s: O(h^2) truncation on rates of O(1e4) W)
    Vec f(n);
    m->smooth_forces(0.0, q, v, f);
    Mat a = f;
    m->solve_mass(q, a);
    const double ht = 1e-7;
    const Vec q1 = q + ht * v + 0.5 * ht * ht * a.col(0),
              q0 = q - ht * v + 0.5 * ht * ht * a.col(0);
    const Vec v1 = v + ht * a.col(0), v0 = v - ht * a.col(0);
    const double dE =
        (m->mechanical_energy(0.0, q1, v1) - m->mechanical_energy(0.0, q0, v0)) / (2 * ht);
    const SmoothPower P = m->smooth_power(0.0, q, v);
    CHECK(dE == Approx(P.external + P.damping).margin(1e-6 * (std::abs(P.external) + 1.0)));
  }
  // the fixed ring gives no Tied linearisation, the Free one has every sprung ring
  CHECK_FALSE(m->linearize(Linearization::Tied));
  const auto free = m->linearize(Linearization::Free);
  REQUIRE(free);
  CHECK(free->size() == 8);
  CHECK(free->nodes.size() == 4);
}

TEST_CASE("Planes: case.resolved.toml writes [[plane]] back, and reads back the same",
          "[unit][planes]") {
  const CaseSpec c = parse_case(planes_text(kTwo), "three.toml");
  const std::string text = to_toml(c);
  CHECK(text.find("[[plane]]") != std::string::npos);
  CHECK(text.find("[stator]") == std::string::npos);
  CHECK(text.find("[contact]") == std::string::npos);
  const CaseSpec d = parse_case(text, "resolved.toml");
  REQUIRE(d.params.planes.size() == 3);
  for (std::size_t k = 0; k < 3; ++k) {
    CHECK(d.params.planes[k].position == c.params.planes[k].position);
    CHECK(d.params.planes[k].contact.mu == c.params.planes[k].contact.mu);
    CHECK(d.params.planes[k].rigid == c.params.planes[k].rigid);
    CHECK(d.params.planes[k].k == c.params.planes[k].k);
  }
  // an override of one plane's key
  const CaseSpec e = parse_case(planes_text(kTwo), "three.toml", {"plane.2.mu=0.45"});
  CHECK(e.params.planes[1].contact.mu == 0.45);
  CHECK(e.params.planes[0].contact.mu == 0.1);
}

TEST_CASE("Planes: every rule of [[plane]] names its key", "[unit][planes]") {
  const std::string two = kTwo;
  // the single plane's keys, with where they now live
  std::string t = planes_text(two);
  t.insert(t.find("d      = 0.3"), "radius = 0.05\n");
  refused(t, "rotor.radius", "each plane has its own seal radius");
  t = planes_text(two + "[stator]\nmass = 2.0\n\n");
  refused(t, "stator.mass", "each plane has its own ring");
  t = planes_text(two + "[contact]\nmu = 0.2\n\n");
  refused(t, "contact.mu", "each plane has its own law");
  // the planes' own keys
  auto one = [](const std::string& body) { return planes_text("[[plane]]\n" + body + "\n"); };
  const std::string ring = "stator_mass = 2.0\nstator_k = 2e6\nstator_c = 100.0\n";
  refused(one("position = 0.6\nradius = 0.05\ngap = 2e-4\nmu = 0.1\n" + ring), "plane.1.position",
          "must lie in (0, L]");
  refused(one("position = 0\nradius = 0.05\ngap = 2e-4\nmu = 0.1\n" + ring), "plane.1.position",
          "must lie in (0, L]");
  refused(one("position = 0.4\nradius = -1\ngap = 2e-4\nmu = 0.1\n" + ring), "plane.1.radius",
          "must be > 0");
  refused(one("position = 0.4\nradius = 0.05\ngap = 0\nmu = 0.1\n" + ring), "plane.1.gap",
          "must be > 0");
  refused(one("position = 0.4\nradius = 0.05\ngap = 2e-4\nmu = -0.1\n" + ring), "plane.1.mu",
          "must be >= 0");
  refused(one("position = 0.4\nradius = 0.05\ngap = 2e-4\nmu = 0.1\ne_n = 1.5\n" + ring),
          "plane.1.e_n", "must lie in [0, 1]");
  refused(one("position = 0.4\nradius = 0.05\ngap = 2e-4\nmu = 0.1\nstator_mass = 0\n"
              "stator_k = 2e6\nstator_c = 1"),
          "plane.1.stator_mass", "must be > 0");
  refused(one("position = 0.4\nradius = 0.05\ngap = 2e-4\nmu = 0.1\nstator_rigid = true\n"
              "stator_k = 2e6"),
          "plane.1.stator_k", "a rigid ring");
  refused(one("position = 0.4\nradius = 0.05\ngap = 2e-4\nmu = 0.1\n"), "plane.1.stator_mass",
          "required key is missing");
  refused(one("position = 0.4\nradius = 0.05\ngap = 2e-4\n" + ring), "plane.1.mu",
          "required key is missing");
  refused(one("position = 0.4\nradius = 0.05\ngap = 2e-4\nmu = 0.1\nwidth = 3\n" + ring),
          "plane.1.width", "unknown key");
  // the array itself
  refused(planes_text("[plane]\nposition = 0.4\n\n"), "plane", "must be an array of tables");
  std::string nine;
  for (int k = 0; k < 9; ++k)
    nine += "[[plane]]\nposition = 0.4\nradius = 0.05\ngap = 2e-4\nmu = 0.1\nstator_rigid = true\n";
  refused(planes_text(nine), "plane", "at most 8 planes");
  refused(planes_text(two), "plane.4", "no such plane", {"plane.4.mu=0.2"});
  // [[plane]] belongs to the rigid rotor
  std::ifstream f(RUBDYN_SOURCE_DIR "/cases/jeffcott.toml");
  std::string jef{std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
  refused(jef + "\n[[plane]]\nposition = 0.4\n", "plane", "rigid-rotor");
}

TEST_CASE("Planes: the two-plane case file is valid and has the documented coordinates",
          "[unit][planes]") {
  const CaseSpec c = load_case(RUBDYN_SOURCE_DIR "/cases/two-plane.toml");
  const auto m = build_model(c);
  REQUIRE(m->contact_count() == 2);
  std::string names;
  for (const auto& x : m->coordinates()) names += x.name + " ";
  CHECK(names == "x_b y_b x_r y_r theta x_s_1 y_s_1 x_s_2 y_s_2 ");
}
