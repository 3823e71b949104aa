// Seeded xorshift32 PRNG for the actuator noise delta ~ U(-1, 1): tiny, and reproducible on every build.
#pragma once

#include <stdint.h>  // uint32_t

namespace mr {

class Xorshift32 {
 public:
  void seed(uint32_t s) { state_ = s ? s : 1u; }  // xorshift's state must not be 0
  uint32_t next() {
    state_ ^= state_ << 13;
    state_ ^= state_ >> 17;
    state_ ^= state_ << 5;
    return state_;
  }
  // Uniform on [-1, 1): the top 24 bits scaled exactly into a float.
  float uniform_pm1() { return static_cast<float>(next() >> 8) * (2.0f / 16777216.0f) - 1.0f; }

 private:
  uint32_t state_ = 1u;
};

}  // namespace mr
