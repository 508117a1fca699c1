#pragma once
// The column tables of the output files: the one statement of what timeseries.csv and
// events.csv hold. The writer (output_folder.hpp), the reader (output_reader.hpp), the Python
// bindings and the Python package all read these tables; none spells the columns out itself.
//
// timeseries.csv, for a model with coordinates q_1..q_n and K contacts:
//   t, <q names>, <rate names>, <the model's observables>, then per contact d_N, v_N, v_t, F_N,
//   F_T, phase
// (the coordinates' names from the model, e.g. x_b, ..., theta, ..., omega, ...; with K > 1 the
// contact columns carry the contact's number: d_N_1, ..., phase_K).
// events.csv: t, kind, phase_before, phase_after, d_N, v_N_minus, v_N_plus, v_t_minus,
//   v_t_plus, P_N, P_T, F_N, F_T, t_accumulation, witness, note (and contact, 1-based, when the
//   model has several contacts).
#include <string>
#include <string_view>
#include <vector>

#include "rubdyn/core/run_types.hpp"
#include "rubdyn/model/coordinates.hpp"
#include "rubdyn/model/lagrangian_model.hpp"

namespace rubdyn {

/// What a timeseries column holds.
enum class SampleField {
  Time,
  Position,
  Velocity,
  Observable,  ///< one of the model's observables (LagrangianModel::observables)
  Gap,
  GapRate,
  SlipSpeed,
  NormalForce,
  TangentialForce,
  Phase
};

struct SampleColumn {
  std::string name;
  SampleField field = SampleField::Time;
  int index = 0;  ///< the coordinate (Position, Velocity), observable, or contact (the others)
  std::string unit;
};

/// timeseries.csv's columns for a model with these coordinates, observables and contacts.
std::vector<SampleColumn> timeseries_columns(const std::vector<Coordinate>& coords,
                                             const std::vector<Observable>& observables,
                                             int contacts);
std::vector<SampleColumn> timeseries_columns(const LagrangianModel& m);

/// A column's value in a sample, as a number (Phase: its code, the Phase enum value).
double sample_value(const Sample& s, const SampleColumn& c);
/// Sets a column's value in a sample (the inverse of sample_value). A Phase value must be a
/// phase's code (0 free .. 3 stick): std::invalid_argument otherwise.
void set_sample_value(Sample& s, const SampleColumn& c, double x);

/// Samples as columns: the model's column table and each column's values in sample order (a
/// phase column: the Phase codes). What the reader makes of timeseries.csv, and what the Python
/// bindings hand to numpy.
struct SeriesTable {
  std::vector<SampleColumn> columns;
  std::vector<std::vector<double>> values;  ///< values[c][row]
  std::size_t rows() const { return values.empty() ? 0 : values.front().size(); }
};
/// The samples of a run of `m` as a SeriesTable.
SeriesTable series_table(const LagrangianModel& m, const std::vector<Sample>& samples);

/// What an events column holds.
enum class EventField { Time, Kind, PhaseBefore, PhaseAfter, Number, Text, Contact };

struct EventColumn {
  std::string name;
  EventField field = EventField::Number;
};

/// events.csv's columns (the contact column only when contacts > 1).
std::vector<EventColumn> event_columns(int contacts = 1);
/// A numeric event column's value (Number fields by name: d_N, v_N_minus, ..., t_accumulation).
double event_number(const EventRecord& e, std::string_view name);
/// A text column's value (witness, note).
const std::string& event_text(const EventRecord& e, std::string_view name);
/// Sets an event column from the text the writer (output_files.cpp) put in events.csv: numbers
/// (an empty t_accumulation: NaN), the kind and phases as words, the 1-based contact number.
/// Throws std::invalid_argument naming the column and the value it cannot read.
void set_event_field(EventRecord& e, const EventColumn& c, const std::string& text);

/// The phase / event kind named by a word of the output files (false: no such word).
bool parse_phase(std::string_view word, Phase& out);
bool parse_event_kind(std::string_view word, EventKind& out);

}  // namespace rubdyn
