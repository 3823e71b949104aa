// Rig constants and the firmware version: the numbers every build of the core shares.
#pragma once

#include <stdint.h>  // uint8_t

namespace mr {

constexpr uint8_t kFirmwareMajor = 0;
constexpr uint8_t kFirmwareMinor = 1;
constexpr uint8_t kFirmwarePatch = 0;

constexpr uint8_t kActuatorCount = 4;
// Travel of each actuator about its reference height z0 [m]: commands live in [-range, +range].
constexpr float kActuatorRange = 0.25f;

}  // namespace mr
