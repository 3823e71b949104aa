// Unit tests of the plane transform: sign convention, the paper's formulas, geometric tilt limit.
#include <doctest/doctest.h>

#include <initializer_list>  // range-for over braced lists
#include <math.h>            // tanf, sinf, cosf, atanf, fabsf, sqrtf, hypotf

#include "plane.h"       // manhattan_normal, euclidean_normal, plane_commands, max_tilt_deg, distance
#include "rig_config.h"  // kActuatorRangeM, kActuatorCount

namespace {

using doctest::Approx;
using Commands = float[mr::kActuatorCount];

void manhattan(float zx, float zy, float m, float n, Commands& a) {
  mr::plane_commands(mr::manhattan_normal(zx, zy), m, n, a);
}

void euclidean(float theta, float ex, float ey, float m, float n, Commands& a) {
  mr::plane_commands(mr::euclidean_normal(theta, ex, ey), m, n, a);
}

float deg(float d) { return d * 0.017453292519943295f; }

}  // namespace

TEST_CASE("plane: actuator numbering 0 (-x,-y), 1 (+x,-y), 2 (-x,+y), 3 (+x,+y)") {
  CHECK(mr::actuator_x(0, 0.5f) == -0.25f);
  CHECK(mr::actuator_y(0, 0.8f) == -0.4f);
  CHECK(mr::actuator_x(1, 0.5f) == 0.25f);
  CHECK(mr::actuator_y(1, 0.8f) == -0.4f);
  CHECK(mr::actuator_x(2, 0.5f) == -0.25f);
  CHECK(mr::actuator_y(2, 0.8f) == 0.4f);
  CHECK(mr::actuator_x(3, 0.5f) == 0.25f);
  CHECK(mr::actuator_y(3, 0.8f) == 0.4f);
}

TEST_CASE("plane: level tilt gives a level surface") {
  Commands a;
  manhattan(0.0f, 0.0f, 0.5f, 0.5f, a);
  for (float v : a) CHECK(v == 0.0f);
  const mr::Normal n = mr::manhattan_normal(0.0f, 0.0f);
  CHECK(n.x == 0.0f);
  CHECK(n.y == 0.0f);
  CHECK(n.z == 1.0f);
}

TEST_CASE("plane: positive tilt_zx lowers the +x corners (1, 3) and raises the -x corners (0, 2)") {
  Commands a;
  manhattan(10.0f, 0.0f, 0.5f, 0.5f, a);
  const float expect = tanf(deg(10.0f)) * 0.25f;  // 0.04408 m
  CHECK(a[1] == Approx(expect));
  CHECK(a[3] == Approx(expect));
  CHECK(a[0] == Approx(-expect));
  CHECK(a[2] == Approx(-expect));
  CHECK(a[1] > 0.0f);
}

TEST_CASE("plane: positive tilt_zy lowers the +y corners (2, 3)") {
  Commands a;
  manhattan(0.0f, 10.0f, 0.5f, 0.6f, a);
  const float expect = sinf(deg(10.0f)) * 0.3f;  // n = (0, sin zy, cos 0): a = sin(zy) y_i
  CHECK(a[2] == Approx(expect));
  CHECK(a[3] == Approx(expect));
  CHECK(a[0] == Approx(-expect));
  CHECK(a[1] == Approx(-expect));
  CHECK(a[2] > 0.0f);
}

TEST_CASE("plane: negative tilts mirror the positive ones") {
  Commands p, n;
  manhattan(7.0f, -3.0f, 0.5f, 0.5f, p);
  manhattan(-7.0f, 3.0f, 0.5f, 0.5f, n);
  for (uint8_t i = 0; i < mr::kActuatorCount; ++i) CHECK(n[i] == Approx(-p[i]));
}

TEST_CASE("plane: the Manhattan normal is the paper's (sin zx, sin zy, cos zx)") {
  const mr::Normal n = mr::manhattan_normal(20.0f, -12.0f);
  CHECK(n.x == Approx(sinf(deg(20.0f))));
  CHECK(n.y == Approx(sinf(deg(-12.0f))));
  CHECK(n.z == Approx(cosf(deg(20.0f))));
}

TEST_CASE("plane: the commands follow a_i = z0 - z_i for any z0 (z0 cancels)") {
  const float m = 0.7f, nn = 0.4f;
  const mr::Normal n = mr::manhattan_normal(12.0f, -8.0f);
  Commands a;
  mr::plane_commands(n, m, nn, a);
  for (float z0 : {0.0f, 0.1f, 0.35f, -2.0f}) {
    for (uint8_t i = 0; i < mr::kActuatorCount; ++i) {
      const float xi = (i & 1) ? 0.5f * m : -0.5f * m;
      const float yi = (i & 2) ? 0.5f * nn : -0.5f * nn;
      const float zi = (z0 * n.z - n.x * xi - n.y * yi) / n.z;  // the paper's plane through (0, 0, z0)
      CAPTURE(z0);
      CAPTURE(static_cast<int>(i));
      CHECK(a[i] == Approx(z0 - zi).epsilon(1e-5));
    }
  }
}

TEST_CASE("plane: the four corners always lie on one plane (a0 + a3 = a1 + a2)") {
  for (float zx : {-25.0f, -3.0f, 0.0f, 11.0f, 26.0f}) {
    for (float zy : {-26.0f, 0.5f, 19.0f}) {
      Commands a;
      manhattan(zx, zy, 0.5f, 0.9f, a);
      CHECK(a[0] + a[3] == Approx(a[1] + a[2]).epsilon(1e-5));
    }
  }
}

TEST_CASE("plane: max_tilt_deg is atan(range / ((m + n) / 2))") {
  CHECK(mr::max_tilt_deg(0.5f, 0.5f, 0.25f) == Approx(26.565051f).epsilon(1e-6));
  CHECK(mr::max_tilt_deg(1.0f, 0.5f, 0.25f) == Approx(18.434949f).epsilon(1e-6));
  CHECK(mr::max_tilt_deg(1.0f, 1.0f, 0.25f) == Approx(14.036243f).epsilon(1e-6));
  CHECK(mr::max_tilt_deg(0.1f, 0.1f, 0.25f) == Approx(68.198591f).epsilon(1e-6));
}

TEST_CASE("plane: at the tilt limit on both axes every command is within range, and one reaches it") {
  const float sizes[][2] = {{0.5f, 0.5f}, {1.0f, 0.5f}, {0.3f, 2.0f}, {0.1f, 0.1f}, {10.0f, 10.0f}, {0.5f, 0.75f}};
  for (const auto& s : sizes) {
    const float lim = mr::max_tilt_deg(s[0], s[1], mr::kActuatorRangeM);
    CAPTURE(s[0]);
    CAPTURE(s[1]);
    float largest = 0.0f;
    for (float sx : {-1.0f, 1.0f}) {
      for (float sy : {-1.0f, 1.0f}) {
        Commands a;
        manhattan(sx * lim, sy * lim, s[0], s[1], a);
        for (float v : a) {
          CHECK(fabsf(v) <= mr::kActuatorRangeM * (1.0f + 1e-5f));
          largest = fabsf(v) > largest ? fabsf(v) : largest;
        }
      }
    }
    CHECK(largest == Approx(mr::kActuatorRangeM).epsilon(1e-4));
  }
}

TEST_CASE("plane: Euclidean at the tilt limit stays in range in every direction") {
  const float lim = mr::max_tilt_deg(0.5f, 0.5f, mr::kActuatorRangeM);
  for (int k = 0; k < 360; k += 5) {
    const float ang = deg(static_cast<float>(k));
    Commands a;
    euclidean(lim, cosf(ang), sinf(ang), 0.5f, 0.5f, a);
    for (float v : a) CHECK(fabsf(v) <= mr::kActuatorRangeM);
  }
}

TEST_CASE("plane: Euclidean with d = 0 is level whatever theta") {
  const mr::Normal n = mr::euclidean_normal(20.0f, 0.0f, 0.0f);
  CHECK(n.x == 0.0f);
  CHECK(n.y == 0.0f);
  CHECK(n.z == 1.0f);
  Commands a;
  euclidean(20.0f, 0.0f, 0.0f, 0.5f, 0.5f, a);
  for (float v : a) CHECK(v == 0.0f);
}

TEST_CASE("plane: Euclidean along +x equals Manhattan with the same tilt on x only") {
  Commands e, m;
  euclidean(15.0f, 0.2f, 0.0f, 0.5f, 0.5f, e);
  manhattan(15.0f, 0.0f, 0.5f, 0.5f, m);
  for (uint8_t i = 0; i < mr::kActuatorCount; ++i) CHECK(e[i] == Approx(m[i]));
}

TEST_CASE("plane: Euclidean tilts towards the error direction; only the direction of e matters") {
  Commands a, b;
  euclidean(10.0f, 0.1f, 0.1f, 0.5f, 0.5f, a);
  euclidean(10.0f, 0.001f, 0.001f, 0.5f, 0.5f, b);
  const float expect = tanf(deg(10.0f)) * 0.25f * sqrtf(2.0f);
  CHECK(a[3] == Approx(expect));   // (+x, +y) corner, along e: lowered
  CHECK(a[0] == Approx(-expect));  // opposite corner: raised
  CHECK(a[1] == Approx(0.0f).epsilon(1e-6));
  CHECK(a[2] == Approx(0.0f).epsilon(1e-6));
  for (uint8_t i = 0; i < mr::kActuatorCount; ++i) CHECK(a[i] == Approx(b[i]));
  // The normal is (e/d sin theta, cos theta).
  const mr::Normal n = mr::euclidean_normal(10.0f, 0.03f, -0.04f);
  CHECK(n.x == Approx(0.6f * sinf(deg(10.0f))));
  CHECK(n.y == Approx(-0.8f * sinf(deg(10.0f))));
  CHECK(n.z == Approx(cosf(deg(10.0f))));
}

TEST_CASE("plane: Euclidean with a subnormal error still gives a finite, in-range plane") {
  // Found by hypothesis: sin(theta) / d overflows to inf for d = 4.2e-45, and 0 * inf is NaN.
  const float limit = mr::max_tilt_deg(1.0f, 1.0f, mr::kActuatorRangeM);
  for (float e : {4.2038954e-45f, 1.0e-40f, 1.1754944e-38f}) {
    Commands a;
    euclidean(limit, 0.0f, e, 1.0f, 1.0f, a);
    for (float ai : a) {
      CHECK(ai == ai);
      CHECK(fabsf(ai) <= mr::kActuatorRangeM * (1.0f + 1e-5f));
    }
    euclidean(limit, e, -e, 1.0f, 1.0f, a);
    for (float ai : a) CHECK(ai == ai);
  }
}

TEST_CASE("plane: distance is hypot's |(x, y)| without its squares' underflow or overflow") {
  CHECK(mr::distance(3.0f, -4.0f) == Approx(5.0f).epsilon(1e-7));
  CHECK(mr::distance(0.0f, 0.0f) == 0.0f);
  CHECK(mr::distance(0.0f, -0.02f) == 0.02f);
  CHECK(mr::distance(1e-30f, 1e-30f) == Approx(1.4142135e-30f).epsilon(1e-6));  // x * x would be 0
  CHECK(mr::distance(1e30f, -1e30f) == Approx(1.4142135e30f).epsilon(1e-6));    // x * x would be inf
  for (float x : {0.013f, -0.21f, 0.25f, 1e-3f}) {
    for (float y : {0.0f, 0.07f, -0.18f, 2e-4f}) {
      CHECK(mr::distance(x, y) == Approx(hypotf(x, y)).epsilon(2e-7));
    }
  }
}
