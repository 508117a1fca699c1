#include "rubdyn/model/coordinates.hpp"

namespace rubdyn {

std::string_view to_string(CoordinateRole r) {
  switch (r) {
    case CoordinateRole::Other: return "other";
    case CoordinateRole::Spin: return "spin";
    case CoordinateRole::RotorX: return "rotor_x";
    case CoordinateRole::RotorY: return "rotor_y";
    case CoordinateRole::StatorX: return "stator_x";
    case CoordinateRole::StatorY: return "stator_y";
    case CoordinateRole::BearingX: return "bearing_x";
    case CoordinateRole::BearingY: return "bearing_y";
  }
  return "?";
}

int find_coordinate(const std::vector<Coordinate>& coords, CoordinateRole role, int plane) {
  const bool planar = role == CoordinateRole::RotorX || role == CoordinateRole::RotorY ||
                      role == CoordinateRole::StatorX || role == CoordinateRole::StatorY;
  for (std::size_t i = 0; i < coords.size(); ++i)
    if (coords[i].role == role && (!planar || coords[i].plane == plane)) return static_cast<int>(i);
  return -1;
}

int find_coordinate(const std::vector<Coordinate>& coords, std::string_view name) {
  for (std::size_t i = 0; i < coords.size(); ++i)
    if (coords[i].name == name) return static_cast<int>(i);
  return -1;
}

PlaneCoordinates plane_coordinates(const std::vector<Coordinate>& coords, int plane) {
  return {find_coordinate(coords, CoordinateRole::RotorX, plane),
          find_coordinate(coords, CoordinateRole::RotorY, plane),
          find_coordinate(coords, CoordinateRole::StatorX, plane),
          find_coordinate(coords, CoordinateRole::StatorY, plane)};
}

}  // namespace rubdyn
