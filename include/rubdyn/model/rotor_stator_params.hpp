#pragma once
// Physical parameters of the rotor-stator model (paper, section 3), SI units. A plain struct;
// validation of user input lives in io/ (case files), which names file, line, key and rule.
#include <vector>

#include "rubdyn/contact/contact_law.hpp"
#include "rubdyn/core/run_types.hpp"
#include "rubdyn/model/loads.hpp"

namespace rubdyn {

struct RotorParams {
  double mass = 5.0;     ///< m [kg]
  double Jd = 0.035;     ///< diametral moment of inertia about G [kg m^2]
  double Jp = 0.06;      ///< polar moment of inertia [kg m^2]
  double L = 0.5;        ///< shaft length, bearing B to free end [m]
  double delta = 0.1;    ///< distance from the free end to the contact plane R [m]
  double d = 0.3;        ///< distance from the bearing B to the centre of mass G [m]
  double radius = 0.05;  ///< seal ring (rotor) radius R_r [m]
};

struct BearingParams {
  double k = 5.0e6;  ///< k_b [N/m]
  double c = 300.0;  ///< c_b [N s/m]
};

struct StatorParams {
  double mass = 2.0;    ///< m_s [kg]
  double k = 2.0e6;     ///< k_s [N/m]
  double c = 100.0;     ///< c_s [N s/m]
  double gap = 2.0e-4;  ///< g0 = R_s - R_r [m]
};

/// One rub plane of the rigid rotor (a case's [[plane]] table): where it is, its seal, its
/// contact law and its ring.
struct PlaneParams {
  double position = 0.4;  ///< axial distance from the bearing B [m], in (0, L]
  double radius = 0.05;   ///< seal radius R_k [m]
  double gap = 2.0e-4;    ///< radial clearance g0_k [m]
  ContactLaw contact{0.1, 0.0, 0.0};
  bool rigid = false;  ///< a fixed ring at the origin: no mass, spring, damper or coordinates
  double mass = 2.0;   ///< the ring's mass m_s,k [kg] (sprung ring)
  double k = 2.0e6;    ///< its support stiffness k_s,k [N/m]
  double c = 100.0;    ///< its support damping c_s,k [N s/m]
};

/// At most this many [[plane]]s (the contact solvers enumerate up to 4 contacts exactly and
/// iterate beyond; 8 planes is 8 rings, 21 coordinates).
inline constexpr int kMaxPlanes = kMaxContacts;  // the largest K (core/run_types.hpp)

/// Defaults are the reference case (cases/reference.toml).
struct RotorStatorParams {
  RotorParams rotor;
  BearingParams bearing;
  StatorParams stator;
  ContactLaw contact{0.1, 0.0, 0.0};
  LoadParams loads;
  /// The rub planes ([[plane]]); empty: the paper's one plane at R (L - delta from B) with the
  /// rotor's radius, [stator] and [contact]. With planes, rotor.radius, stator and contact are
  /// not used.
  std::vector<PlaneParams> planes;
};

}  // namespace rubdyn
