// Unit tests of the tilt controllers: Manhattan vs Euclidean, seeded noise, commands bounded for any input.
#include <doctest/doctest.h>

#include <initializer_list>  // range-for over braced lists
#include <math.h>            // fabsf, sqrtf

#include <limits>  // quiet_NaN, infinity, max

#include "controller.h"  // TiltController, ControllerConfig, ControllerOutput
#include "plane.h"       // max_tilt_deg
#include "prng.h"        // Xorshift32

namespace {

using doctest::Approx;
using mr::proto::Controller;

const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();
const float kMax = std::numeric_limits<float>::max();

mr::ControllerConfig paper(Controller kind, float noise = 0.0f) {
  const mr::PidGains xy{30.9f, 26.78f, 15.45f, 26.565051f};
  const mr::PidGains radial{86.72f, 27.91f, 10.19f, 26.565051f};
  const mr::PidGains velocity{100.0f, 30.0f, 0.0f, 26.565051f};
  return mr::ControllerConfig{kind,
                              0.5f,
                              0.5f,
                              26.565051f,
                              noise,
                              0.05f,
                              {xy, xy, radial, velocity, velocity},
                              mr::ScheduleConfig{0.05f, 1.0f, 1.0f, 0.0f, 0.0f},
                              mr::CascadeConfig{3.0f, 0.15f}};
}

bool commands_ok(const mr::ControllerOutput& out) {
  for (float a : out.command) {
    if (!(a >= -mr::kActuatorRangeM && a <= mr::kActuatorRangeM)) return false;  // also false for NaN
  }
  return true;
}

}  // namespace

TEST_CASE("xorshift32: known sequence, seed 0 replaced by 1, uniform in [-1, 1)") {
  mr::Xorshift32 r;
  r.seed(1);
  CHECK(r.next() == 270369u);  // Marsaglia's xorshift32 (13, 17, 5) from state 1
  CHECK(r.next() == 67634689u);
  mr::Xorshift32 z;
  z.seed(0);
  mr::Xorshift32 one;
  one.seed(1);
  for (int i = 0; i < 10; ++i) CHECK(z.next() == one.next());
  float lo = 1.0f, hi = -1.0f;
  for (int i = 0; i < 100000; ++i) {
    const float u = r.uniform_pm1();
    REQUIRE(u >= -1.0f);
    REQUIRE(u < 1.0f);
    lo = u < lo ? u : lo;
    hi = u > hi ? u : hi;
  }
  CHECK(lo < -0.99f);
  CHECK(hi > 0.99f);
}

TEST_CASE("controller: Manhattan, target along +x tilts +x down (1, 3) by kP * e") {
  mr::TiltController c;
  c.reset(1);
  mr::ControllerOutput out{};
  const float d = c.step(paper(Controller::kManhattan), 0.1f, 0.0f, 0.0f, 0.0f, 0.0f, out);
  CHECK(d == Approx(0.1f));
  CHECK(out.tilt_zx == Approx(3.09f));
  CHECK(out.tilt_zy == 0.0f);
  CHECK(out.command[1] > 0.0f);
  CHECK(out.command[3] > 0.0f);
  CHECK(out.command[0] < 0.0f);
  CHECK(out.command[2] < 0.0f);
  CHECK(out.command[1] == Approx(0.25f * tanf(3.09f * mr::kDegToRad)));
}

TEST_CASE("controller: Manhattan runs one PID per axis; Euclidean one PID on the distance") {
  mr::ControllerOutput man{}, euc{};
  mr::TiltController cm, ce;
  cm.reset(1);
  ce.reset(1);
  // Error (0.03, 0.04): distance 0.05.
  cm.step(paper(Controller::kManhattan), 0.03f, 0.04f, 0.0f, 0.0f, 0.0f, man);
  const float d = ce.step(paper(Controller::kEuclidean), 0.03f, 0.04f, 0.0f, 0.0f, 0.0f, euc);
  CHECK(d == Approx(0.05f));
  CHECK(man.tilt_zx == Approx(30.9f * 0.03f));
  CHECK(man.tilt_zy == Approx(30.9f * 0.04f));
  const float theta = 86.72f * 0.05f;
  CHECK(euc.tilt_zx == Approx(theta * 0.6f));
  CHECK(euc.tilt_zy == Approx(theta * 0.8f));
  // Both tilt the surface down towards the target quadrant (+x, +y): corner 3 lowest, corner 0 highest.
  for (const mr::ControllerOutput* o : {&man, &euc}) {
    CHECK(o->command[3] > o->command[1]);
    CHECK(o->command[3] > o->command[2]);
    CHECK(o->command[0] < o->command[1]);
    CHECK(o->command[0] < o->command[2]);
  }
}

TEST_CASE("controller: Manhattan saturates each axis alone; Euclidean keeps the direction") {
  mr::ControllerOutput man{}, euc{};
  mr::TiltController cm, ce;
  cm.reset(1);
  ce.reset(1);
  cm.step(paper(Controller::kManhattan), 0.45f, 0.01f, -0.45f, 0.0f, 0.0f, man);  // e = (0.9, 0.01)
  ce.step(paper(Controller::kEuclidean), 0.45f, 0.01f, -0.45f, 0.0f, 0.0f, euc);
  CHECK(man.tilt_zx == Approx(26.565051f));
  CHECK(man.tilt_zy == Approx(0.309f));
  const float d = sqrtf(0.9f * 0.9f + 0.01f * 0.01f);
  CHECK(euc.tilt_zx == Approx(26.565051f * 0.9f / d));
  CHECK(euc.tilt_zy == Approx(26.565051f * 0.01f / d));
  CHECK(commands_ok(man));
  CHECK(commands_ok(euc));
}

TEST_CASE("controller: at the target the surface is level (both kinds)") {
  for (Controller kind : {Controller::kManhattan, Controller::kEuclidean}) {
    mr::TiltController c;
    c.reset(1);
    mr::ControllerOutput out{};
    CHECK(c.step(paper(kind), 0.1f, -0.1f, 0.1f, -0.1f, 0.0f, out) == 0.0f);
    CHECK(out.tilt_zx == 0.0f);
    CHECK(out.tilt_zy == 0.0f);
    for (float a : out.command) CHECK(a == 0.0f);
  }
}

TEST_CASE("controller: the integral acts from the second step on") {
  mr::TiltController c;
  c.reset(1);
  mr::ControllerConfig cfg = paper(Controller::kManhattan);
  cfg.pid[0] = mr::PidGains{0.0f, 10.0f, 0.0f, 26.0f};  // I only on x
  mr::ControllerOutput out{};
  c.step(cfg, 0.1f, 0.0f, 0.0f, 0.0f, 0.05f, out);
  CHECK(out.tilt_zx == 0.0f);
  c.step(cfg, 0.1f, 0.0f, 0.0f, 0.0f, 0.05f, out);
  CHECK(out.tilt_zx == Approx(10.0f * 0.1f * 0.05f));
  // reset forgets the integral and the previous position.
  c.reset(1);
  c.step(cfg, 0.1f, 0.0f, 0.0f, 0.0f, 0.05f, out);
  CHECK(out.tilt_zx == 0.0f);
}

TEST_CASE("controller: noise is reproducible with the same seed, differs with another, bounded by alpha") {
  const float alpha = 0.01f;
  const mr::ControllerConfig noisy = paper(Controller::kManhattan, alpha);
  const mr::ControllerConfig quiet = paper(Controller::kManhattan, 0.0f);
  mr::TiltController a, b, other, ref;
  a.reset(42);
  b.reset(42);
  other.reset(43);
  ref.reset(42);
  bool differs_from_other = false, varies = false;
  float prev_delta = 0.0f;
  float largest = 0.0f;
  for (int k = 0; k < 200; ++k) {
    const float x = 0.1f * static_cast<float>(k % 7) / 7.0f - 0.05f;
    const float y = -0.02f + 0.001f * static_cast<float>(k % 11);
    mr::ControllerOutput oa{}, ob{}, oo{}, oq{};
    a.step(noisy, 0.05f, 0.02f, x, y, 0.01f, oa);
    b.step(noisy, 0.05f, 0.02f, x, y, 0.01f, ob);
    other.step(noisy, 0.05f, 0.02f, x, y, 0.01f, oo);
    ref.step(quiet, 0.05f, 0.02f, x, y, 0.01f, oq);
    for (uint8_t i = 0; i < mr::kActuatorCount; ++i) {
      CHECK(oa.command[i] == ob.command[i]);
      differs_from_other = differs_from_other || oa.command[i] != oo.command[i];
      const float delta = oa.command[i] - oq.command[i];
      CHECK(fabsf(delta) <= alpha * (1.0f + 1e-5f));
      largest = fabsf(delta) > largest ? fabsf(delta) : largest;
      varies = varies || delta != prev_delta;
      prev_delta = delta;
    }
    CHECK(oa.tilt_zx == oq.tilt_zx);  // noise is added to the commands, not the tilts
  }
  CHECK(differs_from_other);
  CHECK(varies);
  CHECK(largest > 0.9f * alpha);  // the noise really spans its amplitude
  // Reseeding repeats the sequence from the start.
  mr::TiltController c1, c2;
  c1.reset(42);
  c2.reset(7);
  mr::ControllerOutput o1{}, o2{};
  c1.step(noisy, 0.05f, 0.02f, 0.0f, 0.0f, 0.0f, o1);
  c2.step(noisy, 0.05f, 0.02f, 0.0f, 0.0f, 0.0f, o2);
  c2.reset(42);
  c2.step(noisy, 0.05f, 0.02f, 0.0f, 0.0f, 0.0f, o2);
  for (uint8_t i = 0; i < mr::kActuatorCount; ++i) CHECK(o1.command[i] == o2.command[i]);
}

TEST_CASE("controller: noise is drawn as alpha * U(-1, 1) from the seeded xorshift, one draw per actuator") {
  const float alpha = 0.05f;
  mr::TiltController c;
  c.reset(9);
  mr::ControllerOutput out{};
  c.step(paper(Controller::kEuclidean, alpha), 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, out);  // at target: level + noise
  mr::Xorshift32 r;
  r.seed(9);
  for (float a : out.command) CHECK(a == Approx(alpha * r.uniform_pm1()));
}

TEST_CASE("controller: every command within +-kActuatorRangeM for NaN, inf and huge inputs") {
  const float values[] = {0.0f, 0.1f, -0.25f, 1e3f, -1e30f, kMax, -kMax, kInf, -kInf, kNaN};
  const float dts[] = {0.0f, 1e-3f, 0.1f, 1e30f, kInf, kNaN, -1.0f};
  int steps = 0;
  for (Controller kind :
       {Controller::kManhattan, Controller::kEuclidean, Controller::kScheduled, Controller::kCascade}) {
    for (float noise : {0.0f, 0.25f}) {
      mr::ControllerConfig cfg = paper(kind, noise);
      cfg.tilt_limit = 89.0f;  // even a limit the supervisor would refuse cannot push a command out of range
      cfg.schedule =
          mr::ScheduleConfig{0.3f, 0.3f, 0.5f, 2.0f, 0.1f};  // every part at work, both edges near the centre
      mr::TiltController c;
      c.reset(3);
      for (float tx : values) {
        for (float x : values) {
          for (float dt : dts) {
            mr::ControllerOutput out{};
            c.step(cfg, tx, -0.1f, x, x, dt, out);
            CAPTURE(tx);
            CAPTURE(x);
            CAPTURE(dt);
            REQUIRE(commands_ok(out));
            c.step(cfg, 0.05f, tx, -0.02f, x, dt, out);
            REQUIRE(commands_ok(out));
            steps += 2;
          }
        }
      }
      // After all that abuse, ending on a NaN position a rate is known for, a sane input still gives a sane,
      // finite tilt.
      mr::ControllerOutput out{};
      c.step(cfg, 0.1f, 0.0f, 0.0f, 0.0f, 0.01f, out);
      c.step(cfg, 0.1f, 0.0f, kNaN, kNaN, 0.01f, out);
      REQUIRE(commands_ok(out));
      c.step(paper(kind), 0.1f, 0.0f, 0.0f, 0.0f, 0.01f, out);
      c.step(paper(kind), 0.1f, 0.0f, 0.0f, 0.0f, 0.01f, out);
      CHECK(out.tilt_zx == out.tilt_zx);
      CHECK(fabsf(out.tilt_zx) <= 26.565051f);
      CHECK(out.tilt_zx > 0.0f);  // also the cascade's: its velocity estimate is not left at NaN
      CHECK(commands_ok(out));
    }
  }
  CHECK(steps == 4 * 2 * 10 * 10 * 7 * 2);
}

TEST_CASE("controller: with the geometric tilt limit and no noise, commands never need the final clamp") {
  // tilt_limit = max_tilt_deg keeps every corner in range by geometry alone: push hard on both axes.
  const float sizes[][2] = {{0.5f, 0.5f}, {1.0f, 0.5f}, {0.3f, 2.0f}};
  for (const auto& mn : sizes) {
    mr::ControllerConfig cfg = paper(Controller::kManhattan);
    cfg.module_x = mn[0];
    cfg.module_y = mn[1];
    cfg.tilt_limit = mr::max_tilt_deg(mn[0], mn[1], mr::kActuatorRangeM);
    mr::TiltController c;
    c.reset(1);
    mr::ControllerOutput out{};
    c.step(cfg, 0.5f, 0.5f, -0.5f, -0.5f, 0.0f, out);  // e = (1, 1) m: 30.9 deg > every limit here
    CHECK(out.tilt_zx == Approx(cfg.tilt_limit));
    CHECK(out.tilt_zy == Approx(cfg.tilt_limit));
    CHECK(out.command[3] == Approx(mr::kActuatorRangeM).epsilon(1e-4));
    CHECK(out.command[0] == Approx(-mr::kActuatorRangeM).epsilon(1e-4));
  }
}

TEST_CASE("controller: Euclidean never reports a tilt beyond the limit, even for subnormal errors") {
  // The object arrives fast (D saturates theta at -limit) within a tiny, even subnormal, distance of the
  // target: the direction e/d must stay a unit vector, so each resolved tilt stays within the limit.
  const float limit = 26.565051f;
  for (float mag : {1e-42f, 1e-39f, 1e-30f, 1e-20f, 3e-20f, 1e-19f, 1e-10f, 1e-3f}) {
    for (int k = 0; k < 16; ++k) {
      const float ang = static_cast<float>(k) * 0.39269908f;  // 22.5 deg steps
      const float ex = mag * cosf(ang);
      const float ey = mag * sinf(ang);
      mr::TiltController c;
      c.reset(1);
      mr::ControllerOutput out{};
      c.step(paper(Controller::kEuclidean), 0.0f, 0.0f, 0.2f, 0.0f, 0.0f, out);  // 0.2 m away
      c.step(paper(Controller::kEuclidean), 0.0f, 0.0f, -ex, -ey, 0.01f, out);   // 20 m/s towards it
      CAPTURE(mag);
      CAPTURE(k);
      CHECK(fabsf(out.tilt_zx) <= limit);
      CHECK(fabsf(out.tilt_zy) <= limit);
      // The whole vector too, once d is a normal float (a subnormal d carries only a few bits, so e/d can
      // be a little longer than 1 there, though never along one axis).
      if (mag >= std::numeric_limits<float>::min()) {
        CHECK(out.tilt_zx * out.tilt_zx + out.tilt_zy * out.tilt_zy <= limit * limit * (1.0f + 1e-5f));
      }
      CHECK(commands_ok(out));
    }
  }
}
