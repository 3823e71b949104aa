// Runs every protocol test vector (protocol/vectors.json, via vectors_gen.h) through the C++ frame decoder and encoder.
#include <doctest/doctest.h>

#include <stdint.h>  // uint8_t
#include <string.h>  // memcmp

#include <vector>  // yields collected per vector

#include "frame.h"  // FrameDecoder, frame_encode

#include "vectors_gen.h"  // vectors::kAll (generated from protocol/vectors.json; do not edit)

namespace {

using mr::FrameDecoder;

struct Got {
  FrameDecoder::Result result;
  uint8_t id, seq;
  std::vector<uint8_t> payload;
};

FrameDecoder::Result to_result(vectors::Yield y) {
  switch (y) {
    case vectors::Yield::kFrame:
      return FrameDecoder::Result::kFrame;
    case vectors::Yield::kCrcError:
      return FrameDecoder::Result::kCrcError;
    case vectors::Yield::kFrameError:
      return FrameDecoder::Result::kFrameError;
  }
  return FrameDecoder::Result::kNone;
}

std::vector<Got> feed(const uint8_t* wire, uint16_t len, FrameDecoder& d) {
  std::vector<Got> got;
  for (uint16_t i = 0; i < len; ++i) {
    const FrameDecoder::Result r = d.push(wire[i]);
    if (r == FrameDecoder::Result::kNone) continue;
    Got g{r, 0, 0, {}};
    if (r == FrameDecoder::Result::kFrame) {
      g.id = d.id();
      g.seq = d.seq();
      g.payload.assign(d.payload(), d.payload() + d.payload_len());
    }
    got.push_back(g);
  }
  return got;
}

int count_delimiters(const uint8_t* wire, uint16_t len) {
  int n = 0;
  for (uint16_t i = 0; i < len; ++i) n += wire[i] == 0;
  return n;
}

}  // namespace

TEST_CASE("vectors: the table is not empty and every wire ends with a delimiter") {
  REQUIRE(sizeof vectors::kAll / sizeof vectors::kAll[0] >= 25);
  for (const vectors::Vector& v : vectors::kAll) {
    CAPTURE(v.name);
    REQUIRE(v.wire_len > 0);
    CHECK(v.wire[v.wire_len - 1] == 0);
  }
}

TEST_CASE("vectors: a fresh decoder yields exactly the expected sequence") {
  int frames_checked = 0, fields_checked = 0;
  for (const vectors::Vector& v : vectors::kAll) {
    CAPTURE(v.name);
    FrameDecoder d;
    const std::vector<Got> got = feed(v.wire, v.wire_len, d);
    REQUIRE(got.size() == v.expected_len);
    uint16_t crc_errors = 0, frame_errors = 0;
    for (uint8_t k = 0; k < v.expected_len; ++k) {
      const vectors::Expected& e = v.expected[k];
      CAPTURE(static_cast<int>(k));
      REQUIRE(got[k].result == to_result(e.yield));
      if (e.yield == vectors::Yield::kCrcError) ++crc_errors;
      if (e.yield == vectors::Yield::kFrameError) ++frame_errors;
      if (e.yield != vectors::Yield::kFrame) continue;
      CHECK(static_cast<int>(got[k].id) == static_cast<int>(e.id));
      CHECK(static_cast<int>(got[k].seq) == static_cast<int>(e.seq));
      REQUIRE(got[k].payload.size() == e.payload_len);
      CHECK(got[k].payload == std::vector<uint8_t>(e.payload, e.payload + e.payload_len));
      ++frames_checked;
      if (e.fields_ok != nullptr) {
        CHECK(e.fields_ok(got[k].payload.data()));
        ++fields_checked;
      }
    }
    CHECK(d.crc_errors() == crc_errors);
    CHECK(d.frame_errors() == frame_errors);
  }
  CHECK(frames_checked >= 20);
  CHECK(fields_checked >= 18);
}

TEST_CASE("vectors: a single-frame vector re-encodes to its wire bytes") {
  int reencoded = 0;
  for (const vectors::Vector& v : vectors::kAll) {
    if (v.expected_len != 1 || v.expected[0].yield != vectors::Yield::kFrame) continue;
    if (count_delimiters(v.wire, v.wire_len) != 1) continue;
    CAPTURE(v.name);
    const vectors::Expected& e = v.expected[0];
    uint8_t out[mr::proto::kMaxWire];
    const uint8_t n = mr::frame_encode(e.id, e.seq, e.payload, e.payload_len, out);
    REQUIRE(n == v.wire_len);
    CHECK(memcmp(out, v.wire, n) == 0);
    CHECK(n <= mr::proto::kMaxWire);
    ++reencoded;
  }
  CHECK(reencoded >= 20);
}

TEST_CASE("vectors: fields_ok rejects a payload with one byte changed") {
  // The generated field checks must actually look at the payload, or the test above would be vacuous.
  int rejected = 0;
  for (const vectors::Vector& v : vectors::kAll) {
    for (uint8_t k = 0; k < v.expected_len; ++k) {
      const vectors::Expected& e = v.expected[k];
      if (e.yield != vectors::Yield::kFrame || e.fields_ok == nullptr || e.payload_len == 0) continue;
      CAPTURE(v.name);
      std::vector<uint8_t> p(e.payload, e.payload + e.payload_len);
      // Flip one bit of the last payload byte: a field the vector names changes.
      p[p.size() - 1] = static_cast<uint8_t>(p[p.size() - 1] ^ 0x40);
      if (!e.fields_ok(p.data())) ++rejected;
    }
  }
  CHECK(rejected >= 15);
}

TEST_CASE("vectors: all vectors fed back to back into one decoder give the concatenated yields") {
  FrameDecoder d;
  size_t expected_total = 0;
  size_t got_total = 0;
  for (const vectors::Vector& v : vectors::kAll) {
    CAPTURE(v.name);
    const std::vector<Got> got = feed(v.wire, v.wire_len, d);
    REQUIRE(got.size() == v.expected_len);
    for (uint8_t k = 0; k < v.expected_len; ++k) CHECK(got[k].result == to_result(v.expected[k].yield));
    expected_total += v.expected_len;
    got_total += got.size();
  }
  CHECK(got_total == expected_total);
}
