#include "rubdyn/core/run_types.hpp"

namespace rubdyn {

std::string_view to_string(Phase p) {
  switch (p) {
    case Phase::Free: return "free";
    case Phase::SlipPos: return "slip+";
    case Phase::SlipNeg: return "slip-";
    case Phase::Stick: return "stick";
  }
  return "?";
}

std::string_view to_string(EventKind k) {
  switch (k) {
    case EventKind::Impact: return "impact";
    case EventKind::Contact: return "contact";
    case EventKind::Liftoff: return "liftoff";
    case EventKind::Stick: return "stick";
    case EventKind::Slip: return "slip";
    case EventKind::Reversal: return "reversal";
    case EventKind::Grazing: return "grazing";
    case EventKind::Zeno: return "zeno";
    case EventKind::Painleve: return "painleve";
    case EventKind::Release: return "release";
    case EventKind::Count: break;
  }
  return "?";
}

std::string_view to_string(Termination t) {
  switch (t) {
    case Termination::Completed: return "completed";
    case Termination::SolverFailure: return "solver_failure";
    case Termination::NonFinite: return "non_finite";
    case Termination::Painleve: return "painleve";
    case Termination::Zeno: return "zeno";
    case Termination::Chattering: return "chattering";
    case Termination::Interrupted: return "interrupted";
    case Termination::TimeBudget: return "time_budget";
    case Termination::OutputFailure: return "output_failure";
    case Termination::StepCollapse: return "step_collapse";
    case Termination::Implausible: return "implausible";
    case Termination::LawViolation: return "law_violation";
  }
  return "?";
}

}  // namespace rubdyn
