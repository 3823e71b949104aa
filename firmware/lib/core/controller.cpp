// Manhattan and Euclidean control steps: PID -> tilt -> plane -> noisy, clamped actuator commands.
#include "controller.h"

#include <math.h>  // hypotf

namespace mr {

void TiltController::reset(uint32_t noise_seed) {
  for (Pid& pid : pid_) pid.reset();
  noise_.seed(noise_seed);
  has_prev_ = false;
}

float TiltController::step(const ControllerConfig& config, float target_x, float target_y, float x, float y,
                           float dt, ControllerOutput& out) {
  const bool rate_known = has_prev_ && dt > 0.0f;
  if (!rate_known) dt = 0.0f;
  const float ex = target_x - x;
  const float ey = target_y - y;
  const float distance = hypotf(ex, ey);  // no underflow or overflow of the squares
  Normal normal;
  if (config.kind == proto::Controller::kManhattan) {
    // The error at the previous measurement against today's target: its change is the object's motion only.
    const float rate_x = rate_known ? (ex - (target_x - prev_x_)) / dt : 0.0f;
    const float rate_y = rate_known ? (ey - (target_y - prev_y_)) / dt : 0.0f;
    out.tilt_zx = pid_[0].update(config.pid[0], ex, rate_x, dt, config.tilt_limit);
    out.tilt_zy = pid_[1].update(config.pid[1], ey, rate_y, dt, config.tilt_limit);
    normal = manhattan_normal(out.tilt_zx, out.tilt_zy);
  } else {
    float rate = 0.0f;
    if (rate_known) {
      const float px = target_x - prev_x_;
      const float py = target_y - prev_y_;
      rate = (distance - hypotf(px, py)) / dt;
    }
    const float theta = pid_[2].update(config.pid[2], distance, rate, dt, config.tilt_limit);
    const float ux = distance > 0.0f ? ex / distance : 0.0f;
    const float uy = distance > 0.0f ? ey / distance : 0.0f;
    out.tilt_zx = theta * ux;
    out.tilt_zy = theta * uy;
    normal = euclidean_normal(theta, ex, ey);
  }
  plane_commands(normal, config.module_x, config.module_y, out.command);
  for (float& a : out.command) {
    a = clamp_symmetric(a + config.noise_amplitude * noise_.uniform_pm1(), kActuatorRangeM);
  }
  prev_x_ = x;
  prev_y_ = y;
  has_prev_ = true;
  return distance;
}

}  // namespace mr
