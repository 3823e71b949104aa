// Frame encoder and the resynchronising, bounded frame decoder.
#include "frame.h"

#include "cobs.h"   // cobs_encode, cobs_decode_in_place
#include "crc16.h"  // crc16

namespace mr {

uint8_t frame_encode(uint8_t id, uint8_t seq, const uint8_t* payload, uint8_t payload_len,
                     uint8_t (&out)[proto::kMaxWire]) {
  if (payload_len > proto::kMaxPacket - kMinPacket) return 0;
  uint8_t packet[proto::kMaxPacket];
  packet[0] = id;
  packet[1] = seq;
  for (uint8_t i = 0; i < payload_len; ++i) packet[2 + i] = payload[i];
  const uint8_t body_len = static_cast<uint8_t>(2 + payload_len);
  const uint16_t crc = crc16(packet, body_len);
  packet[body_len] = static_cast<uint8_t>(crc);
  packet[body_len + 1] = static_cast<uint8_t>(crc >> 8);
  const uint8_t n = cobs_encode(packet, static_cast<uint8_t>(body_len + 2), out);
  out[n] = 0;
  return static_cast<uint8_t>(n + 1);
}

FrameDecoder::Result FrameDecoder::push(uint8_t byte) {
  if (byte != 0) {
    if (len_ < sizeof buf_) {
      buf_[len_++] = byte;
    } else {
      overflow_ = true;
    }
    return Result::kNone;
  }
  const Result result = finish();
  len_ = 0;
  overflow_ = false;
  if (result == Result::kCrcError) ++crc_errors_;
  if (result == Result::kFrameError) ++frame_errors_;
  return result;
}

FrameDecoder::Result FrameDecoder::finish() {
  if (overflow_) return Result::kFrameError;
  if (len_ == 0) return Result::kNone;  // back-to-back delimiters: idle line or a resync
  const int16_t n = cobs_decode_in_place(buf_, len_);
  if (n < kMinPacket) return Result::kFrameError;  // malformed COBS (-1) or too short
  const uint8_t body_len = static_cast<uint8_t>(n - 2);
  const uint16_t received = static_cast<uint16_t>(buf_[body_len] | (buf_[body_len + 1] << 8));
  if (crc16(buf_, body_len) != received) return Result::kCrcError;
  payload_len_ = static_cast<uint8_t>(body_len - 2);
  crc_ = received;
  return Result::kFrame;
}

}  // namespace mr
