// Hardware abstraction: the few board functions the core calls. One implementation per build
// (firmware/native for the virtual MCU, the Uno board code for the real rig); chosen at link time.
#pragma once

#include <stdint.h>  // uint8_t, uint32_t

#include "protocol_gen.h"  // proto::ErrorCode, proto::Clock
#include "rig_config.h"    // kActuatorCount

namespace mr {
namespace hal {

// Monotonic firmware clock [us]; wraps after 2^32 us (71.6 min); the core only takes differences.
uint32_t now_us();

// Queues bytes for the serial link; a frame is written whole or not at all (never blocks).
void serial_write(const uint8_t* data, uint8_t len);

// Setpoints of the actuator position loops [m], + lowers the corner, already within the range.
void actuators_command(const float (&command)[kActuatorCount]);
// Measured actuator positions [m], same convention.
void actuators_measured(float (&measured)[kActuatorCount]);
// false cuts every actuator output at once (emergency stop, faults); true restores them.
void actuators_power(bool on);
// The actuators in the mask (bit i: actuator i) now stand at 0 m (homing).
void actuators_zero(uint8_t mask);
// proto::faults bits the actuators latched (stall, encoder); cleared when power comes back on.
uint16_t actuator_faults();
// Actuator-loop runs that started a whole period or more late since boot (0 for ideal actuators).
uint32_t actuator_overruns();

// Which clock now_us() reads.
proto::Clock clock_kind();
// Simulated clock only: set now_us() to t [us]. kUnsupported on a wall clock; kOutOfRange if t < now.
proto::ErrorCode sim_clock_set(uint32_t t_us);

}  // namespace hal
}  // namespace mr
