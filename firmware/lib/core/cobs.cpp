// COBS encoder and in-place decoder on bounded buffers.
#include "cobs.h"

namespace mr {

uint8_t cobs_encode(const uint8_t* in, uint8_t len, uint8_t* out) {
  uint8_t code_at = 0;  // where the current block's code byte goes
  uint8_t n = 1;        // next free byte of out
  uint8_t code = 1;     // 1 + bytes in the current block
  for (uint8_t i = 0; i < len; ++i) {
    if (in[i] == 0) {
      out[code_at] = code;
      code_at = n++;
      code = 1;
      continue;
    }
    out[n++] = in[i];
    if (++code == 0xFF) {
      out[code_at] = code;
      code_at = n++;
      code = 1;
    }
  }
  out[code_at] = code;
  return n;
}

int16_t cobs_decode_in_place(uint8_t* buf, uint8_t len) {
  uint8_t read = 0;
  uint8_t write = 0;
  while (read < len) {
    const uint8_t code = buf[read];
    if (code == 0 || static_cast<uint16_t>(read) + code > len) return -1;
    ++read;
    for (uint8_t i = 1; i < code; ++i) {
      const uint8_t byte = buf[read++];
      if (byte == 0) return -1;
      buf[write++] = byte;
    }
    if (code != 0xFF && read < len) buf[write++] = 0;
  }
  return write;
}

}  // namespace mr
