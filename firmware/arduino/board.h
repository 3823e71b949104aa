// What the Uno's main loop calls on its board layer (hal_arduino.cpp): its HAL, start-up and the actuator loops.
#pragma once

#include "hal.h"  // Hal

namespace mr {
namespace board {

// The board's one HAL, for its one Firmware.
Hal& hal();

// Reads the bench jumper and, on the rig, starts the motors (off) and encoders (present positions = 0 m).
// Returns true in bench mode.
bool begin();
// Runs the actuator loops when their period is due; call on every main-loop pass.
void actuators_tick();

}  // namespace board
}  // namespace mr
