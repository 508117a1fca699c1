#pragma once
// The event-driven integrator for a model with several contacts (K > 1). A model with one
// contact runs the one-contact integrator of event_driven.cpp, unchanged; run_event_driven
// dispatches on contact_count().
//
// The state of the hybrid system is the tuple of the contacts' modes (free, slip+, slip-, stick
// per contact). Phases:
//   every contact open: free flight as in the one-contact integrator (Adams with fixed-point
//            iteration, or BDF), a = M^{-1} f;
//   some contacts closed: the index-reduced DAE in full coordinates with the closed contacts'
//            constraints (d_N,k'' = 0; v_t,k' = 0 in stick; F_T,k = -mu_k s F_N,k in slip s),
//            CVODE-BDF with projection after every step: positions onto d_N,k = 0 of every closed
//            contact (joint Gauss-Newton steps along the W_N,k), velocities mass-weighted onto
//            v_N,k = 0 (and v_t,k = 0 in stick). The one-contact integrator's minimal
//            coordinates are not used here (docs/event-driven.md says where they would compose).
// Witnesses per contact, as in the one-contact integrator: open: d_N,k (closing) and v_N,k
// (rising: a gap minimum, armed after a release); slip: F_N,k (falling) and v_t,k (towards 0,
// not with mu_k = 0); stick: F_N,k and mu_k F_N,k -+ F_T,k; and omega - omega_lim.
// Events are decided jointly by the K-contact solver of contact/contact_set.hpp:
//   contact onset at k: every contact at the constraint (the closed ones, k, and any other
//            within the position tolerance of 0) enters one impulse problem, Newton's law for
//            the impacting ones (v_N < -v_tol), e = 0 for the others; an impacting contact whose
//            next bounce would be below the position tolerance is truncated by a plastic impact
//            (Zeno, per contact); the contacts that leave with v_N below the velocity tolerance
//            join the acceleration-level decision;
//   a closed contact's witness, a grazing gap minimum, an arrival: the acceleration-level problem
//            of every contact at the constraint picks every contact's next mode (the ending
//            contact's ending mode excluded while another is consistent: rule 1 of the set
//            solver's tie rule).
// Painleve cases (no solution) end the run naming the contacts; non-unique ones are logged.
#include "rubdyn/hybrid/event_driven.hpp"

namespace rubdyn::detail {

/// run_event_driven for contact_count() > 1 (the options already checked).
RunSummary run_event_driven_multi(const LagrangianModel& model, const MechanicalState& initial,
                                  double t_end, const EventDrivenOptions& opt, OutputSink& sink);

}  // namespace rubdyn::detail
