// Supervisor: states, configuration validation, deadman, and the controller step at each position frame.
//
// States: idle (surface level, jog allowed) -> start -> running <-> reached (within tolerance; control
// goes on so the object stays) ; a fault -> fault (latched): a deadman timeout levels the surface, a stalled
// or silent actuator cuts actuator power ; emergency_stop -> estop (actuator power cut, latched) ; stop ->
// idle from anywhere, clearing faults. Every fault, the emergency stop included, goes through shutdown().
// Every command is validated whole before anything changes: a refused command changes nothing.
#pragma once

#include <stdint.h>  // uint8_t..uint32_t

#include "controller.h"    // TiltController, ControllerOutput
#include "protocol_gen.h"  // proto messages, ErrorCode, State
#include "rig_config.h"    // kActuatorCount

namespace mr {

class Supervisor {
 public:
  Supervisor();

  // Each returns kOk or the error to nack with; field is set to the offending field's index (or kNoField). None
  // looks at the state: the dispatcher runs a command only in the states its message's schema entry names
  // (proto::taken_in), so configure, configure_pid, configure_schedule, configure_cascade, start, jog and zero run in
  // idle and set_target in any state but estop.
  proto::ErrorCode configure(const proto::Configure& msg, uint8_t& field);
  proto::ErrorCode configure_pid(const proto::ConfigurePid& msg, uint8_t& field);
  proto::ErrorCode configure_schedule(const proto::ConfigureSchedule& msg, uint8_t& field);
  proto::ErrorCode configure_cascade(const proto::ConfigureCascade& msg, uint8_t& field);
  proto::ErrorCode set_target(const proto::SetTarget& msg, uint8_t& field);
  proto::ErrorCode start(uint32_t now_us);
  void stop();
  void emergency_stop();
  proto::ErrorCode jog(const proto::Jog& msg, uint8_t& field);
  // Homing: the actuators in the mask now stand at 0 m; their commands become 0 (hold there). Only in idle.
  proto::ErrorCode zero(const proto::Zero& msg, uint8_t& field);
  // The one shutdown path: latches the fault bits (proto::faults), levels the commands, and enters estop
  // (for kEstop) or fault. Actuator power stays off while estop, stall or encoder is latched.
  void shutdown(uint16_t faults);
  // A camera frame received at now_us (firmware clock); runs one controller step when running.
  proto::ErrorCode position(const proto::ObjectPosition& msg, uint32_t now_us, uint8_t& field);
  // Forgets the camera's frame counter and capture-time history (a new host or a new run).
  void forget_positions() { has_frame_ = false; }
  // Deadman check; call often (every main-loop pass).
  void tick(uint32_t now_us);

  proto::State state() const { return state_; }
  uint16_t faults() const { return faults_; }
  bool actuator_power() const;
  const ControllerOutput& output() const { return output_; }  // tilts and commands to apply now
  const proto::Configure& config() const { return config_; }
  uint16_t last_frame() const { return last_frame_; }
  // [ms] since the last valid (visible) position, saturated at 65535; 65535 if none yet.
  uint16_t position_age_ms(uint32_t now_us) const;

 private:
  void level();
  void take_configure();  // the controller's share of config_ into control_
  void take(const proto::ConfigureSchedule& msg);
  void take(const proto::ConfigureCascade& msg);
  // A controller's own settings: taken whole when the schema's checks pass, else refused and nothing changes.
  template <class Message>
  proto::ErrorCode take_valid(const Message& msg, uint8_t& field);

  proto::Configure config_;
  ControllerConfig control_;  // what every controller step reads: kept, not rebuilt on the Uno's small stack
  TiltController controller_;
  ControllerOutput output_;
  proto::State state_ = proto::State::kIdle;
  uint16_t faults_ = 0;
  float target_x_ = 0.0f;  // [m]
  float target_y_ = 0.0f;  // [m]
  bool has_target_ = false;
  bool has_frame_ = false;             // a frame was accepted since boot, identify or start
  uint16_t last_frame_ = 0;            // its counter
  uint32_t last_capture_us_ = 0;       // its capture time [us], host clock
  uint32_t last_frame_at_us_ = 0;      // when it arrived [us], firmware clock
  bool has_valid_ = false;             // a visible position was accepted since boot
  uint32_t last_valid_us_ = 0;         // when it arrived [us], firmware clock
  uint32_t deadman_from_us_ = 0;       // last valid position or start, whichever is later [us], firmware clock
  bool has_step_ = false;              // the controller stepped since start
  uint32_t last_step_capture_us_ = 0;  // capture time of that step [us], host clock
};

}  // namespace mr
