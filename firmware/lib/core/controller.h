// Tilt controllers of the paper: Manhattan (Algorithm 1) and Euclidean (Algorithm 2), with the noise term.
#pragma once

#include <stdint.h>  // uint32_t

#include "pid.h"           // Pid, PidGains
#include "plane.h"         // plane transform
#include "prng.h"          // Xorshift32
#include "protocol_gen.h"  // proto::Controller, proto::Axis
#include "rig_config.h"    // kActuatorCount

namespace mr {

struct ControllerConfig {
  proto::Controller kind;
  float module_x;         // [m] m
  float module_y;         // [m] n
  float tilt_limit;       // [deg] saturation of every tilt output
  float noise_amplitude;  // [m] alpha
  PidGains pid[3];        // indexed by proto::Axis: x, y (Manhattan), radial (Euclidean)
};

struct ControllerOutput {
  float tilt_zx;                   // [deg] Euclidean: theta resolved along x
  float tilt_zy;                   // [deg] Euclidean: theta resolved along y
  float command[kActuatorCount];   // [m] a_i, + lowers the corner, within +-kActuatorRangeM
};

class TiltController {
 public:
  // Forgets the PIDs' state and the previous position; reseeds the noise.
  void reset(uint32_t noise_seed);

  // One control step at a measured object position (x, y) [m] for the target (target_x, target_y) [m].
  // dt [s] is the time since the previous step's measurement; dt <= 0 marks a first step
  // (proportional only). Returns the distance to the target [m].
  float step(const ControllerConfig& config, float target_x, float target_y, float x, float y, float dt,
             ControllerOutput& out);

 private:
  Pid pid_[3];
  Xorshift32 noise_;
  float prev_x_ = 0.0f;  // [m] previous measured position
  float prev_y_ = 0.0f;  // [m]
  bool has_prev_ = false;
};

}  // namespace mr
