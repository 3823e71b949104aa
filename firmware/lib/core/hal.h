// Hardware abstraction: the few board functions the core calls, as an interface each board implements
// (firmware/native for the virtual MCU, the Uno board code for the real rig). The core holds no global state:
// each Firmware talks to the Hal it was given, so the native build runs many side by side; the Uno has one.
#pragma once

#include <stdint.h>  // uint8_t, uint32_t

#include "protocol_gen.h"  // proto::ErrorCode, proto::Clock
#include "rig_config.h"    // kActuatorCount

namespace mr {

// What the actuators latched since power last came on.
struct ActuatorFaults {
  uint16_t bits;     // proto::faults bits: stall, encoder
  uint8_t actuator;  // the actuator whose fault latched first; kNoActuator if none
};

class Hal {
 public:
  // Monotonic firmware clock [us]; wraps after 2^32 us (71.6 min); the core only takes differences.
  virtual uint32_t now_us() const = 0;

  // Queues bytes for the serial link; a frame is written whole or not at all (never blocks).
  virtual void serial_write(const uint8_t* data, uint8_t len) = 0;

  // Setpoints of the actuator position loops [m], + lowers the corner, already within the range.
  virtual void actuators_command(const float (&command)[kActuatorCount]) = 0;
  // Measured actuator positions [m], same convention.
  virtual void actuators_measured(float (&measured)[kActuatorCount]) const = 0;
  // false cuts every actuator output at once (emergency stop, faults); true restores them.
  virtual void actuators_power(bool on) = 0;
  // The actuators in the mask (bit i: actuator i) now stand at 0 m (homing).
  virtual void actuators_zero(uint16_t mask) = 0;
  // proto::faults bits the actuators latched (stall, encoder), and the actuator whose fault latched first
  // (kNoActuator if none); both cleared when power comes back on.
  virtual ActuatorFaults actuator_faults() const = 0;
  // Actuator-loop runs that started a whole period or more late since boot (0 for ideal actuators).
  virtual uint32_t actuator_overruns() const = 0;

  // Which clock now_us() reads.
  virtual proto::Clock clock_kind() const = 0;
  // Simulated clock only: set now_us() to t [us]. kUnsupported on a wall clock; kOutOfRange if t < now.
  virtual proto::ErrorCode sim_clock_set(uint32_t t_us) = 0;

 protected:
  ~Hal() = default;  // never deleted through the interface (the Uno has no heap)
};

}  // namespace mr
