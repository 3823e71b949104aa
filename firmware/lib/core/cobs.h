// Consistent Overhead Byte Stuffing: removes every 0x00 from a packet so 0x00 can delimit frames.
#pragma once

#include <stdint.h>  // uint8_t

namespace mr {

// Encodes len bytes of in into out (room for len + len / 254 + 1 bytes); returns the encoded length.
// No delimiter is written.
uint8_t cobs_encode(const uint8_t* in, uint8_t len, uint8_t* out);

// Decodes len bytes in place; returns the decoded length, or -1 for a malformed block
// (a 0x00 inside, or a code running past the end).
int16_t cobs_decode_in_place(uint8_t* buf, uint8_t len);

}  // namespace mr
