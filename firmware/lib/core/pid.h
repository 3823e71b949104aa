// PID with anti-windup, derivative on measurement and output saturation; dt is an argument.
//
// Units: the error is a distance [m] and the output a tilt angle [deg]. The paper's gains only make
// sense in degrees: kP = 30.9 turns a 0.1 m error into 3.09 deg of tilt, in the range its phase
// plots show against the +-26 deg limit; read as radians the same output would exceed the limit
// (0.46 rad) at a 1.5 cm error and throw the object off the fabric.
#pragma once

namespace mr {

struct PidGains {
  float kp;              // [deg/m]
  float ki;              // [deg/(m s)]
  float kd;              // [deg s/m]
  float integral_limit;  // [deg] bound on the integral term's contribution
};

class Pid {
 public:
  void reset() { integral_ = 0.0f; }

  // error [m]; error_rate [m/s]: the error's change caused by the measured object's motion alone,
  // computed against the current target, so a new target causes no derivative kick; dt [s] since
  // the previous update, 0 on the first one (no integration then). Returns the tilt [deg] within
  // [low, high] (low <= 0 <= high). The integral stops growing while the output saturates in its direction.
  float update(const PidGains& gains, float error, float error_rate, float dt, float low, float high);
  // The same within +-output_limit.
  float update(const PidGains& gains, float error, float error_rate, float dt, float output_limit) {
    return update(gains, error, error_rate, dt, -output_limit, output_limit);
  }

  float integral() const { return integral_; }  // [deg]

 private:
  float integral_ = 0.0f;  // [deg]
};

// Clamps x to [low, high]; NaN becomes 0. Never inlined: one copy serves its many callers, which on the Uno
// saves half a kilobyte of flash for a call's few cycles.
float clamp(float x, float low, float high) __attribute__((noinline));
// Clamps x to [-limit, limit]; NaN becomes 0.
inline float clamp_symmetric(float x, float limit) { return clamp(x, -limit, limit); }

}  // namespace mr
