#include "rubdyn/io/columns.hpp"

#include <stdexcept>

#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn {

std::vector<SampleColumn> timeseries_columns(const std::vector<Coordinate>& coords,
                                             const std::vector<Observable>& observables,
                                             int contacts) {
  std::vector<SampleColumn> cols;
  cols.push_back({"t", SampleField::Time, 0, "s"});
  const int n = static_cast<int>(coords.size());
  for (int i = 0; i < n; ++i)
    cols.push_back({coords[static_cast<std::size_t>(i)].name, SampleField::Position, i,
                    coords[static_cast<std::size_t>(i)].unit});
  for (int i = 0; i < n; ++i) {
    std::string u = coords[static_cast<std::size_t>(i)].unit;
    u.append("/s");
    cols.push_back({coords[static_cast<std::size_t>(i)].rate, SampleField::Velocity, i, u});
  }
  for (std::size_t i = 0; i < observables.size(); ++i)
    cols.push_back(
        {observables[i].name, SampleField::Observable, static_cast<int>(i), observables[i].unit});
  for (int k = 0; k < contacts; ++k) {
    // (appended, not `"d_N" + sfx`: g++ 12 warns falsely about the latter, -Wrestrict)
    auto name = [&](const char* base) {
      std::string s(base);
      if (contacts > 1) s.append("_").append(std::to_string(k + 1));
      return s;
    };
    cols.push_back({name("d_N"), SampleField::Gap, k, "m"});
    cols.push_back({name("v_N"), SampleField::GapRate, k, "m/s"});
    cols.push_back({name("v_t"), SampleField::SlipSpeed, k, "m/s"});
    cols.push_back({name("F_N"), SampleField::NormalForce, k, "N"});
    cols.push_back({name("F_T"), SampleField::TangentialForce, k, "N"});
    cols.push_back({name("phase"), SampleField::Phase, k, "-"});
  }
  return cols;
}

std::vector<SampleColumn> timeseries_columns(const LagrangianModel& m) {
  return timeseries_columns(m.coordinates(), m.observables(), m.contact_count());
}

double sample_value(const Sample& s, const SampleColumn& c) {
  switch (c.field) {
    case SampleField::Time: return s.t;
    case SampleField::Position: return s.q[c.index];
    case SampleField::Velocity: return s.v[c.index];
    case SampleField::Observable: return s.observables[c.index];
    default: break;
  }
  const ContactSample& k = s.contacts[static_cast<std::size_t>(c.index)];
  switch (c.field) {
    case SampleField::Gap: return k.d_N;
    case SampleField::GapRate: return k.v_N;
    case SampleField::SlipSpeed: return k.v_t;
    case SampleField::NormalForce: return k.F_N;
    case SampleField::TangentialForce: return k.F_T;
    case SampleField::Phase: return static_cast<double>(k.phase);
    default: return 0.0;
  }
}

std::vector<EventColumn> event_columns(int contacts) {
  std::vector<EventColumn> c = {{"t", EventField::Time},
                                {"kind", EventField::Kind},
                                {"phase_before", EventField::PhaseBefore},
                                {"phase_after", EventField::PhaseAfter},
                                {"d_N", EventField::Number},
                                {"v_N_minus", EventField::Number},
                                {"v_N_plus", EventField::Number},
                                {"v_t_minus", EventField::Number},
                                {"v_t_plus", EventField::Number},
                                {"P_N", EventField::Number},
                                {"P_T", EventField::Number},
                                {"F_N", EventField::Number},
                                {"F_T", EventField::Number},
                                {"t_accumulation", EventField::Number},
                                {"witness", EventField::Text},
                                {"note", EventField::Text}};
  if (contacts > 1) c.push_back({"contact", EventField::Contact});
  return c;
}

double event_number(const EventRecord& e, std::string_view name) {
  if (name == "t") return e.t;
  if (name == "d_N") return e.d_N;
  if (name == "v_N_minus") return e.v_N_minus;
  if (name == "v_N_plus") return e.v_N_plus;
  if (name == "v_t_minus") return e.v_t_minus;
  if (name == "v_t_plus") return e.v_t_plus;
  if (name == "P_N") return e.P_N;
  if (name == "P_T") return e.P_T;
  if (name == "F_N") return e.F_N;
  if (name == "F_T") return e.F_T;
  if (name == "t_accumulation") return e.t_accumulation;
  if (name == "contact") return static_cast<double>(e.contact + 1);
  throw std::invalid_argument("not a numeric event column: " + std::string(name));
}

const std::string& event_text(const EventRecord& e, std::string_view name) {
  if (name == "witness") return e.witness;
  if (name == "note") return e.note;
  throw std::invalid_argument("not a text event column: " + std::string(name));
}

}  // namespace rubdyn
