// Encoder unwrapping and the actuator position loop.
#include "actuator.h"

#include "pid.h"  // clamp_symmetric

namespace mr {

namespace {

constexpr uint16_t kCountMask = kEncoderCounts - 1;
constexpr int16_t kHalfTurn = kEncoderCounts / 2;

float abs_f(float x) { return x < 0.0f ? -x : x; }

}  // namespace

void EncoderUnwrap::reset(uint16_t raw) {
  last_ = raw & kCountMask;
  count_ = 0;
}

int32_t EncoderUnwrap::update(uint16_t raw) {
  raw &= kCountMask;
  int16_t delta = static_cast<int16_t>(raw - last_);  // -4095..4095
  if (delta > kHalfTurn) delta = static_cast<int16_t>(delta - kEncoderCounts);
  if (delta < -kHalfTurn) delta = static_cast<int16_t>(delta + kEncoderCounts);
  last_ = raw;
  count_ += delta;
  return count_;
}

void ActuatorLoop::reset(uint16_t raw) {
  encoder_.reset(raw);
  position_m_ = 0.0f;
  stalled_ = false;
  idle();
}

void ActuatorLoop::idle() {
  integral_ = 0.0f;
  window_s_ = 0.0f;
  window_from_m_ = position_m_;
}

float ActuatorLoop::step(const ActuatorConfig& c, float setpoint_m, uint16_t raw, float dt_s) {
  const float previous_m = position_m_;
  position_m_ = static_cast<float>(encoder_.update(raw)) * c.metres_per_count;
  const float speed = dt_s > 0.0f ? (position_m_ - previous_m) / dt_s : 0.0f;  // [m/s]
  const float error = clamp_symmetric(setpoint_m, c.soft_limit_m) - position_m_;

  float duty = 0.0f;
  if (abs_f(error) > c.deadband_m) {
    const float p = c.kp * error;
    const float d = -c.kd * speed;
    const float next = clamp_symmetric(integral_ + c.ki * error * dt_s, c.max_duty);
    const float unsaturated = p + next + d;
    const bool winding_up =
        (unsaturated > c.max_duty && next > integral_) || (unsaturated < -c.max_duty && next < integral_);
    if (!winding_up) integral_ = next;
    duty = clamp_symmetric(p + integral_ + d, c.max_duty);
  }
  // Beyond a soft limit the loop only drives back toward the range.
  if ((position_m_ >= c.soft_limit_m && duty > 0.0f) || (position_m_ <= -c.soft_limit_m && duty < 0.0f)) {
    duty = 0.0f;
  }

  if (abs_f(duty) >= c.stall_duty && abs_f(position_m_ - window_from_m_) < c.stall_travel_m) {
    window_s_ += dt_s;
    if (window_s_ >= c.stall_time_s) stalled_ = true;
  } else {
    window_s_ = 0.0f;
    window_from_m_ = position_m_;
  }
  return stalled_ ? 0.0f : duty;
}

}  // namespace mr
