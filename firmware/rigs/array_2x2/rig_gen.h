// The rig's constants every build of the firmware core shares (a 2 x 2 array of 0.5 x 0.5 m modules on 9 actuators). Generated from protocol/rigs/array_2x2.toml by protocol/generate.py; do not edit.
#pragma once

#include <stdint.h>  // uint8_t..uint32_t

namespace mr {

constexpr uint8_t kModulesX = 2;  // Modules along x: the surface is modules_x x modules_y modules, neighbours sharing the actuators of their common edge (PROTOCOL.md §5). (identify_reply.modules_x)
constexpr uint8_t kModulesY = 2;  // Modules along y. (identify_reply.modules_y)
constexpr uint8_t kActuatorCount = 9;  // Linear actuators, one on each node of the modules' grid: (modules_x + 1) x (modules_y + 1) (PROTOCOL.md §5). (identify_reply.actuator_count)
constexpr float kActuatorRangeM = 0.25f;  // [m] Travel of each actuator about its reference height z0: commands live in [-range, +range] (the paper). (identify_reply.actuator_range)
constexpr float kModuleSizeXM = 0.5f;  // [m] Each module's size m along x: one module's actuators at x = +-m/2 (the paper); configure's default.
constexpr float kModuleSizeYM = 0.5f;  // [m] Each module's size n along y: one module's actuators at y = +-n/2 (the paper); configure's default.
constexpr uint16_t kEncoderCounts = 4096;  // Counts per revolution of the 12-bit magnetic encoder (AS5600). (identify_reply.encoder_counts)
constexpr float kPulleyCircumferenceM = 0.04f;  // [m/rev] Belt travel per motor revolution: a GT2 20-tooth pulley. Measure yours (docs/BRINGUP.md). (identify_reply.pulley_circumference)
constexpr float kMotorSpeedRpm = 120.0f;  // [rev/min] Motor shaft speed at full drive: RS Pro 834-7590, 12 V, no load (the paper).
constexpr uint32_t kActuatorPeriodUs = 6000;  // [us] Period of the actuator position loops (250 Hz). (identify_reply.actuator_period)

}  // namespace mr
