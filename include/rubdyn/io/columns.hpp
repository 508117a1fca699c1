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

// ---- which coordinates a run writes (output.coordinates) -------------------------------------
// A wide model (a finite-element rotor of hundreds of coordinates) need not write every one:
// output.coordinates is "all" (the default), or a comma-separated list of words, each a
// coordinate's name or "contacts". The coordinates that have a role (coordinates.hpp: the spin,
// the contact planes' rotor and stator centres, the bearings: what the analysis, the plots and
// compare read) are always written; the names add others. The model's observables and the
// contact columns are always written. The columns keep the model's order, whatever the list's.
// A run that does not write every coordinate writes the full state to state.csv (the
// timeseries' format with every coordinate) at its first sample, after each event and at its
// last sample: what `--from` restarts read.

/// Models of more coordinates than this are wide: output.coordinates defaults to "contacts"
/// (a 400-coordinate rotor would write 800 columns nobody reads), "all" up to it (every
/// built-in rigid model, the paper's and FE rotors up to 15 nodes).
inline constexpr std::size_t kWideModelCoordinates = 64;
/// output.coordinates when the case does not give it, for a case of n coordinates.
inline const char* default_output_coordinates(std::size_t n) {
  return n > kWideModelCoordinates ? "contacts" : "all";
}

/// The words of a comma-separated list (output.coordinates, rotor.rotations): split at commas,
/// blanks trimmed; empty words kept, for the validator to name.
std::vector<std::string> comma_words(std::string_view list);
/// The first twelve of these coordinates' names for a message, "x0, y0, ..., ... (52 in all)".
std::string brief_coordinate_list(const std::vector<Coordinate>& coords);
/// The problem with an output.coordinates value for a case whose coordinates are `coords`
/// (the [initial] coordinates: a prescribed spin's theta included), or "" when it is valid:
/// "all" alone, otherwise each word "contacts" or one of the coordinates' names.
std::string output_coordinates_problem(std::string_view selection,
                                       const std::vector<Coordinate>& coords);
/// Whether `selection` writes every coordinate of `m`.
bool writes_every_coordinate(const LagrangianModel& m, std::string_view selection);
/// The coordinates of `m` that a run with this output.coordinates writes (ascending indices):
/// those with a role and those named (a name that is no coordinate of m, e.g. the spin angle of
/// a prescribed spin, which is an observable of m, adds nothing).
std::vector<int> written_coordinates(const LagrangianModel& m, std::string_view selection);
/// timeseries.csv's columns for a run of `m` with this output.coordinates: timeseries_columns(m)
/// without the positions and rates of the coordinates it does not write.
std::vector<SampleColumn> timeseries_columns(const LagrangianModel& m, std::string_view selection);

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
/// The samples of a run of `m` as a SeriesTable (of the columns output.coordinates =
/// `selection` writes).
SeriesTable series_table(const LagrangianModel& m, const std::vector<Sample>& samples,
                         std::string_view selection = "all");
/// Samples from a SeriesTable of `m`'s columns (the inverse of series_table): the positions and
/// rates of the coordinates the table lacks are NaN, every other field of a sample its column's
/// value. Throws std::invalid_argument for a phase column whose value is no phase code.
std::vector<Sample> samples_of(const LagrangianModel& m, const SeriesTable& t);

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
