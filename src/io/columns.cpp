#include "rubdyn/io/columns.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <limits>
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

std::vector<std::string> comma_words(std::string_view selection) {
  std::vector<std::string> words;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = selection.find(',', start);
    std::string_view w = selection.substr(
        start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    const auto a = w.find_first_not_of(" \t"), b = w.find_last_not_of(" \t");
    words.emplace_back(a == std::string_view::npos ? std::string_view() : w.substr(a, b - a + 1));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return words;
}

std::string brief_coordinate_list(const std::vector<Coordinate>& coords) {
  std::string names;
  for (std::size_t i = 0; i < coords.size() && i < 12; ++i)
    names += (i ? ", " : "") + coords[i].name;
  if (coords.size() > 12) names += fmt::format(", ... ({} in all)", coords.size());
  return names;
}

std::string output_coordinates_problem(std::string_view selection,
                                       const std::vector<Coordinate>& coords) {
  const std::vector<std::string> words = comma_words(selection);
  if (words.size() == 1 && words.front() == "all") return "";
  for (const std::string& w : words) {
    if (w.empty())
      return "must be \"all\", or a comma-separated list of coordinate names and the word "
             "\"contacts\" (an empty word)";
    if (w == "all")
      return "\"all\" stands alone (every coordinate); a list names the coordinates written "
             "besides those of the contacts and the spin";
    if (w == "contacts" || find_coordinate(coords, w) >= 0) continue;
    return fmt::format(
        "'{}' is no coordinate of the model (its coordinates: {}); the words are \"all\" alone, "
        "or coordinate names and \"contacts\"",
        w, brief_coordinate_list(coords));
  }
  return "";
}

bool writes_every_coordinate(const LagrangianModel& m, std::string_view selection) {
  return written_coordinates(m, selection).size() == m.coordinates().size();
}

std::vector<int> written_coordinates(const LagrangianModel& m, std::string_view selection) {
  const auto& coords = m.coordinates();
  const int n = static_cast<int>(coords.size());
  std::vector<char> keep(coords.size(), 0);
  const std::vector<std::string> words = comma_words(selection);
  const bool all = words.size() == 1 && words.front() == "all";
  for (int i = 0; i < n; ++i)
    keep[static_cast<std::size_t>(i)] =
        all || coords[static_cast<std::size_t>(i)].role != CoordinateRole::Other;
  if (!all)
    for (const std::string& w : words)
      if (const int i = find_coordinate(coords, w); i >= 0) keep[static_cast<std::size_t>(i)] = 1;
  std::vector<int> out;
  for (int i = 0; i < n; ++i)
    if (keep[static_cast<std::size_t>(i)]) out.push_back(i);
  return out;
}

std::vector<SampleColumn> timeseries_columns(const LagrangianModel& m, std::string_view selection) {
  std::vector<SampleColumn> all = timeseries_columns(m);
  const std::vector<int> written = written_coordinates(m, selection);
  if (written.size() == m.coordinates().size()) return all;
  std::vector<char> keep(m.coordinates().size(), 0);
  for (int i : written) keep[static_cast<std::size_t>(i)] = 1;
  std::vector<SampleColumn> out;
  for (auto& c : all) {
    const bool coordinate = c.field == SampleField::Position || c.field == SampleField::Velocity;
    if (!coordinate || keep[static_cast<std::size_t>(c.index)]) out.push_back(std::move(c));
  }
  return out;
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

SeriesTable series_table(const LagrangianModel& m, const std::vector<Sample>& samples,
                         std::string_view selection) {
  SeriesTable t;
  t.columns = timeseries_columns(m, selection);
  t.values.assign(t.columns.size(), std::vector<double>(samples.size()));
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    for (std::size_t i = 0; i < samples.size(); ++i)
      t.values[c][i] = sample_value(samples[i], t.columns[c]);
  return t;
}

std::vector<Sample> samples_of(const LagrangianModel& m, const SeriesTable& t) {
  const std::size_t n = t.rows();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Sample blank(m.num_dofs(), m.contact_count(), static_cast<int>(m.observables().size()));
  blank.q.setConstant(nan);  // a coordinate the table lacks: not written, not zero
  blank.v.setConstant(nan);
  std::vector<Sample> out(n, blank);
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    for (std::size_t i = 0; i < n; ++i) set_sample_value(out[i], t.columns[c], t.values[c][i]);
  return out;
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
