// An array's route (PROTOCOL.md §5, Arrays): which module drives the object, and to where, on its way to the target.
#pragma once

#include <stdint.h>  // uint8_t

#include "rig_config.h"  // kModulesX, kModulesY, kModuleCount

namespace mr {

// The next leg of the object's way: the module whose four actuators drive it now, and the point they drive it to.
struct Leg {
  uint8_t module;  // module k (PROTOCOL.md §5): 0 on one module
  float target_x;  // [m] the target itself once the object is in the target's module; else a waypoint
  float target_y;  // [m]
};

// The centre [m] of module k's column (x) or row (y), the array centred on the origin.
float module_centre_x(uint8_t module, float module_x);
float module_centre_y(uint8_t module, float module_y);

// Where actuator i stands [m], the node of the modules' grid PROTOCOL.md §5 numbers it as: on one module, its corner.
float node_x(uint8_t actuator, float module_x);
float node_y(uint8_t actuator, float module_y);

// Where actuator i stands [m], the node of the modules' grid PROTOCOL.md §5 numbers it as: on one module, its corner.
float node_x(uint8_t actuator, float module_x);
float node_y(uint8_t actuator, float module_y);

// The leg for an object at (x, y) [m] and the target (target_x, target_y) [m] on modules of module_x x module_y [m].
// On one module it is the target. On an array the object goes module by module toward the target's module, along x
// first and then along y (the follow-up paper's Manhattan order over modules). A module drives it to the midpoint of
// the edge it is to cross, pushed band [m] beyond it: the midpoint is where the edge is farthest from the actuators
// that stand on it, which the two modules share. Within band of that edge the object is handed over: the next module
// drives it from there. (The band is configure's tolerance: the distance within which the object counts as there.)
Leg route(float x, float y, float target_x, float target_y, float module_x, float module_y, float band);

}  // namespace mr
