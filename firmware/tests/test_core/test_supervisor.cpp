// Unit tests of the supervisor: state machine, whole-command validation, deadman, stale positions, reached.
#include <doctest/doctest.h>

#include <stdint.h>  // uint8_t..uint32_t

#include <functional>        // per-field mutations of a configure
#include <initializer_list>  // range-for over braced lists
#include <limits>            // quiet_NaN, infinity

#include "plane.h"       // max_tilt_deg
#include "supervisor.h"  // Supervisor

namespace {

using doctest::Approx;
using mr::Supervisor;
using mr::proto::ErrorCode;
using mr::proto::State;
namespace proto = mr::proto;

const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();
constexpr uint8_t kNoField = proto::kNoField;

proto::Configure defaults() {
  proto::Configure c;
  proto::set_defaults(c);
  return c;
}

bool same(const proto::Configure& a, const proto::Configure& b) {
  // Field by field: the struct has padding bytes.
  return a.controller == b.controller && a.module_x == b.module_x && a.module_y == b.module_y &&
         a.tilt_limit == b.tilt_limit && a.tolerance == b.tolerance && a.noise_amplitude == b.noise_amplitude &&
         a.noise_seed == b.noise_seed && a.deadman == b.deadman && a.telemetry_period == b.telemetry_period &&
         a.velocity_filter == b.velocity_filter;
}

proto::ObjectPosition pos(uint16_t frame, uint32_t capture_us, float x, float y, bool visible = true) {
  return proto::ObjectPosition{frame, capture_us, x, y,
                               static_cast<uint8_t>(visible ? 0 : proto::position_flags::kNotVisible)};
}

ErrorCode set_target(Supervisor& s, float x, float y, uint8_t& field) {
  return s.set_target(proto::SetTarget{x, y}, field);
}

ErrorCode set_target(Supervisor& s, float x, float y) {
  uint8_t field = 0;
  return set_target(s, x, y, field);
}

ErrorCode position(Supervisor& s, const proto::ObjectPosition& p, uint32_t now_us) {
  uint8_t field = 0;
  return s.position(p, now_us, field);
}

ErrorCode configure(Supervisor& s, const proto::Configure& c) {
  uint8_t field = 0;
  return s.configure(c, field);
}

// A supervisor that is running towards (tx, ty) since now_us.
void run(Supervisor& s, float tx, float ty, uint32_t now_us = 0) {
  REQUIRE(set_target(s, tx, ty) == ErrorCode::kOk);
  REQUIRE(s.start(now_us) == ErrorCode::kOk);
  REQUIRE(s.state() == State::kRunning);
}

bool level(const Supervisor& s) {
  const mr::ControllerOutput& o = s.output();
  return o.tilt_zx == 0.0f && o.tilt_zy == 0.0f && o.command[0] == 0.0f && o.command[1] == 0.0f &&
         o.command[2] == 0.0f && o.command[3] == 0.0f;
}

}  // namespace

TEST_CASE("supervisor: boots idle, level, powered, with the schema's defaults") {
  Supervisor s;
  CHECK(s.state() == State::kIdle);
  CHECK(s.faults() == 0);
  CHECK(s.actuator_power());
  CHECK(level(s));
  CHECK(same(s.config(), defaults()));
  CHECK(s.position_age_ms(123456) == 0xFFFF);
}

TEST_CASE("supervisor: start needs a target, and only from idle") {
  Supervisor s;
  CHECK(s.start(0) == ErrorCode::kNoTarget);
  CHECK(s.state() == State::kIdle);
  CHECK(set_target(s, 0.1f, 0.0f) == ErrorCode::kOk);
  CHECK(s.start(0) == ErrorCode::kOk);
  CHECK(s.state() == State::kRunning);
  CHECK_FALSE(proto::taken_in(proto::Start::kId, s.state()));  // the dispatcher refuses it (schema states)
  CHECK(s.state() == State::kRunning);
}

TEST_CASE("supervisor: running -> reached within tolerance -> running when it leaves") {
  Supervisor s;
  run(s, 0.1f, 0.0f);
  CHECK(position(s, pos(1, 1000, 0.0f, 0.0f), 1000) == ErrorCode::kOk);
  CHECK(s.state() == State::kRunning);
  CHECK(s.output().tilt_zx > 0.0f);                                               // target at +x: tilt +x down
  CHECK(position(s, pos(2, 2000, 0.1f - 0.019f, 0.0f), 2000) == ErrorCode::kOk);  // tolerance 0.02
  CHECK(s.state() == State::kReached);
  CHECK(position(s, pos(3, 3000, 0.1f, 0.0f), 3000) == ErrorCode::kOk);
  CHECK(s.state() == State::kReached);
  CHECK(position(s, pos(4, 4000, 0.1f - 0.021f, 0.0f), 4000) == ErrorCode::kOk);
  CHECK(s.state() == State::kRunning);
  // Reached is a running state: start is refused, stop levels and idles.
  CHECK(position(s, pos(5, 5000, 0.1f, 0.01f), 5000) == ErrorCode::kOk);
  CHECK(s.state() == State::kReached);
  CHECK_FALSE(proto::taken_in(proto::Start::kId, s.state()));
  s.stop();
  CHECK(s.state() == State::kIdle);
  CHECK(level(s));
}

TEST_CASE("supervisor: positions move the surface only while running") {
  Supervisor s;
  REQUIRE(set_target(s, 0.1f, 0.1f) == ErrorCode::kOk);
  CHECK(position(s, pos(1, 1000, -0.1f, -0.1f), 1000) == ErrorCode::kOk);
  CHECK(level(s));
  CHECK(s.state() == State::kIdle);
  REQUIRE(s.start(2000) == ErrorCode::kOk);
  CHECK(level(s));
  CHECK(position(s, pos(2, 3000, -0.1f, -0.1f), 3000) == ErrorCode::kOk);
  CHECK_FALSE(level(s));
  CHECK(s.output().command[3] > 0.0f);  // towards (+x, +y): corner 3 lowered
  CHECK(s.output().command[0] < 0.0f);
}

TEST_CASE("supervisor: emergency stop latches until stop; stop clears it") {
  Supervisor s;
  run(s, 0.1f, 0.0f);
  REQUIRE(position(s, pos(1, 1000, 0.0f, 0.0f), 1000) == ErrorCode::kOk);
  REQUIRE_FALSE(level(s));
  s.emergency_stop();
  CHECK(s.state() == State::kEstop);
  CHECK((s.faults() & proto::faults::kEstop) != 0);
  CHECK_FALSE(s.actuator_power());
  CHECK(level(s));
  // In estop the dispatcher takes no command but stop, emergency_stop, identify, sim_clock (and positions).
  for (const uint8_t id : {proto::Configure::kId, proto::SetTarget::kId, proto::Start::kId, proto::Jog::kId,
                           proto::ConfigurePid::kId, proto::Zero::kId}) {
    CHECK_FALSE(proto::taken_in(id, s.state()));
  }
  CHECK(proto::taken_in(proto::Stop::kId, s.state()));
  CHECK(proto::taken_in(proto::ObjectPosition::kId, s.state()));
  // Positions in estop change nothing on the surface.
  CHECK(position(s, pos(2, 2000, -0.2f, 0.0f), 2000) == ErrorCode::kOk);
  CHECK(level(s));
  CHECK(s.state() == State::kEstop);
  s.emergency_stop();  // again: still estop
  CHECK(s.state() == State::kEstop);
  s.stop();
  CHECK(s.state() == State::kIdle);
  CHECK(s.faults() == 0);
  CHECK(s.actuator_power());
  CHECK(s.start(3000) == ErrorCode::kOk);  // the target survived the estop
}

TEST_CASE("supervisor: configure refuses each bad field with its index and changes nothing") {
  struct Case {
    const char* what;
    std::function<void(proto::Configure&)> mutate;
    ErrorCode code;
    uint8_t field;
  };
  const Case cases[] = {
      {"controller 4", [](proto::Configure& c) { c.controller = proto::kControllerCount; }, ErrorCode::kOutOfRange, 0},
      {"controller 255", [](proto::Configure& c) { c.controller = 255; }, ErrorCode::kOutOfRange, 0},
      {"module_x NaN", [](proto::Configure& c) { c.module_x = kNaN; }, ErrorCode::kNotFinite, 1},
      {"module_x inf", [](proto::Configure& c) { c.module_x = kInf; }, ErrorCode::kNotFinite, 1},
      {"module_x 0.09", [](proto::Configure& c) { c.module_x = 0.09f; }, ErrorCode::kOutOfRange, 1},
      {"module_x 10.5", [](proto::Configure& c) { c.module_x = 10.5f; }, ErrorCode::kOutOfRange, 1},
      {"module_y -inf", [](proto::Configure& c) { c.module_y = -kInf; }, ErrorCode::kNotFinite, 2},
      {"module_y 0", [](proto::Configure& c) { c.module_y = 0.0f; }, ErrorCode::kOutOfRange, 2},
      {"tilt_limit NaN", [](proto::Configure& c) { c.tilt_limit = kNaN; }, ErrorCode::kNotFinite, 3},
      {"tilt_limit 0.05", [](proto::Configure& c) { c.tilt_limit = 0.05f; }, ErrorCode::kOutOfRange, 3},
      {"tilt_limit 89.5", [](proto::Configure& c) { c.tilt_limit = 89.5f; }, ErrorCode::kOutOfRange, 3},
      {"tilt_limit 30 > geometric 26.57", [](proto::Configure& c) { c.tilt_limit = 30.0f; }, ErrorCode::kOutOfRange, 3},
      {"tilt_limit 26.6 > geometric 26.565", [](proto::Configure& c) { c.tilt_limit = 26.6f; }, ErrorCode::kOutOfRange,
       3},
      {"tolerance inf", [](proto::Configure& c) { c.tolerance = kInf; }, ErrorCode::kNotFinite, 4},
      {"tolerance 0", [](proto::Configure& c) { c.tolerance = 0.0f; }, ErrorCode::kOutOfRange, 4},
      {"tolerance 0.6", [](proto::Configure& c) { c.tolerance = 0.6f; }, ErrorCode::kOutOfRange, 4},
      {"noise NaN", [](proto::Configure& c) { c.noise_amplitude = kNaN; }, ErrorCode::kNotFinite, 5},
      {"noise -0.01", [](proto::Configure& c) { c.noise_amplitude = -0.01f; }, ErrorCode::kOutOfRange, 5},
      {"noise 0.3", [](proto::Configure& c) { c.noise_amplitude = 0.3f; }, ErrorCode::kOutOfRange, 5},
      {"deadman 0", [](proto::Configure& c) { c.deadman = 0; }, ErrorCode::kOutOfRange, 7},
      {"deadman 19", [](proto::Configure& c) { c.deadman = 19; }, ErrorCode::kOutOfRange, 7},
      {"deadman 60001", [](proto::Configure& c) { c.deadman = 60001; }, ErrorCode::kOutOfRange, 7},
      {"telemetry_period 1", [](proto::Configure& c) { c.telemetry_period = 1; }, ErrorCode::kOutOfRange, 8},
      {"telemetry_period 2", [](proto::Configure& c) { c.telemetry_period = 2; }, ErrorCode::kOutOfRange, 8},
      {"telemetry_period 3", [](proto::Configure& c) { c.telemetry_period = 3; }, ErrorCode::kOutOfRange, 8},
      {"telemetry_period 4", [](proto::Configure& c) { c.telemetry_period = 4; }, ErrorCode::kOutOfRange, 8},
      {"telemetry_period 60001", [](proto::Configure& c) { c.telemetry_period = 60001; }, ErrorCode::kOutOfRange, 8},
      {"velocity_filter NaN", [](proto::Configure& c) { c.velocity_filter = kNaN; }, ErrorCode::kNotFinite, 9},
      {"velocity_filter -0.01", [](proto::Configure& c) { c.velocity_filter = -0.01f; }, ErrorCode::kOutOfRange, 9},
      {"velocity_filter 10.5", [](proto::Configure& c) { c.velocity_filter = 10.5f; }, ErrorCode::kOutOfRange, 9},
  };
  Supervisor s;
  // Start from a valid non-default config so "unchanged" is not "back to defaults".
  proto::Configure before = defaults();
  before.controller = 1;
  before.module_x = 0.6f;
  before.tilt_limit = 20.0f;
  before.noise_amplitude = 0.01f;
  before.noise_seed = 77;
  before.deadman = 250;
  before.telemetry_period = 50;
  before.velocity_filter = 0.2f;
  REQUIRE(configure(s, before) == ErrorCode::kOk);
  REQUIRE(same(s.config(), before));
  for (const Case& c : cases) {
    CAPTURE(c.what);
    proto::Configure msg = defaults();
    c.mutate(msg);
    uint8_t field = 0;
    CHECK(s.configure(msg, field) == c.code);
    CHECK(static_cast<int>(field) == static_cast<int>(c.field));
    CHECK(same(s.config(), before));
  }
}

TEST_CASE("supervisor: configure accepts the bounds and applies the whole message") {
  Supervisor s;
  for (uint16_t period : std::initializer_list<uint16_t>{0, 5, 60000}) {
    proto::Configure c = defaults();
    c.telemetry_period = period;
    c.deadman = period == 0 ? 20 : 60000;
    CHECK(configure(s, c) == ErrorCode::kOk);
    CHECK(same(s.config(), c));
  }
  // The geometric limit itself is accepted, for the paper's module and a bigger one.
  proto::Configure c = defaults();
  c.module_x = 1.0f;
  c.module_y = 1.0f;
  c.tilt_limit = mr::max_tilt_deg(1.0f, 1.0f, mr::kActuatorRangeM);  // 14.04 deg
  CHECK(configure(s, c) == ErrorCode::kOk);
  c.tilt_limit = 14.1f;
  uint8_t field = 0;
  CHECK(s.configure(c, field) == ErrorCode::kOutOfRange);
  CHECK(field == 3);
  CHECK(s.config().tilt_limit == Approx(14.036243f));
}

TEST_CASE("supervisor: configure only in idle") {
  Supervisor s;
  CHECK(proto::taken_in(proto::Configure::kId, s.state()));
  run(s, 0.0f, 0.0f);
  CHECK_FALSE(proto::taken_in(proto::Configure::kId, s.state()));  // the dispatcher refuses it (schema states)
}

TEST_CASE("supervisor: shrinking the module forgets a target that no longer fits") {
  Supervisor s;
  REQUIRE(set_target(s, 0.24f, 0.0f) == ErrorCode::kOk);
  proto::Configure c = defaults();
  c.module_x = 0.4f;  // |x| <= 0.2 now
  REQUIRE(configure(s, c) == ErrorCode::kOk);
  CHECK(s.start(0) == ErrorCode::kNoTarget);
  // A target that still fits survives a configure.
  REQUIRE(set_target(s, 0.2f, 0.0f) == ErrorCode::kOk);
  REQUIRE(configure(s, defaults()) == ErrorCode::kOk);
  CHECK(s.start(0) == ErrorCode::kOk);
}

TEST_CASE("supervisor: set_target refuses NaN, inf and outside the module; keeps the old target") {
  Supervisor s;
  REQUIRE(set_target(s, 0.1f, 0.0f) == ErrorCode::kOk);
  struct Case {
    float x, y;
    ErrorCode code;
    uint8_t field;
  };
  const Case cases[] = {
      {kNaN, 0.0f, ErrorCode::kNotFinite, 0},   {0.0f, kNaN, ErrorCode::kNotFinite, 1},
      {kInf, 0.0f, ErrorCode::kNotFinite, 0},   {0.0f, -kInf, ErrorCode::kNotFinite, 1},
      {0.26f, 0.0f, ErrorCode::kOutOfRange, 0}, {-0.2501f, 0.0f, ErrorCode::kOutOfRange, 0},
      {0.0f, 0.26f, ErrorCode::kOutOfRange, 1}, {0.0f, -0.3f, ErrorCode::kOutOfRange, 1},
      {kNaN, 0.3f, ErrorCode::kNotFinite, 0},   {0.3f, 0.3f, ErrorCode::kOutOfRange, 0},
  };
  for (const Case& c : cases) {
    CAPTURE(c.x);
    CAPTURE(c.y);
    uint8_t field = 0;
    CHECK(set_target(s, c.x, c.y, field) == c.code);
    CHECK(static_cast<int>(field) == static_cast<int>(c.field));
  }
  // The corners of the module are inside.
  CHECK(set_target(s, 0.25f, -0.25f) == ErrorCode::kOk);
  CHECK(set_target(s, -0.25f, 0.25f) == ErrorCode::kOk);
  // A refused target left the last good one in place: (-0.25, 0.25) -> object at the origin tilts to -x, +y.
  CHECK(set_target(s, kNaN, 0.0f) == ErrorCode::kNotFinite);
  REQUIRE(s.start(0) == ErrorCode::kOk);
  REQUIRE(position(s, pos(1, 1000, 0.0f, 0.0f), 1000) == ErrorCode::kOk);
  CHECK(s.output().tilt_zx == Approx(-30.9f * 0.25f));
  CHECK(s.output().tilt_zy == Approx(30.9f * 0.25f));
}

TEST_CASE("supervisor: set_target is accepted while running and in fault, and takes effect") {
  Supervisor s;
  run(s, 0.1f, 0.0f);
  REQUIRE(position(s, pos(1, 1000, 0.0f, 0.0f), 1000) == ErrorCode::kOk);
  CHECK(s.output().tilt_zx > 0.0f);
  REQUIRE(set_target(s, -0.1f, 0.0f) == ErrorCode::kOk);
  REQUIRE(position(s, pos(2, 2000, 0.0f, 0.0f), 2000) == ErrorCode::kOk);
  CHECK(s.output().tilt_zx < 0.0f);
  s.tick(2000 + 501000);
  REQUIRE(s.state() == State::kFault);
  CHECK(set_target(s, 0.05f, 0.05f) == ErrorCode::kOk);
}

TEST_CASE("supervisor: configure_pid refuses each bad field; a refused one leaves the gains") {
  struct Case {
    proto::ConfigurePid msg;
    ErrorCode code;
    uint8_t field;
  };
  const Case cases[] = {
      {{proto::kAxisCount, 1.0f, 1.0f, 1.0f, 1.0f}, ErrorCode::kOutOfRange, 0},
      {{0, kNaN, 1.0f, 1.0f, 1.0f}, ErrorCode::kNotFinite, 1},
      {{0, -1.0f, 1.0f, 1.0f, 1.0f}, ErrorCode::kOutOfRange, 1},
      {{1, 10001.0f, 1.0f, 1.0f, 1.0f}, ErrorCode::kOutOfRange, 1},
      {{1, 1.0f, kInf, 1.0f, 1.0f}, ErrorCode::kNotFinite, 2},
      {{1, 1.0f, -0.1f, 1.0f, 1.0f}, ErrorCode::kOutOfRange, 2},
      {{2, 1.0f, 1.0f, -kInf, 1.0f}, ErrorCode::kNotFinite, 3},
      {{2, 1.0f, 1.0f, 20000.0f, 1.0f}, ErrorCode::kOutOfRange, 3},
      {{0, 1.0f, 1.0f, 1.0f, kNaN}, ErrorCode::kNotFinite, 4},
      {{0, 1.0f, 1.0f, 1.0f, 91.0f}, ErrorCode::kOutOfRange, 4},
      {{0, 1.0f, 1.0f, 1.0f, -1.0f}, ErrorCode::kOutOfRange, 4},
  };
  Supervisor s;
  for (const Case& c : cases) {
    CAPTURE(static_cast<int>(c.field));
    uint8_t field = 0;
    CHECK(s.configure_pid(c.msg, field) == c.code);
    CHECK(static_cast<int>(field) == static_cast<int>(c.field));
  }
  // The x gains are still the paper's: the first step is kP * e = 30.9 * 0.1.
  run(s, 0.1f, 0.0f);
  REQUIRE(position(s, pos(1, 1000, 0.0f, 0.0f), 1000) == ErrorCode::kOk);
  CHECK(s.output().tilt_zx == Approx(3.09f));
}

TEST_CASE("supervisor: configure_pid sets the gains of the named axis only, and only in idle") {
  Supervisor s;
  uint8_t field = 0;
  REQUIRE(s.configure_pid(proto::ConfigurePid{0, 10.0f, 0.0f, 0.0f, 5.0f}, field) == ErrorCode::kOk);
  CHECK(field == kNoField);
  run(s, 0.1f, 0.1f);
  REQUIRE(position(s, pos(1, 1000, 0.0f, 0.0f), 1000) == ErrorCode::kOk);
  CHECK(s.output().tilt_zx == Approx(1.0f));                          // new x gain
  CHECK(s.output().tilt_zy == Approx(3.09f));                         // y untouched
  CHECK_FALSE(proto::taken_in(proto::ConfigurePid::kId, s.state()));  // the dispatcher refuses it (schema states)
  // Radial gains drive the Euclidean controller.
  s.stop();
  REQUIRE(s.configure_pid(proto::ConfigurePid{2, 20.0f, 0.0f, 0.0f, 5.0f}, field) == ErrorCode::kOk);
  proto::Configure c = defaults();
  c.controller = 1;
  REQUIRE(configure(s, c) == ErrorCode::kOk);
  REQUIRE(s.start(2000) == ErrorCode::kOk);
  REQUIRE(position(s, pos(2, 3000, 0.1f, 0.0f), 3000) == ErrorCode::kOk);  // e = (0, 0.1)
  CHECK(s.output().tilt_zx == Approx(0.0f));
  CHECK(s.output().tilt_zy == Approx(2.0f));
}

TEST_CASE("supervisor: jog moves one actuator in idle only; start and stop end it") {
  Supervisor s;
  uint8_t field = 0;
  CHECK(s.jog(proto::Jog{2, 0.1f}, field) == ErrorCode::kOk);
  CHECK(field == kNoField);
  CHECK(s.output().command[2] == 0.1f);
  CHECK(s.output().command[0] == 0.0f);
  CHECK(s.jog(proto::Jog{3, -0.25f}, field) == ErrorCode::kOk);
  CHECK(s.output().command[3] == -0.25f);
  CHECK(s.output().command[2] == 0.1f);
  struct Case {
    proto::Jog msg;
    ErrorCode code;
    uint8_t field;
  };
  const Case cases[] = {
      {{4, 0.0f}, ErrorCode::kOutOfRange, 0},    {{255, 0.0f}, ErrorCode::kOutOfRange, 0},
      {{0, kNaN}, ErrorCode::kNotFinite, 1},     {{0, -kInf}, ErrorCode::kNotFinite, 1},
      {{0, 0.2501f}, ErrorCode::kOutOfRange, 1}, {{1, -0.3f}, ErrorCode::kOutOfRange, 1},
  };
  for (const Case& c : cases) {
    CAPTURE(static_cast<int>(c.msg.actuator));
    CAPTURE(c.msg.position);
    CHECK(s.jog(c.msg, field) == c.code);
    CHECK(static_cast<int>(field) == static_cast<int>(c.field));
    CHECK(s.output().command[0] == 0.0f);
    CHECK(s.output().command[1] == 0.0f);
    CHECK(s.output().command[2] == 0.1f);
    CHECK(s.output().command[3] == -0.25f);
  }
  s.stop();
  CHECK(level(s));
  CHECK(s.jog(proto::Jog{1, 0.05f}, field) == ErrorCode::kOk);
  run(s, 0.0f, 0.0f);
  CHECK(level(s));
  CHECK_FALSE(proto::taken_in(proto::Jog::kId, s.state()));  // the dispatcher refuses it (schema states)
  CHECK(level(s));
}

TEST_CASE("supervisor: invalid positions are refused with the field index") {
  Supervisor s;
  run(s, 0.1f, 0.0f);
  uint8_t field = 0;
  CHECK(s.position(pos(1, 1000, kNaN, 0.0f), 1000, field) == ErrorCode::kNotFinite);
  CHECK(field == 2);
  CHECK(s.position(pos(1, 1000, 0.0f, kInf), 1000, field) == ErrorCode::kNotFinite);
  CHECK(field == 3);
  CHECK(level(s));
  // A refused frame is not remembered: the same counter is still fresh.
  CHECK(s.position(pos(1, 1000, 0.0f, 0.0f), 1000, field) == ErrorCode::kOk);
  CHECK(field == kNoField);
  // Not visible: x and y are ignored, NaN included.
  CHECK(s.position(pos(2, 2000, kNaN, kNaN, false), 2000, field) == ErrorCode::kOk);
  CHECK(s.last_frame() == 2);
}

TEST_CASE("supervisor: a repeated frame counter or a capture time that does not advance is stale") {
  Supervisor s;
  run(s, 0.1f, 0.0f);
  uint8_t field = 0;
  REQUIRE(s.position(pos(10, 50000, 0.0f, 0.0f), 1000, field) == ErrorCode::kOk);
  CHECK(s.position(pos(10, 60000, 0.0f, 0.0f), 2000, field) == ErrorCode::kStalePosition);
  CHECK(field == 0);
  CHECK(s.position(pos(11, 50000, 0.0f, 0.0f), 2000, field) == ErrorCode::kStalePosition);
  CHECK(field == 1);
  CHECK(s.position(pos(11, 49999, 0.0f, 0.0f), 2000, field) == ErrorCode::kStalePosition);
  CHECK(field == 1);
  CHECK(s.last_frame() == 10);
  // Not-visible frames obey the same rule.
  CHECK(s.position(pos(10, 70000, 0.0f, 0.0f, false), 2000, field) == ErrorCode::kStalePosition);
  CHECK(field == 0);
  CHECK(s.position(pos(11, 60000, 0.0f, 0.0f), 3000, field) == ErrorCode::kOk);
  // Both counters wrap: 65535 -> 0, and capture times past 2^32 us (less than 2^31 us apart) are fresh.
  CHECK(s.position(pos(65535, 0x7FFFFFFFu, 0.0f, 0.0f), 4000, field) == ErrorCode::kOk);
  CHECK(s.position(pos(0, 0xFFFFFF00u, 0.0f, 0.0f), 5000, field) == ErrorCode::kOk);
  CHECK(s.last_frame() == 0);
  CHECK(s.position(pos(1, 0x100u, 0.0f, 0.0f), 6000, field) == ErrorCode::kOk);
  // A capture time more than 2^31 us "ahead" reads as going backwards.
  CHECK(s.position(pos(2, 0x80000200u, 0.0f, 0.0f), 7000, field) == ErrorCode::kStalePosition);
  CHECK(field == 1);
}

TEST_CASE("supervisor: start forgets the frame history; forget_positions does too") {
  Supervisor s;
  REQUIRE(set_target(s, 0.1f, 0.0f) == ErrorCode::kOk);
  REQUIRE(position(s, pos(5, 90000, 0.0f, 0.0f), 1000) == ErrorCode::kOk);
  REQUIRE(position(s, pos(5, 90001, 0.0f, 0.0f), 1000) == ErrorCode::kStalePosition);
  REQUIRE(s.start(2000) == ErrorCode::kOk);
  CHECK(position(s, pos(5, 10, 0.0f, 0.0f), 3000) == ErrorCode::kOk);  // a new camera run
  s.forget_positions();
  CHECK(position(s, pos(5, 5, 0.0f, 0.0f), 4000) == ErrorCode::kOk);
}

TEST_CASE("supervisor: the deadman trips after deadman ms without a valid position, not before") {
  Supervisor s;
  proto::Configure c = defaults();
  c.deadman = 100;
  REQUIRE(configure(s, c) == ErrorCode::kOk);
  const uint32_t t0 = 7000;
  run(s, 0.1f, 0.0f, t0);
  SUBCASE("no position at all after start") {
    s.tick(t0 + 100000);
    CHECK(s.state() == State::kRunning);
    s.tick(t0 + 100001);
    CHECK(s.state() == State::kFault);
  }
  SUBCASE("measured from the last valid position") {
    REQUIRE(position(s, pos(1, 1, 0.0f, 0.0f), t0 + 60000) == ErrorCode::kOk);
    REQUIRE_FALSE(level(s));
    s.tick(t0 + 160000);
    CHECK(s.state() == State::kRunning);
    s.tick(t0 + 160001);
    CHECK(s.state() == State::kFault);
  }
  SUBCASE("not-visible frames do not feed it") {
    REQUIRE(position(s, pos(1, 1, 0.0f, 0.0f), t0 + 10000) == ErrorCode::kOk);
    for (uint16_t k = 2; k < 12; ++k) {
      REQUIRE(position(s, pos(k, k, 0.0f, 0.0f, false), t0 + 10000u * k) == ErrorCode::kOk);
      s.tick(t0 + 10000u * k);
    }
    CHECK(s.state() == State::kRunning);  // t0 + 110 ms: 100 ms since the last visible one
    s.tick(t0 + 110001);
    CHECK(s.state() == State::kFault);
  }
  SUBCASE("refused (stale or NaN) frames do not feed it") {
    REQUIRE(position(s, pos(1, 1, 0.0f, 0.0f), t0 + 10000) == ErrorCode::kOk);
    CHECK(position(s, pos(1, 2, 0.0f, 0.0f), t0 + 90000) == ErrorCode::kStalePosition);
    CHECK(position(s, pos(2, 3, kNaN, 0.0f), t0 + 95000) == ErrorCode::kNotFinite);
    s.tick(t0 + 110001);
    CHECK(s.state() == State::kFault);
  }
  CHECK((s.faults() & proto::faults::kPositionTimeout) != 0);
  CHECK(level(s));
  CHECK(s.actuator_power());
  // The fault holds: positions no longer move the surface, start is refused.
  CHECK(position(s, pos(100, 1000000, -0.2f, 0.0f), t0 + 120000) == ErrorCode::kOk);
  CHECK(level(s));
  CHECK(s.state() == State::kFault);
  CHECK_FALSE(proto::taken_in(proto::Start::kId, s.state()));
  s.stop();
  CHECK(s.state() == State::kIdle);
  CHECK(s.faults() == 0);
}

TEST_CASE("supervisor: the deadman does not run in idle and restarts at start") {
  Supervisor s;
  REQUIRE(set_target(s, 0.0f, 0.0f) == ErrorCode::kOk);
  s.tick(10000000);
  CHECK(s.state() == State::kIdle);
  CHECK(s.faults() == 0);
  REQUIRE(s.start(10000000) == ErrorCode::kOk);
  s.tick(10000000 + 500000);
  CHECK(s.state() == State::kRunning);
  s.tick(10000000 + 500001);
  CHECK(s.state() == State::kFault);
}

TEST_CASE("supervisor: the deadman runs in reached too") {
  Supervisor s;
  run(s, 0.0f, 0.0f);
  REQUIRE(position(s, pos(1, 1, 0.0f, 0.0f), 1000) == ErrorCode::kOk);
  REQUIRE(s.state() == State::kReached);
  s.tick(1000 + 500001);
  CHECK(s.state() == State::kFault);
}

TEST_CASE("supervisor: the deadman copes with the firmware clock wrapping") {
  Supervisor s;
  const uint32_t t0 = 0xFFFFFFFFu - 50000u;
  run(s, 0.1f, 0.0f, t0);
  s.tick(t0 + 500000u);  // wraps past 0
  CHECK(s.state() == State::kRunning);
  s.tick(t0 + 500001u);
  CHECK(s.state() == State::kFault);
}

TEST_CASE("supervisor: position age counts from the last visible position and saturates") {
  Supervisor s;
  CHECK(s.position_age_ms(0) == 0xFFFF);
  REQUIRE(position(s, pos(1, 1, 0.0f, 0.0f, false), 1000) == ErrorCode::kOk);
  CHECK(s.position_age_ms(2000) == 0xFFFF);  // not visible: still none
  REQUIRE(position(s, pos(2, 2, 0.0f, 0.0f), 1000) == ErrorCode::kOk);
  CHECK(s.position_age_ms(1000) == 0);
  CHECK(s.position_age_ms(251999) == 250);
  CHECK(s.position_age_ms(1000 + 70000000u) == 0xFFFF);
}

TEST_CASE("supervisor: dt comes from capture times; a gap longer than the deadman restarts the derivative") {
  Supervisor s;
  uint8_t field = 0;
  REQUIRE(s.configure_pid(proto::ConfigurePid{0, 0.0f, 0.0f, 1.0f, 5.0f}, field) == ErrorCode::kOk);  // D only on x
  run(s, 0.2f, 0.0f);
  REQUIRE(position(s, pos(1, 100000, 0.0f, 0.0f), 1000) == ErrorCode::kOk);
  // Moved 0.01 m in 10 ms of capture time (the firmware saw it 40 ms later): rate -1 m/s -> -1 deg.
  REQUIRE(position(s, pos(2, 110000, 0.01f, 0.0f), 41000) == ErrorCode::kOk);
  CHECK(s.output().tilt_zx == Approx(-1.0f));
  // 600 ms of capture time: longer than the 500 ms deadman, so no derivative from that step.
  REQUIRE(position(s, pos(3, 710000, 0.02f, 0.0f), 42000) == ErrorCode::kOk);
  CHECK(s.output().tilt_zx == 0.0f);
}
