// One linear actuator's position loop: multi-turn encoder unwrapping, PID to a motor duty, soft limits, stall.
//
// Positions follow the commands' convention (PROTOCOL.md §5): [m] from the reference height z0, + lowers
// the corner; a positive duty drives the corner down. The board maps duty and counts to its wiring.
#pragma once

#include <stdint.h>  // uint16_t, int32_t

#include "rig_gen.h"  // kEncoderCounts (protocol/rig.toml)

namespace mr {

// A 12-bit angle that wraps every revolution, as a count that does not. Correct while the shaft turns
// less than half a revolution between readings (at the 250 Hz loop rate: 7.5 rev/s; the motor tops out
// at 2 rev/s).
class EncoderUnwrap {
 public:
  void reset(uint16_t raw);      // this reading becomes count 0
  int32_t update(uint16_t raw);  // counts since reset, + when the raw angle increases
  int32_t count() const { return count_; }

 private:
  uint16_t last_ = 0;
  int32_t count_ = 0;
};

struct ActuatorConfig {
  float metres_per_count;  // [m/count] pulley circumference / kEncoderCounts; negative if the encoder counts
                           // down as the corner lowers
  float kp;                // [1/m] duty per metre of error
  float ki;                // [1/(m s)]
  float kd;                // [s/m] duty per metre per second of motion (on the measurement)
  float max_duty;          // [-] output limit, 0..1
  float deadband_m;        // [m] within this error the motor is not driven
  float soft_limit_m;      // [m] setpoints are clamped to +-this; no drive further out beyond it
  float stall_duty;        // [-] at or above this |duty| the carriage must move ...
  float stall_travel_m;    // [m] ... at least this far ...
  float stall_time_s;      // [s] ... within this time, or the loop reports a stall
};

class ActuatorLoop {
 public:
  // Takes this encoder reading as position 0 m (zeroing) and clears the integral and any stall.
  void reset(uint16_t raw);
  // One iteration dt_s [s] after the previous one: returns the duty in [-max_duty, max_duty].
  float step(const ActuatorConfig& config, float setpoint_m, uint16_t raw, float dt_s);
  // Forgets the integral and the stall timer (power cut: the carriage is not being driven).
  void idle();

  float position_m() const { return position_m_; }
  bool stalled() const { return stalled_; }
  void clear_stall() { stalled_ = false; }

 private:
  EncoderUnwrap encoder_;
  float position_m_ = 0.0f;
  float integral_ = 0.0f;       // [-] the integral term's duty
  float window_s_ = 0.0f;       // [s] time driven hard without travelling stall_travel_m
  float window_from_m_ = 0.0f;  // [m] where that window started
  bool stalled_ = false;
};

}  // namespace mr
