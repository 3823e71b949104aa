// C ABI of the virtual MCU and the plane transform, for in-process use from Python (ctypes): the same firmware
// the pty process runs, without the pty. Each handle is one virtual MCU; any number run side by side.
#include <stddef.h>  // size_t
#include <stdint.h>  // uint8_t, uint32_t

#include "firmware.h"    // Firmware
#include "native_hal.h"  // NativeHal
#include "plane.h"       // transform functions

namespace {

// One virtual MCU: its board and the firmware on it.
struct Vmcu {
  explicit Vmcu(mr::proto::Clock clock) : hal(clock), firmware(hal) {}
  mr::NativeHal hal;
  mr::Firmware firmware;
};

}  // namespace

extern "C" {

// A virtual MCU as if just powered on: clock 0 = wall, 1 = simulated. Its boot frame is queued.
// Free it with mr_vmcu_free.
void* mr_vmcu_new(int clock) {
  Vmcu* vmcu = new Vmcu(clock == 1 ? mr::proto::Clock::kSimulated : mr::proto::Clock::kWall);
  vmcu->firmware.boot(mr::proto::ResetCause::kPowerOn);
  return vmcu;
}

void mr_vmcu_free(void* handle) { delete static_cast<Vmcu*>(handle); }

// Host -> MCU bytes; each is handled as the serial receive path would, followed by one main-loop pass.
void mr_vmcu_write(void* handle, const uint8_t* data, size_t len) {
  mr::Firmware& firmware = static_cast<Vmcu*>(handle)->firmware;
  for (size_t i = 0; i < len; ++i) firmware.rx_byte(data[i]);
  firmware.poll();
}

// MCU -> host bytes: moves up to cap queued bytes to out and returns their count.
size_t mr_vmcu_read(void* handle, uint8_t* out, size_t cap) {
  return static_cast<Vmcu*>(handle)->hal.take_tx(out, cap);
}

// Paper transform, for checking against an independent implementation. Commands in [m], + lowers.
void mr_manhattan_commands(float tilt_zx_deg, float tilt_zy_deg, float module_x, float module_y, float* out4) {
  float(&command)[mr::kCorners] = *reinterpret_cast<float(*)[mr::kCorners]>(out4);
  mr::plane_commands(mr::manhattan_normal(tilt_zx_deg, tilt_zy_deg), module_x, module_y, command);
}

void mr_euclidean_commands(float theta_deg, float error_x, float error_y, float module_x, float module_y, float* out4) {
  float(&command)[mr::kCorners] = *reinterpret_cast<float(*)[mr::kCorners]>(out4);
  mr::plane_commands(mr::euclidean_normal(theta_deg, error_x, error_y), module_x, module_y, command);
}

float mr_max_tilt_deg(float module_x, float module_y, float range) {
  return mr::max_tilt_deg(module_x, module_y, range);
}

}  // extern "C"
