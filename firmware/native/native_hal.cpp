// HAL for the native virtual MCU: monotonic or simulated clock, queued serial output, ideal actuators.
#include "native_hal.h"

#include <time.h>  // clock_gettime

#include <deque>  // output queue

#include "hal.h"  // the interface implemented here

namespace mr {

namespace {

proto::Clock g_clock = proto::Clock::kWall;
uint64_t g_wall_origin_ns = 0;
uint32_t g_sim_now_us = 0;
std::deque<uint8_t> g_tx;
float g_measured[kActuatorCount] = {};
bool g_power = true;

uint64_t monotonic_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<uint64_t>(ts.tv_nsec);
}

}  // namespace

namespace native {

void reset(proto::Clock kind) {
  g_clock = kind;
  g_wall_origin_ns = monotonic_ns();
  g_sim_now_us = 0;
  g_tx.clear();
  for (float& m : g_measured) m = 0.0f;
  g_power = true;
}

size_t take_tx(uint8_t* out, size_t cap) {
  size_t n = 0;
  while (n < cap && !g_tx.empty()) {
    out[n++] = g_tx.front();
    g_tx.pop_front();
  }
  return n;
}

size_t tx_pending() { return g_tx.size(); }

}  // namespace native

namespace hal {

uint32_t now_us() {
  if (g_clock == proto::Clock::kSimulated) return g_sim_now_us;
  return static_cast<uint32_t>((monotonic_ns() - g_wall_origin_ns) / 1000u);
}

void serial_write(const uint8_t* data, uint8_t len) { g_tx.insert(g_tx.end(), data, data + len); }

// Ideal actuators: with power on they are where they are told, at once; with power off they stay put.
void actuators_command(const float (&command)[kActuatorCount]) {
  if (!g_power) return;
  for (uint8_t i = 0; i < kActuatorCount; ++i) g_measured[i] = command[i];
}

void actuators_measured(float (&measured)[kActuatorCount]) {
  for (uint8_t i = 0; i < kActuatorCount; ++i) measured[i] = g_measured[i];
}

void actuators_power(bool on) { g_power = on; }

proto::Clock clock_kind() { return g_clock; }

proto::ErrorCode sim_clock_set(uint32_t t_us) {
  if (g_clock != proto::Clock::kSimulated) return proto::ErrorCode::kUnsupported;
  if (static_cast<int32_t>(t_us - g_sim_now_us) < 0) return proto::ErrorCode::kOutOfRange;
  g_sim_now_us = t_us;
  return proto::ErrorCode::kOk;
}

}  // namespace hal
}  // namespace mr
