// Little-endian field access on byte buffers and a NaN/inf test, for the generated protocol code.
#pragma once

#include <stdint.h>  // uint8_t..uint32_t
#include <string.h>  // memcpy (float <-> bits)

namespace mr {

// True for every float but NaN and +-inf (inf - inf and NaN - NaN are NaN); no <math.h> needed.
inline bool is_finite(float x) { return x - x == 0.0f; }

inline void put_u8(uint8_t* p, uint8_t v) { p[0] = v; }
inline void put_u16(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}
inline void put_u32(uint8_t* p, uint32_t v) {
  put_u16(p, static_cast<uint16_t>(v));
  put_u16(p + 2, static_cast<uint16_t>(v >> 16));
}
inline void put_i16(uint8_t* p, int16_t v) { put_u16(p, static_cast<uint16_t>(v)); }
inline void put_f32(uint8_t* p, float v) {
  uint32_t bits;
  memcpy(&bits, &v, sizeof bits);
  put_u32(p, bits);
}

inline uint8_t get_u8(const uint8_t* p) { return p[0]; }
inline uint16_t get_u16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (static_cast<uint16_t>(p[1]) << 8)); }
inline uint32_t get_u32(const uint8_t* p) { return get_u16(p) | (static_cast<uint32_t>(get_u16(p + 2)) << 16); }
inline int16_t get_i16(const uint8_t* p) { return static_cast<int16_t>(get_u16(p)); }
inline float get_f32(const uint8_t* p) {
  const uint32_t bits = get_u32(p);
  float v;
  memcpy(&v, &bits, sizeof v);
  return v;
}

}  // namespace mr
