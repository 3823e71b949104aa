// Tilt control steps: the paper's Manhattan and Euclidean, and the scheduled and cascaded controllers beyond it:
// PIDs -> tilt -> plane -> noisy, clamped actuator commands.
#include "controller.h"

#include <math.h>  // fabsf, isfinite

#include "route.h"  // module_centre_x, module_centre_y

namespace mr {

namespace {

float clamp01(float x) { return x < 0.0f ? 0.0f : (x > 1.0f ? 1.0f : x); }

// The velocity estimate [m/s] after one frame: v low-passed toward the frame difference raw with weight blend. A
// non-finite result (a NaN or infinite position in this frame or the last) restarts it at rest, so one bad frame
// cannot hold it at NaN for the rest of the run.
float filtered_velocity(float v, float raw, float blend) {
  const float next = v + blend * (raw - v);
  return isfinite(next) ? next : 0.0f;
}

// One axis of the position-scheduled Manhattan controller. p [m] is the object's coordinate on the axis, half [m]
// the module's half side along it, v [m/s] its filtered velocity. Within edge_zone of the edge the object is
// nearest to, kp and ki ease toward edge_gain times themselves, kd grows by edge_brake times itself and the tilt
// toward that edge is limited toward edge_tilt times the limit. An edge_zone wider than half the module also
// limits the tilt toward the other edge by its own distance, so the limits do not jump at the centre. With
// brake_speed > 0 the tilt along the motion fades to 0 as the speed reaches brake_speed (a tilt against it, which
// brakes, stays free).
float scheduled_axis(Pid& pid, const PidGains& gains, const ScheduleConfig& s, float tilt_limit, float half, float p,
                     float error, float error_rate, float v, float dt) {
  const float near_edge = clamp01(1.0f - (half - fabsf(p)) / s.edge_zone);  // 0 inside, 1 at or past the edge
  const float far_edge = clamp01(1.0f - (half + fabsf(p)) / s.edge_zone);   // the other: 0 unless zone > half
  const float ease = 1.0f - near_edge * (1.0f - s.edge_gain);
  const PidGains scheduled{gains.kp * ease, gains.ki * ease, gains.kd * (1.0f + near_edge * s.edge_brake),
                           gains.integral_limit};
  const float toward_near = tilt_limit * (1.0f - near_edge * (1.0f - s.edge_tilt));
  const float toward_far = tilt_limit * (1.0f - far_edge * (1.0f - s.edge_tilt));
  float high = p > 0.0f ? toward_near : toward_far;  // a positive tilt moves the object toward +x (+y)
  float low = p > 0.0f ? -toward_far : -toward_near;
  if (s.brake_speed > 0.0f) {
    const float along_motion = clamp01(1.0f - fabsf(v) / s.brake_speed);
    if (v > 0.0f) high *= along_motion;
    if (v < 0.0f) low *= along_motion;
  }
  return pid.update(scheduled, error, error_rate, dt, low, high);
}

// One axis of the cascaded controller: the outer loop asks for a velocity toward the target, the inner PID
// tilts for it. v [m/s] is the filtered velocity and acceleration [m/s^2] its change since the previous step.
float cascade_axis(Pid& pid, const PidGains& gains, const CascadeConfig& c, float tilt_limit, float error, float v,
                   float acceleration, float dt) {
  const float wanted = clamp_symmetric(c.position_gain * error, c.speed_limit);  // [m/s]
  return pid.update(gains, wanted - v, -acceleration, dt, -tilt_limit, tilt_limit);
}

}  // namespace

void TiltController::reset(uint32_t noise_seed) {
  restart();
  noise_.seed(noise_seed);
}

void TiltController::restart() {
  for (Pid& pid : pid_) pid.reset();
  has_prev_ = false;
  vx_ = vy_ = 0.0f;
}

float TiltController::step(const ControllerConfig& config, float target_x, float target_y, float x, float y, float dt,
                           ControllerOutput& out, uint8_t module) {
  if (kModuleCount > 1 && module != module_) {  // a hand-over: the next module starts afresh (sim/README.md, Arrays)
    restart();
    module_ = module;
  }
  const bool rate_known = has_prev_ && dt > 0.0f;
  if (!rate_known) dt = 0.0f;
  const float ex = target_x - x;
  const float ey = target_y - y;
  const float distance = mr::distance(ex, ey);
  // The object's velocity [m/s]: camera-frame differences through a first-order low-pass of velocity_filter [s].
  const float last_vx = vx_;
  const float last_vy = vy_;
  if (rate_known) {
    const float blend = dt / (config.velocity_filter + dt);
    vx_ = filtered_velocity(vx_, (x - prev_x_) / dt, blend);
    vy_ = filtered_velocity(vy_, (y - prev_y_) / dt, blend);
  } else {
    vx_ = vy_ = 0.0f;
  }
  // Manhattan's (and the schedule's) derivative: the error at the previous measurement against today's target,
  // so its change is the object's motion only.
  const float rate_x = rate_known ? (ex - (target_x - prev_x_)) / dt : 0.0f;
  const float rate_y = rate_known ? (ey - (target_y - prev_y_)) / dt : 0.0f;
  Normal normal;
  switch (config.kind) {
    case proto::Controller::kEuclidean: {
      float rate = 0.0f;
      if (rate_known) {
        const float px = target_x - prev_x_;
        const float py = target_y - prev_y_;
        rate = (distance - mr::distance(px, py)) / dt;
      }
      const float theta = pid_[kRadial].update(config.pid[kRadial], distance, rate, dt, config.tilt_limit);
      const float ux = distance > 0.0f ? ex / distance : 0.0f;
      const float uy = distance > 0.0f ? ey / distance : 0.0f;
      out.tilt_zx = theta * ux;
      out.tilt_zy = theta * uy;
      normal = euclidean_normal(theta, ex, ey);
      break;
    }
    case proto::Controller::kScheduled:
      // The schedule's edges are the driven module's: the position about its centre.
      out.tilt_zx = scheduled_axis(pid_[kX], config.pid[kX], config.schedule, config.tilt_limit, 0.5f * config.module_x,
                                   x - module_centre_x(module, config.module_x), ex, rate_x, vx_, dt);
      out.tilt_zy = scheduled_axis(pid_[kY], config.pid[kY], config.schedule, config.tilt_limit, 0.5f * config.module_y,
                                   y - module_centre_y(module, config.module_y), ey, rate_y, vy_, dt);
      normal = manhattan_normal(out.tilt_zx, out.tilt_zy);
      break;
    case proto::Controller::kCascade:
      out.tilt_zx = cascade_axis(pid_[kVx], config.pid[kVx], config.cascade, config.tilt_limit, ex, vx_,
                                 rate_known ? (vx_ - last_vx) / dt : 0.0f, dt);
      out.tilt_zy = cascade_axis(pid_[kVy], config.pid[kVy], config.cascade, config.tilt_limit, ey, vy_,
                                 rate_known ? (vy_ - last_vy) / dt : 0.0f, dt);
      normal = manhattan_normal(out.tilt_zx, out.tilt_zy);
      break;
    default:  // Manhattan
      out.tilt_zx = pid_[kX].update(config.pid[kX], ex, rate_x, dt, config.tilt_limit);
      out.tilt_zy = pid_[kY].update(config.pid[kY], ey, rate_y, dt, config.tilt_limit);
      normal = manhattan_normal(out.tilt_zx, out.tilt_zy);
      break;
  }
  // Every actuator on the driven module's plane, turned about that module's centre. On one module these are its
  // corners, by the paper's transform as written (plane.h). On an array the plane goes on over the other modules,
  // each actuator clamped to its travel, so the edges the module shares are neither a ridge nor a valley for the
  // object to stick on (sim/README.md, Arrays); its slopes are taken once for the nine, and no noise is drawn without
  // noise (the Mega's frame budget).
  out.module = module;
  if (kModuleCount == 1) {
    float corner[kCorners];
    plane_commands(normal, config.module_x, config.module_y, corner);
    for (uint8_t c = 0; c < kCorners; ++c) {
      out.command[c] = clamp_symmetric(corner[c] + config.noise_amplitude * noise_.uniform_pm1(), kActuatorRangeM);
    }
  } else {
    // The plane's part along x of each column of nodes, and along y of each row: a_i is a column's plus a row's.
    constexpr uint8_t kColumns = kModulesX + 1, kRows = kModulesY + 1;
    const float slope_x = normal.x / normal.z, slope_y = normal.y / normal.z;  // [m/m] a_i per metre along x, y
    const float centre_x = module_centre_x(module, config.module_x);
    const float centre_y = module_centre_y(module, config.module_y);
    float along_x[kColumns], along_y[kRows];  // [m]
    for (uint8_t p = 0; p < kColumns; ++p) along_x[p] = slope_x * (node_x(p, config.module_x) - centre_x);
    for (uint8_t q = 0; q < kRows; ++q) along_y[q] = slope_y * (node_y(q * kColumns, config.module_y) - centre_y);
    const bool noisy = config.noise_amplitude != 0.0f;  // without noise no draw: the same commands, a shorter frame
    for (uint8_t i = 0; i < kActuatorCount; ++i) {
      const float a = along_x[i % kColumns] + along_y[i / kColumns];
      out.command[i] =
          clamp_symmetric(a + (noisy ? config.noise_amplitude * noise_.uniform_pm1() : 0.0f), kActuatorRangeM);
    }
  }
  prev_x_ = x;
  prev_y_ = y;
  has_prev_ = true;
  return distance;
}

}  // namespace mr
