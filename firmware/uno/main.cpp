// Uno entry point (protocol-only board build): serial bytes into the core, the core polled on every loop pass.
#include <Arduino.h>  // setup()/loop() contract, Serial
#include <avr/io.h>   // MCUSR and its reset flags

#include "firmware.h"      // mr::Firmware
#include "protocol_gen.h"  // mr::proto::ResetCause

namespace {

mr::Firmware g_firmware;

// Why the MCU started, from MCUSR, which is then cleared so that the next reset reports its own cause.
// Several flags can be set at once (a power-on ramp also trips the brown-out detector): the first listed
// wins. The stock Uno bootloader (Optiboot) clears MCUSR before it starts the sketch, so behind it this
// reads kUnknown; flashed without a bootloader (ISP) the cause comes through.
mr::proto::ResetCause take_reset_cause() {
  const uint8_t flags = MCUSR;
  MCUSR = 0;
  if (flags & _BV(PORF)) return mr::proto::ResetCause::kPowerOn;
  if (flags & _BV(BORF)) return mr::proto::ResetCause::kBrownOut;
  if (flags & _BV(WDRF)) return mr::proto::ResetCause::kWatchdog;
  if (flags & _BV(EXTRF)) return mr::proto::ResetCause::kExternal;
  return mr::proto::ResetCause::kUnknown;
}

}  // namespace

void setup() {
  Serial.begin(115200);  // [baud] the host link's rate (platformio.ini monitor_speed)
  g_firmware.boot(take_reset_cause());
}

void loop() {
  while (Serial.available() > 0) g_firmware.rx_byte(static_cast<uint8_t>(Serial.read()));
  g_firmware.poll();
}
