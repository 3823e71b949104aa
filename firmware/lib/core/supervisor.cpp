// Supervisor state machine and validation.
#include "supervisor.h"

#include <math.h>  // fabsf

#include "plane.h"  // max_tilt_deg
#include "route.h"  // route, Leg
#include "wire.h"   // is_finite

namespace mr {

namespace {

using proto::ErrorCode;
using proto::State;

constexpr uint16_t kMinTelemetryPeriodMs = 5;  // [ms] faster than the link can carry
constexpr float kTiltLimitSlackDeg = 1e-4f;    // [deg] float rounding of the derived limit

bool running(State s) { return s == State::kRunning || s == State::kReached; }

// [m] Half the surface along x and y: one module, or an array of kModulesX x kModulesY of them.
float half_x(const proto::Configure& c) { return 0.5f * kModulesX * c.module_x; }
float half_y(const proto::Configure& c) { return 0.5f * kModulesY * c.module_y; }

// A finite coordinate [m] within +-half (a NaN is not).
bool within(float v, float half) { return fabsf(v) <= half; }

}  // namespace

Supervisor::Supervisor() {
  proto::set_defaults(config_);
  take_configure();
  for (uint8_t axis = 0; axis < kPidCount; ++axis) {
    const proto::PidDefaults& d = proto::kPidDefaults[axis];
    control_.pid[axis] = PidGains{d.kp, d.ki, d.kd, d.integral_limit};
  }
  proto::ConfigureSchedule schedule;
  proto::set_defaults(schedule);
  take(schedule);
  proto::ConfigureCascade cascade;
  proto::set_defaults(cascade);
  take(cascade);
  level();
}

void Supervisor::level() {
  output_.tilt_zx = 0.0f;
  output_.tilt_zy = 0.0f;
  output_.module = 0;
  for (float& a : output_.command) a = 0.0f;
}

void Supervisor::take_configure() {
  control_.kind = static_cast<proto::Controller>(config_.controller);
  control_.module_x = config_.module_x;
  control_.module_y = config_.module_y;
  control_.tilt_limit = config_.tilt_limit;
  control_.noise_amplitude = config_.noise_amplitude;
  control_.velocity_filter = config_.velocity_filter;
}

void Supervisor::take(const proto::ConfigureSchedule& msg) {
  control_.schedule = ScheduleConfig{msg.edge_zone, msg.edge_gain, msg.edge_tilt, msg.edge_brake, msg.brake_speed};
}

void Supervisor::take(const proto::ConfigureCascade& msg) {
  control_.cascade = CascadeConfig{msg.position_gain, msg.speed_limit};
}

ErrorCode Supervisor::configure(const proto::Configure& msg, uint8_t& field) {
  field = proto::kNoField;
  const ErrorCode local = proto::validate(msg, field);
  if (local != ErrorCode::kOk) return local;
  if (msg.tilt_limit > max_tilt_deg(msg.module_x, msg.module_y, kActuatorRangeM) + kTiltLimitSlackDeg) {
    field = proto::Configure::kFieldTiltLimit;
    return ErrorCode::kOutOfRange;
  }
  if (msg.telemetry_period != 0 && msg.telemetry_period < kMinTelemetryPeriodMs) {
    field = proto::Configure::kFieldTelemetryPeriod;
    return ErrorCode::kOutOfRange;
  }
  config_ = msg;
  take_configure();
  if (has_target_ && !(within(target_x_, half_x(config_)) && within(target_y_, half_y(config_)))) has_target_ = false;
  return ErrorCode::kOk;
}

ErrorCode Supervisor::configure_pid(const proto::ConfigurePid& msg, uint8_t& field) {
  field = proto::kNoField;
  const ErrorCode local = proto::validate(msg, field);
  if (local != ErrorCode::kOk) return local;
  control_.pid[msg.axis] = PidGains{msg.kp, msg.ki, msg.kd, msg.integral_limit};
  return ErrorCode::kOk;
}

template <class Message>
ErrorCode Supervisor::take_valid(const Message& msg, uint8_t& field) {
  field = proto::kNoField;
  const ErrorCode local = proto::validate(msg, field);
  if (local != ErrorCode::kOk) return local;
  take(msg);
  return ErrorCode::kOk;
}

ErrorCode Supervisor::configure_schedule(const proto::ConfigureSchedule& msg, uint8_t& field) {
  return take_valid(msg, field);
}

ErrorCode Supervisor::configure_cascade(const proto::ConfigureCascade& msg, uint8_t& field) {
  return take_valid(msg, field);
}

ErrorCode Supervisor::set_target(const proto::SetTarget& msg, uint8_t& field) {
  field = proto::kNoField;
  const ErrorCode local = proto::validate(msg, field);
  if (local != ErrorCode::kOk) return local;
  if (!within(msg.x, half_x(config_))) {
    field = proto::SetTarget::kFieldX;
    return ErrorCode::kOutOfRange;
  }
  if (!within(msg.y, half_y(config_))) {
    field = proto::SetTarget::kFieldY;
    return ErrorCode::kOutOfRange;
  }
  target_x_ = msg.x;
  target_y_ = msg.y;
  has_target_ = true;
  return ErrorCode::kOk;
}

ErrorCode Supervisor::start(uint32_t now_us) {
  if (!has_target_) return ErrorCode::kNoTarget;
  controller_.reset(config_.noise_seed);
  level();
  forget_positions();
  has_step_ = false;
  deadman_from_us_ = now_us;  // the first position must arrive within the deadman
  state_ = State::kRunning;
  return ErrorCode::kOk;
}

void Supervisor::stop() {
  state_ = State::kIdle;
  faults_ = 0;
  level();
}

void Supervisor::emergency_stop() { shutdown(proto::faults::kEstop); }

void Supervisor::shutdown(uint16_t faults) {
  faults_ |= faults;
  state_ = (faults_ & proto::faults::kEstop) ? State::kEstop : State::kFault;
  level();
}

bool Supervisor::actuator_power() const {
  constexpr uint16_t kPowerCut = proto::faults::kEstop | proto::faults::kStall | proto::faults::kEncoder;
  return !(faults_ & kPowerCut);
}

ErrorCode Supervisor::jog(const proto::Jog& msg, uint8_t& field) {
  field = proto::kNoField;
  const ErrorCode local = proto::validate(msg, field);
  if (local != ErrorCode::kOk) return local;
  if (msg.actuator >= kActuatorCount) {  // the schema's bound is the protocol's 16; this rig has fewer
    field = proto::Jog::kFieldActuator;
    return ErrorCode::kOutOfRange;
  }
  if (msg.position > kActuatorRangeM || msg.position < -kActuatorRangeM) {
    field = proto::Jog::kFieldPosition;
    return ErrorCode::kOutOfRange;
  }
  output_.command[msg.actuator] = msg.position;
  output_.module = lowest_module(msg.actuator);  // telemetry shows the jogged actuator
  return ErrorCode::kOk;
}

ErrorCode Supervisor::zero(const proto::Zero& msg, uint8_t& field) {
  field = proto::kNoField;
  const ErrorCode local = proto::validate(msg, field);
  if (local != ErrorCode::kOk) return local;
  if (kActuatorCount < 16 && (msg.actuators >> (kActuatorCount % 16))) {  // a bit for an actuator this rig lacks
    field = proto::Zero::kFieldActuators;
    return ErrorCode::kOutOfRange;
  }
  for (uint8_t i = 0; i < kActuatorCount; ++i) {
    if (msg.actuators & (1u << i)) output_.command[i] = 0.0f;
  }
  return ErrorCode::kOk;
}

ErrorCode Supervisor::position(const proto::ObjectPosition& msg, uint32_t now_us, uint8_t& field) {
  field = proto::kNoField;
  const bool visible = !(msg.flags & proto::position_flags::kNotVisible);
  if (visible) {
    const ErrorCode local = proto::validate(msg, field);
    if (local != ErrorCode::kOk) return local;
    // On the fabric, or beside it by at most half a module (an object falling off): anything farther is no
    // measurement of it, and near 1e38 m would overflow the Euclidean distance.
    if (!within(msg.x, half_x(config_) + 0.5f * config_.module_x)) {
      field = proto::ObjectPosition::kFieldX;
      return ErrorCode::kOutOfRange;
    }
    if (!within(msg.y, half_y(config_) + 0.5f * config_.module_y)) {
      field = proto::ObjectPosition::kFieldY;
      return ErrorCode::kOutOfRange;
    }
  }
  // Frames more than a deadman apart are no longer one stream (the camera paused): the next one starts afresh,
  // however far its capture time jumped (a jump of 2^31 us or more would otherwise read as going backwards).
  if (has_frame_ && now_us - last_frame_at_us_ > static_cast<uint32_t>(config_.deadman) * 1000u) {
    has_frame_ = false;
  }
  if (has_frame_) {
    if (msg.frame == last_frame_) {
      field = proto::ObjectPosition::kFieldFrame;
      return ErrorCode::kStalePosition;
    }
    if (static_cast<int32_t>(msg.capture_time - last_capture_us_) <= 0) {
      field = proto::ObjectPosition::kFieldCaptureTime;
      return ErrorCode::kStalePosition;
    }
  }
  has_frame_ = true;
  last_frame_ = msg.frame;
  last_capture_us_ = msg.capture_time;
  last_frame_at_us_ = now_us;
  if (!visible) return ErrorCode::kOk;  // no measurement: commands hold, the deadman keeps counting
  has_valid_ = true;
  last_valid_us_ = now_us;
  deadman_from_us_ = now_us;
  if (!running(state_)) return ErrorCode::kOk;

  // dt from the capture times, as the camera saw the motion; a gap longer than the deadman is a restart.
  float dt = 0.0f;
  if (has_step_) {
    const uint32_t gap_us = msg.capture_time - last_step_capture_us_;
    if (gap_us <= static_cast<uint32_t>(config_.deadman) * 1000u) dt = static_cast<float>(gap_us) * 1e-6f;
  }
  has_step_ = true;
  last_step_capture_us_ = msg.capture_time;
  const Leg leg = route(msg.x, msg.y, target_x_, target_y_, config_.module_x, config_.module_y, config_.tolerance);
  const float distance = controller_.step(control_, leg.target_x, leg.target_y, msg.x, msg.y, dt, output_, leg.module);
  bool reached = distance < config_.tolerance;
  if (kModuleCount > 1) {  // to the target, not a waypoint; squared: no square root in the Mega's frame
    const float ex = target_x_ - msg.x, ey = target_y_ - msg.y;
    reached = ex * ex + ey * ey < config_.tolerance * config_.tolerance;
  }
  state_ = reached ? State::kReached : State::kRunning;
  return ErrorCode::kOk;
}

void Supervisor::tick(uint32_t now_us) {
  if (!running(state_)) return;
  if (now_us - deadman_from_us_ > static_cast<uint32_t>(config_.deadman) * 1000u) {
    shutdown(proto::faults::kPositionTimeout);
  }
}

uint16_t Supervisor::position_age_ms(uint32_t now_us) const {
  if (!has_valid_) return 0xFFFF;
  const uint32_t age_ms = (now_us - last_valid_us_) / 1000u;
  return age_ms > 0xFFFFu ? 0xFFFF : static_cast<uint16_t>(age_ms);
}

}  // namespace mr
