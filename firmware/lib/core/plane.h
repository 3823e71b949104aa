// Geometric transformation (paper, Methods): tilt angles -> plane normal -> a module's four corner commands.
//
// Frame and sign conventions, stated once for the whole stack:
//   - x, y [m] in the fabric plane, origin at the module's centre; z up.
//   - Corner i sits at (x_i, y_i) = (+-m/2, +-n/2), numbered 0 (-x,-y), 1 (+x,-y), 2 (-x,+y), 3 (+x,+y): on one
//     module corner i is actuator i; on an array, corner_actuator (rig_config.h) says which actuator it is.
//   - A command a_i [m] is how far corner i is LOWERED below the reference height z0:
//     a_i = z0 - z_i, so a positive a_i moves the corner down.
//   - A positive tilt theta_zx [deg] lowers the +x corners (1, 3) and raises the -x corners (0, 2);
//     a positive theta_zy lowers the +y corners (2, 3). The object rolls downhill, i.e. towards +x for
//     theta_zx > 0, which is why the PID's positive output (target at larger x) is a positive tilt.
#pragma once

#include <stdint.h>  // uint8_t

namespace mr {

constexpr uint8_t kCorners = 4;  // a module's corners

struct Normal {
  float x, y, z;  // plane normal n = (n_x, n_y, n_z), as the paper defines it (not unit length)
};

// Manhattan (Algorithm 1): n = (sin theta_zx, sin theta_zy, cos theta_zx).
Normal manhattan_normal(float tilt_zx_deg, float tilt_zy_deg);

// |(x, y)| as max * sqrt(1 + (min / max)^2): no underflow or overflow of the squares, as hypotf, from the square root
// and division the image links anyway (avr-libc's hypot is 218 bytes of its own on the Uno); 0 for (0, 0).
float distance(float x, float y);

// Euclidean (Algorithm 2): n = (e_x/d sin theta, e_y/d sin theta, cos theta), d = |e|; (0, 0, 1) when d = 0.
Normal euclidean_normal(float theta_deg, float error_x, float error_y);

// a_i = z0 - z_i with z_i = (z0 n_z - n_x x_i - n_y y_i) / n_z, which is (n_x x_i + n_y y_i) / n_z:
// z0 cancels, so it is not an input. module_x, module_y [m] are the module's m and n.
void plane_commands(const Normal& n, float module_x, float module_y, float (&command)[kCorners]);

// Largest tilt [deg] on both axes at once that keeps every corner within +-range [m]:
// atan(range / ((m + n) / 2)); 26.57 deg for the paper's 0.5 x 0.5 m module and +-0.25 m.
float max_tilt_deg(float module_x, float module_y, float range);

// Base position [m] of corner i, about the module's centre.
float actuator_x(uint8_t i, float module_x);
float actuator_y(uint8_t i, float module_y);

constexpr float kDegToRad = 0.017453292519943295f;

}  // namespace mr
