// The route across an array's modules, and the hand-over at their shared edges.
#include "route.h"

namespace mr {

namespace {

// The column (or row) among count modules of size [m] whose span holds p [m], clamped to the array; on an edge, the
// one beyond it. Compared with the edges rather than divided by the size: no division in the Mega's frame.
uint8_t cell(float p, float size, uint8_t count) {
  uint8_t at = 0;
  while (at + 1 < count && p >= (static_cast<float>(at + 1) - 0.5f * static_cast<float>(count)) * size) ++at;
  return at;
}

float centre(uint8_t cell_index, float size, uint8_t count) {
  return (static_cast<float>(cell_index) - 0.5f * static_cast<float>(count - 1)) * size;
}

// One axis of the route: the object in cell `at` goes toward cell `to`. Within band of the edge toward `to` it is
// already in the next cell (returned through at); waypoint is then set beyond the edge it is to cross next, if any.
bool leg_along(float p, float size, uint8_t count, uint8_t to, float band, uint8_t& at, float& waypoint) {
  if (at == to) return false;
  const bool up = to > at;
  const float sign = up ? 1.0f : -1.0f;
  const float edge = centre(at, size, count) + sign * 0.5f * size;
  if (sign * (p - edge) > -band) at = static_cast<uint8_t>(up ? at + 1 : at - 1);  // handed over
  if (at == to) return false;
  waypoint = centre(at, size, count) + sign * (0.5f * size + band);
  return true;
}

}  // namespace

float module_centre_x(uint8_t module, float module_x) {
  return kModulesX == 1 ? 0.0f : centre(static_cast<uint8_t>(module % kModulesX), module_x, kModulesX);
}

float module_centre_y(uint8_t module, float module_y) {
  return kModulesY == 1 ? 0.0f : centre(static_cast<uint8_t>(module / kModulesX), module_y, kModulesY);
}

float node_x(uint8_t actuator, float module_x) {
  return (static_cast<float>(actuator % (kModulesX + 1)) - 0.5f * static_cast<float>(kModulesX)) * module_x;
}

float node_y(uint8_t actuator, float module_y) {
  return (static_cast<float>(actuator / (kModulesX + 1)) - 0.5f * static_cast<float>(kModulesY)) * module_y;
}

Leg route(float x, float y, float target_x, float target_y, float module_x, float module_y, float band) {
  if (kModuleCount == 1) return Leg{0, target_x, target_y};
  uint8_t col = cell(x, module_x, kModulesX);
  uint8_t row = cell(y, module_y, kModulesY);
  Leg leg{0, target_x, target_y};
  float waypoint = 0.0f;
  if (leg_along(x, module_x, kModulesX, cell(target_x, module_x, kModulesX), band, col, waypoint)) {
    leg.target_x = waypoint;
    leg.target_y = centre(row, module_y, kModulesY);  // the shared edge's midpoint
  } else if (leg_along(y, module_y, kModulesY, cell(target_y, module_y, kModulesY), band, row, waypoint)) {
    leg.target_x = centre(col, module_x, kModulesX);
    leg.target_y = waypoint;
  }
  leg.module = static_cast<uint8_t>(row * kModulesX + col);
  return leg;
}

}  // namespace mr
