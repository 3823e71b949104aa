// Plane normal and actuator commands from tilt angles, as in the paper's equations for n, z_i and a_i.
#include "plane.h"

#include <math.h>  // sinf, cosf, fabsf, sqrtf, atanf

namespace mr {

Normal manhattan_normal(float tilt_zx_deg, float tilt_zy_deg) {
  const float zx = tilt_zx_deg * kDegToRad;
  const float zy = tilt_zy_deg * kDegToRad;
  return Normal{sinf(zx), sinf(zy), cosf(zx)};
}

float distance(float x, float y) {
  const float ax = fabsf(x), ay = fabsf(y);
  const float big = ax > ay ? ax : ay, small = ax > ay ? ay : ax;
  if (!(big > 0.0f)) return big;  // 0, or NaN passed on
  const float r = small / big;
  return big * sqrtf(1.0f + r * r);
}

Normal euclidean_normal(float theta_deg, float error_x, float error_y) {
  const float d = distance(error_x, error_y);
  if (!(d > 0.0f)) return Normal{0.0f, 0.0f, 1.0f};
  const float theta = theta_deg * kDegToRad;
  const float s = sinf(theta);
  // Direction first: |e/d| <= 1 for any d > 0, whereas sin(theta) / d overflows for a subnormal d.
  return Normal{(error_x / d) * s, (error_y / d) * s, cosf(theta)};
}

float actuator_x(uint8_t i, float module_x) { return (i & 1u) ? 0.5f * module_x : -0.5f * module_x; }
float actuator_y(uint8_t i, float module_y) { return (i & 2u) ? 0.5f * module_y : -0.5f * module_y; }

void plane_commands(const Normal& n, float module_x, float module_y, float (&command)[kCorners]) {
  for (uint8_t i = 0; i < kCorners; ++i) {
    command[i] = (n.x * actuator_x(i, module_x) + n.y * actuator_y(i, module_y)) / n.z;
  }
}

float max_tilt_deg(float module_x, float module_y, float range) {
  return atanf(range / (0.5f * (module_x + module_y))) / kDegToRad;
}

}  // namespace mr
