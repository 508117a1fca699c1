#pragma once
// A prescribed spin speed (loads.spin = "prescribed"; docs/models.md, section 3.2): any rotor
// model whose spin is a free coordinate becomes, with
//     omega(t) = omega0 + alpha (t - t0),   theta(t) = theta0 + omega0 (t - t0) + alpha (t - t0)^2
//     / 2,
// a model of the other coordinates: theta is a given function of time (a rheonomic constraint)
// and its equation is dropped. With the full coordinates q_f = (q, theta(t)), v_f = (v, omega(t)),
// a_f = (a, alpha) and the inner model's M_f, f_f, W_f:
//   M = the inner M_f without the spin's row and column (it must not depend on theta: true of
//       every rotor model, where theta enters M only through its own row and column),
//   f = the inner f_f without the spin's row, minus M_f's spin column times alpha (the inertial
//       force of the spin's acceleration on the others: the unbalance's Euler force and, for the
//       rigid rotor, the H_x, H_y coupling),
//   W_N, W_T = the inner rows without the spin's entry; their spin entries times omega(t) are
//       the speeds' prescribed share b_N, b_T (contact_kinematics.hpp), and times alpha part of
//       wdot_N, wdot_T.
// The dropped row gives the torque that holds the speed, once the accelerations and the contact
// forces are known (docs/models.md, (3.1)):
//   tau_d = [M_f a_f]_theta - f_f,theta - sum_k (W_N,k,theta F_N,k + W_T,k,theta F_T,k),
// the inner model being built without a drive torque. Its power tau_d omega is the drive's in the
// energy balance (applied_power), and theta, omega, tau_d are the model's observables (output
// columns theta, omega, drive_torque), then the inner model's own (a matrices model's modal
// amplitudes, output.modes) at the full state. The energies are the whole system's, the spin's
// kinetic energy included.
// Every service of the inner model is passed through in the wrapper's coordinates: the planes'
// centres (plane_motion: a rigid rotor's [[plane]] point interpolates between B and R) and the
// ring chart (ring_chart: the inner chart with the spin's index dropped and theta(t) given, so
// that a sticking contact's rolling constraint phi_k = phi_k0 - (R_k / g_k)(theta(t) - theta(t_a))
// is rheonomic: contact/ring_chart.hpp). The one-contact chart (contact_chart: its coordinates
// hold theta) is not passed through: every rotor model also has a ring chart for one contact.
#include <memory>
#include <optional>
#include <vector>

#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn {

class PrescribedSpin final : public LagrangianModel {
 public:
  /// `inner`: a model with a spin coordinate and without a drive torque. The prescription starts
  /// at t0 from theta0, omega0 with the constant acceleration alpha.
  PrescribedSpin(std::unique_ptr<LagrangianModel> inner, double t0, double theta0, double omega0,
                 double alpha);

  std::string_view name() const override { return inner_->name(); }
  int num_dofs() const override { return n_; }
  const std::vector<Coordinate>& coordinates() const override { return coords_; }
  void mass_matrix(VecIn q, MatOut M) const override;
  void mass_product(VecIn q, VecIn x, VecOut y) const override;
  void solve_mass(VecIn q, MatOut B) const override;
  void mass_matrix_product_jacobian(VecIn q, VecIn a, MatOut J) const override;
  void smooth_forces(double t, VecIn q, VecIn v, VecOut f) const override;
  void smooth_force_jacobians(double t, VecIn q, VecIn v, MatOut dfdq, MatOut dfdv) const override;
  int contact_count() const override { return inner_->contact_count(); }
  void compute_contact(int k, double t, VecIn q, VecIn v, ContactKinematics& c) const override;
  const ContactLaw& contact_law(int k = 0) const override { return inner_->contact_law(k); }
  double gap_scale(int k = 0) const override { return inner_->gap_scale(k); }
  double contact_radius(int k = 0) const override { return inner_->contact_radius(k); }
  bool plane_motion(int k, double t, VecIn q, VecIn v, PlaneMotion& out) const override;
  const RingChart* ring_chart() const override { return ring_chart_ ? &*ring_chart_ : nullptr; }
  double kinetic_energy(double t, VecIn q, VecIn v) const override;
  double potential_energy(double t, VecIn q) const override;
  SmoothPower smooth_power(double t, VecIn q, VecIn v) const override;
  bool newton_entries(double t, VecIn q, VecIn v, VecIn a, NewtonEntries& e) const override;
  bool rheonomic() const override { return true; }
  double applied_power(double t, VecIn q, VecIn v, VecIn a, const ContactForce* F) const override;
  const std::vector<Observable>& observables() const override;
  void compute_observables(double t, VecIn q, VecIn v, VecIn a, const ContactForce* F,
                           VecOut out) const override;
  double spin(double t, VecIn q, VecIn v) const override;
  std::optional<LinearModel> linearize(Linearization mode) const override {
    return inner_->linearize(mode);  // the spin is imposed there too
  }

  /// theta(t), omega(t), alpha.
  double theta(double t) const { return law_.theta(t); }
  double omega(double t) const { return law_.omega(t); }
  double alpha() const { return law_.alpha; }
  /// The torque that holds the speed at (t, q, v) with the accelerations a and contact forces F.
  double drive_torque(double t, VecIn q, VecIn v, VecIn a, const ContactForce* F) const;
  const LagrangianModel& inner() const { return *inner_; }

 private:
  /// Scratch of the full model's size, per thread (a model serves several threads).
  struct Scratch;
  Scratch& scratch() const;
  /// q, v (and a) with the spin's entries inserted at time t.
  void embed(double t, VecIn q, VecIn v, Scratch& s) const;

  std::unique_ptr<LagrangianModel> inner_;
  int s_;        // the inner spin coordinate
  int n_;        // inner dofs - 1
  SpinLaw law_;  ///< theta(t), omega(t), alpha (the ring chart's too)
  std::vector<Coordinate> coords_;
  /// theta, omega, drive_torque, then the inner model's observables
  std::vector<Observable> observables_;
  /// The inner model's ring chart in these coordinates, with the prescription (none when the
  /// inner has none, or when a contact's point or ring involves the spin coordinate).
  std::optional<RingChart> ring_chart_;
};

}  // namespace rubdyn
