#pragma once
// The names and roles of a model's generalised coordinates. A model declares them once; the
// output columns (timeseries.csv), the initial-state keys of a case file ([initial]), the
// analysis (which coordinates are the rotor and the stator in a contact plane, which one is the
// spin) and the Python module all read them from here, never from a fixed layout.
#include <string>
#include <string_view>
#include <vector>

namespace rubdyn {

/// What a coordinate is, for the layers above the model (analysis, restarts, plots).
enum class CoordinateRole : int {
  Other = 0,
  Spin,    ///< the spin angle theta; its rate is the spin speed omega
  RotorX,  ///< the rotor centre in a contact plane (plane = the contact's index)
  RotorY,
  StatorX,  ///< the stator centre in a contact plane
  StatorY,
  BearingX,  ///< a bearing (support) translation of the rotor
  BearingY,
};
std::string_view to_string(CoordinateRole r);

struct Coordinate {
  std::string name;      ///< q column of timeseries.csv and initial-state key: "x_r"
  std::string rate;      ///< v column of timeseries.csv: "vx_r", "omega"
  std::string rate_key;  ///< initial-state key of the rate: "vx_r", "omega0"
  std::string unit;      ///< "m" or "rad"
  std::string meaning;   ///< one line for the documentation
  CoordinateRole role = CoordinateRole::Other;
  int plane = 0;  ///< contact plane of a Rotor*/Stator* coordinate (0-based contact index)
  /// The integrator's error weights (hybrid/phase_session.cpp): a unit of this coordinate counts
  /// as `length` metres, so it is resolved to atol / length (its rate to atol_v / length). 1 for
  /// deflections and for the models' own angles (the spin angle, weighted by rtol |theta|); a
  /// rotation of a matrices model (an FE shaft's slope, a disc's tilt) has the length of equal
  /// kinetic energy, sqrt(M_ii / m) (MatrixModel, docs/fe-rotors.md).
  double length = 1.0;
};

/// Index of the coordinate with `role` (in contact plane `plane` for the plane roles), or -1.
int find_coordinate(const std::vector<Coordinate>& coords, CoordinateRole role, int plane = 0);
/// Index of the coordinate named `name`, or -1.
int find_coordinate(const std::vector<Coordinate>& coords, std::string_view name);

/// Where a contact plane's centres are among the coordinates: the rotor centre (x, y) and the
/// stator centre (x, y), -1 for a stator fixed at the origin (no coordinates).
struct PlaneCoordinates {
  int rotor_x = -1, rotor_y = -1, stator_x = -1, stator_y = -1;
};
PlaneCoordinates plane_coordinates(const std::vector<Coordinate>& coords, int plane = 0);

}  // namespace rubdyn
