// Uno actuator I/O: analogWrite/digitalWrite for the H-bridges, Wire for the multiplexed encoders.
#include "actuator_io.h"

#include <Arduino.h>  // pinMode, digitalWrite, analogWrite, analogRead
#include <Wire.h>     // TwoWire: the TCA9548A and the AS5600s

#include "board_config.h"  // pins, addresses, signs

namespace mr {
namespace board {

namespace {

constexpr uint16_t kAdcFullScale = 1023;  // 10-bit ADC

void all_pwm_off() {
  for (uint8_t i = 0; i < kActuatorCount; ++i) analogWrite(kPwmPin[i], 0);
}

bool write_mux(uint8_t address, uint8_t channels) {
  Wire.beginTransmission(address);
  Wire.write(channels);
  return Wire.endTransmission() == 0;
}

// Connects actuator i's encoder to the bus alone: its multiplexer's channel, and (with more than one multiplexer)
// none of the other's, as every AS5600 answers at the one address.
bool select_encoder(uint8_t actuator) {
  static uint8_t connected = 0;  // the multiplexer left with a channel on; 0: none known
  const uint8_t address = mux_address(actuator);
  if (kMuxAddressCount > 1 && connected != 0 && connected != address && !write_mux(connected, 0)) return false;
  connected = address;
  return write_mux(address, static_cast<uint8_t>(1u << kMuxChannel[actuator]));
}

bool read_as5600(uint16_t& raw) {
  Wire.beginTransmission(kEncoderAddress);
  Wire.write(kEncoderAngleRegister);
  if (Wire.endTransmission(false) != 0) return false;  // repeated start: the register pointer stays
  if (Wire.requestFrom(kEncoderAddress, static_cast<uint8_t>(2)) != 2) return false;
  const uint8_t high = static_cast<uint8_t>(Wire.read());
  const uint8_t low = static_cast<uint8_t>(Wire.read());
  raw = static_cast<uint16_t>(((high & 0x0Fu) << 8) | low);
  return true;
}

}  // namespace

void ArduinoActuatorIo::begin() {
  for (uint8_t i = 0; i < kActuatorCount; ++i) {
    pinMode(kPwmPin[i], OUTPUT);
    pinMode(kDirPin[i], OUTPUT);
  }
  motors_off();
  if (kEncoderSource == EncoderSource::kI2cMux) {
    Wire.begin();
    Wire.setClock(kI2cClockHz);
    Wire.setWireTimeout(kI2cTimeoutUs, true);
    if (kMuxAddressCount > 1) {  // a reset that kept power left a channel on: two encoders would answer at once
      for (uint8_t i = 0; i < kActuatorCount; ++i) write_mux(mux_address(i), 0);
    }
  }
}

bool ArduinoActuatorIo::encoder_read(uint8_t actuator, uint16_t& raw) {
  uint16_t angle = 0;
  if (kEncoderSource == EncoderSource::kAnalog) {
    angle = static_cast<uint16_t>(static_cast<uint32_t>(analogRead(kAnalogPin[actuator])) * (kEncoderCounts - 1) /
                                  kAdcFullScale);
  } else if (!select_encoder(actuator) || !read_as5600(angle)) {
    return false;
  }
  raw = kEncoderSign[actuator] > 0 ? angle : static_cast<uint16_t>((kEncoderCounts - angle) % kEncoderCounts);
  return true;
}

void ArduinoActuatorIo::motor_write(uint8_t actuator, float duty) {
  duty *= kMotorSign[actuator];
  digitalWrite(kDirPin[actuator], duty >= 0.0f ? HIGH : LOW);
  const float magnitude = duty >= 0.0f ? duty : -duty;
  analogWrite(kPwmPin[actuator], static_cast<int>(magnitude * kPwmMax + 0.5f));
}

void ArduinoActuatorIo::motors_off() { all_pwm_off(); }

void on_watchdog_timeout(ResetMark& survives) {
  all_pwm_off();
  survives.set(kWatchdogMark);
}

proto::ResetCause reset_cause(uint8_t mcusr, ResetMark& survives) {
  const bool marked = survives.holds(kWatchdogMark);
  survives.clear();
  if (mcusr & (1u << 0)) return proto::ResetCause::kPowerOn;               // PORF
  if (marked || (mcusr & (1u << 3))) return proto::ResetCause::kWatchdog;  // WDRF
  if (mcusr & (1u << 2)) return proto::ResetCause::kBrownOut;              // BORF
  if (mcusr & (1u << 1)) return proto::ResetCause::kExternal;              // EXTRF
  return proto::ResetCause::kUnknown;
}

void keep_estop(ResetMark& survives, bool latched) {
  if (latched) {
    survives.set(kEstopMark);
  } else {
    survives.clear();
  }
}

bool estop_survived(uint8_t mcusr, const ResetMark& survives) {
  return !(mcusr & (1u << 0)) && survives.holds(kEstopMark);  // PORF: RAM is random after a power-on
}

void Probe::begin(uint8_t pin) {
  pinMode(pin, OUTPUT);
  port = portOutputRegister(digitalPinToPort(pin));
  mask = digitalPinToBitMask(pin);
}

}  // namespace board
}  // namespace mr
