// A host stand-in for the Arduino Wire (I2C master) API, backed by fake::I2cBus devices in the board tests.
#pragma once

#include <stddef.h>  // size_t
#include <stdint.h>  // uint8_t..uint32_t

namespace fake {

// What answers on the bus: a TCA9548A multiplexer and an AS5600 behind each of its channels.
struct I2cBus {
  uint8_t mux_address = 0x70;
  uint8_t encoder_address = 0x36;
  uint8_t selected = 0;     // channel mask last written to the multiplexer
  uint16_t angle[8] = {};   // each channel's AS5600 ANGLE register, 12 bits
  bool silent[8] = {};      // an encoder that does not answer (NACK)
  uint8_t pointer[8] = {};  // each AS5600's register pointer
  unsigned long transactions = 0;
};

extern I2cBus bus;

}  // namespace fake

class TwoWire {
 public:
  void begin() {}
  void setClock(uint32_t) {}
  void setWireTimeout(uint32_t, bool) {}
  void beginTransmission(uint8_t address);
  size_t write(uint8_t byte);
  uint8_t endTransmission(bool stop = true);
  uint8_t requestFrom(uint8_t address, uint8_t count);
  int read();

 private:
  uint8_t address_ = 0;
  uint8_t written_[4] = {};
  uint8_t n_written_ = 0;
  uint8_t rx_[4] = {};
  uint8_t rx_len_ = 0;
  uint8_t rx_pos_ = 0;
};

extern TwoWire Wire;
