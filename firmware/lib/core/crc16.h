// CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final xor): "123456789" -> 0x29B1.
#pragma once

#include <stdint.h>  // uint8_t, uint16_t

namespace mr {

constexpr uint16_t kCrc16Init = 0xFFFF;

uint16_t crc16_update(uint16_t crc, uint8_t byte);
uint16_t crc16(const uint8_t* data, uint8_t len);

}  // namespace mr
