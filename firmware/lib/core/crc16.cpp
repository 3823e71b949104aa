// CRC-16/CCITT-FALSE without a table, so it costs no RAM on the Uno: avr-libc's hand-written update on the AVR, bitwise
// elsewhere (the same polynomial, unreflected; CCITT-FALSE is its XMODEM update from 0xFFFF).
#include "crc16.h"

#ifdef __AVR__
#include <util/crc16.h>  // _crc_xmodem_update
#endif

namespace mr {

uint16_t crc16_update(uint16_t crc, uint8_t byte) {
#ifdef __AVR__
  return _crc_xmodem_update(crc, byte);
#else
  crc ^= static_cast<uint16_t>(byte) << 8;
  for (uint8_t bit = 0; bit < 8; ++bit) {
    crc = (crc & 0x8000) ? static_cast<uint16_t>((crc << 1) ^ 0x1021) : static_cast<uint16_t>(crc << 1);
  }
  return crc;
#endif
}

uint16_t crc16(const uint8_t* data, uint8_t len) {
  uint16_t crc = kCrc16Init;
  for (uint8_t i = 0; i < len; ++i) crc = crc16_update(crc, data[i]);
  return crc;
}

}  // namespace mr
