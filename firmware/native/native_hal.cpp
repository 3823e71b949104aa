// The native board's clock and actuator power; the rest of NativeHal is inline in native_hal.h.
#include "native_hal.h"

#include <time.h>  // clock_gettime

namespace mr {

namespace {

uint64_t monotonic_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<uint64_t>(ts.tv_nsec);
}

}  // namespace

NativeHal::NativeHal(proto::Clock kind) : clock_(kind), wall_origin_ns_(monotonic_ns()) {}

size_t NativeHal::take_tx(uint8_t* out, size_t cap) {
  size_t n = 0;
  while (n < cap && !tx_.empty()) {
    out[n++] = tx_.front();
    tx_.pop_front();
  }
  return n;
}

uint32_t NativeHal::now_us() const {
  if (clock_ == proto::Clock::kSimulated) return sim_clock_.now_us();
  return static_cast<uint32_t>((monotonic_ns() - wall_origin_ns_) / 1000u);
}

void NativeHal::actuators_power(bool on) {
  if (on && !power_) injected_ = {0, kNoActuator};  // as a board's bank clears its latched faults
  power_ = on;
  actuators_.power(on);
}

proto::ErrorCode NativeHal::sim_clock_set(uint32_t t_us) {
  if (clock_ != proto::Clock::kSimulated) return proto::ErrorCode::kUnsupported;
  return sim_clock_.set(t_us);
}

}  // namespace mr
