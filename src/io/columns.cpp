#include "rubdyn/io/columns.hpp"

#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

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

void set_sample_value(Sample& s, const SampleColumn& c, double x) {
  switch (c.field) {
    case SampleField::Time: s.t = x; return;
    case SampleField::Position: s.q[c.index] = x; return;
    case SampleField::Velocity: s.v[c.index] = x; return;
    case SampleField::Observable: s.observables[c.index] = x; return;
    default: break;
  }
  ContactSample& k = s.contacts[static_cast<std::size_t>(c.index)];
  switch (c.field) {
    case SampleField::Gap: k.d_N = x; return;
    case SampleField::GapRate: k.v_N = x; return;
    case SampleField::SlipSpeed: k.v_t = x; return;
    case SampleField::NormalForce: k.F_N = x; return;
    case SampleField::TangentialForce: k.F_T = x; return;
    case SampleField::Phase:
      if (!(x >= 0.0 && x < static_cast<double>(kNumPhases) && x == std::floor(x)))
        throw std::invalid_argument(c.name + ": phase codes are 0 (free) to 3 (stick)");
      k.phase = static_cast<Phase>(static_cast<int>(x));
      return;
    default: return;
  }
}

SeriesTable series_table(const LagrangianModel& m, const std::vector<Sample>& samples) {
  SeriesTable t;
  t.columns = timeseries_columns(m);
  t.values.assign(t.columns.size(), std::vector<double>(samples.size()));
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    for (std::size_t i = 0; i < samples.size(); ++i)
      t.values[c][i] = sample_value(samples[i], t.columns[c]);
  return t;
}

bool parse_phase(std::string_view word, Phase& out) {
  for (int k = 0; k < kNumPhases; ++k) {
    if (word == to_string(static_cast<Phase>(k))) {
      out = static_cast<Phase>(k);
      return true;
    }
  }
  return false;
}

bool parse_event_kind(std::string_view word, EventKind& out) {
  for (int k = 0; k < kNumEventKinds; ++k) {
    if (word == to_string(static_cast<EventKind>(k))) {
      out = static_cast<EventKind>(k);
      return true;
    }
  }
  return false;
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

namespace {

/// The double an event's numeric column names (t, d_N, ..., t_accumulation; not contact).
template <class Record>
auto* number_field(Record& e, std::string_view name) {
  if (name == "t") return &e.t;
  if (name == "d_N") return &e.d_N;
  if (name == "v_N_minus") return &e.v_N_minus;
  if (name == "v_N_plus") return &e.v_N_plus;
  if (name == "v_t_minus") return &e.v_t_minus;
  if (name == "v_t_plus") return &e.v_t_plus;
  if (name == "P_N") return &e.P_N;
  if (name == "P_T") return &e.P_T;
  if (name == "F_N") return &e.F_N;
  if (name == "F_T") return &e.F_T;
  if (name == "t_accumulation") return &e.t_accumulation;
  throw std::invalid_argument("not a numeric event column: " + std::string(name));
}

template <class Record>
auto* text_field(Record& e, std::string_view name) {
  if (name == "witness") return &e.witness;
  if (name == "note") return &e.note;
  throw std::invalid_argument("not a text event column: " + std::string(name));
}

}  // namespace

double event_number(const EventRecord& e, std::string_view name) {
  if (name == "contact") return static_cast<double>(e.contact + 1);
  return *number_field(e, name);
}

const std::string& event_text(const EventRecord& e, std::string_view name) {
  return *text_field(e, name);
}

void set_event_field(EventRecord& e, const EventColumn& c, const std::string& text) {
  auto bad = [&](const char* what) {
    return std::invalid_argument("column " + c.name + ": '" + text + "' is not " + what);
  };
  auto number = [&]() {
    char* end = nullptr;
    const double x = std::strtod(text.c_str(), &end);
    if (text.empty() || !end || *end != '\0') throw bad("a number");
    return x;
  };
  switch (c.field) {
    case EventField::Time: e.t = number(); return;
    case EventField::Kind:
      if (!parse_event_kind(text, e.kind)) throw bad("an event kind");
      return;
    case EventField::PhaseBefore:
      if (!parse_phase(text, e.phase_before)) throw bad("a phase");
      return;
    case EventField::PhaseAfter:
      if (!parse_phase(text, e.phase_after)) throw bad("a phase");
      return;
    case EventField::Contact: {
      const double k = number();
      if (!(k >= 1.0 && k == std::floor(k) && k < 1e9)) throw bad("a contact number (1, 2, ...)");
      e.contact = static_cast<int>(k) - 1;
      return;
    }
    case EventField::Text: *text_field(e, c.name) = text; return;
    case EventField::Number:
      // the writer leaves an absent accumulation time empty
      *number_field(e, c.name) =
          text.empty() && c.name == "t_accumulation" ? std::nan("") : number();
      return;
  }
}

}  // namespace rubdyn
