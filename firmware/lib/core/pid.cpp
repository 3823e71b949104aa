// PID update: clamped integral, conditional integration while saturated.
#include "pid.h"

namespace mr {

float clamp(float x, float low, float high) {
  if (!(x == x)) return 0.0f;
  if (x > high) return high;
  if (x < low) return low;
  return x;
}

float Pid::update(const PidGains& gains, float error, float error_rate, float dt, float low, float high) {
  const float p = gains.kp * error;
  const float d = gains.kd * error_rate;
  float next = clamp_symmetric(integral_ + gains.ki * error * dt, gains.integral_limit);
  const float unsaturated = p + next + d;
  const bool winding_up = (unsaturated > high && next > integral_) || (unsaturated < low && next < integral_);
  if (!winding_up) integral_ = next;
  return clamp(p + integral_ + d, low, high);
}

}  // namespace mr
