// The fake Arduino and Wire: pins as arrays, an I2C bus with a multiplexer and four AS5600 encoders.
#include <string.h>  // memset

#include "Arduino.h"
#include "Wire.h"

namespace fake {

Pins pins;
uint32_t now_us = 0;
I2cBus bus;

void reset() {
  memset(&pins, 0, sizeof pins);
  now_us = 0;
  bus = I2cBus();
}

namespace {

// The one encoder the multiplexer connects, or -1 (none, or several at once: a bus conflict).
int selected_encoder() {
  int channel = -1;
  for (int c = 0; c < 8; ++c) {
    if (bus.selected & (1u << c)) {
      if (channel >= 0) return -1;
      channel = c;
    }
  }
  return channel >= 0 && !bus.silent[channel] ? channel : -1;
}

}  // namespace

}  // namespace fake

void pinMode(uint8_t pin, uint8_t mode) { fake::pins.mode[pin] = mode; }
void digitalWrite(uint8_t pin, uint8_t value) {
  fake::pins.digital[pin] = value;
  fake::pins.pwm[pin] = 0;
}
int digitalRead(uint8_t pin) { return fake::pins.mode[pin] == INPUT_PULLUP ? HIGH : fake::pins.digital[pin]; }
void analogWrite(uint8_t pin, int value) { fake::pins.pwm[pin] = value; }
int analogRead(uint8_t pin) { return fake::pins.analog_in[pin]; }
unsigned long micros() { return fake::now_us; }

TwoWire Wire;

void TwoWire::beginTransmission(uint8_t address) {
  address_ = address;
  n_written_ = 0;
}

size_t TwoWire::write(uint8_t byte) {
  if (n_written_ < sizeof written_) written_[n_written_++] = byte;
  return 1;
}

uint8_t TwoWire::endTransmission(bool) {
  ++fake::bus.transactions;
  if (address_ == fake::bus.mux_address) {
    if (n_written_ == 1) fake::bus.selected = written_[0];
    return 0;
  }
  const int channel = fake::selected_encoder();
  if (address_ != fake::bus.encoder_address || channel < 0) return 2;  // address NACK
  if (n_written_ >= 1) fake::bus.pointer[channel] = written_[0];
  return 0;
}

uint8_t TwoWire::requestFrom(uint8_t address, uint8_t count) {
  ++fake::bus.transactions;
  rx_len_ = rx_pos_ = 0;
  const int channel = fake::selected_encoder();
  if (address != fake::bus.encoder_address || channel < 0 || count > sizeof rx_) return 0;
  const uint16_t angle = fake::bus.angle[channel] & 0x0FFFu;
  const uint8_t reg[2] = {static_cast<uint8_t>(angle >> 8), static_cast<uint8_t>(angle & 0xFFu)};
  if (fake::bus.pointer[channel] != 0x0E) return 0;  // only ANGLE is modelled
  for (uint8_t i = 0; i < count; ++i) rx_[rx_len_++] = i < 2 ? reg[i] : 0;
  return rx_len_;
}

int TwoWire::read() { return rx_pos_ < rx_len_ ? rx_[rx_pos_++] : -1; }
