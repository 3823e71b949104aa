// The Uno's actuator I/O: H-bridge PWM and direction pins, AS5600 encoders behind a TCA9548A (or the ADC).
#pragma once

#include <stdint.h>  // uint8_t, uint16_t

#include "actuators.h"     // ActuatorIo
#include "protocol_gen.h"  // proto::ResetCause

namespace mr {
namespace board {

class ArduinoActuatorIo final : public ActuatorIo {
 public:
  // Pins to outputs at 0, the I2C bus at kI2cClockHz with its timeout.
  void begin();
  bool encoder_read(uint8_t actuator, uint16_t& raw) override;
  void motor_write(uint8_t actuator, float duty) override;
  void motors_off() override;
};

// A probe pin for timing (AVR simulator, scope), written through its port register: digitalWrite() takes
// about 4 us, this two cycles.
struct Probe {
  volatile uint8_t* port;
  uint8_t mask;
  void begin(uint8_t pin);
  void high() const { *port |= mask; }
  void low() const { *port &= static_cast<uint8_t>(~mask); }
  void toggle() const { *port ^= mask; }
};

// What survives a reset in memory the C runtime leaves alone (.noinit): a mark and its complement, so a reset
// that follows it is known even behind a bootloader that clears MCUSR. Every reset but a power-on keeps RAM.
struct ResetMark {
  uint16_t mark;
  uint16_t check;  // ~mark: random RAM at power-on passes both with odds of 1 in 2^32

  void set(uint16_t word) {
    mark = word;
    check = static_cast<uint16_t>(~word);
  }
  bool holds(uint16_t word) const { return mark == word && check == static_cast<uint16_t>(~word); }
  void clear() { mark = check = 0; }
};
constexpr uint16_t kWatchdogMark = 0x57D6;
constexpr uint16_t kEstopMark = 0xE5A7;

// The watchdog's interrupt, one timeout before it resets the MCU: every motor off, and the mark written.
void on_watchdog_timeout(ResetMark& survives);

// Why the MCU started, from MCUSR as the reset left it (bits as the ATmega328P's: PORF 0, EXTRF 1, BORF 2,
// WDRF 3) and the mark, which it clears. Power-on wins (RAM is random then), then the watchdog (by flag or
// mark), brown-out and external; nothing known (the stock bootloader cleared the flags) is unknown.
proto::ResetCause reset_cause(uint8_t mcusr, ResetMark& survives);

// The emergency stop across a reset: the main loop copies the core's latch into its mark on every pass, and the
// next boot starts latched if the mark holds, after any reset but a power-on (reset pin or the host opening the
// port, watchdog, brown-out).
void keep_estop(ResetMark& survives, bool latched);
bool estop_survived(uint8_t mcusr, const ResetMark& survives);

}  // namespace board
}  // namespace mr
