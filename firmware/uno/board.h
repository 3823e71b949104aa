// What the Uno's main loop calls on its board layer (hal_uno.cpp), besides the HAL the core uses.
#pragma once

namespace mr {
namespace board {

// Reads the bench jumper and, on the rig, starts the motors (off) and encoders (present positions = 0 m).
// Returns true in bench mode.
bool begin();
// Runs the actuator loops when their period is due; call on every main-loop pass.
void actuators_tick();

}  // namespace board
}  // namespace mr
