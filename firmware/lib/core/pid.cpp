// PID update: clamped integral, conditional integration while saturated.
#include "pid.h"

namespace mr {

float clamp_symmetric(float x, float limit) {
  if (!(x == x)) return 0.0f;
  if (x > limit) return limit;
  if (x < -limit) return -limit;
  return x;
}

float Pid::update(const PidGains& gains, float error, float error_rate, float dt, float output_limit) {
  const float p = gains.kp * error;
  const float d = gains.kd * error_rate;
  float next = clamp_symmetric(integral_ + gains.ki * error * dt, gains.integral_limit);
  const float unsaturated = p + next + d;
  const bool winding_up = (unsaturated > output_limit && next > integral_) ||
                          (unsaturated < -output_limit && next < integral_);
  if (!winding_up) integral_ = next;
  return clamp_symmetric(p + integral_ + d, output_limit);
}

}  // namespace mr
