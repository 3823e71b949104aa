// HAL for the native virtual MCU: monotonic or simulated clock, queued serial output, ideal actuators.
#include "native_hal.h"

#include <time.h>  // clock_gettime

#include <deque>  // output queue

#include "hal.h"              // the interface implemented here
#include "ideal_actuators.h"  // IdealActuators, SimulatedClock

namespace mr {

namespace {

proto::Clock g_clock = proto::Clock::kWall;
uint64_t g_wall_origin_ns = 0;
SimulatedClock g_sim_clock;
std::deque<uint8_t> g_tx;
IdealActuators g_actuators;
uint16_t g_injected_faults = 0;
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
  g_sim_clock = SimulatedClock();
  g_tx.clear();
  g_actuators = IdealActuators();
  g_injected_faults = 0;
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

void inject_actuator_faults(uint16_t faults) { g_injected_faults |= faults; }

}  // namespace native

namespace hal {

uint32_t now_us() {
  if (g_clock == proto::Clock::kSimulated) return g_sim_clock.now_us();
  return static_cast<uint32_t>((monotonic_ns() - g_wall_origin_ns) / 1000u);
}

void serial_write(const uint8_t* data, uint8_t len) { g_tx.insert(g_tx.end(), data, data + len); }

void actuators_command(const float (&command)[kActuatorCount]) { g_actuators.command(command); }

void actuators_measured(float (&measured)[kActuatorCount]) { g_actuators.measured(measured); }

void actuators_power(bool on) {
  if (on && !g_power) g_injected_faults = 0;  // as a board's bank clears its latched faults
  g_power = on;
  g_actuators.power(on);
}

void actuators_zero(uint8_t mask) { g_actuators.zero(mask); }

uint16_t actuator_faults() { return g_injected_faults; }
uint32_t actuator_overruns() { return 0; }  // ideal actuators have no loop to run late

proto::Clock clock_kind() { return g_clock; }

proto::ErrorCode sim_clock_set(uint32_t t_us) {
  if (g_clock != proto::Clock::kSimulated) return proto::ErrorCode::kUnsupported;
  return g_sim_clock.set(t_us);
}

}  // namespace hal
}  // namespace mr
