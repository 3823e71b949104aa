// Protocol-only Uno HAL until the actuator layer exists: real clock and serial; no motors, measured = last command.
#include <Arduino.h>  // micros(), Serial

#include "hal.h"  // the interface implemented here

namespace mr {
namespace hal {

namespace {

// Stand-in for the actuators: where they were last told to be [m], frozen while the power is off.
float g_measured[kActuatorCount] = {};
bool g_power = true;

}  // namespace

// micros() has a 4 us resolution at 16 MHz and wraps like the HAL's clock (2^32 us).
uint32_t now_us() { return micros(); }

// A frame goes out only if the whole of it fits in the serial TX buffer (SERIAL_TX_BUFFER_SIZE bytes);
// otherwise it is dropped, never waited for: a blocking write would stall the control loop.
void serial_write(const uint8_t* data, uint8_t len) {
  if (Serial.availableForWrite() < len) return;
  Serial.write(data, len);
}

void actuators_command(const float (&command)[kActuatorCount]) {
  if (!g_power) return;
  for (uint8_t i = 0; i < kActuatorCount; ++i) g_measured[i] = command[i];
}

void actuators_measured(float (&measured)[kActuatorCount]) {
  for (uint8_t i = 0; i < kActuatorCount; ++i) measured[i] = g_measured[i];
}

void actuators_power(bool on) { g_power = on; }

proto::Clock clock_kind() { return proto::Clock::kWall; }

// The Uno only has its wall clock.
proto::ErrorCode sim_clock_set(uint32_t /*t_us*/) { return proto::ErrorCode::kUnsupported; }

}  // namespace hal
}  // namespace mr
