// Tests of mr::Firmware end to end on the native HAL: bytes in, frames out, with the simulated clock.
#include <doctest/doctest.h>

#include <stdint.h>  // uint8_t..uint32_t
#include <math.h>    // fabsf

#include <limits>  // quiet_NaN
#include <vector>  // byte streams and decoded frames

#include "firmware.h"    // Firmware
#include "frame.h"       // FrameDecoder, frame_encode
#include "native_hal.h"  // NativeHal

namespace {

using mr::proto::ErrorCode;
using mr::proto::State;
namespace proto = mr::proto;

const float kNaN = std::numeric_limits<float>::quiet_NaN();

struct Frame {
  uint8_t id, seq;
  std::vector<uint8_t> payload;
  size_t wire_len;  // [bytes] on the wire, delimiter included
};

// The host's end of the link: encodes commands into the firmware, decodes what it sends back.
class Host {
 public:
  explicit Host(proto::Clock clock = proto::Clock::kSimulated) : hal(clock), fw(hal) {
    fw.boot(proto::ResetCause::kPowerOn);
  }

  void send_raw(const std::vector<uint8_t>& bytes) {
    for (uint8_t b : bytes) fw.rx_byte(b);
  }

  std::vector<uint8_t> wire(uint8_t id, uint8_t seq, const uint8_t* payload, uint8_t len) {
    uint8_t out[proto::kMaxWire];
    const uint8_t n = mr::frame_encode(id, seq, payload, len, out);
    REQUIRE(n > 0);
    return std::vector<uint8_t>(out, out + n);
  }

  void send(uint8_t id, uint8_t seq, const uint8_t* payload = nullptr, uint8_t len = 0) {
    send_raw(wire(id, seq, payload, len));
  }

  template <typename Msg>
  void send_msg(const Msg& msg, uint8_t seq) {
    uint8_t payload[Msg::kSize > 0 ? Msg::kSize : 1];
    proto::encode(msg, payload);
    send(Msg::kId, seq, payload, Msg::kSize);
  }

  // Everything the firmware has sent since the last call, decoded; every byte must belong to a good frame.
  std::vector<Frame> take() {
    std::vector<Frame> frames;
    uint8_t buf[256];
    size_t n;
    while ((n = hal.take_tx(buf, sizeof buf)) > 0) {
      for (size_t i = 0; i < n; ++i) {
        ++pending_len_;
        const mr::FrameDecoder::Result r = rx_.push(buf[i]);
        if (buf[i] != 0) continue;
        REQUIRE(r == mr::FrameDecoder::Result::kFrame);
        frames.push_back(Frame{rx_.id(), rx_.seq(),
                               std::vector<uint8_t>(rx_.payload(), rx_.payload() + rx_.payload_len()), pending_len_});
        CHECK(pending_len_ <= proto::kMaxWire);
        pending_len_ = 0;
      }
    }
    CHECK(pending_len_ == 0);  // frames are written whole
    for (const Frame& f : frames) {
      CHECK(f.seq == next_tx_seq_);  // the firmware numbers its frames 0, 1, 2, ...
      next_tx_seq_ = static_cast<uint8_t>(f.seq + 1);
    }
    return frames;
  }

  // Exactly one frame, of this id.
  Frame take_one(uint8_t id) {
    const std::vector<Frame> frames = take();
    REQUIRE(frames.size() == 1);
    CHECK(static_cast<int>(frames[0].id) == static_cast<int>(id));
    return frames[0];
  }

  void expect_ack(uint8_t ref_id, uint8_t ref_seq) {
    const Frame f = take_one(proto::Ack::kId);
    REQUIRE(f.payload.size() == +proto::Ack::kSize);
    proto::Ack a;
    proto::decode(f.payload.data(), a);
    CHECK(static_cast<int>(a.ref_id) == static_cast<int>(ref_id));
    CHECK(static_cast<int>(a.ref_seq) == static_cast<int>(ref_seq));
  }

  void expect_nack(uint8_t ref_id, uint8_t ref_seq, ErrorCode code, uint8_t field) {
    const Frame f = take_one(proto::Nack::kId);
    REQUIRE(f.payload.size() == +proto::Nack::kSize);
    proto::Nack a;
    proto::decode(f.payload.data(), a);
    CHECK(static_cast<int>(a.ref_id) == static_cast<int>(ref_id));
    CHECK(static_cast<int>(a.ref_seq) == static_cast<int>(ref_seq));
    CHECK(static_cast<int>(a.code) == static_cast<int>(code));
    CHECK(static_cast<int>(a.field) == static_cast<int>(field));
  }

  static proto::Telemetry telemetry_of(const Frame& f) {
    REQUIRE(static_cast<int>(f.id) == static_cast<int>(proto::Telemetry::kId));
    REQUIRE(f.payload.size() == +proto::Telemetry::kSize);
    proto::Telemetry t;
    proto::decode(f.payload.data(), t);
    return t;
  }

  proto::Telemetry expect_telemetry() { return telemetry_of(take_one(proto::Telemetry::kId)); }

  // Sets the simulated clock through the protocol and expects the ack (and whatever poll() sent first).
  std::vector<Frame> clock_to(uint32_t t_us, uint8_t seq) {
    send_msg(proto::SimClock{t_us}, seq);
    std::vector<Frame> frames = take();
    REQUIRE_FALSE(frames.empty());
    CHECK(static_cast<int>(frames.back().id) == static_cast<int>(proto::Ack::kId));
    frames.pop_back();
    return frames;
  }

  mr::NativeHal hal;  // this host's board (declared first: the firmware is built on it)
  mr::Firmware fw;

 private:
  mr::FrameDecoder rx_;
  size_t pending_len_ = 0;
  uint8_t next_tx_seq_ = 0;
};

proto::Configure defaults() {
  proto::Configure c;
  proto::set_defaults(c);
  return c;
}

proto::ObjectPosition pos(uint16_t frame, uint32_t capture_us, float x, float y, uint8_t flags = 0) {
  return proto::ObjectPosition{frame, capture_us, x, y, flags};
}

}  // namespace

TEST_CASE("firmware: boot announces itself once, seq 0, with the reset cause") {
  mr::NativeHal hal(proto::Clock::kSimulated);
  mr::Firmware fw(hal);
  fw.boot(proto::ResetCause::kWatchdog);
  uint8_t buf[64];
  const size_t n = hal.take_tx(buf, sizeof buf);
  mr::FrameDecoder d;
  int frames = 0;
  for (size_t i = 0; i < n; ++i) {
    if (d.push(buf[i]) != mr::FrameDecoder::Result::kFrame) continue;
    ++frames;
    CHECK(d.id() == +proto::Boot::kId);
    CHECK(d.seq() == 0);
    REQUIRE(d.payload_len() == +proto::Boot::kSize);
    CHECK(d.payload()[0] == static_cast<uint8_t>(proto::ResetCause::kWatchdog));
  }
  CHECK(frames == 1);
  CHECK(hal.tx_pending() == 0);
}

TEST_CASE("firmware: identify reply carries versions, schema hash, max_wire and the clock kind") {
  for (proto::Clock clock : {proto::Clock::kSimulated, proto::Clock::kWall}) {
    Host h(clock);
    h.take_one(proto::Boot::kId);
    h.send_msg(proto::Identify{}, 1);
    const Frame f = h.take_one(proto::IdentifyReply::kId);
    REQUIRE(f.payload.size() == +proto::IdentifyReply::kSize);
    proto::IdentifyReply r;
    proto::decode(f.payload.data(), r);
    CHECK(r.protocol_version == proto::kProtocolVersion);
    CHECK(r.protocol_version == 2);
    CHECK(r.firmware_major == mr::kFirmwareMajor);
    CHECK(r.firmware_minor == mr::kFirmwareMinor);
    CHECK(r.firmware_patch == mr::kFirmwarePatch);
    CHECK(r.schema_hash == proto::kSchemaHash);
    CHECK(r.max_wire == 46);
    CHECK(r.clock == static_cast<uint8_t>(clock));
    CHECK(r.actuator_count == mr::kActuatorCount);  // the rig it was built for (protocol/rig.toml)
    CHECK(r.modules_x == mr::kModulesX);
    CHECK(r.modules_y == mr::kModulesY);
    CHECK(r.actuator_count == (r.modules_x + 1) * (r.modules_y + 1));
  }
}

TEST_CASE("firmware: commands are acked with their id and seq; refusals nacked with code and field") {
  Host h;
  h.take();
  h.send_msg(proto::SetTarget{0.1f, 0.0f}, 17);
  h.expect_ack(proto::SetTarget::kId, 17);
  h.send_msg(proto::SetTarget{kNaN, 0.0f}, 18);
  h.expect_nack(proto::SetTarget::kId, 18, ErrorCode::kNotFinite, 0);
  h.send_msg(proto::SetTarget{0.0f, 0.4f}, 19);
  h.expect_nack(proto::SetTarget::kId, 19, ErrorCode::kOutOfRange, 1);
  proto::Configure c = defaults();
  c.telemetry_period = 3;
  h.send_msg(c, 20);
  h.expect_nack(proto::Configure::kId, 20, ErrorCode::kOutOfRange, 8);
  CHECK(h.fw.supervisor().config().telemetry_period == 100);
  h.send_msg(proto::ConfigurePid{5, 1.0f, 1.0f, 1.0f, 1.0f}, 21);
  h.expect_nack(proto::ConfigurePid::kId, 21, ErrorCode::kOutOfRange, 0);
  h.send_msg(proto::Jog{1, 0.3f}, 22);
  h.expect_nack(proto::Jog::kId, 22, ErrorCode::kOutOfRange, 1);
  h.send_msg(proto::Start{}, 23);
  h.expect_ack(proto::Start::kId, 23);
  CHECK(h.fw.supervisor().state() == State::kRunning);
  h.send_msg(proto::Start{}, 24);
  h.expect_nack(proto::Start::kId, 24, ErrorCode::kBadState, proto::kNoField);
  h.send_msg(proto::EmergencyStop{}, 25);
  h.expect_ack(proto::EmergencyStop::kId, 25);
  CHECK(h.fw.supervisor().state() == State::kEstop);
  h.send_msg(proto::Stop{}, 26);
  h.expect_ack(proto::Stop::kId, 26);
  CHECK(h.fw.supervisor().state() == State::kIdle);
}

TEST_CASE("firmware: start before any target is nacked no_target") {
  Host h;
  h.take();
  h.send_msg(proto::Start{}, 0);
  h.expect_nack(proto::Start::kId, 0, ErrorCode::kNoTarget, proto::kNoField);
  CHECK(h.fw.supervisor().state() == State::kIdle);
}

TEST_CASE("firmware: an unknown or firmware-to-host id is nacked unknown_message") {
  Host h;
  h.take();
  for (uint8_t id : {uint8_t{0x7F}, uint8_t{0x00}, proto::Telemetry::kId, proto::Ack::kId, uint8_t{0xFF}}) {
    CAPTURE(static_cast<int>(id));
    h.send(id, 42);
    h.expect_nack(id, 42, ErrorCode::kUnknownMessage, proto::kNoField);
  }
}

TEST_CASE("firmware: a payload of the wrong length is nacked bad_length and not applied") {
  Host h;
  h.take();
  const uint8_t four[4] = {0x00, 0x00, 0x80, 0x3E};
  h.send(proto::SetTarget::kId, 6, four, 4);
  h.expect_nack(proto::SetTarget::kId, 6, ErrorCode::kBadLength, proto::kNoField);
  h.send(proto::Identify::kId, 7, four, 1);
  h.expect_nack(proto::Identify::kId, 7, ErrorCode::kBadLength, proto::kNoField);
  uint8_t pos_payload[proto::ObjectPosition::kSize + 1] = {};
  h.send(proto::ObjectPosition::kId, 8, pos_payload, sizeof pos_payload);
  h.expect_nack(proto::ObjectPosition::kId, 8, ErrorCode::kBadLength, proto::kNoField);
  h.send(proto::Start::kId, 9, four, 2);  // start with a payload: refused on length before any state check
  h.expect_nack(proto::Start::kId, 9, ErrorCode::kBadLength, proto::kNoField);
  CHECK(h.fw.supervisor().state() == State::kIdle);
}

TEST_CASE("firmware: a retransmitted command is answered again but applied once") {
  Host h;
  h.take();
  h.send_msg(proto::SetTarget{0.1f, 0.0f}, 1);
  h.expect_ack(proto::SetTarget::kId, 1);
  const std::vector<uint8_t> start = h.wire(proto::Start::kId, 2, nullptr, 0);
  h.send_raw(start);
  h.expect_ack(proto::Start::kId, 2);
  REQUIRE(h.fw.supervisor().state() == State::kRunning);
  // Applied again, start would be refused (bad_state): the same ack proves it was not.
  h.send_raw(start);
  h.expect_ack(proto::Start::kId, 2);
  h.send_raw(start);
  h.expect_ack(proto::Start::kId, 2);
  CHECK(h.fw.supervisor().state() == State::kRunning);
  // A new seq is a new command.
  h.send(proto::Start::kId, 3);
  h.expect_nack(proto::Start::kId, 3, ErrorCode::kBadState, proto::kNoField);
  // A retransmitted refusal gets the same refusal.
  h.send(proto::Start::kId, 3);
  h.expect_nack(proto::Start::kId, 3, ErrorCode::kBadState, proto::kNoField);
}

TEST_CASE("firmware: same id and seq with a different payload is a stale copy, not a retransmission") {
  Host h;
  h.take();
  h.send_msg(proto::Jog{0, 0.1f}, 5);
  h.expect_ack(proto::Jog::kId, 5);
  CHECK(h.fw.supervisor().output().command[0] == 0.1f);
  h.send_msg(proto::Jog{0, 0.1f}, 5);  // retransmission: ack, nothing new
  h.expect_ack(proto::Jog::kId, 5);
  CHECK(h.fw.supervisor().output().command[0] == 0.1f);
  // Same id and seq but a different payload (hence CRC): not the newest frame, so refused and not applied.
  h.send_msg(proto::Jog{0, 0.2f}, 5);
  h.expect_nack(proto::Jog::kId, 5, ErrorCode::kStaleSequence, proto::kNoField);
  CHECK(h.fw.supervisor().output().command[0] == 0.1f);
}

TEST_CASE("firmware: a frame 1..64 behind the newest is stale, 65 behind is new (a wrap-safe window)") {
  Host h;
  h.take();
  for (int behind : {1, 64}) {
    const uint8_t newest = static_cast<uint8_t>(200 + behind);
    h.send_msg(proto::Jog{0, 0.1f}, newest);
    h.expect_ack(proto::Jog::kId, newest);
    const uint8_t old_seq = static_cast<uint8_t>(newest - behind);
    h.send_msg(proto::Jog{0, 0.2f}, old_seq);
    h.expect_nack(proto::Jog::kId, old_seq, ErrorCode::kStaleSequence, proto::kNoField);
    CHECK(h.fw.supervisor().output().command[0] == 0.1f);
  }
  const uint8_t far = static_cast<uint8_t>(200 + 64 - 65);  // 65 behind the newest (264 mod 256 = 8): 191 ahead
  h.send_msg(proto::Jog{0, 0.2f}, far);
  h.expect_ack(proto::Jog::kId, far);
  CHECK(h.fw.supervisor().output().command[0] == 0.2f);
}

TEST_CASE("firmware: identify forgets the last command, so the same id and seq applies again") {
  Host h;
  h.take();
  h.send_msg(proto::SetTarget{0.1f, 0.0f}, 1);
  h.expect_ack(proto::SetTarget::kId, 1);
  h.send(proto::Start::kId, 2);
  h.expect_ack(proto::Start::kId, 2);
  h.send_msg(proto::Identify{}, 3);
  h.take_one(proto::IdentifyReply::kId);
  h.send(proto::Start::kId, 2);  // a new host's first start: applied, and refused since running
  h.expect_nack(proto::Start::kId, 2, ErrorCode::kBadState, proto::kNoField);
}

TEST_CASE("firmware: identify forgets the camera's frame history") {
  Host h;
  h.take();
  h.send_msg(pos(9, 1000, 0.0f, 0.0f), 1);
  h.expect_telemetry();
  h.send_msg(pos(9, 2000, 0.0f, 0.0f), 2);
  h.expect_nack(proto::ObjectPosition::kId, 2, ErrorCode::kStalePosition, 0);
  h.send_msg(proto::Identify{}, 3);
  h.take_one(proto::IdentifyReply::kId);
  h.send_msg(pos(9, 500, 0.0f, 0.0f), 4);
  CHECK(h.expect_telemetry().position_frame == 9);
}

TEST_CASE("firmware: object_position is answered by telemetry describing the step") {
  Host h;
  h.take();
  h.send_msg(proto::SetTarget{0.1f, -0.05f}, 1);
  h.expect_ack(proto::SetTarget::kId, 1);
  h.send_msg(proto::Start{}, 2);
  h.expect_ack(proto::Start::kId, 2);
  h.clock_to(30000, 3);  // 30 ms
  h.send_msg(pos(321, 29000, 0.0f, 0.0f), 4);
  const proto::Telemetry t = h.expect_telemetry();
  CHECK(t.time == 30);
  CHECK(t.state == static_cast<uint8_t>(State::kRunning));
  CHECK(t.faults == 0);
  CHECK(t.position_frame == 321);
  CHECK(t.position_age == 0);
  // First step: P only, 30.9 deg/m -> 3.09 and -1.545 deg, sent in 0.01 deg.
  CHECK(t.tilt_zx == 309);
  CHECK(t.tilt_zy == -155);  // -154.5 rounds away from zero
  const mr::ControllerOutput& out = h.fw.supervisor().output();
  for (uint8_t i = 0; i < mr::kActuatorCount; ++i) {
    CAPTURE(static_cast<int>(i));
    CHECK(fabsf(static_cast<float>(t.command[i]) - out.command[i] / 1e-5f) <= 0.5f);
    CHECK(t.measured[i] == t.command[i]);  // ideal actuators: they are where they were told
  }
  CHECK(t.command[1] > 0);  // +x corners down, towards the target
  CHECK(t.command[2] < 0);  // -x, +y: raised (target is at -y)
  CHECK(t.crc_errors == 0);
  CHECK(t.frame_errors == 0);
  // Object within tolerance: reached.
  h.send_msg(pos(322, 39000, 0.095f, -0.045f), 5);
  CHECK(h.expect_telemetry().state == static_cast<uint8_t>(State::kReached));
}

TEST_CASE("firmware: bad positions are nacked with the frame's seq; not-visible ones answered") {
  Host h;
  h.take();
  h.send_msg(pos(1, 1000, kNaN, 0.0f), 7);
  h.expect_nack(proto::ObjectPosition::kId, 7, ErrorCode::kNotFinite, 2);
  h.send_msg(pos(1, 1000, 0.0f, 0.0f), 8);
  h.expect_telemetry();
  h.send_msg(pos(1, 2000, 0.0f, 0.0f), 9);
  h.expect_nack(proto::ObjectPosition::kId, 9, ErrorCode::kStalePosition, 0);
  h.send_msg(pos(2, 1000, 0.0f, 0.0f), 10);
  h.expect_nack(proto::ObjectPosition::kId, 10, ErrorCode::kStalePosition, 1);
  h.send_msg(pos(3, 3000, kNaN, kNaN, proto::position_flags::kNotVisible), 11);
  CHECK(h.expect_telemetry().position_frame == 3);
  // A repeated object_position (same seq, same bytes): a copy of the newest frame, answered again.
  h.send_msg(pos(3, 3000, kNaN, kNaN, proto::position_flags::kNotVisible), 11);
  CHECK(h.expect_telemetry().position_frame == 3);
  // The same frame counter with a new seq is a new frame that repeats the camera's count: stale_position.
  h.send_msg(pos(3, 3000, kNaN, kNaN, proto::position_flags::kNotVisible), 12);
  h.expect_nack(proto::ObjectPosition::kId, 12, ErrorCode::kStalePosition, 0);
}

TEST_CASE("firmware: periodic telemetry every telemetry_period, counted from the last one") {
  Host h;
  h.take();
  CHECK(h.clock_to(99999, 1).empty());  // default period 100 ms, counted from boot at 0
  std::vector<Frame> due = h.clock_to(100000, 2);
  REQUIRE(due.size() == 1);  // sent by the poll() that sim_clock runs, before the ack
  CHECK(Host::telemetry_of(due[0]).time == 100);
  h.fw.poll();
  CHECK(h.take().empty());
  CHECK(h.clock_to(199999, 3).empty());
  h.fw.poll();
  CHECK(h.take().empty());
  CHECK(h.clock_to(200000, 4).size() == 1);
  // A position's telemetry restarts the period.
  h.clock_to(250000, 5);
  h.send_msg(pos(1, 1, 0.0f, 0.0f), 6);
  h.expect_telemetry();
  CHECK(h.clock_to(349999, 7).empty());
  CHECK(h.clock_to(350000, 8).size() == 1);
  // A long jump sends one telemetry, not a burst.
  CHECK(h.clock_to(5000000, 9).size() == 1);
}

TEST_CASE("firmware: telemetry_period 0 sends telemetry only in answer to positions") {
  Host h;
  h.take();
  proto::Configure c = defaults();
  c.telemetry_period = 0;
  h.send_msg(c, 1);
  h.expect_ack(proto::Configure::kId, 1);
  CHECK(h.clock_to(10000000, 2).empty());
  h.fw.poll();
  CHECK(h.take().empty());
  h.send_msg(pos(1, 1, 0.0f, 0.0f), 3);
  h.expect_telemetry();
}

TEST_CASE("firmware: sim_clock sets the firmware time, refuses going backwards, unsupported on a wall clock") {
  Host h;
  h.take();
  h.clock_to(83333, 1);
  CHECK(h.hal.now_us() == 83333);
  h.send_msg(proto::SimClock{83333}, 2);  // the same time is not backwards
  h.expect_ack(proto::SimClock::kId, 2);
  h.send_msg(proto::SimClock{83332}, 3);
  const Frame f = h.take_one(proto::Nack::kId);
  proto::Nack n;
  proto::decode(f.payload.data(), n);
  CHECK(n.ref_seq == 3);
  CHECK(n.code == static_cast<uint8_t>(ErrorCode::kOutOfRange));
  CHECK(h.hal.now_us() == 83333);

  Host wall(proto::Clock::kWall);
  wall.take();
  wall.send_msg(proto::SimClock{1000000000u}, 1);
  wall.expect_nack(proto::SimClock::kId, 1, ErrorCode::kUnsupported, proto::kNoField);
  CHECK(wall.hal.now_us() < 1000000000u);
}

TEST_CASE("firmware: the deadman faults a running firmware when positions stop, and levels it") {
  Host h;
  h.take();
  proto::Configure c = defaults();
  c.deadman = 100;
  c.telemetry_period = 0;
  h.send_msg(c, 1);
  h.expect_ack(proto::Configure::kId, 1);
  h.send_msg(proto::SetTarget{0.2f, 0.0f}, 2);
  h.expect_ack(proto::SetTarget::kId, 2);
  h.send_msg(proto::Start{}, 3);
  h.expect_ack(proto::Start::kId, 3);
  h.send_msg(pos(1, 1000, 0.0f, 0.0f), 4);
  CHECK(h.expect_telemetry().command[1] > 0);
  h.clock_to(100000, 5);
  h.fw.poll();
  CHECK(h.fw.supervisor().state() == State::kRunning);
  h.clock_to(100001, 6);  // sim_clock's own poll() runs the deadman before the ack
  CHECK(h.fw.supervisor().state() == State::kFault);
  h.send_msg(pos(2, 2000, 0.0f, 0.0f), 7);
  const proto::Telemetry t = h.expect_telemetry();
  CHECK(t.state == static_cast<uint8_t>(State::kFault));
  CHECK((t.faults & proto::faults::kPositionTimeout) != 0);
  for (int16_t a : t.command) CHECK(a == 0);
  for (int16_t m : t.measured) CHECK(m == 0);
  h.send_msg(proto::Stop{}, 8);
  h.expect_ack(proto::Stop::kId, 8);
  h.send_msg(pos(3, 3000, 0.0f, 0.0f), 9);
  const proto::Telemetry after = h.expect_telemetry();
  CHECK(after.state == static_cast<uint8_t>(State::kIdle));
  CHECK(after.faults == 0);
}

TEST_CASE("firmware: emergency stop cuts actuator power: the measured positions stay where they were") {
  Host h;
  h.take();
  h.send_msg(proto::Jog{1, 0.1f}, 1);
  h.expect_ack(proto::Jog::kId, 1);
  h.send_msg(pos(1, 1, 0.0f, 0.0f), 2);
  CHECK(h.expect_telemetry().measured[1] == 10000);
  h.send_msg(proto::EmergencyStop{}, 3);
  h.expect_ack(proto::EmergencyStop::kId, 3);
  h.send_msg(pos(2, 2, 0.0f, 0.0f), 4);
  proto::Telemetry t = h.expect_telemetry();
  CHECK(t.state == static_cast<uint8_t>(State::kEstop));
  CHECK((t.faults & proto::faults::kEstop) != 0);
  CHECK(t.command[1] == 0);       // the setpoint is level
  CHECK(t.measured[1] == 10000);  // but nothing moves without power
  h.send_msg(proto::Stop{}, 5);
  h.expect_ack(proto::Stop::kId, 5);
  h.send_msg(pos(3, 3, 0.0f, 0.0f), 6);
  t = h.expect_telemetry();
  CHECK(t.measured[1] == 0);  // power back: level
  CHECK(t.faults == 0);
}

TEST_CASE("firmware: an emergency stop the board kept across its reset holds from boot until stop") {
  mr::NativeHal hal(proto::Clock::kSimulated);
  mr::Firmware fw(hal);
  hal.actuators_command({0.1f, 0.0f, 0.0f, 0.0f});  // where the carriage stood when the board reset
  fw.boot(proto::ResetCause::kExternal, true);
  CHECK(fw.supervisor().state() == State::kEstop);
  CHECK(fw.supervisor().faults() == proto::faults::kEstop);
  CHECK_FALSE(fw.supervisor().actuator_power());
  float measured[mr::kActuatorCount];
  hal.actuators_measured(measured);
  CHECK(measured[0] == 0.1f);  // the levelled command did not reach the unpowered actuator
  uint8_t wire[proto::kMaxWire];
  const uint8_t n = mr::frame_encode(proto::Stop::kId, 1, nullptr, 0, wire);
  for (uint8_t i = 0; i < n; ++i) fw.rx_byte(wire[i]);
  CHECK(fw.supervisor().state() == State::kIdle);  // the host's stop clears it, as any emergency stop
  CHECK(fw.supervisor().faults() == 0);
  hal.actuators_measured(measured);
  CHECK(measured[0] == 0.0f);  // power back: level
}

TEST_CASE("firmware: corrupted frames get no reply and are counted in telemetry") {
  Host h;
  h.take();
  std::vector<uint8_t> bad = h.wire(proto::Start::kId, 1, nullptr, 0);
  bad[2] = static_cast<uint8_t>(bad[2] ^ 0x10);
  h.send_raw(bad);
  h.send_raw({0x13, 0x37, 0x00});               // garbage: a frame error
  h.send_raw(std::vector<uint8_t>(100, 0x42));  // oversize run...
  h.send_raw({0x00});                           // ...ended: one frame error
  CHECK(h.take().empty());
  CHECK(h.fw.supervisor().state() == State::kIdle);
  h.send_msg(pos(1, 1, 0.0f, 0.0f), 2);
  const proto::Telemetry t = h.expect_telemetry();
  CHECK(t.crc_errors == 1);
  CHECK(t.frame_errors == 2);
}

TEST_CASE("firmware: a whole session in one byte stream gives one reply per frame, in order") {
  Host h;
  h.take();
  std::vector<uint8_t> stream;
  auto add = [&](uint8_t id, uint8_t seq, const uint8_t* p, uint8_t len) {
    const std::vector<uint8_t> w = h.wire(id, seq, p, len);
    stream.insert(stream.end(), w.begin(), w.end());
  };
  uint8_t p[proto::kMaxPacket];
  add(proto::Identify::kId, 0, nullptr, 0);
  proto::encode(proto::SetTarget{0.05f, 0.05f}, p);
  add(proto::SetTarget::kId, 1, p, proto::SetTarget::kSize);
  add(proto::Start::kId, 2, nullptr, 0);
  for (uint16_t k = 0; k < 5; ++k) {
    proto::encode(pos(k, 1000u * (k + 1u), 0.0f, 0.0f), p);
    add(proto::ObjectPosition::kId, static_cast<uint8_t>(3 + k), p, proto::ObjectPosition::kSize);
  }
  add(proto::Stop::kId, 8, nullptr, 0);
  h.send_raw(stream);
  const std::vector<Frame> frames = h.take();
  REQUIRE(frames.size() == 9);
  CHECK(frames[0].id == +proto::IdentifyReply::kId);
  CHECK(frames[1].id == +proto::Ack::kId);
  CHECK(frames[2].id == +proto::Ack::kId);
  for (int k = 3; k < 8; ++k) CHECK(frames[static_cast<size_t>(k)].id == +proto::Telemetry::kId);
  CHECK(frames[8].id == +proto::Ack::kId);
  CHECK(h.fw.supervisor().state() == State::kIdle);
}

TEST_CASE("firmware: an actuator fault from the board goes through the one shutdown path: fault, power cut") {
  for (uint16_t fault : {proto::faults::kStall, proto::faults::kEncoder}) {
    Host h;
    h.take();
    h.send_msg(proto::SetTarget{0.1f, 0.0f}, 1);
    h.expect_ack(proto::SetTarget::kId, 1);
    h.send_msg(proto::Start{}, 2);
    h.expect_ack(proto::Start::kId, 2);
    h.send_msg(pos(1, 1000, 0.0f, 0.0f), 3);
    const proto::Telemetry driving = h.expect_telemetry();
    CHECK(driving.command[1] > 0);  // the controller lowers the +x corners
    h.hal.inject_actuator_faults(fault, 2);
    h.fw.poll();
    h.send_msg(pos(2, 84000, 0.05f, 0.0f), 4);
    proto::Telemetry t = h.expect_telemetry();
    CHECK(t.state == static_cast<uint8_t>(State::kFault));
    CHECK(t.faults == fault);
    CHECK(t.fault_actuator == 2);                 // the telemetry names the actuator
    CHECK(t.command[1] == 0);                     // levelled ...
    CHECK(t.measured[1] == driving.measured[1]);  // ... but with power cut nothing moves
    h.send_msg(proto::Start{}, 5);
    h.expect_nack(proto::Start::kId, 5, ErrorCode::kBadState, proto::kNoField);
    h.send_msg(proto::Stop{}, 6);
    h.expect_ack(proto::Stop::kId, 6);
    h.fw.poll();
    h.send_msg(pos(3, 168000, 0.0f, 0.0f), 7);
    t = h.expect_telemetry();
    CHECK(t.state == static_cast<uint8_t>(State::kIdle));
    CHECK(t.faults == 0);
    CHECK(t.fault_actuator == mr::kNoActuator);
    CHECK(t.measured[1] == 0);  // power back: level
  }
}

TEST_CASE("firmware: zero makes the masked actuators stand at 0 m, in idle only") {
  Host h;
  h.take();
  h.send_msg(proto::Jog{0, 0.1f}, 1);
  h.expect_ack(proto::Jog::kId, 1);
  h.send_msg(proto::Jog{3, -0.05f}, 2);
  h.expect_ack(proto::Jog::kId, 2);
  h.send_msg(proto::Zero{0b0001}, 3);
  h.expect_ack(proto::Zero::kId, 3);
  h.send_msg(pos(1, 1, 0.0f, 0.0f), 4);
  const proto::Telemetry t = h.expect_telemetry();
  CHECK(t.command[0] == 0);
  CHECK(t.measured[0] == 0);
  CHECK(t.command[3] == -5000);  // not in the mask: untouched
  h.send_msg(proto::Zero{0}, 5);
  h.expect_nack(proto::Zero::kId, 5, ErrorCode::kOutOfRange, 0);
  h.send_msg(proto::Zero{static_cast<uint16_t>(1u << mr::kActuatorCount)}, 6);  // an actuator this rig lacks
  h.expect_nack(proto::Zero::kId, 6, ErrorCode::kOutOfRange, 0);
  h.send_msg(proto::Jog{mr::kActuatorCount, 0.0f}, 7);
  h.expect_nack(proto::Jog::kId, 7, ErrorCode::kOutOfRange, 0);
  h.send_msg(proto::EmergencyStop{}, 8);
  h.expect_ack(proto::EmergencyStop::kId, 8);
  h.send_msg(proto::Zero{0b1111}, 9);
  h.expect_nack(proto::Zero::kId, 9, ErrorCode::kBadState, proto::kNoField);
}
