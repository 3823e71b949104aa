// The firmware's version, and the rig's constants every build of the core shares (generated from protocol/rig.toml).
#pragma once

#include <stdint.h>  // uint8_t

#include "rig_gen.h"  // kActuatorCount, kActuatorRangeM, kEncoderCounts, ... (protocol/rig.toml)

namespace mr {

constexpr uint8_t kFirmwareMajor = 0;
constexpr uint8_t kFirmwareMinor = 1;
constexpr uint8_t kFirmwarePatch = 0;

constexpr uint8_t kModuleCount = kModulesX * kModulesY;
constexpr uint8_t kNoActuator = 0xFF;  // telemetry.fault_actuator when no actuator faulted

// Module k's corner c (0..3: one module's order, (-x, -y), (+x, -y), (-x, +y), (+x, +y)) is this actuator, the
// node (k % modules_x + c % 2, k / modules_x + c / 2) of the modules' grid (PROTOCOL.md §5).
constexpr uint8_t corner_actuator(uint8_t module, uint8_t corner) {
  return static_cast<uint8_t>((module / kModulesX + corner / 2) * (kModulesX + 1) + module % kModulesX + corner % 2);
}

// The lowest-numbered module actuator a is a corner of: the one telemetry shows after a jog of a (PROTOCOL.md §5).
constexpr uint8_t lowest_module(uint8_t actuator) {
  return kModuleCount == 1
             ? 0
             : static_cast<uint8_t>((actuator / (kModulesX + 1) > 0 ? actuator / (kModulesX + 1) - 1 : 0) * kModulesX +
                                    (actuator % (kModulesX + 1) > 0 ? actuator % (kModulesX + 1) - 1 : 0));
}

}  // namespace mr
