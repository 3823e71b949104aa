// Unit tests of the frame layer: encode/decode round trips, resynchronisation, oversize, counters, bounds.
#include <doctest/doctest.h>

#include <initializer_list>  // range-for over braced lists
#include <stdint.h>          // uint8_t, uint16_t
#include <string.h>          // memset

#include <vector>  // byte streams

#include "crc16.h"  // crc16, to check FrameDecoder::crc()
#include "frame.h"  // FrameDecoder, frame_encode, kMinPacket
#include "prng.h"   // Xorshift32

namespace {

using mr::FrameDecoder;
using Result = FrameDecoder::Result;
using Bytes = std::vector<uint8_t>;

constexpr uint8_t kMaxPayload = mr::proto::kMaxPacket - mr::kMinPacket;  // 40

Bytes wire_of(uint8_t id, uint8_t seq, const Bytes& payload) {
  uint8_t out[mr::proto::kMaxWire];
  const uint8_t n = mr::frame_encode(id, seq, payload.data(), static_cast<uint8_t>(payload.size()), out);
  REQUIRE(n > 0);
  return Bytes(out, out + n);
}

std::vector<Result> feed(FrameDecoder& d, const Bytes& bytes) {
  std::vector<Result> got;
  for (uint8_t b : bytes) {
    const Result r = d.push(b);
    if (r != Result::kNone) got.push_back(r);
  }
  return got;
}

Bytes operator+(Bytes a, const Bytes& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace

TEST_CASE("frame: round trip for every payload length, with and without zeros") {
  mr::Xorshift32 rng;
  rng.seed(99);
  for (uint8_t len = 0; len <= kMaxPayload; ++len) {
    for (int zeros = 0; zeros < 2; ++zeros) {
      Bytes payload(len);
      for (uint8_t& b : payload)
        b = zeros ? static_cast<uint8_t>(rng.next() % 3) : static_cast<uint8_t>(1 + rng.next() % 255);
      const uint8_t id = static_cast<uint8_t>(rng.next());
      const uint8_t seq = static_cast<uint8_t>(rng.next());
      const Bytes wire = wire_of(id, seq, payload);
      CAPTURE(static_cast<int>(len));
      CHECK(wire.size() == static_cast<size_t>(len) + 6);  // id, seq, CRC, one COBS code, delimiter
      CHECK(wire.size() <= mr::proto::kMaxWire);
      CHECK(wire.back() == 0);
      for (size_t i = 0; i + 1 < wire.size(); ++i) CHECK(wire[i] != 0);
      FrameDecoder d;
      for (size_t i = 0; i + 1 < wire.size(); ++i) CHECK(d.push(wire[i]) == Result::kNone);
      REQUIRE(d.push(0) == Result::kFrame);
      CHECK(d.id() == id);
      CHECK(d.seq() == seq);
      REQUIRE(d.payload_len() == len);
      CHECK(Bytes(d.payload(), d.payload() + d.payload_len()) == payload);
      // The frame's CRC is the little-endian pair just before the delimiter, in the decoded packet.
      Bytes packet{id, seq};
      packet.insert(packet.end(), payload.begin(), payload.end());
      CHECK(d.crc() == mr::crc16(packet.data(), static_cast<uint8_t>(packet.size())));
      CHECK(d.crc_errors() == 0);
      CHECK(d.frame_errors() == 0);
    }
  }
}

TEST_CASE("frame: a payload longer than kMaxPacket allows is not encoded") {
  uint8_t payload[kMaxPayload + 1] = {};
  uint8_t out[mr::proto::kMaxWire];
  memset(out, 0xEE, sizeof out);
  CHECK(mr::frame_encode(1, 2, payload, kMaxPayload + 1, out) == 0);
  CHECK(out[0] == 0xEE);  // nothing written
  CHECK(mr::frame_encode(1, 2, payload, kMaxPayload, out) == mr::proto::kMaxWire);
}

TEST_CASE("frame: resynchronises after garbage") {
  const Bytes frame = wire_of(0x04, 6, {1, 2, 3, 4, 5, 6, 7, 8});
  SUBCASE("garbage without zeros, then a delimiter") {
    FrameDecoder d;
    const std::vector<Result> got = feed(d, Bytes{0x13, 0x37, 0x42, 0x99, 0x01, 0x00} + frame);
    REQUIRE(got.size() == 2);
    CHECK(got[0] != Result::kFrame);
    CHECK(got[1] == Result::kFrame);
    CHECK(d.id() == 0x04);
    CHECK(d.seq() == 6);
    CHECK(d.crc_errors() + d.frame_errors() == 1);
  }
  SUBCASE("garbage glued to the front of a frame costs that frame; the next one decodes") {
    FrameDecoder d;
    const std::vector<Result> got = feed(d, Bytes{0x55, 0x66} + frame + frame);
    REQUIRE(got.size() == 2);
    CHECK(got[0] != Result::kFrame);
    CHECK(got[1] == Result::kFrame);
  }
  SUBCASE("a frame cut short by a delimiter is dropped; the next one decodes") {
    FrameDecoder d;
    Bytes cut(frame.begin(), frame.begin() + 5);
    cut.push_back(0);
    const std::vector<Result> got = feed(d, cut + frame);
    REQUIRE(got.size() == 2);
    CHECK(got[0] != Result::kFrame);
    CHECK(got[1] == Result::kFrame);
    CHECK(d.payload_len() == 8);
  }
  SUBCASE("leading and repeated delimiters yield nothing and count nothing") {
    FrameDecoder d;
    const std::vector<Result> got = feed(d, Bytes{0, 0, 0} + frame + Bytes{0, 0});
    REQUIRE(got.size() == 1);
    CHECK(got[0] == Result::kFrame);
    CHECK(d.crc_errors() == 0);
    CHECK(d.frame_errors() == 0);
  }
}

TEST_CASE("frame: the largest frame (kMaxWire bytes) is accepted; one byte more is a single frame error") {
  Bytes payload(kMaxPayload, 0x5A);
  const Bytes frame = wire_of(0x10, 1, payload);
  REQUIRE(frame.size() == mr::proto::kMaxWire);
  FrameDecoder d;
  CHECK(feed(d, frame) == std::vector<Result>{Result::kFrame});
  // kMaxWire non-zero bytes before the delimiter cannot be a frame.
  Bytes big(mr::proto::kMaxWire, 0x5A);
  big.push_back(0);
  CHECK(feed(d, big) == std::vector<Result>{Result::kFrameError});
  CHECK(d.frame_errors() == 1);
}

TEST_CASE("frame: an oversized run is counted once however long it is, and the next frame decodes") {
  const Bytes frame = wire_of(0x01, 9, {});
  for (size_t run : {46, 47, 60, 255, 256, 1000, 5000}) {
    CAPTURE(run);
    FrameDecoder d;
    Bytes garbage(run, 0xA7);
    garbage.push_back(0);
    const std::vector<Result> got = feed(d, garbage + frame);
    CHECK(got == std::vector<Result>{Result::kFrameError, Result::kFrame});
    CHECK(d.frame_errors() == 1);
    CHECK(d.crc_errors() == 0);
    CHECK(d.id() == 0x01);
    CHECK(d.seq() == 9);
  }
}

TEST_CASE("frame: counters tell CRC errors from framing errors") {
  FrameDecoder d;
  Bytes flipped = wire_of(0x04, 6, {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x08});
  flipped[4] = static_cast<uint8_t>(flipped[4] ^ 0x02);  // a data byte, stays non-zero
  CHECK(feed(d, flipped) == std::vector<Result>{Result::kCrcError});
  CHECK(feed(d, Bytes{0x02, 0x01, 0x03, 0x00}) == std::vector<Result>{Result::kFrameError});  // 3 bytes: too short
  CHECK(feed(d, Bytes{0x07, 0x01, 0x02, 0x00}) == std::vector<Result>{Result::kFrameError});  // code past the end
  CHECK(feed(d, Bytes{0x01, 0x00}) == std::vector<Result>{Result::kFrameError});              // empty packet
  CHECK(d.crc_errors() == 1);
  CHECK(d.frame_errors() == 3);
  CHECK(feed(d, wire_of(2, 3, {})) == std::vector<Result>{Result::kFrame});
  CHECK(d.crc_errors() == 1);
  CHECK(d.frame_errors() == 3);
}

TEST_CASE("frame: the error counters wrap at 2^16") {
  FrameDecoder d;
  for (uint32_t i = 0; i < 65537u; ++i) {
    d.push(0x01);
    d.push(0x00);
  }
  CHECK(d.frame_errors() == 1);
}

TEST_CASE("frame: no single-bit error in a frame is delivered as a frame") {
  const Bytes payloads[] = {
      {}, {0x00, 0x00, 0x80, 0x3E, 0x00, 0x00, 0x80, 0xBD}, Bytes(15, 0x00), Bytes(kMaxPayload, 0xC3)};
  for (const Bytes& payload : payloads) {
    const Bytes frame = wire_of(0x10, 0x42, payload);
    for (size_t i = 0; i + 1 < frame.size(); ++i) {
      for (uint8_t bit = 0; bit < 8; ++bit) {
        Bytes bad = frame;
        bad[i] = static_cast<uint8_t>(bad[i] ^ (1u << bit));
        FrameDecoder d;
        const std::vector<Result> got = feed(d, bad);
        CAPTURE(i);
        CAPTURE(static_cast<int>(bit));
        CHECK_FALSE(got.empty());
        for (Result r : got) CHECK(r != Result::kFrame);
        CHECK(static_cast<size_t>(d.crc_errors() + d.frame_errors()) == got.size());
      }
    }
  }
}

TEST_CASE("frame: 10,000 random bytes never write outside the decoder and keep its invariants") {
  struct Guarded {
    uint8_t before[64];
    FrameDecoder d;
    uint8_t after[64];
  };
  for (uint32_t seed : {1u, 2u, 0xC0FFEEu}) {
    Guarded g;
    memset(g.before, 0xA5, sizeof g.before);
    memset(g.after, 0x5A, sizeof g.after);
    mr::Xorshift32 rng;
    rng.seed(seed);
    uint32_t frames = 0, crc = 0, framing = 0;
    for (int i = 0; i < 10000; ++i) {
      // Mostly non-zero bytes with a delimiter now and then, so long runs and short frames both happen.
      const uint32_t r = rng.next();
      const uint8_t byte = (r % 23 == 0) ? 0 : static_cast<uint8_t>(r >> 8);
      const Result res = g.d.push(byte);
      if (res == Result::kFrame) {
        ++frames;
        CHECK(g.d.payload_len() <= kMaxPayload);
      }
      crc += res == Result::kCrcError;
      framing += res == Result::kFrameError;
      if (byte != 0) CHECK(res == Result::kNone);
    }
    CHECK(g.d.crc_errors() == crc);
    CHECK(g.d.frame_errors() == framing);
    CHECK(crc + framing + frames > 100);  // the stream really exercised the decoder
    for (uint8_t b : g.before) REQUIRE(b == 0xA5);
    for (uint8_t b : g.after) REQUIRE(b == 0x5A);
    // And it still decodes a good frame afterwards.
    CHECK(feed(g.d, Bytes{0} + wire_of(7, 7, {1, 2, 3})).back() == Result::kFrame);
  }
}
