// Actuator bank: fixed-rate loops, encoder and stall faults, power and zeroing.
#include "actuators.h"

#include "protocol_gen.h"  // proto::faults

namespace mr {

constexpr uint8_t ActuatorBank::kReadFailuresForFault;  // C++14: the definition of an odr-used constant

void ActuatorBank::begin(uint32_t now_us) {
  for (uint8_t i = 0; i < kActuatorCount; ++i) {
    if (!io_.encoder_read(i, raw_[i])) {
      latch(proto::faults::kEncoder, i);
      read_failures_[i] = kReadFailuresForFault;
    }
    loop_[i].reset(raw_[i]);
    setpoint_m_[i] = 0.0f;
  }
  last_run_us_ = now_us;
  if (faults_) io_.motors_off();
}

void ActuatorBank::tick(uint32_t now_us) {
  if (!due(now_us)) return;
  const uint32_t elapsed_us = now_us - last_run_us_;
  if (elapsed_us >= 2 * period_us_) ++overruns_;
  last_run_us_ = now_us;
  const float dt_s = static_cast<float>(elapsed_us) * 1e-6f;
  for (uint8_t i = 0; i < kActuatorCount; ++i) {
    if (io_.encoder_read(i, raw_[i])) {
      read_failures_[i] = 0;
    } else if (read_failures_[i] < kReadFailuresForFault && ++read_failures_[i] == kReadFailuresForFault) {
      latch(proto::faults::kEncoder, i);
    }
    if (read_failures_[i]) continue;  // a missed reading: keep the last duty for at most two periods
    const float duty = loop_[i].step(config_, setpoint_m_[i], raw_[i], dt_s);
    if (loop_[i].stalled()) latch(proto::faults::kStall, i);
    if (powered_ && !faults_) io_.motor_write(i, duty);
  }
  if (!powered_ || faults_) io_.motors_off();
}

void ActuatorBank::set_setpoints(const float (&setpoints_m)[kActuatorCount]) {
  for (uint8_t i = 0; i < kActuatorCount; ++i) setpoint_m_[i] = setpoints_m[i];
}

void ActuatorBank::power(bool on) {
  if (on == powered_) return;
  powered_ = on;
  if (!on) {
    io_.motors_off();
    for (ActuatorLoop& loop : loop_) loop.idle();
    return;
  }
  for (uint8_t i = 0; i < kActuatorCount; ++i) {
    loop_[i].clear_stall();
    loop_[i].idle();
    if (read_failures_[i] >= kReadFailuresForFault) read_failures_[i] = 0;  // retried at the next run
  }
  faults_ = 0;
  fault_actuator_ = kNoActuator;
}

void ActuatorBank::latch(uint16_t fault, uint8_t actuator) {
  if (!faults_) fault_actuator_ = actuator;
  faults_ |= fault;
}

void ActuatorBank::zero(uint16_t mask) {
  for (uint8_t i = 0; i < kActuatorCount; ++i) {
    if (mask & (1u << i)) loop_[i].reset(raw_[i]);
  }
}

void ActuatorBank::measured(float (&out_m)[kActuatorCount]) const {
  for (uint8_t i = 0; i < kActuatorCount; ++i) out_m[i] = loop_[i].position_m();
}

}  // namespace mr
