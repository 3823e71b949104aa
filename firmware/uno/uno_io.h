// The Uno's actuator I/O: H-bridge PWM and direction pins, AS5600 encoders behind a TCA9548A (or the ADC).
#pragma once

#include <stdint.h>  // uint8_t, uint16_t

#include "actuators.h"  // ActuatorIo

namespace mr {
namespace board {

class UnoActuatorIo final : public ActuatorIo {
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

// The watchdog's interrupt, one timeout before it resets the MCU: every motor off, nothing else.
void on_watchdog_timeout();

}  // namespace board
}  // namespace mr
