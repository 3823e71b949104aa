// The four actuator position loops at a fixed rate, with power, zeroing and fault flags; the board does the I/O.
#pragma once

#include <stdint.h>  // uint8_t..uint32_t

#include "actuator.h"    // ActuatorLoop, ActuatorConfig
#include "rig_config.h"  // kActuatorCount

namespace mr {

// The board's side of the actuators: Arduino calls on the Uno, motor and encoder models in the host tests.
class ActuatorIo {
 public:
  // The raw 12-bit angle of one encoder; false if it did not answer.
  virtual bool encoder_read(uint8_t actuator, uint16_t& raw) = 0;
  // Motor drive in [-1, 1]; + lowers the corner (the board applies its wiring's direction).
  virtual void motor_write(uint8_t actuator, float duty) = 0;
  // Every motor output to 0 at once: the shutdown and watchdog path.
  virtual void motors_off() = 0;

 protected:
  ~ActuatorIo() = default;
};

class ActuatorBank {
 public:
  static constexpr uint8_t kReadFailuresForFault = 3;  // consecutive failed reads of one encoder

  // config is kept by reference, not copied (the Uno's RAM): it must outlive the bank, as the board's constant does.
  ActuatorBank(ActuatorIo& io, const ActuatorConfig& config, uint32_t period_us)
      : io_(io), config_(config), period_us_(period_us) {}

  // Reads every encoder and takes the present positions as 0 m (the carriages must stand at z0).
  void begin(uint32_t now_us);
  // Whether a period has passed since the last run.
  bool due(uint32_t now_us) const { return now_us - last_run_us_ >= period_us_; }
  // Runs the loops when they are due; call on every main-loop pass.
  void tick(uint32_t now_us);
  void set_setpoints(const float (&setpoints_m)[kActuatorCount]);
  // Off: every motor off at once, loops idle. Off -> on: the loops drive again, latched stalls clear.
  void power(bool on);
  // Present positions of the actuators in the mask (bit i: actuator i) become 0 m.
  void zero(uint16_t mask);
  void measured(float (&out_m)[kActuatorCount]) const;
  // proto::faults bits (stall, encoder) latched since the last power-on.
  uint16_t faults() const { return faults_; }
  uint8_t fault_actuator() const { return fault_actuator_; }  // whose fault latched first; kNoActuator if none
  // Loop runs that came more than one whole period late since boot.
  uint32_t overruns() const { return overruns_; }

 private:
  void latch(uint16_t fault, uint8_t actuator);  // the first fault since power-on also names its actuator

  ActuatorIo& io_;
  const ActuatorConfig& config_;
  const uint32_t period_us_;
  ActuatorLoop loop_[kActuatorCount];
  float setpoint_m_[kActuatorCount] = {};
  uint16_t raw_[kActuatorCount] = {};
  uint8_t read_failures_[kActuatorCount] = {};
  uint32_t last_run_us_ = 0;
  uint32_t overruns_ = 0;
  uint16_t faults_ = 0;
  uint8_t fault_actuator_ = kNoActuator;
  bool powered_ = true;
};

}  // namespace mr
