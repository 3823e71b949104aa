// The firmware's version, and the rig's constants every build of the core shares (generated from protocol/rig.toml).
#pragma once

#include <stdint.h>  // uint8_t

#include "rig_gen.h"  // kActuatorCount, kActuatorRangeM, kEncoderCounts, ... (protocol/rig.toml)

namespace mr {

constexpr uint8_t kFirmwareMajor = 0;
constexpr uint8_t kFirmwareMinor = 1;
constexpr uint8_t kFirmwarePatch = 0;

}  // namespace mr
