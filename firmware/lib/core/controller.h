// Tilt controllers: the paper's Manhattan (Algorithm 1) and Euclidean (Algorithm 2), and beyond the paper a
// position-scheduled Manhattan and a cascaded position-velocity controller; all with the noise term.
#pragma once

#include <stdint.h>  // uint32_t

#include "pid.h"           // Pid, PidGains
#include "plane.h"         // plane transform
#include "prng.h"          // Xorshift32
#include "protocol_gen.h"  // proto::Controller, proto::Axis, proto::kAxisCount
#include "rig_config.h"    // kActuatorCount

namespace mr {

// The PIDs by proto::Axis: x, y (Manhattan, scheduled), radial (Euclidean), vx, vy (the cascade's inner loops).
constexpr uint8_t kX = static_cast<uint8_t>(proto::Axis::kX);
constexpr uint8_t kY = static_cast<uint8_t>(proto::Axis::kY);
constexpr uint8_t kRadial = static_cast<uint8_t>(proto::Axis::kRadial);
constexpr uint8_t kVx = static_cast<uint8_t>(proto::Axis::kVx);
constexpr uint8_t kVy = static_cast<uint8_t>(proto::Axis::kVy);
constexpr uint8_t kPidCount = proto::kAxisCount;

struct ScheduleConfig {  // configure_schedule
  float edge_zone;       // [m] width of the band along each edge where the schedule acts
  float edge_gain;       // [-] kp and ki at the edge, relative to the axis's own
  float edge_tilt;       // [-] the tilt toward the nearest edge at the edge, relative to the limit
  float edge_brake;      // [-] extra kd at the edge, relative to the axis's own
  float brake_speed;     // [m/s] speed at which the tilt along the motion reaches 0; 0: off
};

struct CascadeConfig {  // configure_cascade
  float position_gain;  // [1/s] velocity asked per metre of error
  float speed_limit;    // [m/s] the most the outer loop asks for
};

struct ControllerConfig {
  proto::Controller kind;
  float module_x;         // [m] m
  float module_y;         // [m] n
  float tilt_limit;       // [deg] saturation of every tilt output
  float noise_amplitude;  // [m] alpha
  float velocity_filter;  // [s] time constant of the velocity estimate's low-pass
  PidGains pid[kPidCount];
  ScheduleConfig schedule;
  CascadeConfig cascade;
};

struct ControllerOutput {
  float tilt_zx;                  // [deg] Euclidean: theta resolved along x
  float tilt_zy;                  // [deg] Euclidean: theta resolved along y
  uint8_t module;                 // the module whose corners drive the object (0 on one module)
  float command[kActuatorCount];  // [m] a_i, + lowers the corner, within +-kActuatorRangeM; on an array every
                                  // actuator on the driven module's plane
};

class TiltController {
 public:
  // Forgets the PIDs' state, the previous position and the velocity; reseeds the noise.
  void reset(uint32_t noise_seed);

  // One control step at a measured object position (x, y) [m] for the target (target_x, target_y) [m], driven by
  // module k's plane (route.h; 0 on one module). dt [s] is the time since the previous step's measurement; dt <= 0
  // marks a first step (proportional only). Returns the distance to the target [m]. A change of module (a
  // hand-over) starts the PIDs and the velocity afresh, as a first step: carried on, the integral wound up toward
  // the last leg's waypoint threw the object on (sim/README.md, Arrays). The noise runs on.
  float step(const ControllerConfig& config, float target_x, float target_y, float x, float y, float dt,
             ControllerOutput& out, uint8_t module = 0);

 private:
  Pid pid_[kPidCount];
  Xorshift32 noise_;
  float prev_x_ = 0.0f;  // [m] previous measured position
  float prev_y_ = 0.0f;  // [m]
  float vx_ = 0.0f;      // [m/s] filtered velocity (0 until a rate is known)
  float vy_ = 0.0f;      // [m/s]
  bool has_prev_ = false;
  uint8_t module_ = 0;  // the module of the last step (arrays)

  void restart();  // the PIDs, the previous position and the velocity forgotten; the noise runs on
};

}  // namespace mr
