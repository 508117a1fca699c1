// The model registry in case files ([model] kind) and the Jeffcott-Black model: model-aware
// validation messages, round trips of case.resolved.toml, the documentation of every key, and
// the Jeffcott model's structured operations against dense or finite-difference ones. (Its
// equations against an independent formulation: python/tests/test_models.py.)
#include <Eigen/Cholesky>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

#include "rubdyn/hybrid/event_driven.hpp"
#include "rubdyn/io/case_error.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/model/jeffcott_model.hpp"
#include "rubdyn/stepping/fixed_step.hpp"

using namespace rubdyn;

namespace {

const char* kJeffcott = R"(
[model]
kind = "jeffcott"
[rotor]
mass = 5.0
k = 5.0e6
c = 300.0
radius = 0.05
Jp = 0.06
[stator]
mass = 2.0
k = 2.0e7
c = 2500.0
gap = 2.0e-4
[contact]
mu = 0.1
[loads]
gravity = 9.81
torque = 20.0
[run]
t_end = 0.01
omega_lim = 2000.0
)";

/// kJeffcott with a rigid stator (its mass, spring and damper removed).
std::string rigid_jeffcott() {
  const std::string t = kJeffcott;
  return t.substr(0, t.find("[stator]")) + "[stator]\nrigid = true\ngap = 2.0e-4\n" +
         t.substr(t.find("[contact]"));
}

/// The issues of a case that must be refused (fails the test if it is accepted).
std::vector<CaseIssue> issues_of(const std::string& text, const std::vector<std::string>& sets) {
  try {
    parse_case(text, "case.toml", sets);
  } catch (const CaseError& e) {
    return e.issues();
  }
  FAIL("the case was accepted");
  return {};
}

bool has_issue(const std::vector<CaseIssue>& issues, const std::string& key,
               const std::string& words) {
  for (const auto& i : issues)
    if (i.key == key && i.rule.find(words) != std::string::npos) return true;
  return false;
}

std::string read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST_CASE("A Jeffcott case: its keys, its coordinates, its model", "[models][io]") {
  const CaseSpec c = parse_case(kJeffcott, "j.toml");
  CHECK(c.model == "jeffcott");
  CHECK(c.jeffcott.rotor.k == 5e6);
  CHECK(c.jeffcott.stator.c == 2500.0);
  CHECK(c.initial.q0.size() == 5);
  const auto model = build_model(c);
  CHECK(model->num_dofs() == 5);
  CHECK(model->name() == "jeffcott");
  // a rigid stator: three coordinates
  const CaseSpec r = parse_case(rigid_jeffcott(), "j.toml");
  CHECK(r.initial.q0.size() == 3);
  CHECK(build_model(r)->num_dofs() == 3);
  CHECK(initial_coordinates(r).back().name == "theta");
}

TEST_CASE("Keys of another model and keys the settings leave unread are refused, by name",
          "[models][io]") {
  // a rigid stator with its mass, spring and damper: three issues naming the rule and the line
  auto is = issues_of(kJeffcott, {"stator.rigid=true"});
  CHECK(has_issue(is, "stator.mass", "rigid stator"));
  CHECK(has_issue(is, "stator.k", "rigid stator"));
  CHECK(has_issue(is, "stator.c", "rigid stator"));
  for (const auto& i : is)
    if (i.key == "stator.mass") CHECK(i.line == 11);  // (the text opens with a line end)
  // a section of the rigid rotor in a Jeffcott case
  is = issues_of(std::string(kJeffcott) + "[bearing]\nk = 5e6\n", {});
  CHECK(has_issue(is, "bearing", "not a section of model 'jeffcott'"));
  CHECK(has_issue(is, "bearing", "'rigid-rotor'"));
  // a key of the rigid rotor in a Jeffcott case, and of the Jeffcott rotor in a rigid-rotor one
  is = issues_of(kJeffcott, {"rotor.Jd=0.035"});
  CHECK(has_issue(is, "rotor.Jd", "not a key of model 'jeffcott'"));
  is = issues_of(read(RUBDYN_SOURCE_DIR "/cases/reference.toml"), {"rotor.k=5e6"});
  CHECK(has_issue(is, "rotor.k", "not a key of model 'rigid-rotor'"));
  // an unknown kind, with a suggestion
  is = issues_of(kJeffcott, {"model.kind=jefcott"});
  CHECK(has_issue(is, "model.kind", "did you mean 'jeffcott'"));
  // a coordinate the model does not have
  is = issues_of(kJeffcott, {"stator.rigid=true", "initial.x_s=1e-5"});
  CHECK(has_issue(is, "initial.x_s", "not a coordinate"));
  is = issues_of(kJeffcott, {"initial.x_b=1e-5"});
  CHECK(has_issue(is, "initial.x_b", "not a key of model 'jeffcott'"));
  // loads the settings leave unread
  is = issues_of(kJeffcott, {"loads.spin_accel=10"});
  CHECK(has_issue(is, "loads.spin_accel", "prescribed"));
  is = issues_of(kJeffcott, {"loads.torque_free_speed=300"});
  CHECK(has_issue(is, "loads.torque_free_speed", "linear"));
  is = issues_of(kJeffcott, {"loads.torque_law=\"linear\""});
  CHECK(has_issue(is, "loads.torque_free_speed", "required"));
  is = issues_of(kJeffcott, {"loads.torque_law=\"quadratic\""});
  CHECK(has_issue(is, "loads.torque_law", "must be one of"));
  // an unbalance the polar inertia cannot hold (M(q) would not be positive definite)
  is = issues_of(kJeffcott, {"loads.unbalance=1"});
  CHECK(has_issue(is, "rotor.Jp", "loads.unbalance^2 / rotor.mass"));
  // a Jeffcott rotor that starts inside its stator
  is = issues_of(kJeffcott, {"initial.x_r=3e-4"});
  CHECK(has_issue(is, "initial.x_r", "penetrates"));
}

TEST_CASE("case.resolved.toml of every model and setting reads back to the same case",
          "[models][io]") {
  const std::vector<std::pair<std::string, std::vector<std::string>>> variants = {
      {kJeffcott, {}},
      {rigid_jeffcott(), {"initial.vx_r=0.1"}},
      {kJeffcott,
       {"loads.torque_law=\"linear\"", "loads.torque_free_speed=400", "loads.unbalance=1e-4",
        "loads.unbalance_phase=0.3", "initial.vx_s=0.1"}},
      {read(RUBDYN_SOURCE_DIR "/cases/reference.toml"), {"loads.unbalance=1e-4"}},
  };
  for (const auto& [text, sets] : variants) {
    const CaseSpec c = parse_case(text, "j.toml", sets);
    const CaseSpec back = parse_case(to_toml(c), "resolved.toml");
    INFO(to_toml(c));
    CHECK(to_toml(back) == to_toml(c));
    CHECK(back.model == c.model);
    CHECK(back.jeffcott.stator.rigid == c.jeffcott.stator.rigid);
    CHECK(back.initial.q0 == c.initial.q0);
    CHECK(back.initial.v0 == c.initial.v0);
    CHECK(back.loads().torque_law == c.loads().torque_law);
    CHECK(back.loads().unbalance == c.loads().unbalance);
  }
}

TEST_CASE("cases/README.md documents every key of every model", "[models][io][docs]") {
  const std::string doc = read(RUBDYN_SOURCE_DIR "/cases/README.md");
  auto section_text = [&](const std::string& heading) {
    const auto a = doc.find(heading);
    if (a == std::string::npos) return std::string();
    const auto b = doc.find("\n## ", a + heading.size());
    return doc.substr(a, b == std::string::npos ? std::string::npos : b - a);
  };
  for (const auto& e : model_registry()) {
    CaseSpec c;
    c.model = std::string(e.kind);
    // the keys with the settings that show them all: a sprung stator, a linear torque law
    // (and, separately, a prescribed spin)
    for (bool prescribed : {false, true}) {
      c.loads().spin = prescribed ? SpinDrive::Prescribed : SpinDrive::Torque;
      c.loads().torque_law = TorqueLaw::Linear;
      c.initial.q0 = c.initial.v0 = Vec::Zero(static_cast<int>(initial_coordinates(c).size()));
      for (const std::string& full : case_keys(c)) {
        const std::string sec = full.substr(0, full.find('.')),
                          key = full.substr(full.find('.') + 1);
        // the model's own sections under "## Model `kind`", the others under "## [section]"
        bool own = false;
        for (auto s : e.sections) own = own || s == sec;
        const std::string text =
            own ? section_text("## Model `" + c.model + "`") : section_text("## [" + sec + "]");
        INFO(c.model << ": " << full);
        CHECK(text.find("`" + key + "`") != std::string::npos);
      }
    }
  }
}

// ---- the Jeffcott model's operations -------------------------------------------------------

namespace {

JeffcottParams unbalanced(bool rigid) {
  JeffcottParams p;
  p.stator.rigid = rigid;
  p.stator.k = 2e7;
  p.stator.c = 2500.0;
  p.loads.unbalance = 3e-3;
  p.loads.unbalance_phase = 0.7;
  p.loads.torque_law = TorqueLaw::Linear;
  p.loads.torque_free_speed = 300.0;
  return p;
}

}  // namespace

TEST_CASE("Jeffcott: structured solve, product and kinetic energy equal the dense M(q)",
          "[models][model]") {
  for (bool rigid : {false, true}) {
    const JeffcottModel m(unbalanced(rigid));
    const int n = m.num_dofs();
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int trial = 0; trial < 100; ++trial) {
      Vec q(n), v(n), x(n), y(n);
      for (int i = 0; i < n; ++i) {
        q[i] = 2e-4 * u(rng);
        v[i] = u(rng);
        x[i] = 1e3 * u(rng);
      }
      q[JeffcottModel::TH] = 50.0 * u(rng);
      v[JeffcottModel::TH] = 300.0 * u(rng);
      Mat M(n, n), B(n, 2);
      m.mass_matrix(q, M);
      B.col(0) = x;
      B.col(1) = v;
      const Mat X_ref = M.ldlt().solve(B);
      m.solve_mass(q, B);
      // M's entries span 3e-3 .. 5 (conditioning ~1e3): backward stable solves agree to
      // ~1e3 ulps of the solution
      CHECK((B - X_ref).norm() <= 1e-12 * X_ref.norm());
      m.mass_product(q, x, y);
      CHECK((y - M * x).norm() <= 1e-14 * (M * x).norm());
      CHECK(m.kinetic_energy(0.0, q, v) == Approx(0.5 * v.dot(M * v)).epsilon(1e-14));
    }
  }
}

TEST_CASE("Jeffcott: the Jacobians are the derivatives of f and of M a", "[models][model]") {
  for (bool rigid : {false, true}) {
    const JeffcottModel m(unbalanced(rigid));
    const int n = m.num_dofs();
    Vec q = Vec::Zero(n), v = Vec::Zero(n), a = Vec::Ones(n);
    q[0] = 1e-4;
    q[1] = -5e-5;
    q[2] = 1.3;
    v[0] = 0.2;
    v[1] = -0.1;
    v[2] = 250.0;
    Mat dfdq(n, n), dfdv(n, n), J(n, n);
    m.smooth_force_jacobians(0.0, q, v, dfdq, dfdv);
    m.mass_matrix_product_jacobian(q, a, J);
    // central differences, step h relative to each coordinate's scale: truncation h^2 f'''
    // ~1e-10 of f, round-off eps f / h ~1e-10 of f; 1e-6 relative to the largest entry is ample
    // and far below any wrong sign or factor
    for (int j = 0; j < n; ++j) {
      const double hq = j == 2 ? 1e-5 : 1e-9, hv = j == 2 ? 1e-3 : 1e-5;
      Vec qp = q, qm = q, vp = v, vm = v, fp(n), fm(n), Mp(n), Mm(n);
      qp[j] += hq;
      qm[j] -= hq;
      vp[j] += hv;
      vm[j] -= hv;
      m.smooth_forces(0.0, qp, v, fp);
      m.smooth_forces(0.0, qm, v, fm);
      CHECK(((fp - fm) / (2 * hq) - dfdq.col(j)).norm() <= 1e-6 * dfdq.norm() + 1e-6);
      m.smooth_forces(0.0, q, vp, fp);
      m.smooth_forces(0.0, q, vm, fm);
      CHECK(((fp - fm) / (2 * hv) - dfdv.col(j)).norm() <= 1e-6 * dfdv.norm() + 1e-6);
      m.mass_product(qp, a, Mp);
      m.mass_product(qm, a, Mm);
      CHECK(((Mp - Mm) / (2 * hq) - J.col(j)).norm() <= 1e-6 * (J.norm() + 1.0));
    }
  }
}

TEST_CASE("Jeffcott: the contact chart embeds onto the constraints and inverts itself",
          "[models][contact]") {
  for (bool rigid : {false, true}) {
    const JeffcottModel m(unbalanced(rigid));
    const ContactChart& chart = *m.contact_chart();
    const int n = m.num_dofs();
    const double g0 = m.gap_scale(0), R = m.contact_radius(0);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (ChartMode mode : {ChartMode::Slip, ChartMode::Stick}) {
      INFO((rigid ? "rigid " : "sprung ") << (mode == ChartMode::Slip ? "slip" : "stick"));
      const int d = chart.dim(mode);
      CHECK(d == (mode == ChartMode::Slip ? 2 : 1) + (rigid ? 0 : 2));
      for (int trial = 0; trial < 50; ++trial) {
        // a state on the manifold: the rotor on the clearance circle about the stator
        Vec q = Vec::Zero(n), v = Vec::Zero(n);
        const double phi = 3.0 * u(rng), omega = 800.0 + 100.0 * u(rng);
        if (!rigid) {
          q[3] = 1e-5 * u(rng), q[4] = 1e-5 * u(rng), v[3] = 0.1 * u(rng), v[4] = 0.1 * u(rng);
        }
        const double xs = rigid ? 0.0 : q[3], ys = rigid ? 0.0 : q[4];
        const double vxs = rigid ? 0.0 : v[3], vys = rigid ? 0.0 : v[4];
        const double phid = mode == ChartMode::Stick ? -R / g0 * omega : 500.0 * u(rng);
        q[0] = xs + g0 * std::cos(phi);
        q[1] = ys + g0 * std::sin(phi);
        q[2] = 20.0 * u(rng);
        v[0] = vxs - g0 * phid * std::sin(phi);
        v[1] = vys + g0 * phid * std::cos(phi);
        v[2] = omega;
        ChartAnchor anchor;
        Vec p(d), pd(d), q2(n), v2(n);
        chart.chart(mode, q, v, anchor, p, pd);
        chart.embed(mode, anchor, p, pd, q2, v2);
        CHECK((q2 - q).cwiseAbs().maxCoeff() <= 1e-15 * 30.0);
        CHECK((v2 - v).cwiseAbs().maxCoeff() <= 1e-12);
        // any reduced state embeds on the manifold: d_N = 0, v_N = 0 (v_t = 0 in stick)
        // (angles by 0.1 rad, the stator's coordinates by 1e-5 m: positions of O(g0), whose
        // round-off in d_N is then a few ulps of g0)
        const int angles = mode == ChartMode::Slip ? 2 : 1;
        for (int i = 0; i < d; ++i) {
          p[i] += (i < angles ? 0.1 : 1e-5) * u(rng);
          pd[i] += 0.05 * u(rng);
        }
        chart.embed(mode, anchor, p, pd, q2, v2);
        const ContactKinematics c = m.contact(0, 0.0, q2, v2);
        CHECK(std::abs(c.d_N) <= 8 * 2.2e-16 * g0);
        CHECK(std::abs(c.v_N) <= 1e-15 * (1.0 + v2.norm()));
        if (mode == ChartMode::Stick) CHECK(std::abs(c.v_t) <= 1e-13);
        // reduce inverts the embedding's acceleration for an acceleration on the manifold
        Vec pdd = Vec::Zero(d), back(d);
        for (int i = 0; i < d; ++i) pdd[i] = 1e3 * u(rng);
        const double h = 1e-9;
        Vec qm(n), vm(n), qp(n), vp(n), q0(n), v0(n);
        const Vec pm = p - pd * h + 0.5 * pdd * h * h, pdm = pd - pdd * h;
        const Vec pp = p + pd * h + 0.5 * pdd * h * h, pdp = pd + pdd * h;
        chart.embed(mode, anchor, pm, pdm, qm, vm);
        chart.embed(mode, anchor, pp, pdp, qp, vp);
        chart.embed(mode, anchor, p, pd, q0, v0);
        const Vec a_fd = (vp - vm) / (2 * h);
        chart.reduce(mode, anchor, p, pd, q0, a_fd, back);
        // central differences at h = 1e-9 s of a motion whirling at up to 1e5 rad/s: 1e-5
        CHECK((back - pdd).norm() <= 1e-5 * pdd.norm());
      }
    }
  }
}

TEST_CASE("Jeffcott runs close their energy balance with every solver", "[models][events]") {
  CaseSpec c = parse_case(kJeffcott, "j.toml",
                          {"loads.unbalance=5e-4", "initial.omega0=800", "run.t_end=0.05"});
  const auto model = build_model(c);
  const MechanicalState s0 = initial_state(c);
  {
    MemorySink sink;
    EventDrivenOptions o;
    const RunSummary s = run_event_driven(*model, s0, 0.05, o, sink);
    INFO(s.message);
    REQUIRE(s.complete());
    REQUIRE(s.events[static_cast<int>(EventKind::Impact)] >= 1);  // the unbalance closes the gap
    // rtol 1e-10 on works of ~1e3 J: the quadratures' error ~1e-7 J
    CHECK(std::abs(s.energy_residual) <= 1e-9 * std::abs(s.work_torque) + 1e-6);
    CHECK(s.max_penetration <= 1e-12 * c.jeffcott.stator.gap);
    CHECK(s.max_cone_violation <= 1e-9);
  }
  for (auto scheme : {FixedStepScheme::CarpOneVC, FixedStepScheme::CarpQN,
                      FixedStepScheme::MoreauJean, FixedStepScheme::MoreauJeanProjected}) {
    INFO(to_string(scheme));
    MemorySink sink;
    FixedStepOptions o;
    o.scheme = scheme;
    o.h = 1e-6;
    const RunSummary s = run_fixed_step(*model, s0, 0.05, o, sink);
    REQUIRE(s.complete());
    // first-order schemes in contact: the balance closes to O(h) of the flows (measured
    // 1e-7 .. 1e-6 relative at h = 1e-6)
    CHECK(std::abs(s.energy_residual) <= 1e-4 * std::abs(s.work_torque));
  }
}
