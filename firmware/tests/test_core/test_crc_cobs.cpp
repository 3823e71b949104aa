// Unit tests of CRC-16/CCITT-FALSE and COBS: known-answer vectors, round trips, malformed input.
#include <doctest/doctest.h>

#include <stdint.h>  // uint8_t, uint16_t
#include <string.h>  // memcmp

#include <vector>  // variable-length test buffers

#include "cobs.h"   // cobs_encode, cobs_decode_in_place
#include "crc16.h"  // crc16, crc16_update
#include "prng.h"   // Xorshift32 for reproducible random buffers

namespace {

using Bytes = std::vector<uint8_t>;

Bytes encode(const Bytes& in) {
  Bytes out(in.size() + in.size() / 254 + 1, 0xEE);
  const uint8_t n = mr::cobs_encode(in.data(), static_cast<uint8_t>(in.size()), out.data());
  out.resize(n);
  return out;
}

// Decoded bytes, or an empty optional-like flag through ok.
Bytes decode(Bytes in, bool& ok) {
  const int16_t n = mr::cobs_decode_in_place(in.data(), static_cast<uint8_t>(in.size()));
  ok = n >= 0;
  if (!ok) return Bytes();
  in.resize(static_cast<size_t>(n));
  return in;
}

Bytes count_up(uint8_t first, size_t n) {
  Bytes b(n);
  for (size_t i = 0; i < n; ++i) b[i] = static_cast<uint8_t>(first + i);
  return b;
}

}  // namespace

TEST_CASE("crc16: CCITT-FALSE known answers") {
  const uint8_t check[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  CHECK(mr::crc16(check, sizeof check) == 0x29B1);
  CHECK(mr::crc16(check, 0) == 0xFFFF);  // no bytes: the init value
  const uint8_t a[] = {'A'};
  CHECK(mr::crc16(a, 1) == 0xB915);
  CHECK(mr::kCrc16Init == 0xFFFF);
}

TEST_CASE("crc16: byte-wise update equals the whole-buffer CRC") {
  const uint8_t data[] = {0x00, 0xFF, 0x12, 0x80, 0x01, 0x7F, 0x55, 0xAA};
  uint16_t crc = mr::kCrc16Init;
  for (uint8_t b : data) crc = mr::crc16_update(crc, b);
  CHECK(crc == mr::crc16(data, sizeof data));
}

TEST_CASE("crc16: appending the CRC big-endian leaves a zero residue (no reflection, no final xor)") {
  mr::Xorshift32 rng;
  rng.seed(7);
  for (int trial = 0; trial < 50; ++trial) {
    uint8_t buf[34];
    const uint8_t len = static_cast<uint8_t>(rng.next() % 32);
    for (uint8_t i = 0; i < len; ++i) buf[i] = static_cast<uint8_t>(rng.next());
    const uint16_t crc = mr::crc16(buf, len);
    buf[len] = static_cast<uint8_t>(crc >> 8);
    buf[len + 1] = static_cast<uint8_t>(crc);
    CHECK(mr::crc16(buf, static_cast<uint8_t>(len + 2)) == 0);
  }
}

TEST_CASE("crc16: every single-bit error changes the CRC") {
  uint8_t data[] = {0x04, 0x06, 0x00, 0x00, 0x00, 0x3E, 0x00, 0x00, 0x80, 0xBD};
  const uint16_t good = mr::crc16(data, sizeof data);
  for (size_t i = 0; i < sizeof data; ++i) {
    for (uint8_t bit = 0; bit < 8; ++bit) {
      data[i] = static_cast<uint8_t>(data[i] ^ (1u << bit));
      CHECK(mr::crc16(data, sizeof data) != good);
      data[i] = static_cast<uint8_t>(data[i] ^ (1u << bit));
    }
  }
}

TEST_CASE("cobs: known-answer vectors (Cheshire and Baker; Wikipedia's examples)") {
  struct Kat {
    Bytes in, out;
  };
  const Kat kats[] = {
      {{}, {0x01}},
      {{0x00}, {0x01, 0x01}},
      {{0x00, 0x00}, {0x01, 0x01, 0x01}},
      {{0x00, 0x11, 0x00}, {0x01, 0x02, 0x11, 0x01}},
      {{0x11, 0x22, 0x00, 0x33}, {0x03, 0x11, 0x22, 0x02, 0x33}},
      {{0x11, 0x22, 0x33, 0x44}, {0x05, 0x11, 0x22, 0x33, 0x44}},
      {{0x11, 0x00, 0x00, 0x00}, {0x02, 0x11, 0x01, 0x01, 0x01}},
  };
  for (const Kat& k : kats) {
    CAPTURE(k.in.size());
    CHECK(encode(k.in) == k.out);
    bool ok = false;
    CHECK(decode(k.out, ok) == k.in);
    CHECK(ok);
  }
}

TEST_CASE("cobs: a 253-byte run without zeros is one block (code 0xFE); the output has no 0x00") {
  const Bytes in = count_up(1, 253);
  const Bytes out = encode(in);
  REQUIRE(out.size() == 254);
  CHECK(out[0] == 0xFE);
  CHECK(memcmp(out.data() + 1, in.data(), in.size()) == 0);
  bool ok = false;
  CHECK(decode(out, ok) == in);
  CHECK(ok);
}

TEST_CASE("cobs: the decoder accepts a full 0xFF block without an implied zero") {
  // Wikipedia's canonical encoding of 01..FE (254 bytes): FF 01 .. FE.
  Bytes wire(1, 0xFF);
  const Bytes data = count_up(1, 254);
  wire.insert(wire.end(), data.begin(), data.end());
  bool ok = false;
  CHECK(decode(wire, ok) == data);
  CHECK(ok);
}

TEST_CASE("cobs: random round trips up to 253 bytes never put a 0x00 on the wire") {
  mr::Xorshift32 rng;
  rng.seed(12345);
  for (int trial = 0; trial < 2000; ++trial) {
    const size_t len = rng.next() % 254;        // 0..253: the encoder's uint8_t result holds their length
    const uint32_t zero_odds = rng.next() % 4;  // 0: no zeros .. 3: many zeros
    Bytes in(len);
    for (uint8_t& b : in) {
      const uint32_t r = rng.next();
      b = (zero_odds != 0 && r % (8u >> (zero_odds - 1)) == 0) ? 0 : static_cast<uint8_t>(r >> 8);
    }
    const Bytes out = encode(in);
    CAPTURE(len);
    CHECK(out.size() <= len + len / 254 + 1);
    CHECK(out.size() >= len + 1);
    bool has_zero = false;
    for (uint8_t b : out) has_zero = has_zero || b == 0;
    CHECK_FALSE(has_zero);
    bool ok = false;
    CHECK(decode(out, ok) == in);
    CHECK(ok);
  }
}

TEST_CASE("cobs: malformed blocks are refused with -1") {
  const Bytes bad[] = {
      {0x00},                    // a zero code byte
      {0x03, 0x11, 0x00},        // a zero inside a block
      {0x05, 0x11, 0x22},        // code runs past the end
      {0x02},                    // code 2 with no data byte
      {0x02, 0x11, 0x04, 0x22},  // second block runs past the end
      {0x01, 0x00, 0x01},        // zero code byte in the middle
  };
  for (const Bytes& b : bad) {
    CAPTURE(b.size());
    Bytes copy = b;
    CHECK(mr::cobs_decode_in_place(copy.data(), static_cast<uint8_t>(copy.size())) == -1);
  }
}

TEST_CASE("cobs: decoding an empty block is empty") {
  uint8_t none[1] = {0xEE};
  CHECK(mr::cobs_decode_in_place(none, 0) == 0);
  CHECK(none[0] == 0xEE);  // untouched
}
