// A host stand-in for the few Arduino calls the Uno board code makes, recording pins for the board tests.
#pragma once

#include <stdint.h>  // uint8_t..uint32_t

#define HIGH 1
#define LOW 0
#define INPUT 0
#define OUTPUT 1
#define INPUT_PULLUP 2

namespace fake {

constexpr int kPins = 20;  // D0..D13, A0..A5

struct Pins {
  int mode[kPins];
  int digital[kPins];    // digitalWrite level
  int pwm[kPins];        // analogWrite value 0..255 (0 after a digitalWrite)
  int analog_in[kPins];  // what analogRead returns
  uint8_t port[kPins];   // per-pin output register that portOutputRegister hands out
};

extern Pins pins;
extern uint32_t now_us;  // what micros() returns
void reset();

}  // namespace fake

void pinMode(uint8_t pin, uint8_t mode);
void digitalWrite(uint8_t pin, uint8_t value);
int digitalRead(uint8_t pin);
void analogWrite(uint8_t pin, int value);
int analogRead(uint8_t pin);
unsigned long micros();

#define digitalPinToPort(pin) (pin)
#define portOutputRegister(p) (&fake::pins.port[(p)])
#define digitalPinToBitMask(pin) (static_cast<uint8_t>(1))
