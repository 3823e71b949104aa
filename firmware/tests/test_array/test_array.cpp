// The core built for the 2 x 2 array (protocol/rigs/array_2x2.toml): the route across modules, the hand-over, and the
// supervisor driving one module's plane, which every other actuator follows within its travel.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <stdint.h>  // uint8_t..uint32_t

#include <cmath>   // std::fabs, std::hypot
#include <random>  // std::mt19937, seeded cases

#include "plane.h"       // manhattan_normal
#include "rig_gen.h"     // kActuatorRangeM
#include "route.h"       // route, Leg, module_centre_x, module_centre_y, node_x, node_y
#include "supervisor.h"  // Supervisor

namespace {

using mr::Leg;
using mr::Supervisor;
using mr::proto::ErrorCode;
using mr::proto::State;
namespace proto = mr::proto;

constexpr float kModule = 0.5f;  // [m] each module's m and n (configure's default)
constexpr float kBand = 0.02f;   // [m] configure's default tolerance: the hand-over band

// Which module's span holds (x, y) [m]: column and row of the 1 x 1 m array about its centre.
int module_at(float x, float y) {
  const int col = x < 0.0f ? 0 : 1;
  const int row = y < 0.0f ? 0 : 1;
  return row * 2 + col;
}

proto::ObjectPosition pos(uint16_t frame, uint32_t capture_us, float x, float y) {
  return proto::ObjectPosition{frame, capture_us, x, y, 0};
}

}  // namespace

TEST_CASE("array: the core is built for 2 x 2 modules on 9 actuators, corners numbered as PROTOCOL.md §5") {
  CHECK(mr::kModulesX == 2);
  CHECK(mr::kModulesY == 2);
  CHECK(mr::kActuatorCount == 9);
  // module 0 (-x, -y): actuators 0 1 3 4; module 3 (+x, +y): 4 5 7 8; the centre actuator 4 is in all four
  const uint8_t expected[4][4] = {{0, 1, 3, 4}, {1, 2, 4, 5}, {3, 4, 6, 7}, {4, 5, 7, 8}};
  for (uint8_t k = 0; k < 4; ++k) {
    for (uint8_t c = 0; c < 4; ++c) CHECK(mr::corner_actuator(k, c) == expected[k][c]);
  }
  CHECK(mr::module_centre_x(0, kModule) == doctest::Approx(-0.25f));
  CHECK(mr::module_centre_y(3, kModule) == doctest::Approx(0.25f));
}

TEST_CASE("array: in the target's module the leg is the target itself") {
  const Leg leg = mr::route(0.1f, 0.2f, 0.3f, 0.4f, kModule, kModule, kBand);
  CHECK(leg.module == 3);
  CHECK(leg.target_x == 0.3f);
  CHECK(leg.target_y == 0.4f);
}

TEST_CASE("array: the route goes along x first, to the shared edge's midpoint, then along y") {
  // From module 0 to module 3: first to module 1 across x = 0, at the midpoint of that edge, y = -0.25
  Leg leg = mr::route(-0.3f, -0.3f, 0.3f, 0.3f, kModule, kModule, kBand);
  CHECK(leg.module == 0);
  CHECK(leg.target_x == doctest::Approx(kBand));
  CHECK(leg.target_y == doctest::Approx(-0.25f));
  // in module 1, across y = 0 into module 3, at x = 0.25
  leg = mr::route(0.2f, -0.3f, 0.3f, 0.3f, kModule, kModule, kBand);
  CHECK(leg.module == 1);
  CHECK(leg.target_x == doctest::Approx(0.25f));
  CHECK(leg.target_y == doctest::Approx(kBand));
}

TEST_CASE("array: within the band of the edge on the route, the next module takes the object over") {
  CHECK(mr::route(-0.03f, -0.2f, 0.3f, -0.2f, kModule, kModule, kBand).module == 0);  // 3 cm short: not yet
  const Leg leg = mr::route(-0.01f, -0.2f, 0.3f, -0.2f, kModule, kModule, kBand);     // 1 cm short
  CHECK(leg.module == 1);
  CHECK(leg.target_x == 0.3f);  // module 1 holds the target: it drives there
  // The band is the route's: an object 1 cm short of an edge it is not crossing stays where it is.
  CHECK(mr::route(-0.01f, -0.2f, -0.3f, -0.2f, kModule, kModule, kBand).module == 0);
}

TEST_CASE("array: every leg is driven by the object's module, or by one it is handed to toward the target") {
  std::mt19937 rng(2028);
  std::uniform_real_distribution<float> inside(-0.5f, 0.5f);
  for (int n = 0; n < 20000; ++n) {
    const float x = inside(rng), y = inside(rng), tx = inside(rng), ty = inside(rng);
    const Leg leg = mr::route(x, y, tx, ty, kModule, kModule, kBand);
    const int here = module_at(x, y), goal = module_at(tx, ty);
    const int d_here = std::abs(here % 2 - goal % 2) + std::abs(here / 2 - goal / 2);  // modules to go
    const int d_leg = std::abs(leg.module % 2 - goal % 2) + std::abs(leg.module / 2 - goal / 2);
    if (leg.module != here) {  // a hand-over: toward the goal, and only within the band of a shared edge
      CHECK(d_leg < d_here);
      CHECK((std::fabs(x) < kBand || std::fabs(y) < kBand));
    }
    if (leg.module == goal) {
      CHECK((leg.target_x == tx && leg.target_y == ty));
    } else {  // a waypoint beyond the edge toward the goal, in the next module on the way
      const int next = module_at(leg.target_x, leg.target_y);
      const int d_next = std::abs(next % 2 - goal % 2) + std::abs(next / 2 - goal / 2);
      CHECK(d_next == d_leg - 1);
      CHECK(std::abs(next % 2 - leg.module % 2) + std::abs(next / 2 - leg.module / 2) == 1);
    }
  }
}

TEST_CASE("array: the supervisor takes targets anywhere on the 1 x 1 m surface, and no farther") {
  Supervisor s;
  uint8_t field = 0;
  CHECK(s.set_target(proto::SetTarget{0.45f, -0.45f}, field) == ErrorCode::kOk);
  CHECK(s.set_target(proto::SetTarget{0.55f, 0.0f}, field) == ErrorCode::kOutOfRange);
  CHECK(field == proto::SetTarget::kFieldX);
  CHECK(s.set_target(proto::SetTarget{0.0f, -0.51f}, field) == ErrorCode::kOutOfRange);
  CHECK(field == proto::SetTarget::kFieldY);
}

// Every actuator on the plane of the tilts out shows, turned about module k's centre, within its travel.
void check_on_the_plane(const mr::ControllerOutput& out, uint8_t module) {
  const mr::Normal n = mr::manhattan_normal(out.tilt_zx, out.tilt_zy);
  const float cx = mr::module_centre_x(module, kModule), cy = mr::module_centre_y(module, kModule);
  for (uint8_t i = 0; i < mr::kActuatorCount; ++i) {
    float a = (n.x * (mr::node_x(i, kModule) - cx) + n.y * (mr::node_y(i, kModule) - cy)) / n.z;
    a = a > mr::kActuatorRangeM ? mr::kActuatorRangeM : (a < -mr::kActuatorRangeM ? -mr::kActuatorRangeM : a);
    CHECK(std::fabs(out.command[i] - a) < 1e-6f);
  }
}

TEST_CASE("array: actuators stand on the grid's nodes, numbered as PROTOCOL.md §5") {
  for (uint8_t i = 0; i < mr::kActuatorCount; ++i) {
    CHECK(mr::node_x(i, kModule) == doctest::Approx(0.5f * static_cast<float>(i % 3) - 0.5f));
    CHECK(mr::node_y(i, kModule) == doctest::Approx(0.5f * static_cast<float>(i / 3) - 0.5f));
  }
}

TEST_CASE(
    "array: every actuator follows the driven module's plane within its travel, and the module changes at the "
    "hand-over") {
  Supervisor s;
  uint8_t field = 0;
  REQUIRE(s.set_target(proto::SetTarget{0.3f, -0.25f}, field) == ErrorCode::kOk);
  REQUIRE(s.start(0) == ErrorCode::kOk);
  REQUIRE(s.position(pos(1, 1000, -0.3f, -0.25f), 1000, field) == ErrorCode::kOk);
  const mr::ControllerOutput& out = s.output();
  CHECK(out.module == 0);
  CHECK(s.state() == State::kRunning);
  CHECK(out.tilt_zx > 0.0f);     // toward +x, the waypoint at the edge
  CHECK(out.command[1] > 0.0f);  // module 0's +x corners lower ...
  CHECK(out.command[4] > 0.0f);
  CHECK(out.command[0] < 0.0f);            // ... its -x corners rise ...
  CHECK(out.command[2] > out.command[1]);  // ... and the plane goes on down over module 1
  check_on_the_plane(out, 0);
  REQUIRE(s.position(pos(2, 84000, -0.005f, -0.25f), 84000, field) == ErrorCode::kOk);  // within the band
  CHECK(out.module == 1);
  check_on_the_plane(out, 1);
  REQUIRE(s.position(pos(3, 168000, 0.295f, -0.25f), 168000, field) == ErrorCode::kOk);
  CHECK(s.state() == State::kReached);  // judged against the target, not a waypoint
}

TEST_CASE("array: a hand-over starts the next module's PIDs afresh, as a first step would") {
  // Ten frames in module 0 wind its integral up toward the edge; the frame that hands over to module 1 must tilt as a
  // supervisor that starts at that very position does on its first frame (proportional only).
  Supervisor carried, fresh;
  uint8_t field = 0;
  for (Supervisor* s : {&carried, &fresh}) {
    REQUIRE(s->set_target(proto::SetTarget{0.3f, -0.3f}, field) == ErrorCode::kOk);
    REQUIRE(s->start(0) == ErrorCode::kOk);
  }
  uint32_t t = 0;
  for (uint16_t frame = 1; frame <= 10; ++frame) {
    t += 83333;
    REQUIRE(carried.position(pos(frame, t, -0.3f + 0.02f * frame, -0.3f), t, field) == ErrorCode::kOk);
  }
  CHECK(carried.output().module == 0);
  t += 83333;
  REQUIRE(carried.position(pos(11, t, -0.01f, -0.3f), t, field) == ErrorCode::kOk);
  REQUIRE(fresh.position(pos(1, t, -0.01f, -0.3f), t, field) == ErrorCode::kOk);
  CHECK(carried.output().module == 1);
  CHECK(fresh.output().module == 1);
  CHECK(carried.output().tilt_zx == fresh.output().tilt_zx);
  CHECK(carried.output().tilt_zy == fresh.output().tilt_zy);
}

TEST_CASE("array: an object beside the surface by up to half a module is still a measurement") {
  Supervisor s;
  uint8_t field = 0;
  REQUIRE(s.set_target(proto::SetTarget{0.0f, 0.0f}, field) == ErrorCode::kOk);
  REQUIRE(s.start(0) == ErrorCode::kOk);
  CHECK(s.position(pos(1, 1000, 0.74f, 0.0f), 1000, field) == ErrorCode::kOk);
  CHECK(s.position(pos(2, 2000, 0.76f, 0.0f), 2000, field) == ErrorCode::kOutOfRange);
  CHECK(field == proto::ObjectPosition::kFieldX);
}
