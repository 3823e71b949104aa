// libFuzzer target: arbitrary bytes into mr::Firmware on the native HAL, checking every reply and every command.
//
// Each input boots a fresh mr::Firmware on the simulated clock and is used twice:
//   1. raw: every input byte goes through Firmware::rx_byte (and a standalone FrameDecoder), one poll()
//      per byte, and each 0x00 advances the clock by an amount taken from the byte before it;
//   2. messages: the same input is read as a list of messages (class Messages) that the harness encodes
//      and frames with a valid CRC, so the fuzzer reaches the dispatcher and the supervisor, with floats
//      near their bounds, without having to forge CRCs or hit narrow float ranges by chance.
// After every byte: each command within +-kActuatorRangeM and not NaN, the configuration still valid,
// every output frame a well-formed frame of at most kMaxWire bytes whose id and length match the schema,
// every accepted frame answered (ack/nack naming it, identify_reply, telemetry), a nack changing nothing,
// and telemetry's error counters equal to those of a standalone decoder fed the same bytes.
#include <math.h>    // powf
#include <stddef.h>  // size_t
#include <stdint.h>  // uint8_t..uint32_t
#include <stdio.h>   // fprintf
#include <stdlib.h>  // abort
#include <string.h>  // memcmp, memcpy

#include <limits>  // quiet_NaN, infinity, max, denorm_min

#include "firmware.h"    // Firmware
#include "frame.h"       // FrameDecoder, frame_encode
#include "native_hal.h"  // NativeHal
#include "plane.h"       // max_tilt_deg

namespace {

namespace proto = mr::proto;
using mr::FrameDecoder;

// Aborts, which libFuzzer reports as a crash with the input that caused it.
#define FUZZ_CHECK(cond)                                                                     \
  do {                                                                                       \
    if (!(cond)) {                                                                           \
      fprintf(stderr, "fuzz_decoder: %s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
      abort();                                                                               \
    }                                                                                        \
  } while (0)

// The harness's own branches are not coverage for the fuzzer to chase (and tracing them costs time).
#define HARNESS __attribute__((no_sanitize("coverage")))

struct OutFrame {
  uint8_t id, seq, len;
  uint8_t payload[proto::kMaxPacket];
};

struct Snapshot {
  proto::State state;
  uint16_t faults;
  proto::Configure config;
  float command[mr::kActuatorCount];
};

HARNESS bool same_config(const proto::Configure& a, const proto::Configure& b) {
  return a.controller == b.controller && memcmp(&a.module_x, &b.module_x, 4) == 0 &&
         memcmp(&a.module_y, &b.module_y, 4) == 0 && memcmp(&a.tilt_limit, &b.tilt_limit, 4) == 0 &&
         memcmp(&a.tolerance, &b.tolerance, 4) == 0 && memcmp(&a.noise_amplitude, &b.noise_amplitude, 4) == 0 &&
         a.noise_seed == b.noise_seed && a.deadman == b.deadman && a.telemetry_period == b.telemetry_period;
}

class Harness {
 public:
  HARNESS Harness() : hal_(proto::Clock::kSimulated), fw_(hal_) {
    fw_.boot(proto::ResetCause::kPowerOn);
    OutFrame frames[4];
    const int n = drain(frames, 4);
    FUZZ_CHECK(n == 1);
    FUZZ_CHECK(frames[0].id == proto::Boot::kId);
    FUZZ_CHECK(frames[0].payload[0] == static_cast<uint8_t>(proto::ResetCause::kPowerOn));
  }

  HARNESS mr::NativeHal& hal() { return hal_; }

  // One received byte, as the board's main loop handles it: rx_byte, then a poll.
  HARNESS void byte(uint8_t b, uint32_t advance_us) {
    const Snapshot before = snapshot();
    const FrameDecoder::Result r = standalone_.push(b);
    if (r == FrameDecoder::Result::kFrame) check_standalone_frame();
    fw_.rx_byte(b);
    OutFrame replies[8];
    const int n = drain(replies, 8);
    if (r == FrameDecoder::Result::kFrame) {
      FUZZ_CHECK(n >= 1);
      check_reply(replies[n - 1], before);
    } else {
      FUZZ_CHECK(n == 0);  // nothing but a good frame gets an answer
    }
    check_outputs();
    if (r == FrameDecoder::Result::kFrame) check_config();
    if (advance_us != 0) hal_.sim_clock_set(hal_.now_us() + advance_us);
    fw_.poll();
    OutFrame periodic[4];
    const int m = drain(periodic, 4);
    FUZZ_CHECK(m <= 1);  // at most one periodic telemetry per pass
    if (m == 1) FUZZ_CHECK(periodic[0].id == proto::Telemetry::kId);
    check_outputs();
  }

 private:
  HARNESS Snapshot snapshot() const {
    const mr::Supervisor& s = fw_.supervisor();
    Snapshot snap{s.state(), s.faults(), s.config(), {}};
    for (uint8_t i = 0; i < mr::kActuatorCount; ++i) snap.command[i] = s.output().command[i];
    return snap;
  }

  HARNESS void check_standalone_frame() {
    FUZZ_CHECK(standalone_.payload_len() <= proto::kMaxPacket - mr::kMinPacket);
    uint8_t wire[proto::kMaxWire];
    const uint8_t n =
        mr::frame_encode(standalone_.id(), standalone_.seq(), standalone_.payload(), standalone_.payload_len(), wire);
    FUZZ_CHECK(n >= 6 && n <= proto::kMaxWire);
    FrameDecoder again;
    for (uint8_t i = 0; i + 1 < n; ++i) FUZZ_CHECK(again.push(wire[i]) == FrameDecoder::Result::kNone);
    FUZZ_CHECK(again.push(wire[n - 1]) == FrameDecoder::Result::kFrame);
    FUZZ_CHECK(again.id() == standalone_.id() && again.seq() == standalone_.seq());
    FUZZ_CHECK(again.payload_len() == standalone_.payload_len());
    FUZZ_CHECK(memcmp(again.payload(), standalone_.payload(), again.payload_len()) == 0);
  }

  // The answer to the frame the standalone decoder just delivered (the firmware decoded the same bytes).
  HARNESS void check_reply(const OutFrame& f, const Snapshot& before) {
    const uint8_t id = standalone_.id();
    const uint8_t seq = standalone_.seq();
    const int size = proto::host_to_mcu_size(id);
    const bool well_formed = size >= 0 && size == standalone_.payload_len();
    if (f.id == proto::Nack::kId) {
      proto::Nack nack;
      proto::decode(f.payload, nack);
      FUZZ_CHECK(nack.ref_id == id && nack.ref_seq == seq);
      FUZZ_CHECK(nack.code >= 1 && nack.code <= proto::kLastErrorCode);
      FUZZ_CHECK(nack.field < proto::kMostFields || nack.field == proto::kNoField);
      if (size < 0) FUZZ_CHECK(nack.code == static_cast<uint8_t>(proto::ErrorCode::kUnknownMessage));
      if (size >= 0 && !well_formed) FUZZ_CHECK(nack.code == static_cast<uint8_t>(proto::ErrorCode::kBadLength));
      // A refused command changed nothing.
      const Snapshot after = snapshot();
      FUZZ_CHECK(after.state == before.state && after.faults == before.faults);
      FUZZ_CHECK(same_config(after.config, before.config));
      FUZZ_CHECK(memcmp(after.command, before.command, sizeof after.command) == 0);
      return;
    }
    FUZZ_CHECK(well_formed);
    if (id == proto::Identify::kId) {
      FUZZ_CHECK(f.id == proto::IdentifyReply::kId);
      proto::IdentifyReply r;
      proto::decode(f.payload, r);
      FUZZ_CHECK(r.schema_hash == proto::kSchemaHash && r.max_wire == proto::kMaxWire);
      FUZZ_CHECK(r.clock == static_cast<uint8_t>(proto::Clock::kSimulated));
    } else if (id == proto::ObjectPosition::kId) {
      FUZZ_CHECK(f.id == proto::Telemetry::kId);
      proto::ObjectPosition p;
      proto::decode(standalone_.payload(), p);
      proto::Telemetry t;
      proto::decode(f.payload, t);
      FUZZ_CHECK(t.position_frame == p.frame);
    } else {
      FUZZ_CHECK(f.id == proto::Ack::kId);
      proto::Ack ack;
      proto::decode(f.payload, ack);
      FUZZ_CHECK(ack.ref_id == id && ack.ref_seq == seq);
      if (id == proto::Configure::kId && before.state == proto::State::kIdle) {
        proto::Configure c;
        proto::decode(standalone_.payload(), c);
        FUZZ_CHECK(same_config(fw_.supervisor().config(), c));  // accepted whole (or a retransmission of it)
      }
      if (id == proto::EmergencyStop::kId) FUZZ_CHECK(fw_.supervisor().state() == proto::State::kEstop);
    }
  }

  // After every byte: the commands the HAL gets, the state, nothing left unsent.
  HARNESS void check_outputs() const {
    const mr::Supervisor& s = fw_.supervisor();
    for (float a : s.output().command) {
      FUZZ_CHECK(a == a);
      FUZZ_CHECK(a >= -mr::kActuatorRangeM && a <= mr::kActuatorRangeM);
    }
    FUZZ_CHECK(static_cast<uint8_t>(s.state()) <= static_cast<uint8_t>(proto::State::kEstop));
    FUZZ_CHECK(s.actuator_power() == (s.state() != proto::State::kEstop));
    FUZZ_CHECK(hal_.tx_pending() == 0);
  }

  // After every frame: the configuration is one the validation would accept.
  HARNESS void check_config() const {
    const proto::Configure& c = fw_.supervisor().config();
    uint8_t field = 0;
    FUZZ_CHECK(proto::validate(c, field) == proto::ErrorCode::kOk);
    FUZZ_CHECK(c.tilt_limit <= mr::max_tilt_deg(c.module_x, c.module_y, mr::kActuatorRangeM) + 1e-3f);
    FUZZ_CHECK(c.telemetry_period == 0 || c.telemetry_period >= 5);
  }

  // Moves the firmware's output to frames; every byte must belong to a good, small enough frame.
  HARNESS int drain(OutFrame* frames, int cap) {
    int n = 0;
    uint8_t buf[64];
    size_t got;
    while ((got = hal_.take_tx(buf, sizeof buf)) > 0) {
      for (size_t i = 0; i < got; ++i) {
        ++pending_;
        const FrameDecoder::Result r = out_.push(buf[i]);
        if (buf[i] != 0) {
          FUZZ_CHECK(r == FrameDecoder::Result::kNone);
          continue;
        }
        FUZZ_CHECK(r == FrameDecoder::Result::kFrame);
        FUZZ_CHECK(pending_ <= proto::kMaxWire);
        pending_ = 0;
        FUZZ_CHECK(out_.seq() == next_seq_);
        next_seq_ = static_cast<uint8_t>(next_seq_ + 1);
        FUZZ_CHECK(proto::mcu_to_host_size(out_.id()) == out_.payload_len());
        FUZZ_CHECK(n < cap);
        OutFrame& f = frames[n++];
        f.id = out_.id();
        f.seq = out_.seq();
        f.len = out_.payload_len();
        memcpy(f.payload, out_.payload(), f.len);
        if (f.id == proto::Telemetry::kId) check_telemetry(f);
      }
    }
    FUZZ_CHECK(pending_ == 0);  // frames are written whole
    return n;
  }

  HARNESS void check_telemetry(const OutFrame& f) const {
    proto::Telemetry t;
    proto::decode(f.payload, t);
    FUZZ_CHECK(t.time == hal_.now_us() / 1000u);
    FUZZ_CHECK(t.state <= static_cast<uint8_t>(proto::State::kEstop));
    FUZZ_CHECK((t.faults & ~(proto::faults::kPositionTimeout | proto::faults::kEstop)) == 0);
    for (int16_t a : t.command) FUZZ_CHECK(a >= -25000 && a <= 25000);
    for (int16_t m : t.measured) FUZZ_CHECK(m >= -25000 && m <= 25000);
    FUZZ_CHECK(t.tilt_zx >= -8900 && t.tilt_zx <= 8900);
    FUZZ_CHECK(t.tilt_zy >= -8900 && t.tilt_zy <= 8900);
    // The firmware's decoder saw the very bytes the standalone one did.
    FUZZ_CHECK(t.crc_errors == standalone_.crc_errors());
    FUZZ_CHECK(t.frame_errors == standalone_.frame_errors());
  }

  mr::NativeHal hal_;  // the board (declared first: the firmware is built on it)
  mr::Firmware fw_;
  FrameDecoder standalone_;  // fed every byte the firmware gets
  FrameDecoder out_;         // decodes what the firmware sends
  size_t pending_ = 0;
  uint8_t next_seq_ = 0;
};

// Reads the input as a list of messages, each: selector, seq, then fields. A selector below 0xF0 picks
// one of the host ids (selector % 10) and a clock step of (selector / 10) * 4001 us (0 .. 96 ms); its
// fields are built from few bytes each: an f32 from one byte, mostly within the field's range, else from a
// second byte (a table of NaN, infinities, bounds and their neighbours, or a signed value 1e-3 .. 1e2 on a
// log scale), u16 and u32 from raw bytes, enums
// mostly valid, object_position's frame counter and capture time mostly advancing. From 0xF0 on, the
// next byte is the id and the one after it the payload length (0 .. 40), then raw payload bytes.
class Messages {
 public:
  HARNESS Messages(const uint8_t* data, size_t size, mr::Hal& clock) : data_(data), size_(size), clock_(clock) {}
  HARNESS bool done() const { return i_ >= size_; }

  HARNESS void next_message(uint8_t& id, uint8_t& seq, uint8_t* payload, uint8_t& len, uint32_t& advance_us) {
    const uint8_t sel = u8();
    if (sel >= 0xF0) {
      id = u8();
      len = static_cast<uint8_t>(u8() % (proto::kMaxPacket - mr::kMinPacket + 1));
      seq = u8();
      for (uint8_t k = 0; k < len; ++k) payload[k] = u8();
      advance_us = 0;
      return;
    }
    id = proto::kHostToMcuIds[sel % sizeof proto::kHostToMcuIds];
    advance_us = (sel / 10u) * 4001u;
    seq = u8();
    len = static_cast<uint8_t>(proto::host_to_mcu_size(id));
    switch (id) {
      case proto::Configure::kId: {
        const uint8_t c = u8();
        proto::Configure m{static_cast<uint8_t>(c < 0xF0 ? c % proto::kControllerCount : c),
                           f32(0.1f, 10.0f),
                           f32(0.1f, 10.0f),
                           f32(0.1f, 30.0f),
                           f32(0.001f, 0.5f),
                           f32(0.0f, 0.25f),
                           u32(),
                           u16(),
                           u16(),
                           f32(0.0f, 10.0f)};
        return proto::encode(m, payload);
      }
      case proto::ConfigurePid::kId: {
        const uint8_t a = u8();
        proto::ConfigurePid m{static_cast<uint8_t>(a < 0xF0 ? a % proto::kAxisCount : a), f32(0.0f, 200.0f),
                              f32(0.0f, 200.0f), f32(0.0f, 200.0f), f32(0.0f, 90.0f)};
        return proto::encode(m, payload);
      }
      case proto::ConfigureSchedule::kId: {
        const float zone = f32(0.001f, 0.3f);
        const float gain = f32(0.0f, 1.0f);
        const float tilt = f32(0.0f, 1.0f);
        const float brake = f32(0.0f, 20.0f);
        return proto::encode(proto::ConfigureSchedule{zone, gain, tilt, brake, f32(0.0f, 2.0f)}, payload);
      }
      case proto::ConfigureCascade::kId: {
        const float gain = f32(0.0f, 20.0f);
        return proto::encode(proto::ConfigureCascade{gain, f32(0.001f, 1.0f)}, payload);
      }
      case proto::SetTarget::kId: {
        const float x = f32(-0.6f, 0.6f);
        return proto::encode(proto::SetTarget{x, f32(-0.6f, 0.6f)}, payload);
      }
      case proto::Jog::kId: {
        const uint8_t a = u8();
        return proto::encode(proto::Jog{static_cast<uint8_t>(a < 0xF0 ? a & 3 : a), f32(-0.3f, 0.3f)}, payload);
      }
      case proto::SimClock::kId: {
        // A step of -0.5 .. +0.5 s from the firmware's time: backwards now and then.
        const int32_t step = static_cast<int16_t>(u16()) * 16;
        return proto::encode(proto::SimClock{clock_.now_us() + static_cast<uint32_t>(step)}, payload);
      }
      case proto::ObjectPosition::kId: {
        const uint8_t f = u8();
        frame_ = static_cast<uint16_t>(frame_ + (f < 0xF0 ? f % 3 : f));  // 0: repeated -> stale
        capture_ += static_cast<uint32_t>(static_cast<int32_t>(static_cast<int8_t>(u8())) * 1000);  // ms steps
        const float x = f32(-1.0f, 1.0f);
        const float y = f32(-1.0f, 1.0f);
        const uint8_t flags = static_cast<uint8_t>(u8() & 0x81);
        return proto::encode(proto::ObjectPosition{frame_, capture_, x, y, flags}, payload);
      }
      case proto::Zero::kId: {
        const uint8_t a = u8();
        return proto::encode(proto::Zero{static_cast<uint8_t>(a < 0xF0 ? a & 0x0F : a)}, payload);
      }
      default:  // identify, start, stop, emergency_stop (no payload), and any message added since: raw bytes
        for (uint8_t k = 0; k < len; ++k) payload[k] = u8();
        return;
    }
  }

 private:
  HARNESS uint8_t u8() { return i_ < size_ ? data_[i_++] : 0; }
  HARNESS uint16_t u16() {
    const uint8_t lo = u8();
    return static_cast<uint16_t>(lo | (u8() << 8));
  }
  HARNESS uint32_t u32() {
    const uint16_t lo = u16();
    return lo | (static_cast<uint32_t>(u16()) << 16);
  }
  // Three bytes in four: lo .. hi (mostly the field's valid range); else a special value or a log-scale one.
  HARNESS float f32(float lo, float hi) {
    const uint8_t b = u8();
    if (b < 0xC0) return lo + (hi - lo) * static_cast<float>(b) / 191.0f;
    const uint8_t s = u8();
    static const float kSpecial[32] = {std::numeric_limits<float>::quiet_NaN(),
                                       std::numeric_limits<float>::infinity(),
                                       -std::numeric_limits<float>::infinity(),
                                       0.0f,
                                       -0.0f,
                                       std::numeric_limits<float>::max(),
                                       -std::numeric_limits<float>::max(),
                                       std::numeric_limits<float>::denorm_min(),
                                       0.001f,
                                       0.02f,
                                       0.1f,
                                       0.0999f,
                                       0.25f,
                                       -0.25f,
                                       0.2501f,
                                       -0.2501f,
                                       0.5f,
                                       0.75f,
                                       10.0f,
                                       10.01f,
                                       26.565051f,
                                       26.5651f,
                                       14.036243f,
                                       89.0f,
                                       89.01f,
                                       90.0f,
                                       90.01f,
                                       10000.0f,
                                       10000.1f,
                                       -1.0f,
                                       1e30f,
                                       0.24f};
    if (s < 32) return kSpecial[s];
    const float mag = powf(10.0f, static_cast<float>(s & 0x3F) / 63.0f * 5.0f - 3.0f);  // 1e-3 .. 1e2
    return (s & 0x40) ? -mag : mag;
  }

  const uint8_t* data_;
  size_t size_;
  mr::Hal& clock_;  // the board whose time sim_clock steps from
  size_t i_ = 0;
  uint16_t frame_ = 0;
  uint32_t capture_ = 0;
};

}  // namespace

extern "C" HARNESS int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Harness h;

  // Pass 1: the raw bytes. A delimiter advances the clock by (the byte before it) * 401 us (0 .. 102 ms).
  uint8_t last = 0;
  for (size_t i = 0; i < size; ++i) {
    h.byte(data[i], data[i] == 0 ? last * 401u : 0u);
    if (data[i] != 0) last = data[i];
  }

  // Pass 2: the same bytes as messages (see Messages): valid CRCs, fields mostly near their bounds.
  Messages msgs(data, size, h.hal());
  while (!msgs.done()) {
    uint8_t id = 0, seq = 0, len = 0;
    uint32_t advance_us = 0;
    uint8_t payload[proto::kMaxPacket] = {};
    msgs.next_message(id, seq, payload, len, advance_us);
    uint8_t wire[proto::kMaxWire];
    const uint8_t n = mr::frame_encode(id, seq, payload, len, wire);
    FUZZ_CHECK(n > 0 && n <= proto::kMaxWire);
    for (uint8_t k = 0; k < n; ++k) h.byte(wire[k], k + 1 == n ? advance_us : 0u);
  }
  return 0;
}
