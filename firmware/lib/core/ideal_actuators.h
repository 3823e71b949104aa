// Actuators that are where they are told, and a clock that sim_clock sets: the virtual MCU's, and the Uno's bench mode.
#pragma once

#include <stdint.h>  // uint8_t, uint32_t

#include "protocol_gen.h"  // proto::ErrorCode
#include "rig_config.h"    // kActuatorCount

namespace mr {

// With power on they take every command at once; with power off they stay where they were.
class IdealActuators {
 public:
  void command(const float (&command_m)[kActuatorCount]) {
    if (!powered_) return;
    for (uint8_t i = 0; i < kActuatorCount; ++i) position_m_[i] = command_m[i];
  }
  void measured(float (&out_m)[kActuatorCount]) const {
    for (uint8_t i = 0; i < kActuatorCount; ++i) out_m[i] = position_m_[i];
  }
  void power(bool on) { powered_ = on; }
  // Zeroing: the supervisor sets these actuators' commands to 0, so their positions follow.
  void zero(uint16_t mask) {
    for (uint8_t i = 0; i < kActuatorCount; ++i) {
      if (mask & (1u << i)) position_m_[i] = 0.0f;
    }
  }

 private:
  float position_m_[kActuatorCount] = {};
  bool powered_ = true;
};

// Time [us] that only moves when set, and never backwards.
class SimulatedClock {
 public:
  uint32_t now_us() const { return now_us_; }
  proto::ErrorCode set(uint32_t t_us) {
    if (static_cast<int32_t>(t_us - now_us_) < 0) return proto::ErrorCode::kOutOfRange;
    now_us_ = t_us;
    return proto::ErrorCode::kOk;
  }

 private:
  uint32_t now_us_ = 0;
};

}  // namespace mr
