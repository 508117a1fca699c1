#pragma once
// The contact law shared by EVERY solver (event-driven, Carpenter, Moreau-Jean): one unilateral
// contact with Coulomb friction (mu_s = mu_d = mu) and Newton's impact law.
//
//   Signorini:  d_N >= 0, F_N >= 0, d_N F_N = 0            (paper, section 2.1)
//   Coulomb:    |F_T| <= mu F_N;  v_t != 0  =>  F_T = -mu sign(v_t) F_N
//   Impact:     v_N+ = -e_n v_N-  (normal), tangential restitution e_t (v_t+ = -e_t v_t- when the
//               impact sticks), with the impulses inside the Coulomb cone.
// With e_n = e_t = 0 (the paper's setting, Table 1) impacts are plastic.

namespace rubdyn {

struct ContactLaw {
  double mu = 0.0;   ///< Coulomb friction coefficient [-], >= 0
  double e_n = 0.0;  ///< Newton normal restitution [-], in [0, 1]
  double e_t = 0.0;  ///< tangential restitution [-], in [0, 1]

  bool has_friction() const { return mu > 0.0; }
  bool has_restitution() const { return e_n > 0.0; }
};

}  // namespace rubdyn
