// Uno entry point: serial bytes into the core, the actuator loops at their rate, the watchdog, timing probes.
//
// The main loop never blocks: each pass drains the serial receive buffer (64 bytes, filled by interrupt;
// at 115200 baud it takes 5.6 ms to overflow), runs the actuator loops if their 4 ms period is due,
// and polls the core (deadman, periodic telemetry). The controller runs inside the core on each
// object_position frame. A pass that hangs for 250 ms trips the watchdog: its interrupt cuts every
// motor and leaves a mark in RAM, and the MCU resets 250 ms later; the next boot reports reset_cause
// watchdog, also behind the stock bootloader, which clears MCUSR. Each pass also copies the emergency
// stop's latch to RAM that survives a reset, so after any reset but a power-on the board boots in estop.
#include <Arduino.h>        // setup()/loop() contract, Serial, pin helpers
#include <avr/interrupt.h>  // ISR, cli, sei
#include <avr/io.h>         // MCUSR, WDTCSR
#include <avr/wdt.h>        // wdt_reset, wdt_disable

#include "board.h"         // board::hal, board::begin, board::actuators_tick
#include "board_config.h"  // probe pins
#include "firmware.h"      // mr::Firmware
#include "protocol_gen.h"  // mr::proto::faults
#include "actuator_io.h"   // board::on_watchdog_timeout, board::keep_estop, board::Probe

namespace {

mr::Firmware g_firmware(mr::board::hal());

// MCUSR as the reset left it, saved before anything else runs (a watchdog reset leaves the watchdog
// running with its shortest timeout, so it is stopped here too, before the C runtime's start-up).
uint8_t g_reset_flags __attribute__((section(".noinit")));

void save_reset_flags() __attribute__((naked, used, section(".init3")));
void save_reset_flags() {
  g_reset_flags = MCUSR;
  MCUSR = 0;
  wdt_disable();
}

// Written by the watchdog's interrupt, read at the next boot (board::reset_cause): it survives the reset.
mr::board::ResetMark g_reset_mark __attribute__((section(".noinit")));
// The emergency stop's latch as of the last pass, read at the next boot (board::estop_survived).
mr::board::ResetMark g_estop_mark __attribute__((section(".noinit")));

// Interrupt-then-reset mode, 250 ms: the first timeout runs the interrupt, the second resets.
void watchdog_start() {
  cli();
  wdt_reset();
  WDTCSR = _BV(WDCE) | _BV(WDE);
  WDTCSR = _BV(WDIE) | _BV(WDE) | _BV(WDP2);
  sei();
}

// Each pass restarts the count and re-arms the interrupt (the hardware clears WDIE when it fires).
void watchdog_kick() {
  wdt_reset();
  WDTCSR |= _BV(WDIE);
}

mr::board::Probe g_probe_frame;
mr::board::Probe g_probe_loop;

}  // namespace

ISR(WDT_vect) { mr::board::on_watchdog_timeout(g_reset_mark); }

void setup() {
  Serial.begin(115200);  // [baud] the host link's rate (platformio.ini monitor_speed)
  g_probe_frame.begin(mr::board::kProbeControllerPin);
  g_probe_loop.begin(mr::board::kProbeLoopPin);
  mr::board::begin();
  const bool estop = mr::board::estop_survived(g_reset_flags, g_estop_mark);
  g_firmware.boot(mr::board::reset_cause(g_reset_flags, g_reset_mark), estop);
  watchdog_start();
}

void loop() {
  g_probe_loop.toggle();
  watchdog_kick();
  while (Serial.available() > 0) {
    const uint8_t byte = static_cast<uint8_t>(Serial.read());
    g_probe_frame.high();  // long only for the byte that completes a frame: the controller step and reply
    g_firmware.rx_byte(byte);
    g_probe_frame.low();
  }
  mr::board::actuators_tick();
  g_firmware.poll();
  mr::board::keep_estop(g_estop_mark, g_firmware.supervisor().faults() & mr::proto::faults::kEstop);
}
