// rubdyn check CASE: validate a case and print its derived quantities (analysis/derived.hpp).
#include <fmt/format.h>

#include <memory>
#include <numbers>
#include <string>

#include "cli_common.hpp"
#include "commands.hpp"
#include "rubdyn/analysis/derived.hpp"
#include "rubdyn/hybrid/method_choice.hpp"
#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/model/matrix_model.hpp"

namespace rubdyn::app {

namespace {

void row(const std::string& label, double value, const std::string& unit) {
  fmt::print("  {:<36}{:>14.6g} {}\n", label, value, unit);
}

void spin_rows(double omega0, double omega_lim, FreeAcceleration a, double t, const char* how) {
  const double rpm = 30.0 / std::numbers::pi;
  fmt::print("spin speed\n");
  row("omega0", omega0, fmt::format("rad/s = {:.6g} rpm", omega0 * rpm));
  row("omega_lim", omega_lim, fmt::format("rad/s = {:.6g} rpm", omega_lim * rpm));
  switch (a) {
    case FreeAcceleration::reaches: row("free acceleration to omega_lim", t, how); break;
    case FreeAcceleration::already_reached:
      fmt::print("  free acceleration: omega0 >= omega_lim, already reached (0 s)\n");
      break;
    case FreeAcceleration::never:
      fmt::print("  free acceleration: never reaches omega_lim (no driving torque there)\n");
      break;
  }
}

int check_jeffcott(const CaseSpec& c) {
  const auto& p = c.jeffcott;
  const double omega0 = c.initial.v0[JeffcottModel::TH], omega_lim = c.run.omega_lim;
  const JeffcottQuantities d = compute_jeffcott_quantities(p, omega0, omega_lim);
  fmt::print("case {} ({}): valid\n", c.name, c.source);
  fmt::print("model jeffcott: a disc on a massless shaft, {} stator\n",
             p.stator.rigid ? "a rigid" : "a sprung");
  fmt::print("natural frequencies without contact (no gyroscopic effect: forward = backward)\n");
  row("rotor sqrt(k_r/m_r) / 2pi", d.f_rotor, fmt::format("Hz (zeta {:.4g})", d.zeta_rotor));
  if (!p.stator.rigid) {
    row("stator sqrt(k_s/m_s) / 2pi", d.f_stator, fmt::format("Hz (zeta {:.4g})", d.zeta_stator));
    row("tied sqrt((k_r+k_s)/(m_r+m_s)) / 2pi", d.f_tied, "Hz");
  }
  fmt::print("static equilibrium under gravity\n");
  row("rotor sag -m_r g / k_r", d.sag_rotor, "m");
  if (!p.stator.rigid) row("stator sag -m_s g / k_s", d.sag_stator, "m");
  if (d.rests_on_stator) {
    fmt::print("  the sags close the clearance: the rotor rests on the stator\n");
    row("contact force F_N", d.F_N, "N");
    row("rotor  y_r", d.y_r, "m");
    if (!p.stator.rigid) row("stator y_s", d.y_s, "m");
  } else {
    fmt::print("  the rotor hangs free inside the clearance (F_N = 0)\n");
  }
  if (p.loads.unbalance > 0.0) {
    fmt::print("unbalance\n");
    row("eccentricity eps = u_b / m_r", d.eps, "m");
    row("inertia about G, J - u_b^2 / m_r", d.J_G, "kg m^2");
    row("free steady whirl radius at omega0", d.unbalance_orbit,
        fmt::format("m ({:.3g} g0)", d.unbalance_orbit / p.stator.gap));
  }
  if (d.rolling_closed_form) {
    fmt::print("rolling on the rigid stator under the constant torque (closed form)\n");
    row("steady spin tau / (c_r R^2)", d.rolling_omega, "rad/s");
    row("whirl -(R / g0) Omega", d.rolling_whirl, "rad/s");
    row("contact force g0 (m_r w^2 - k_r)", d.rolling_F_N, "N");
    row("time constant (J + m_r R^2)/(c_r R^2)", d.rolling_time_constant, "s");
  }
  if (p.loads.spin == SpinDrive::Prescribed) {
    fmt::print("prescribed spin: omega(t) = omega0 + {:.6g} (t - t_start) rad/s\n",
               p.loads.spin_accel);
  }
  spin_rows(omega0, omega_lim, d.free_acceleration, d.t_free_to_omega_lim,
            p.loads.spin == SpinDrive::Prescribed ? "s = (omega_lim - omega0) / spin_accel"
            : p.loads.torque_law == TorqueLaw::Linear
                ? "s (the linear torque law, without contact)"
                : "s = (omega_lim - omega0) J / tau_a (without contact)");
  return 0;
}

/// Kind "matrices": what was read (its derived quantities are the user's: `rubdyn campbell`
/// gives its frequencies).
int check_matrices(const CaseSpec& c) {
  const MatrixParams p = matrix_model_params(c);  // (the reduced model with a [reduction])
  const MatrixModel m(p);
  fmt::print("case {} ({}): valid\n", c.name, c.source);
  fmt::print("a user's linear rotor (matrices), n = {}\n", p.rotor.size());
  if (const std::string note = model_note(c); !note.empty()) fmt::print("  {}\n", note);
  std::string names;
  for (const auto& x : m.coordinates()) names += (names.empty() ? "" : ", ") + x.name;
  fmt::print("  coordinates: {}\n", names);
  for (const auto* f : {&c.matrix_files.M, &c.matrix_files.C, &c.matrix_files.K, &c.matrix_files.G,
                        &c.matrix_files.f0})
    if (!f->empty()) fmt::print("  read {}\n", *f);
  const auto& cn = m.coordinates();
  const std::vector<MatrixNode> nodes = p.node_list();
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const MatrixNode& nd = nodes[k];
    fmt::print("  contact node{}: ({}, {}), radius {} m, gap {} m, mu {}, {}\n",
               nodes.size() > 1 ? fmt::format(" {}", k + 1) : std::string(),
               cn[static_cast<std::size_t>(nd.at.x)].name,
               cn[static_cast<std::size_t>(nd.at.y)].name, nd.at.radius, nd.at.gap, nd.law.mu,
               nd.stator.rigid ? std::string("rigid ring")
                               : fmt::format("ring {} kg, {} N/m, {} N s/m", nd.stator.mass,
                                             nd.stator.k, nd.stator.c));
  }
  row("Schur complement of theta at q0", m.schur(c.initial.q0), "kg m^2 (> 0: M_full SPD)");
  row("omega0", c.initial.v0[p.rotor.size()], "rad/s");
  return 0;
}

/// The event solver's method for this case: as given, or chosen from the model's stiffness at
/// the initial state (hybrid/method_choice.hpp), as the run will choose it.
void print_event_method(const CaseSpec& c) {
  if (c.solver.kind != "event") return;
  const auto model = build_model(c);
  const MechanicalState s = initial_state(c);
  const StiffnessAssessment a = assess_stiffness(*model, s.t, s.q, s.v);
  fmt::print("event solver's multistep method (solver.method = auto: BDF when stiff)\n");
  fmt::print("  {}\n", a.reason());
  const auto said = [&](const std::string& m) {
    return m == "auto" ? fmt::format("{} (auto)", a.stiff ? "bdf" : "adams") : m + " (as given)";
  };
  fmt::print("  free flight: {}; contact phases: {}\n", said(c.solver.method),
             said(c.solver.contact_method));
}

int check_model(const CaseSpec& c) {
  if (c.model == "jeffcott") return check_jeffcott(c);
  if (c.model == "matrices") return check_matrices(c);
  const double omega0 = c.initial.v0[TH], omega_lim = c.run.omega_lim;
  const DerivedQuantities d = compute_derived_quantities(c.params, omega0, omega_lim);
  const double rpm = 30.0 / std::numbers::pi;

  fmt::print("case {} ({}): valid\n", c.name, c.source);
  fmt::print("geometry and inertia (paper eq. 9-11)\n");
  row("l = L - delta", d.l, "m");
  row("nu = d / l", d.nu, "-");
  row("M11 = (1-nu)^2 m + Jd/l^2", d.M11, "kg");
  row("M12 = nu (1-nu) m - Jd/l^2", d.M12, "kg");
  row("M22 = nu^2 m + Jd/l^2", d.M22, "kg");
  row("H = Jp / l^2", d.H, "kg");
  if (!c.params.planes.empty()) {
    // several planes: the statics and frequencies below are the single plane's formulas;
    // `rubdyn campbell` gives this model's frequencies
    fmt::print("rub planes ([[plane]]; rotor point z_k = (1 - s) z_b + s z_r, s = position / l)\n");
    fmt::print("  {:>5} {:>10} {:>8} {:>10} {:>10} {:>6}  {}\n", "plane", "position", "s", "radius",
               "gap", "mu", "ring");
    for (std::size_t k = 0; k < c.params.planes.size(); ++k) {
      const PlaneParams& pl = c.params.planes[k];
      fmt::print("  {:>5} {:>10.6g} {:>8.4g} {:>10.6g} {:>10.6g} {:>6.3g}  {}\n", k + 1,
                 pl.position, pl.position / d.l, pl.radius, pl.gap, pl.contact.mu,
                 pl.rigid ? std::string("fixed")
                          : fmt::format("m_s {:.6g} kg, k_s {:.6g} N/m, c_s {:.6g} N s/m", pl.mass,
                                        pl.k, pl.c));
    }
    fmt::print("  natural frequencies: rubdyn campbell (this model's linearisation)\n");
    spin_rows(omega0, omega_lim, d.free_acceleration, d.t_free_to_omega_lim,
              "s = (omega_lim - omega0) Jp / tau_a (without contact)");
    return 0;
  }
  fmt::print("static equilibrium under gravity, rotor at rest\n");
  if (d.rests_on_stator) {
    fmt::print(
        "  the rotor pivots about its bearing and rests on the stator (bottom of the gap)\n");
    row("contact force F_N = nu m g", d.F_N, "N");
    row("bearing y_b = -(1-nu) m g / k_b", d.y_b, "m");
    row("stator  y_s = -F_N / k_s", d.y_s, "m");
    row("rotor   y_r = y_s - g0", d.y_r, "m");
  } else {
    fmt::print("  no gravity: the rotor stays centred, no contact (F_N = 0)\n");
  }
  fmt::print("natural frequencies at rest\n");
  row("coupled rotor + stator, f1 (double)", d.f1, "Hz");
  row("coupled rotor + stator, f2 (double)", d.f2, "Hz");
  row("stator alone, sqrt(k_s/m_s) / 2pi", d.f_stator, "Hz");
  row("rotor on its bearing, no stator", d.f_bearing_rotor, "Hz (and 0 Hz: free pivot)");
  fmt::print("spin speed\n");
  row("omega0", omega0, fmt::format("rad/s = {:.6g} rpm", omega0 * rpm));
  row("omega_lim", omega_lim, fmt::format("rad/s = {:.6g} rpm", omega_lim * rpm));
  switch (d.free_acceleration) {
    case FreeAcceleration::reaches:
      row("free acceleration to omega_lim", d.t_free_to_omega_lim,
          "s = (omega_lim - omega0) Jp / tau_a");
      break;
    case FreeAcceleration::already_reached:
      fmt::print("  free acceleration: omega0 >= omega_lim, already reached (0 s)\n");
      break;
    case FreeAcceleration::never:
      fmt::print("  free acceleration: never reaches omega_lim (tau_a <= 0)\n");
      break;
  }
  return 0;
}

int check_command(const CaseArgs& a) {
  const CaseSpec c = load_case(a.path, a.sets);  // throws CaseError: exit 2
  const int rc = check_model(c);
  print_event_method(c);
  return rc;
}

}  // namespace

void add_check_command(CLI::App& app, Action& action) {
  auto a = std::make_shared<CaseArgs>();
  auto* sub = app.add_subcommand(
      "check", "Validate a case and print its derived quantities (inertia, statics, frequencies)");
  add_case_options(*sub, *a);
  sub->callback([a, &action] { action = [a] { return check_command(*a); }; });
}

}  // namespace rubdyn::app
