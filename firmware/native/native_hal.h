// The native (virtual MCU) board: monotonic or simulated clock, the output byte queue and ideal actuators.
// Each instance is one board; many run side by side in one process (the C library, the fuzzer, the tests).
#pragma once

#include <stddef.h>  // size_t
#include <stdint.h>  // uint8_t

#include <deque>  // output queue

#include "hal.h"              // Hal
#include "ideal_actuators.h"  // IdealActuators, SimulatedClock
#include "protocol_gen.h"     // proto::Clock
#include "rig_config.h"       // kActuatorCount

namespace mr {

class NativeHal final : public Hal {
 public:
  // The wall clock counts from construction; the simulated one starts at 0.
  explicit NativeHal(proto::Clock kind);

  // Moves up to cap queued output bytes to out; returns how many.
  size_t take_tx(uint8_t* out, size_t cap);
  // Bytes waiting in the output queue.
  size_t tx_pending() const { return tx_.size(); }
  // Fault injection: the ideal actuators report these proto::faults bits (stall, encoder) of this actuator as a
  // board's loops would, until actuator power next comes back on.
  void inject_actuator_faults(uint16_t faults, uint8_t actuator) {
    if (!injected_.bits) injected_.actuator = actuator;
    injected_.bits = static_cast<uint16_t>(injected_.bits | faults);
  }

  uint32_t now_us() const override;
  void serial_write(const uint8_t* data, uint8_t len) override { tx_.insert(tx_.end(), data, data + len); }
  void actuators_command(const float (&command)[kActuatorCount]) override { actuators_.command(command); }
  void actuators_measured(float (&measured)[kActuatorCount]) const override { actuators_.measured(measured); }
  void actuators_power(bool on) override;
  void actuators_zero(uint16_t mask) override { actuators_.zero(mask); }
  ActuatorFaults actuator_faults() const override { return injected_; }
  uint32_t actuator_overruns() const override { return 0; }  // ideal actuators have no loop to run late
  proto::Clock clock_kind() const override { return clock_; }
  proto::ErrorCode sim_clock_set(uint32_t t_us) override;

 private:
  proto::Clock clock_;
  uint64_t wall_origin_ns_;
  SimulatedClock sim_clock_;
  std::deque<uint8_t> tx_;
  IdealActuators actuators_;
  ActuatorFaults injected_ = {0, kNoActuator};
  bool power_ = true;
};

}  // namespace mr
