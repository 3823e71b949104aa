// C ABI of the virtual MCU and the plane transform, for in-process use from Python (ctypes):
// the same firmware the pty process runs, without the pty. One virtual MCU per process.
#include <stddef.h>  // size_t
#include <stdint.h>  // uint8_t, uint32_t

#include <new>  // placement new

#include "firmware.h"    // Firmware
#include "native_hal.h"  // native::reset, take_tx
#include "plane.h"       // transform functions

namespace {

alignas(mr::Firmware) unsigned char g_storage[sizeof(mr::Firmware)];
mr::Firmware* g_firmware = nullptr;

}  // namespace

extern "C" {

// (Re)starts the virtual MCU as if powered on: clock 0 = wall, 1 = simulated. Its boot frame is queued.
void mr_vmcu_boot(int clock) {
  mr::native::reset(clock == 1 ? mr::proto::Clock::kSimulated : mr::proto::Clock::kWall);
  g_firmware = new (g_storage) mr::Firmware();
  g_firmware->boot(mr::proto::ResetCause::kPowerOn);
}

// Host -> MCU bytes; each is handled as the serial receive path would, followed by one main-loop pass.
void mr_vmcu_write(const uint8_t* data, size_t len) {
  for (size_t i = 0; i < len; ++i) g_firmware->rx_byte(data[i]);
  g_firmware->poll();
}

// MCU -> host bytes: moves up to cap queued bytes to out and returns their count.
size_t mr_vmcu_read(uint8_t* out, size_t cap) { return mr::native::take_tx(out, cap); }

// Paper transform, for checking against an independent implementation. Commands in [m], + lowers.
void mr_manhattan_commands(float tilt_zx_deg, float tilt_zy_deg, float module_x, float module_y, float* out4) {
  float (&command)[mr::kActuatorCount] = *reinterpret_cast<float(*)[mr::kActuatorCount]>(out4);
  mr::plane_commands(mr::manhattan_normal(tilt_zx_deg, tilt_zy_deg), module_x, module_y, command);
}

void mr_euclidean_commands(float theta_deg, float error_x, float error_y, float module_x, float module_y,
                           float* out4) {
  float (&command)[mr::kActuatorCount] = *reinterpret_cast<float(*)[mr::kActuatorCount]>(out4);
  mr::plane_commands(mr::euclidean_normal(theta_deg, error_x, error_y), module_x, module_y, command);
}

float mr_max_tilt_deg(float module_x, float module_y, float range) {
  return mr::max_tilt_deg(module_x, module_y, range);
}

}  // extern "C"
