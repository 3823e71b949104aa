// Frame layer: COBS(id, seq, payload, CRC16 LE) + 0x00; a bounded decoder that resynchronises after garbage.
#pragma once

#include <stdint.h>  // uint8_t, uint16_t

#include "protocol_gen.h"  // kMaxPacket, kMaxWire

namespace mr {

constexpr uint8_t kMinPacket = 4;  // [bytes] id + seq + CRC, empty payload

// Writes the wire bytes of one frame (delimiter included) to out; returns their count,
// or 0 if the payload is too long for kMaxPacket.
uint8_t frame_encode(uint8_t id, uint8_t seq, const uint8_t* payload, uint8_t payload_len,
                     uint8_t (&out)[proto::kMaxWire]);

class FrameDecoder {
 public:
  enum class Result : uint8_t { kNone, kFrame, kCrcError, kFrameError };

  // Feeds one received byte. After kFrame, id(), seq(), payload() and payload_len() describe the
  // frame until the next push(). Never stores more than kMaxWire - 1 bytes.
  Result push(uint8_t byte);

  uint8_t id() const { return buf_[0]; }
  uint8_t seq() const { return buf_[1]; }
  const uint8_t* payload() const { return buf_ + 2; }
  uint8_t payload_len() const { return payload_len_; }
  uint16_t crc() const { return crc_; }  // the frame's CRC, which tells a retransmission from a new command

  uint16_t crc_errors() const { return crc_errors_; }
  uint16_t frame_errors() const { return frame_errors_; }

 private:
  Result finish();

  uint8_t buf_[proto::kMaxWire - 1] = {};
  uint8_t len_ = 0;
  uint8_t payload_len_ = 0;
  uint16_t crc_ = 0;
  bool overflow_ = false;
  uint16_t crc_errors_ = 0;
  uint16_t frame_errors_ = 0;
};

}  // namespace mr
