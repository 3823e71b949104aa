// Unit tests of the PID: each term by hand, integral clamp, conditional integration, saturation, no kick.
#include <doctest/doctest.h>

#include <limits>  // quiet_NaN, infinity

#include "controller.h"  // TiltController, for the no-kick and first-step checks
#include "pid.h"         // Pid, PidGains, clamp_symmetric

namespace {

using doctest::Approx;
using mr::Pid;
using mr::PidGains;

const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();

mr::ControllerConfig manhattan(PidGains g, float tilt_limit = 26.565051f) {
  return mr::ControllerConfig{mr::proto::Controller::kManhattan,
                              0.5f,
                              0.5f,
                              tilt_limit,
                              0.0f,
                              0.05f,
                              {g, g, g, g, g},
                              mr::ScheduleConfig{0.05f, 1.0f, 1.0f, 0.0f, 0.0f},
                              mr::CascadeConfig{3.0f, 0.15f}};
}

}  // namespace

TEST_CASE("clamp_symmetric: inside, both limits, infinities and NaN") {
  CHECK(mr::clamp_symmetric(1.5f, 2.0f) == 1.5f);
  CHECK(mr::clamp_symmetric(-1.5f, 2.0f) == -1.5f);
  CHECK(mr::clamp_symmetric(2.5f, 2.0f) == 2.0f);
  CHECK(mr::clamp_symmetric(-2.5f, 2.0f) == -2.0f);
  CHECK(mr::clamp_symmetric(kInf, 2.0f) == 2.0f);
  CHECK(mr::clamp_symmetric(-kInf, 2.0f) == -2.0f);
  CHECK(mr::clamp_symmetric(kNaN, 2.0f) == 0.0f);
  CHECK(mr::clamp_symmetric(-kNaN, 2.0f) == 0.0f);
}

TEST_CASE("pid: proportional term alone") {
  Pid pid;
  const PidGains g{30.9f, 0.0f, 0.0f, 26.565051f};
  CHECK(pid.update(g, 0.1f, 0.0f, 0.01f, 26.565051f) == Approx(3.09f));
  CHECK(pid.update(g, -0.05f, 0.0f, 0.01f, 26.565051f) == Approx(-1.545f));
  CHECK(pid.integral() == 0.0f);
}

TEST_CASE("pid: integral term accumulates ki * e * dt") {
  Pid pid;
  const PidGains g{0.0f, 10.0f, 0.0f, 50.0f};
  CHECK(pid.update(g, 0.2f, 0.0f, 0.1f, 45.0f) == Approx(0.2f));
  CHECK(pid.integral() == Approx(0.2f));
  CHECK(pid.update(g, 0.2f, 0.0f, 0.1f, 45.0f) == Approx(0.4f));
  CHECK(pid.update(g, -0.1f, 0.0f, 0.5f, 45.0f) == Approx(-0.1f));  // 0.4 - 10 * 0.1 * 0.5
  pid.reset();
  CHECK(pid.integral() == 0.0f);
  CHECK(pid.update(g, 0.0f, 0.0f, 0.1f, 45.0f) == 0.0f);
}

TEST_CASE("pid: derivative term is kd * error_rate") {
  Pid pid;
  const PidGains g{0.0f, 0.0f, 2.0f, 10.0f};
  CHECK(pid.update(g, 0.3f, 0.5f, 0.01f, 20.0f) == Approx(1.0f));
  CHECK(pid.update(g, 0.3f, -1.25f, 0.01f, 20.0f) == Approx(-2.5f));
}

TEST_CASE("pid: the three terms add") {
  Pid pid;
  const PidGains g{30.9f, 26.78f, 15.45f, 26.565051f};
  // p = 30.9 * 0.1 = 3.09; i = 26.78 * 0.1 * 0.02 = 0.05356; d = 15.45 * -0.2 = -3.09
  CHECK(pid.update(g, 0.1f, -0.2f, 0.02f, 26.565051f) == Approx(0.05356f).epsilon(1e-4));
  CHECK(pid.integral() == Approx(0.05356f).epsilon(1e-4));
}

TEST_CASE("pid: dt = 0 does not integrate (first step is P, plus whatever rate is passed)") {
  Pid pid;
  const PidGains g{10.0f, 1000.0f, 0.0f, 50.0f};
  CHECK(pid.update(g, 0.1f, 0.0f, 0.0f, 45.0f) == Approx(1.0f));
  CHECK(pid.integral() == 0.0f);
}

TEST_CASE("pid: the integral is clamped to +-integral_limit") {
  Pid pid;
  const PidGains g{0.0f, 100.0f, 0.0f, 3.0f};
  for (int i = 0; i < 100; ++i) pid.update(g, 1.0f, 0.0f, 0.1f, 45.0f);
  CHECK(pid.integral() == 3.0f);
  CHECK(pid.update(g, 1.0f, 0.0f, 0.1f, 45.0f) == 3.0f);
  for (int i = 0; i < 200; ++i) pid.update(g, -1.0f, 0.0f, 0.1f, 45.0f);
  CHECK(pid.integral() == -3.0f);
  // integral_limit 0 disables the integral altogether.
  Pid none;
  const PidGains g0{1.0f, 100.0f, 0.0f, 0.0f};
  CHECK(none.update(g0, 0.5f, 0.0f, 1.0f, 45.0f) == Approx(0.5f));
  CHECK(none.integral() == 0.0f);
}

TEST_CASE("pid: the output saturates at +-output_limit") {
  Pid pid;
  const PidGains g{1000.0f, 0.0f, 0.0f, 10.0f};
  CHECK(pid.update(g, 0.5f, 0.0f, 0.01f, 26.0f) == 26.0f);
  CHECK(pid.update(g, -0.5f, 0.0f, 0.01f, 26.0f) == -26.0f);
  CHECK(pid.update(g, kInf, 0.0f, 0.01f, 26.0f) == 26.0f);
  CHECK(pid.update(g, 0.01f, 0.0f, 0.01f, 26.0f) == Approx(10.0f));
}

TEST_CASE("pid: no integration while the output saturates in the integral's direction") {
  Pid pid;
  const PidGains g{100.0f, 10.0f, 0.0f, 100.0f};
  // p = 100 * 0.5 = 50 > 20: saturated upward, and the error would grow the integral upward: hold it.
  for (int i = 0; i < 50; ++i) CHECK(pid.update(g, 0.5f, 0.0f, 0.1f, 20.0f) == 20.0f);
  CHECK(pid.integral() == 0.0f);
  // Same downward.
  for (int i = 0; i < 50; ++i) CHECK(pid.update(g, -0.5f, 0.0f, 0.1f, 20.0f) == -20.0f);
  CHECK(pid.integral() == 0.0f);
  // Unsaturated: it integrates.
  pid.update(g, 0.1f, 0.0f, 0.1f, 20.0f);  // p = 10, i = 0.1
  CHECK(pid.integral() == Approx(0.1f));
}

TEST_CASE("pid: while saturated one way, integration that unwinds the integral goes on") {
  Pid pid;
  const PidGains g{0.0f, 10.0f, 100.0f, 100.0f};
  for (int i = 0; i < 10; ++i) pid.update(g, 0.1f, 0.0f, 0.1f, 20.0f);  // integral 1.0
  REQUIRE(pid.integral() == Approx(1.0f));
  // A large positive rate saturates the output upward while a negative error drives the integral down.
  CHECK(pid.update(g, -0.1f, 1.0f, 0.1f, 20.0f) == 20.0f);
  CHECK(pid.integral() == Approx(0.9f));
  // Saturated downward by the rate while a positive error would grow the integral: allowed, it moves
  // away from the saturation.
  CHECK(pid.update(g, 0.1f, -1.0f, 0.1f, 20.0f) == -20.0f);
  CHECK(pid.integral() == Approx(1.0f));
  // Saturated upward and the error pushes upward: held.
  CHECK(pid.update(g, 0.1f, 1.0f, 0.1f, 20.0f) == 20.0f);
  CHECK(pid.integral() == Approx(1.0f));
}

TEST_CASE("pid: NaN error gives 0 output and leaves no NaN behind") {
  Pid pid;
  const PidGains g{30.9f, 26.78f, 15.45f, 26.565051f};
  CHECK(pid.update(g, kNaN, 0.0f, 0.01f, 26.565051f) == 0.0f);
  CHECK(pid.integral() == 0.0f);  // a NaN integral is clamped to 0, not kept
  const float next = pid.update(g, 0.1f, 0.0f, 0.01f, 26.565051f);
  CHECK(pid.integral() == Approx(0.02678f));
  CHECK(next == Approx(3.09f + 0.02678f));
}

TEST_CASE("pid through TiltController: the first step after reset is proportional only") {
  mr::TiltController c;
  c.reset(1);
  const mr::ControllerConfig cfg = manhattan({30.9f, 26.78f, 15.45f, 26.565051f});
  mr::ControllerOutput out{};
  // dt > 0 on the first step still has no previous position: P only, no I, no D.
  c.step(cfg, 0.1f, -0.05f, 0.0f, 0.0f, 0.02f, out);
  CHECK(out.tilt_zx == Approx(3.09f));
  CHECK(out.tilt_zy == Approx(-1.545f));
}

TEST_CASE("pid through TiltController: a target change causes no derivative kick") {
  mr::TiltController c;
  c.reset(1);
  const mr::ControllerConfig cfg = manhattan({0.0f, 0.0f, 10.0f, 26.565051f});  // D only
  mr::ControllerOutput out{};
  c.step(cfg, 0.1f, 0.1f, 0.02f, -0.03f, 0.0f, out);
  c.step(cfg, 0.1f, 0.1f, 0.02f, -0.03f, 0.01f, out);
  CHECK(out.tilt_zx == 0.0f);
  // The target jumps 0.2 m while the object stands still: the error jumps, its rate from motion is 0.
  c.step(cfg, -0.1f, -0.1f, 0.02f, -0.03f, 0.01f, out);
  CHECK(out.tilt_zx == 0.0f);
  CHECK(out.tilt_zy == 0.0f);
  // Object motion does produce a derivative: +0.01 m in x over 0.01 s is 1 m/s, error rate -1 m/s.
  c.step(cfg, -0.1f, -0.1f, 0.03f, -0.03f, 0.01f, out);
  CHECK(out.tilt_zx == Approx(-10.0f));
  CHECK(out.tilt_zy == 0.0f);
}

TEST_CASE("pid through TiltController, Euclidean: a target change causes no derivative kick either") {
  mr::TiltController c;
  c.reset(1);
  mr::ControllerConfig cfg = manhattan({0.0f, 0.0f, 10.0f, 26.565051f});
  cfg.kind = mr::proto::Controller::kEuclidean;
  mr::ControllerOutput out{};
  c.step(cfg, 0.1f, 0.0f, 0.0f, 0.0f, 0.0f, out);
  c.step(cfg, 0.2f, 0.0f, 0.0f, 0.0f, 0.01f, out);  // target moves away, object still
  CHECK(out.tilt_zx == 0.0f);
  // Object moves 0.01 m towards the target in 0.01 s: distance rate -1 m/s -> theta = -10 deg.
  c.step(cfg, 0.2f, 0.0f, 0.01f, 0.0f, 0.01f, out);
  CHECK(out.tilt_zx == Approx(-10.0f));
}
