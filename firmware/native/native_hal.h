// Native (virtual MCU) side of the HAL: clock choice, the output byte queue and the ideal actuators.
// One virtual MCU per process: this state is global, as a board's hardware is.
#pragma once

#include <stddef.h>  // size_t
#include <stdint.h>  // uint8_t

#include "protocol_gen.h"  // proto::Clock
#include "rig_config.h"    // kActuatorCount

namespace mr {
namespace native {

// Selects the clock and resets it: the wall clock counts from this call, the simulated one starts at 0.
void reset(proto::Clock kind);
// Moves up to cap queued output bytes to out; returns how many.
size_t take_tx(uint8_t* out, size_t cap);
// Bytes waiting in the output queue.
size_t tx_pending();
// Fault injection: the ideal actuators report these proto::faults bits (stall, encoder) as a board's
// loops would, until actuator power next comes back on.
void inject_actuator_faults(uint16_t faults);

}  // namespace native
}  // namespace mr
