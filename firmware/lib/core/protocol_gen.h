// Generated from protocol/schema.toml by protocol/generate.py; do not edit.
#pragma once

#include <stdint.h>  // fixed-width wire types

#include "wire.h"  // put_*/get_* little-endian helpers, is_finite

namespace mr {
namespace proto {

constexpr uint16_t kProtocolVersion = 2;
constexpr uint32_t kSchemaHash = 0xFDED63EDu;
constexpr uint32_t kBootGainsCrc = 0x6DD8DF21u;  // of kPidDefaults, for identify
constexpr uint8_t kMaxPacket = 44;  // [bytes] id + seq + payload + CRC
constexpr uint8_t kMaxWire = 46;  // [bytes] COBS packet + delimiter
constexpr uint8_t kNoField = 255;  // nack.field when no single field is at fault

enum class ErrorCode : uint8_t {
  kOk = 0,
  kUnknownMessage = 1,  // The message id is not one the firmware handles in this direction.
  kBadLength = 2,  // The payload length differs from the schema's length for that message id.
  kNotFinite = 3,  // A float field is NaN or infinite (nack.field names it).
  kOutOfRange = 4,  // A field is outside its documented bounds, or an enum value is unknown (nack.field names it).
  kBadState = 5,  // The command is not allowed in the current supervisor state (see PROTOCOL.md, state table).
  kNoTarget = 6,  // start was sent before any set_target.
  kUnsupported = 7,  // The command exists but this build cannot do it (sim_clock on a wall-clock or real board).
  kStalePosition = 8,  // object_position whose frame counter repeats the last one or whose capture time does not advance.
  kStaleSequence = 9,  // A frame whose sequence number is 1 to 64 behind the newest one taken, or equals it with other content: a delayed or duplicated copy of an older frame, not applied (PROTOCOL.md section 3).
};
constexpr uint8_t kLastErrorCode = 9;  // nack.code is 1..this
constexpr uint8_t kMostFields = 10;  // fields of the widest host -> MCU message: nack.field is below this or kNoField

// Supervisor state.
enum class State : uint8_t {
  kIdle = 0,
  kRunning = 1,
  kReached = 2,
  kFault = 3,
  kEstop = 4,
};
constexpr uint8_t kStateCount = 5;  // values 0..this - 1

// Tilt controller: the paper's Manhattan (Algorithm 1, PIDs x and y) or Euclidean (Algorithm 2, PID radial); beyond the paper, scheduled (Manhattan's PIDs with gains and tilt limits scheduled on the position and speed, configure_schedule) or cascade (a position loop asking for a velocity, PIDs vx and vy tilting for it, configure_cascade).
enum class Controller : uint8_t {
  kManhattan = 0,
  kEuclidean = 1,
  kScheduled = 2,
  kCascade = 3,
};
constexpr uint8_t kControllerCount = 4;  // values 0..this - 1

// Which PID configure_pid sets: x and y are Manhattan's and scheduled's, radial is Euclidean's, vx and vy the cascade's inner loops (their error is a velocity: kp in deg s/m, ki in deg/m, kd in deg s^2/m).
enum class Axis : uint8_t {
  kX = 0,
  kY = 1,
  kRadial = 2,
  kVx = 3,
  kVy = 4,
};
constexpr uint8_t kAxisCount = 5;  // values 0..this - 1

// Where the firmware's time comes from.
enum class Clock : uint8_t {
  kWall = 0,
  kSimulated = 1,
};
constexpr uint8_t kClockCount = 2;  // values 0..this - 1

// Why the firmware (re)started, reported in boot.
enum class ResetCause : uint8_t {
  kPowerOn = 0,
  kExternal = 1,
  kBrownOut = 2,
  kWatchdog = 3,
  kUnknown = 4,
};
constexpr uint8_t kResetCauseCount = 5;  // values 0..this - 1

// object_position.flags bits.
namespace position_flags {
constexpr uint16_t kNotVisible = 1u << 0;
}  // namespace position_flags

// telemetry.faults bits; latched until stop.
namespace faults {
constexpr uint16_t kPositionTimeout = 1u << 0;
constexpr uint16_t kEstop = 1u << 1;
constexpr uint16_t kStall = 1u << 2;
constexpr uint16_t kEncoder = 1u << 3;
}  // namespace faults

// Boot gains of each PID, indexed by Axis: {kp [deg/m], ki [deg/(m s)], kd [deg s/m], integral_limit [deg]}.
struct PidDefaults { float kp, ki, kd, integral_limit; };
constexpr PidDefaults kPidDefaults[] = {
    {30.9f, 26.78f, 15.45f, 26.565051f},  // x
    {30.9f, 26.78f, 15.45f, 26.565051f},  // y
    {86.72f, 27.91f, 10.19f, 26.565051f},  // radial
    {100.0f, 30.0f, 0.0f, 26.565051f},  // vx
    {100.0f, 30.0f, 0.0f, 26.565051f},  // vy
};

// Handshake: ask for protocol version, firmware version and schema hash.
struct Identify {
  static constexpr uint8_t kId = 0x01;
  static constexpr uint8_t kSize = 0;  // [bytes] payload
};
inline void encode(const Identify&, uint8_t*) {}
inline void decode(const uint8_t*, Identify&) {}
// Field-local checks from the schema (NaN/inf, bounds, enum values); field = index of the first bad one.
inline ErrorCode validate(const Identify& /*m*/, uint8_t& /*field*/) {
  return ErrorCode::kOk;
}

// Controller-wide settings. Validated whole: any bad field refuses the lot and changes nothing.
struct Configure {
  static constexpr uint8_t kId = 0x02;
  static constexpr uint8_t kSize = 33;  // [bytes] payload
  uint8_t controller;  // The tilt controller: manhattan, euclidean, scheduled or cascade. (enum controller)
  float module_x;  // [m] Module size m along x (actuators at x = +-m/2).
  float module_y;  // [m] Module size n along y (actuators at y = +-n/2).
  float tilt_limit;  // [deg] Saturation of each tilt angle; at most atan(range / ((m + n) / 2)), which keeps every corner in range.
  float tolerance;  // [m] epsilon: the object counts as reached within this distance of the target.
  float noise_amplitude;  // [m] alpha: each command gets alpha * delta, delta ~ U(-1, 1), drawn every control step.
  uint32_t noise_seed;  // Seed of the noise PRNG (xorshift32; 0 is replaced by 1); reseeded at every start.
  uint16_t deadman;  // [ms] Longest time without a valid position while running before the surface levels and a position_timeout fault latches.
  uint16_t telemetry_period;  // [ms] Period of unsolicited telemetry; 0 = only in answer to object_position. Nonzero values below 5 ms are refused (the link cannot carry them).
  float velocity_filter;  // [s] Time constant of the first-order low-pass on the camera-frame velocity (scheduled and cascade); 0: the raw frame difference.
  static constexpr uint8_t kFieldController = 0;
  static constexpr uint8_t kFieldModuleX = 1;
  static constexpr uint8_t kFieldModuleY = 2;
  static constexpr uint8_t kFieldTiltLimit = 3;
  static constexpr uint8_t kFieldTolerance = 4;
  static constexpr uint8_t kFieldNoiseAmplitude = 5;
  static constexpr uint8_t kFieldNoiseSeed = 6;
  static constexpr uint8_t kFieldDeadman = 7;
  static constexpr uint8_t kFieldTelemetryPeriod = 8;
  static constexpr uint8_t kFieldVelocityFilter = 9;
};
inline void encode(const Configure& m, uint8_t* out) {
  put_u8(out + 0, m.controller);
  put_f32(out + 1, m.module_x);
  put_f32(out + 5, m.module_y);
  put_f32(out + 9, m.tilt_limit);
  put_f32(out + 13, m.tolerance);
  put_f32(out + 17, m.noise_amplitude);
  put_u32(out + 21, m.noise_seed);
  put_u16(out + 25, m.deadman);
  put_u16(out + 27, m.telemetry_period);
  put_f32(out + 29, m.velocity_filter);
}
inline void decode(const uint8_t* in, Configure& m) {
  m.controller = get_u8(in + 0);
  m.module_x = get_f32(in + 1);
  m.module_y = get_f32(in + 5);
  m.tilt_limit = get_f32(in + 9);
  m.tolerance = get_f32(in + 13);
  m.noise_amplitude = get_f32(in + 17);
  m.noise_seed = get_u32(in + 21);
  m.deadman = get_u16(in + 25);
  m.telemetry_period = get_u16(in + 27);
  m.velocity_filter = get_f32(in + 29);
}
// Field-local checks from the schema (NaN/inf, bounds, enum values); field = index of the first bad one.
inline ErrorCode validate(const Configure& m, uint8_t& field) {
  if ((m.controller != 0 && m.controller != 1 && m.controller != 2 && m.controller != 3)) { field = 0; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.module_x)) { field = 1; return ErrorCode::kNotFinite; }
  if ((m.module_x < 0.1f) || (m.module_x > 10.0f)) { field = 1; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.module_y)) { field = 2; return ErrorCode::kNotFinite; }
  if ((m.module_y < 0.1f) || (m.module_y > 10.0f)) { field = 2; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.tilt_limit)) { field = 3; return ErrorCode::kNotFinite; }
  if ((m.tilt_limit < 0.1f) || (m.tilt_limit > 89.0f)) { field = 3; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.tolerance)) { field = 4; return ErrorCode::kNotFinite; }
  if ((m.tolerance < 0.001f) || (m.tolerance > 0.5f)) { field = 4; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.noise_amplitude)) { field = 5; return ErrorCode::kNotFinite; }
  if ((m.noise_amplitude < 0.0f) || (m.noise_amplitude > 0.25f)) { field = 5; return ErrorCode::kOutOfRange; }
  if ((m.deadman < 20) || (m.deadman > 60000)) { field = 7; return ErrorCode::kOutOfRange; }
  if ((m.telemetry_period > 60000)) { field = 8; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.velocity_filter)) { field = 9; return ErrorCode::kNotFinite; }
  if ((m.velocity_filter < 0.0f) || (m.velocity_filter > 10.0f)) { field = 9; return ErrorCode::kOutOfRange; }
  return ErrorCode::kOk;
}
// Boot values from the schema.
inline void set_defaults(Configure& m) {
  m.controller = 0;
  m.module_x = 0.5f;
  m.module_y = 0.5f;
  m.tilt_limit = 26.565051f;
  m.tolerance = 0.02f;
  m.noise_amplitude = 0.0f;
  m.noise_seed = 1;
  m.deadman = 500;
  m.telemetry_period = 100;
  m.velocity_filter = 0.05f;
}

// Gains of one PID. Output unit is degrees of tilt (see PROTOCOL.md, units).
struct ConfigurePid {
  static constexpr uint8_t kId = 0x03;
  static constexpr uint8_t kSize = 17;  // [bytes] payload
  uint8_t axis;  // Which PID: x, y (manhattan, scheduled), radial (euclidean), vx, vy (cascade). (enum axis)
  float kp;  // [deg/m] Proportional gain.
  float ki;  // [deg/(m s)] Integral gain.
  float kd;  // [deg s/m] Derivative gain (on measurement: no kick when the target changes).
  float integral_limit;  // [deg] Anti-windup bound on the integral term's contribution.
  static constexpr uint8_t kFieldAxis = 0;
  static constexpr uint8_t kFieldKp = 1;
  static constexpr uint8_t kFieldKi = 2;
  static constexpr uint8_t kFieldKd = 3;
  static constexpr uint8_t kFieldIntegralLimit = 4;
};
inline void encode(const ConfigurePid& m, uint8_t* out) {
  put_u8(out + 0, m.axis);
  put_f32(out + 1, m.kp);
  put_f32(out + 5, m.ki);
  put_f32(out + 9, m.kd);
  put_f32(out + 13, m.integral_limit);
}
inline void decode(const uint8_t* in, ConfigurePid& m) {
  m.axis = get_u8(in + 0);
  m.kp = get_f32(in + 1);
  m.ki = get_f32(in + 5);
  m.kd = get_f32(in + 9);
  m.integral_limit = get_f32(in + 13);
}
// Field-local checks from the schema (NaN/inf, bounds, enum values); field = index of the first bad one.
inline ErrorCode validate(const ConfigurePid& m, uint8_t& field) {
  if ((m.axis != 0 && m.axis != 1 && m.axis != 2 && m.axis != 3 && m.axis != 4)) { field = 0; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.kp)) { field = 1; return ErrorCode::kNotFinite; }
  if ((m.kp < 0.0f) || (m.kp > 10000.0f)) { field = 1; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.ki)) { field = 2; return ErrorCode::kNotFinite; }
  if ((m.ki < 0.0f) || (m.ki > 10000.0f)) { field = 2; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.kd)) { field = 3; return ErrorCode::kNotFinite; }
  if ((m.kd < 0.0f) || (m.kd > 10000.0f)) { field = 3; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.integral_limit)) { field = 4; return ErrorCode::kNotFinite; }
  if ((m.integral_limit < 0.0f) || (m.integral_limit > 90.0f)) { field = 4; return ErrorCode::kOutOfRange; }
  return ErrorCode::kOk;
}

// Target position p_d in the fabric frame. Must lie on the surface: |x| <= modules_x m/2, |y| <= modules_y n/2 (one module: m/2, n/2).
struct SetTarget {
  static constexpr uint8_t kId = 0x04;
  static constexpr uint8_t kSize = 8;  // [bytes] payload
  float x;  // [m] x_d.
  float y;  // [m] y_d.
  static constexpr uint8_t kFieldX = 0;
  static constexpr uint8_t kFieldY = 1;
};
inline void encode(const SetTarget& m, uint8_t* out) {
  put_f32(out + 0, m.x);
  put_f32(out + 4, m.y);
}
inline void decode(const uint8_t* in, SetTarget& m) {
  m.x = get_f32(in + 0);
  m.y = get_f32(in + 4);
}
// Field-local checks from the schema (NaN/inf, bounds, enum values); field = index of the first bad one.
inline ErrorCode validate(const SetTarget& m, uint8_t& field) {
  if (!is_finite(m.x)) { field = 0; return ErrorCode::kNotFinite; }
  if (!is_finite(m.y)) { field = 1; return ErrorCode::kNotFinite; }
  return ErrorCode::kOk;
}

// idle -> running: reset the PIDs, reseed the noise, start the deadman.
struct Start {
  static constexpr uint8_t kId = 0x05;
  static constexpr uint8_t kSize = 0;  // [bytes] payload
};
inline void encode(const Start&, uint8_t*) {}
inline void decode(const uint8_t*, Start&) {}
// Field-local checks from the schema (NaN/inf, bounds, enum values); field = index of the first bad one.
inline ErrorCode validate(const Start& /*m*/, uint8_t& /*field*/) {
  return ErrorCode::kOk;
}

// Any state -> idle: level the surface. Also how a fault or an emergency stop is cleared.
struct Stop {
  static constexpr uint8_t kId = 0x06;
  static constexpr uint8_t kSize = 0;  // [bytes] payload
};
inline void encode(const Stop&, uint8_t*) {}
inline void decode(const uint8_t*, Stop&) {}
// Field-local checks from the schema (NaN/inf, bounds, enum values); field = index of the first bad one.
inline ErrorCode validate(const Stop& /*m*/, uint8_t& /*field*/) {
  return ErrorCode::kOk;
}

// Any state -> estop: actuator power cut at once; latched until stop.
struct EmergencyStop {
  static constexpr uint8_t kId = 0x07;
  static constexpr uint8_t kSize = 0;  // [bytes] payload
};
inline void encode(const EmergencyStop&, uint8_t*) {}
inline void decode(const uint8_t*, EmergencyStop&) {}
// Field-local checks from the schema (NaN/inf, bounds, enum values); field = index of the first bad one.
inline ErrorCode validate(const EmergencyStop& /*m*/, uint8_t& /*field*/) {
  return ErrorCode::kOk;
}

// Move one actuator to a position, for calibration; stop or start ends the jog.
struct Jog {
  static constexpr uint8_t kId = 0x08;
  static constexpr uint8_t kSize = 5;  // [bytes] payload
  uint8_t actuator;  // Actuator index (PROTOCOL.md §5); one the firmware's rig does not have is refused (out_of_range).
  float position;  // [m] Command, + lowers the corner; within the actuator range.
  static constexpr uint8_t kFieldActuator = 0;
  static constexpr uint8_t kFieldPosition = 1;
};
inline void encode(const Jog& m, uint8_t* out) {
  put_u8(out + 0, m.actuator);
  put_f32(out + 1, m.position);
}
inline void decode(const uint8_t* in, Jog& m) {
  m.actuator = get_u8(in + 0);
  m.position = get_f32(in + 1);
}
// Field-local checks from the schema (NaN/inf, bounds, enum values); field = index of the first bad one.
inline ErrorCode validate(const Jog& m, uint8_t& field) {
  if ((m.actuator > 15)) { field = 0; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.position)) { field = 1; return ErrorCode::kNotFinite; }
  return ErrorCode::kOk;
}

// Simulated clock only: set the firmware's time; it must not go backwards. Real boards answer unsupported.
struct SimClock {
  static constexpr uint8_t kId = 0x09;
  static constexpr uint8_t kSize = 4;  // [bytes] payload
  uint32_t now;  // [us] New time of the firmware clock.
  static constexpr uint8_t kFieldNow = 0;
};
inline void encode(const SimClock& m, uint8_t* out) {
  put_u32(out + 0, m.now);
}
inline void decode(const uint8_t* in, SimClock& m) {
  m.now = get_u32(in + 0);
}
// Field-local checks from the schema (NaN/inf, bounds, enum values); field = index of the first bad one.
inline ErrorCode validate(const SimClock& /*m*/, uint8_t& /*field*/) {
  return ErrorCode::kOk;
}

// Homing: take the present position of each actuator in the mask as 0 m, the reference height z0.
struct Zero {
  static constexpr uint8_t kId = 0x0A;
  static constexpr uint8_t kSize = 2;  // [bytes] payload
  uint16_t actuators;  // Bit i set: zero actuator i (PROTOCOL.md §5); a bit for an actuator the firmware's rig does not have is refused (out_of_range).
  static constexpr uint8_t kFieldActuators = 0;
};
inline void encode(const Zero& m, uint8_t* out) {
  put_u16(out + 0, m.actuators);
}
inline void decode(const uint8_t* in, Zero& m) {
  m.actuators = get_u16(in + 0);
}
// Field-local checks from the schema (NaN/inf, bounds, enum values); field = index of the first bad one.
inline ErrorCode validate(const Zero& m, uint8_t& field) {
  if ((m.actuators < 1)) { field = 0; return ErrorCode::kOutOfRange; }
  return ErrorCode::kOk;
}

// The position-scheduled Manhattan controller's schedule (PROTOCOL.md, controllers). Its defaults schedule nothing: it then steps as Manhattan.
struct ConfigureSchedule {
  static constexpr uint8_t kId = 0x0B;
  static constexpr uint8_t kSize = 20;  // [bytes] payload
  float edge_zone;  // [m] Width of the band along each edge where the schedule acts, growing linearly to the edge.
  float edge_gain;  // kp and ki at the edge the object is nearest to along the axis, relative to the axis's own.
  float edge_tilt;  // Tilt limit toward an edge, at that edge, relative to tilt_limit (the tilt away from the nearest edge keeps the whole limit unless edge_zone is wider than half the module).
  float edge_brake;  // kd at the edge is (1 + edge_brake) times the axis's own.
  float brake_speed;  // [m/s] Speed at which the tilt along the object's motion on an axis has faded to 0 (a tilt against it, which brakes, stays free); 0: no such limit.
  static constexpr uint8_t kFieldEdgeZone = 0;
  static constexpr uint8_t kFieldEdgeGain = 1;
  static constexpr uint8_t kFieldEdgeTilt = 2;
  static constexpr uint8_t kFieldEdgeBrake = 3;
  static constexpr uint8_t kFieldBrakeSpeed = 4;
};
inline void encode(const ConfigureSchedule& m, uint8_t* out) {
  put_f32(out + 0, m.edge_zone);
  put_f32(out + 4, m.edge_gain);
  put_f32(out + 8, m.edge_tilt);
  put_f32(out + 12, m.edge_brake);
  put_f32(out + 16, m.brake_speed);
}
inline void decode(const uint8_t* in, ConfigureSchedule& m) {
  m.edge_zone = get_f32(in + 0);
  m.edge_gain = get_f32(in + 4);
  m.edge_tilt = get_f32(in + 8);
  m.edge_brake = get_f32(in + 12);
  m.brake_speed = get_f32(in + 16);
}
// Field-local checks from the schema (NaN/inf, bounds, enum values); field = index of the first bad one.
inline ErrorCode validate(const ConfigureSchedule& m, uint8_t& field) {
  if (!is_finite(m.edge_zone)) { field = 0; return ErrorCode::kNotFinite; }
  if ((m.edge_zone < 0.001f) || (m.edge_zone > 5.0f)) { field = 0; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.edge_gain)) { field = 1; return ErrorCode::kNotFinite; }
  if ((m.edge_gain < 0.0f) || (m.edge_gain > 1.0f)) { field = 1; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.edge_tilt)) { field = 2; return ErrorCode::kNotFinite; }
  if ((m.edge_tilt < 0.0f) || (m.edge_tilt > 1.0f)) { field = 2; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.edge_brake)) { field = 3; return ErrorCode::kNotFinite; }
  if ((m.edge_brake < 0.0f) || (m.edge_brake > 100.0f)) { field = 3; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.brake_speed)) { field = 4; return ErrorCode::kNotFinite; }
  if ((m.brake_speed < 0.0f) || (m.brake_speed > 10.0f)) { field = 4; return ErrorCode::kOutOfRange; }
  return ErrorCode::kOk;
}
// Boot values from the schema.
inline void set_defaults(ConfigureSchedule& m) {
  m.edge_zone = 0.05f;
  m.edge_gain = 1.0f;
  m.edge_tilt = 1.0f;
  m.edge_brake = 0.0f;
  m.brake_speed = 0.0f;
}

// The cascaded controller's outer loop (PROTOCOL.md, controllers); its inner PIDs are configure_pid's vx and vy.
struct ConfigureCascade {
  static constexpr uint8_t kId = 0x0C;
  static constexpr uint8_t kSize = 8;  // [bytes] payload
  float position_gain;  // [1/s] Velocity asked for per metre of error, on each axis.
  float speed_limit;  // [m/s] The most the outer loop asks for, on each axis.
  static constexpr uint8_t kFieldPositionGain = 0;
  static constexpr uint8_t kFieldSpeedLimit = 1;
};
inline void encode(const ConfigureCascade& m, uint8_t* out) {
  put_f32(out + 0, m.position_gain);
  put_f32(out + 4, m.speed_limit);
}
inline void decode(const uint8_t* in, ConfigureCascade& m) {
  m.position_gain = get_f32(in + 0);
  m.speed_limit = get_f32(in + 4);
}
// Field-local checks from the schema (NaN/inf, bounds, enum values); field = index of the first bad one.
inline ErrorCode validate(const ConfigureCascade& m, uint8_t& field) {
  if (!is_finite(m.position_gain)) { field = 0; return ErrorCode::kNotFinite; }
  if ((m.position_gain < 0.0f) || (m.position_gain > 100.0f)) { field = 0; return ErrorCode::kOutOfRange; }
  if (!is_finite(m.speed_limit)) { field = 1; return ErrorCode::kNotFinite; }
  if ((m.speed_limit < 0.001f) || (m.speed_limit > 5.0f)) { field = 1; return ErrorCode::kOutOfRange; }
  return ErrorCode::kOk;
}
// Boot values from the schema.
inline void set_defaults(ConfigureCascade& m) {
  m.position_gain = 3.0f;
  m.speed_limit = 0.15f;
}

// One camera measurement. Answered by telemetry (or a nack); one controller step when running.
struct ObjectPosition {
  static constexpr uint8_t kId = 0x10;
  static constexpr uint8_t kSize = 15;  // [bytes] payload
  uint16_t frame;  // Camera frame counter, +1 per frame (wraps).
  uint32_t capture_time;  // [us] When the frame was captured, host clock; the controller's dt is the difference of these.
  float x;  // [m] Object x in the fabric frame; on the fabric or at most half a module beside it (one module: within +-module_x), else out_of_range.
  float y;  // [m] Object y in the fabric frame; on the fabric or at most half a module beside it (one module: within +-module_y), else out_of_range.
  uint8_t flags;  // not_visible: the camera lost the object; x and y are ignored. (flags position_flags)
  static constexpr uint8_t kFieldFrame = 0;
  static constexpr uint8_t kFieldCaptureTime = 1;
  static constexpr uint8_t kFieldX = 2;
  static constexpr uint8_t kFieldY = 3;
  static constexpr uint8_t kFieldFlags = 4;
};
inline void encode(const ObjectPosition& m, uint8_t* out) {
  put_u16(out + 0, m.frame);
  put_u32(out + 2, m.capture_time);
  put_f32(out + 6, m.x);
  put_f32(out + 10, m.y);
  put_u8(out + 14, m.flags);
}
inline void decode(const uint8_t* in, ObjectPosition& m) {
  m.frame = get_u16(in + 0);
  m.capture_time = get_u32(in + 2);
  m.x = get_f32(in + 6);
  m.y = get_f32(in + 10);
  m.flags = get_u8(in + 14);
}
// Field-local checks from the schema (NaN/inf, bounds, enum values); field = index of the first bad one.
inline ErrorCode validate(const ObjectPosition& m, uint8_t& field) {
  if (!is_finite(m.x)) { field = 2; return ErrorCode::kNotFinite; }
  if (!is_finite(m.y)) { field = 3; return ErrorCode::kNotFinite; }
  return ErrorCode::kOk;
}

// Answer to identify.
struct IdentifyReply {
  static constexpr uint8_t kId = 0x81;
  static constexpr uint8_t kSize = 32;  // [bytes] payload
  uint16_t protocol_version;  // [protocol] version of the firmware's schema.
  uint8_t firmware_major;  // Firmware version, major.
  uint8_t firmware_minor;  // Firmware version, minor.
  uint8_t firmware_patch;  // Firmware version, patch.
  uint32_t schema_hash;  // CRC-32 of the canonical schema; the host refuses a mismatch.
  uint8_t max_wire;  // [bytes] Largest frame the firmware accepts, delimiter included.
  uint8_t clock;  // Wall or simulated clock. (enum clock)
  uint8_t actuator_count;  // Actuators the firmware drives (protocol/rig.toml, as every field below).
  float actuator_range;  // [m] Travel of each actuator about z0 the firmware was built for.
  uint16_t encoder_counts;  // Counts per encoder revolution the firmware was built for.
  float pulley_circumference;  // [m/rev] Belt travel per motor revolution the firmware was built for.
  uint32_t actuator_period;  // [us] Period of the firmware's actuator position loops.
  uint8_t modules_x;  // Modules along x: the firmware drives a modules_x x modules_y array (1 x 1: one module).
  uint8_t modules_y;  // Modules along y.
  uint32_t boot_gains_crc;  // CRC-32 of the PIDs' boot gains the firmware was built with ([pid_defaults] as f32, in axis order); outside schema_hash, so a retuned default is reported, not refused.
  static constexpr uint8_t kFieldProtocolVersion = 0;
  static constexpr uint8_t kFieldFirmwareMajor = 1;
  static constexpr uint8_t kFieldFirmwareMinor = 2;
  static constexpr uint8_t kFieldFirmwarePatch = 3;
  static constexpr uint8_t kFieldSchemaHash = 4;
  static constexpr uint8_t kFieldMaxWire = 5;
  static constexpr uint8_t kFieldClock = 6;
  static constexpr uint8_t kFieldActuatorCount = 7;
  static constexpr uint8_t kFieldActuatorRange = 8;
  static constexpr uint8_t kFieldEncoderCounts = 9;
  static constexpr uint8_t kFieldPulleyCircumference = 10;
  static constexpr uint8_t kFieldActuatorPeriod = 11;
  static constexpr uint8_t kFieldModulesX = 12;
  static constexpr uint8_t kFieldModulesY = 13;
  static constexpr uint8_t kFieldBootGainsCrc = 14;
};
inline void encode(const IdentifyReply& m, uint8_t* out) {
  put_u16(out + 0, m.protocol_version);
  put_u8(out + 2, m.firmware_major);
  put_u8(out + 3, m.firmware_minor);
  put_u8(out + 4, m.firmware_patch);
  put_u32(out + 5, m.schema_hash);
  put_u8(out + 9, m.max_wire);
  put_u8(out + 10, m.clock);
  put_u8(out + 11, m.actuator_count);
  put_f32(out + 12, m.actuator_range);
  put_u16(out + 16, m.encoder_counts);
  put_f32(out + 18, m.pulley_circumference);
  put_u32(out + 22, m.actuator_period);
  put_u8(out + 26, m.modules_x);
  put_u8(out + 27, m.modules_y);
  put_u32(out + 28, m.boot_gains_crc);
}
inline void decode(const uint8_t* in, IdentifyReply& m) {
  m.protocol_version = get_u16(in + 0);
  m.firmware_major = get_u8(in + 2);
  m.firmware_minor = get_u8(in + 3);
  m.firmware_patch = get_u8(in + 4);
  m.schema_hash = get_u32(in + 5);
  m.max_wire = get_u8(in + 9);
  m.clock = get_u8(in + 10);
  m.actuator_count = get_u8(in + 11);
  m.actuator_range = get_f32(in + 12);
  m.encoder_counts = get_u16(in + 16);
  m.pulley_circumference = get_f32(in + 18);
  m.actuator_period = get_u32(in + 22);
  m.modules_x = get_u8(in + 26);
  m.modules_y = get_u8(in + 27);
  m.boot_gains_crc = get_u32(in + 28);
}

// The command with this id and seq was applied (or was a retransmission of one that was).
struct Ack {
  static constexpr uint8_t kId = 0x82;
  static constexpr uint8_t kSize = 2;  // [bytes] payload
  uint8_t ref_id;  // Message id of the command.
  uint8_t ref_seq;  // Sequence number of the command.
  static constexpr uint8_t kFieldRefId = 0;
  static constexpr uint8_t kFieldRefSeq = 1;
};
inline void encode(const Ack& m, uint8_t* out) {
  put_u8(out + 0, m.ref_id);
  put_u8(out + 1, m.ref_seq);
}
inline void decode(const uint8_t* in, Ack& m) {
  m.ref_id = get_u8(in + 0);
  m.ref_seq = get_u8(in + 1);
}

// The command with this id and seq was refused and changed nothing.
struct Nack {
  static constexpr uint8_t kId = 0x83;
  static constexpr uint8_t kSize = 4;  // [bytes] payload
  uint8_t ref_id;  // Message id of the command.
  uint8_t ref_seq;  // Sequence number of the command.
  uint8_t code;  // Error code (errors above).
  uint8_t field;  // Index of the offending field in the command, 255 if none.
  static constexpr uint8_t kFieldRefId = 0;
  static constexpr uint8_t kFieldRefSeq = 1;
  static constexpr uint8_t kFieldCode = 2;
  static constexpr uint8_t kFieldField = 3;
};
inline void encode(const Nack& m, uint8_t* out) {
  put_u8(out + 0, m.ref_id);
  put_u8(out + 1, m.ref_seq);
  put_u8(out + 2, m.code);
  put_u8(out + 3, m.field);
}
inline void decode(const uint8_t* in, Nack& m) {
  m.ref_id = get_u8(in + 0);
  m.ref_seq = get_u8(in + 1);
  m.code = get_u8(in + 2);
  m.field = get_u8(in + 3);
}

// Firmware state; after every accepted object_position and every telemetry_period.
struct Telemetry {
  static constexpr uint8_t kId = 0x84;
  static constexpr uint8_t kSize = 39;  // [bytes] payload
  uint32_t time;  // [ms] Firmware clock: every microsecond counted, so it wraps at 2^32 ms (49.7 days).
  uint8_t state;  // Supervisor state. (enum state)
  uint16_t faults;  // Latched fault flags. (flags faults)
  uint16_t position_frame;  // Frame counter of the last accepted object_position.
  uint16_t position_age;  // [ms] Time since the last valid position (65535: none, or longer).
  int16_t tilt_zx;  // [deg] theta_zx after saturation (Euclidean: theta resolved along x). (wire = value / 0.01)
  int16_t tilt_zy;  // [deg] theta_zy after saturation (Euclidean: theta resolved along y). (wire = value / 0.01)
  int16_t command[4];  // [m] Commands a_i of module `module`'s four actuators (its corners in PROTOCOL.md §5's order), + lowers the corner. (wire = value / 1e-05)
  int16_t measured[4];  // [m] Measured positions of the same four actuators, same convention. (wire = value / 1e-05)
  uint16_t crc_errors;  // Frames dropped for a bad CRC since boot (wraps).
  uint16_t frame_errors;  // Frames dropped for bad COBS, oversize or truncation since boot (wraps).
  uint16_t loop_overruns;  // Actuator-loop runs that started a whole period or more late since boot (saturates at 65535; 0 where the actuators are ideal).
  uint8_t module;  // The module whose actuators command and measured are (PROTOCOL.md §5): the one the controller drives; after a jog, the lowest-numbered module the jogged actuator is a corner of; 0 on one module.
  uint8_t fault_actuator;  // The actuator whose stall or encoder fault latched first, 255 if none: on an array it stops every module.
  static constexpr uint8_t kFieldTime = 0;
  static constexpr uint8_t kFieldState = 1;
  static constexpr uint8_t kFieldFaults = 2;
  static constexpr uint8_t kFieldPositionFrame = 3;
  static constexpr uint8_t kFieldPositionAge = 4;
  static constexpr uint8_t kFieldTiltZx = 5;
  static constexpr uint8_t kFieldTiltZy = 6;
  static constexpr uint8_t kFieldCommand = 7;
  static constexpr uint8_t kFieldMeasured = 8;
  static constexpr uint8_t kFieldCrcErrors = 9;
  static constexpr uint8_t kFieldFrameErrors = 10;
  static constexpr uint8_t kFieldLoopOverruns = 11;
  static constexpr uint8_t kFieldModule = 12;
  static constexpr uint8_t kFieldFaultActuator = 13;
  static constexpr float kTiltZxScale = 0.01f;  // [deg] per wire unit
  static constexpr float kTiltZyScale = 0.01f;  // [deg] per wire unit
  static constexpr float kCommandScale = 1e-05f;  // [m] per wire unit
  static constexpr float kMeasuredScale = 1e-05f;  // [m] per wire unit
};
inline void encode(const Telemetry& m, uint8_t* out) {
  put_u32(out + 0, m.time);
  put_u8(out + 4, m.state);
  put_u16(out + 5, m.faults);
  put_u16(out + 7, m.position_frame);
  put_u16(out + 9, m.position_age);
  put_i16(out + 11, m.tilt_zx);
  put_i16(out + 13, m.tilt_zy);
  put_i16(out + 15, m.command[0]);
  put_i16(out + 17, m.command[1]);
  put_i16(out + 19, m.command[2]);
  put_i16(out + 21, m.command[3]);
  put_i16(out + 23, m.measured[0]);
  put_i16(out + 25, m.measured[1]);
  put_i16(out + 27, m.measured[2]);
  put_i16(out + 29, m.measured[3]);
  put_u16(out + 31, m.crc_errors);
  put_u16(out + 33, m.frame_errors);
  put_u16(out + 35, m.loop_overruns);
  put_u8(out + 37, m.module);
  put_u8(out + 38, m.fault_actuator);
}
inline void decode(const uint8_t* in, Telemetry& m) {
  m.time = get_u32(in + 0);
  m.state = get_u8(in + 4);
  m.faults = get_u16(in + 5);
  m.position_frame = get_u16(in + 7);
  m.position_age = get_u16(in + 9);
  m.tilt_zx = get_i16(in + 11);
  m.tilt_zy = get_i16(in + 13);
  m.command[0] = get_i16(in + 15);
  m.command[1] = get_i16(in + 17);
  m.command[2] = get_i16(in + 19);
  m.command[3] = get_i16(in + 21);
  m.measured[0] = get_i16(in + 23);
  m.measured[1] = get_i16(in + 25);
  m.measured[2] = get_i16(in + 27);
  m.measured[3] = get_i16(in + 29);
  m.crc_errors = get_u16(in + 31);
  m.frame_errors = get_u16(in + 33);
  m.loop_overruns = get_u16(in + 35);
  m.module = get_u8(in + 37);
  m.fault_actuator = get_u8(in + 38);
}

// An array's commands to every actuator, sent just before each telemetry by a firmware of more than one module (one module's telemetry shows all four): the driven module's plane goes on over the others (PROTOCOL.md §5, Arrays).
struct ArrayCommands {
  static constexpr uint8_t kId = 0x86;
  static constexpr uint8_t kSize = 32;  // [bytes] payload
  int16_t command[16];  // [m] Command a_i of actuator i (PROTOCOL.md §5's numbering), + lowers it; 0 past actuator_count. (wire = value / 1e-05)
  static constexpr uint8_t kFieldCommand = 0;
  static constexpr float kCommandScale = 1e-05f;  // [m] per wire unit
};
inline void encode(const ArrayCommands& m, uint8_t* out) {
  put_i16(out + 0, m.command[0]);
  put_i16(out + 2, m.command[1]);
  put_i16(out + 4, m.command[2]);
  put_i16(out + 6, m.command[3]);
  put_i16(out + 8, m.command[4]);
  put_i16(out + 10, m.command[5]);
  put_i16(out + 12, m.command[6]);
  put_i16(out + 14, m.command[7]);
  put_i16(out + 16, m.command[8]);
  put_i16(out + 18, m.command[9]);
  put_i16(out + 20, m.command[10]);
  put_i16(out + 22, m.command[11]);
  put_i16(out + 24, m.command[12]);
  put_i16(out + 26, m.command[13]);
  put_i16(out + 28, m.command[14]);
  put_i16(out + 30, m.command[15]);
}
inline void decode(const uint8_t* in, ArrayCommands& m) {
  m.command[0] = get_i16(in + 0);
  m.command[1] = get_i16(in + 2);
  m.command[2] = get_i16(in + 4);
  m.command[3] = get_i16(in + 6);
  m.command[4] = get_i16(in + 8);
  m.command[5] = get_i16(in + 10);
  m.command[6] = get_i16(in + 12);
  m.command[7] = get_i16(in + 14);
  m.command[8] = get_i16(in + 16);
  m.command[9] = get_i16(in + 18);
  m.command[10] = get_i16(in + 20);
  m.command[11] = get_i16(in + 22);
  m.command[12] = get_i16(in + 24);
  m.command[13] = get_i16(in + 26);
  m.command[14] = get_i16(in + 28);
  m.command[15] = get_i16(in + 30);
}

// Sent once when the firmware starts, so the host notices a reset.
struct Boot {
  static constexpr uint8_t kId = 0x85;
  static constexpr uint8_t kSize = 1;  // [bytes] payload
  uint8_t reset_cause;  // Why it started. (enum reset_cause)
  static constexpr uint8_t kFieldResetCause = 0;
};
inline void encode(const Boot& m, uint8_t* out) {
  put_u8(out + 0, m.reset_cause);
}
inline void decode(const uint8_t* in, Boot& m) {
  m.reset_cause = get_u8(in + 0);
}

// Payload size [bytes] of a message id travelling host -> MCU, or -1 if the MCU handles no such id.
inline int8_t host_to_mcu_size(uint8_t id) {
  switch (id) {
    case Identify::kId: return Identify::kSize;
    case Configure::kId: return Configure::kSize;
    case ConfigurePid::kId: return ConfigurePid::kSize;
    case SetTarget::kId: return SetTarget::kSize;
    case Start::kId: return Start::kSize;
    case Stop::kId: return Stop::kSize;
    case EmergencyStop::kId: return EmergencyStop::kSize;
    case Jog::kId: return Jog::kSize;
    case SimClock::kId: return SimClock::kSize;
    case Zero::kId: return Zero::kSize;
    case ConfigureSchedule::kId: return ConfigureSchedule::kSize;
    case ConfigureCascade::kId: return ConfigureCascade::kSize;
    case ObjectPosition::kId: return ObjectPosition::kSize;
    default: return -1;
  }
}

// Payload size [bytes] of a message id travelling MCU -> host, or -1 if the MCU sends no such id.
inline int8_t mcu_to_host_size(uint8_t id) {
  switch (id) {
    case IdentifyReply::kId: return IdentifyReply::kSize;
    case Ack::kId: return Ack::kSize;
    case Nack::kId: return Nack::kSize;
    case Telemetry::kId: return Telemetry::kSize;
    case ArrayCommands::kId: return ArrayCommands::kSize;
    case Boot::kId: return Boot::kSize;
    default: return -1;
  }
}

// Supervisor states a host -> MCU message is taken in (bit i: State i); 0 for an id the MCU handles not.
// Bit tests on the id, not a switch: avr-gcc would make that a lookup table in the Uno's RAM.
inline uint8_t host_to_mcu_states(uint8_t id) {
  if (id >= 32) return 0;
  const uint32_t bit = static_cast<uint32_t>(1) << id;
  if (bit & 0x000102C2u) return 0x1F;  // identify, stop, emergency_stop, sim_clock, object_position
  if (bit & 0x00001D2Cu) return 0x01;  // configure, configure_pid, start, jog, zero, configure_schedule, configure_cascade
  if (bit & 0x00000010u) return 0x0F;  // set_target
  return 0;
}

// nack.code of a command sent in a state its message is not taken in, before any field is looked at.
constexpr ErrorCode kStateError = ErrorCode::kBadState;
// Whether the firmware takes message id in state (schema.toml, the message's states).
inline bool taken_in(uint8_t id, State state) {
  return (host_to_mcu_states(id) >> static_cast<uint8_t>(state)) & 1u;
}

// Every message id travelling host -> MCU, in schema order (for the fuzzer and the tests: no hand-kept list).
constexpr uint8_t kHostToMcuIds[] = {Identify::kId, Configure::kId, ConfigurePid::kId, SetTarget::kId, Start::kId, Stop::kId, EmergencyStop::kId, Jog::kId, SimClock::kId, Zero::kId, ConfigureSchedule::kId, ConfigureCascade::kId, ObjectPosition::kId};

}  // namespace proto
}  // namespace mr
