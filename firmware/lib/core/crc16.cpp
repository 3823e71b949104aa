// CRC-16/CCITT-FALSE (polynomial 0x1021, unreflected), a byte at a time without a table, so it costs no RAM on the
// Uno: the bitwise update's eight conditional shifts folded into three on the byte that falls out (the Mega's frame
// budget).
#include "crc16.h"

namespace mr {

uint16_t crc16_update(uint16_t crc, uint8_t byte) {
  uint8_t x = static_cast<uint8_t>((crc >> 8) ^ byte);
  x ^= static_cast<uint8_t>(x >> 4);
  return static_cast<uint16_t>((crc << 8) ^ (static_cast<uint16_t>(x) << 12) ^ (static_cast<uint16_t>(x) << 5) ^ x);
}

uint16_t crc16(const uint8_t* data, uint8_t len) {
  uint16_t crc = kCrc16Init;
  for (uint8_t i = 0; i < len; ++i) crc = crc16_update(crc, data[i]);
  return crc;
}

}  // namespace mr
