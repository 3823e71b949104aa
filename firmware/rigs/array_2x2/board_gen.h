// The mega2560's pin map and bus addresses (wiring: firmware/README.md). Generated from protocol/rigs/array_2x2.toml by protocol/generate.py; do not edit.
#pragma once

#include <stdint.h>  // uint8_t, int8_t, uint32_t

namespace mr {
namespace board {

constexpr uint8_t kPwmPin[9] = {2, 3, 5, 6, 7, 8, 44, 45, 46};  // Each actuator's H-bridge PWM input: a PWM pin of the board's (protocol/boards.py).
constexpr uint8_t kDirPin[9] = {22, 23, 24, 25, 26, 27, 28, 29, 30};  // Each H-bridge's direction input: HIGH lowers the corner (before motor_sign).
constexpr int8_t kMotorSign[9] = {1, 1, 1, 1, 1, 1, 1, 1, 1};  // -1 where a motor is wired the other way round.
constexpr uint8_t kPwmMax = 255;  // analogWrite() full scale.
constexpr uint8_t kMuxAddress[9] = {0x70, 0x70, 0x70, 0x70, 0x70, 0x70, 0x70, 0x70, 0x71};  // TCA9548A I2C multiplexer with A0..A2 low: every AS5600 answers at one address, so each sits on its own channel. One address for all encoders, or one per actuator where more than eight need a second multiplexer.
constexpr uint8_t mux_address(uint8_t actuator) { return kMuxAddress[actuator]; }
constexpr uint8_t kMuxAddressCount = 2;  // distinct values
constexpr uint8_t kMuxChannel[9] = {0, 1, 2, 3, 4, 5, 6, 7, 0};  // Multiplexer channel of each actuator's encoder.
constexpr uint8_t kEncoderAddress = 0x36;  // AS5600's I2C address (fixed).
constexpr uint8_t kEncoderAngleRegister = 0x0E;  // AS5600's ANGLE register: 12 bits, high byte first.
constexpr uint32_t kI2cClockHz = 400000;  // [Hz] I2C clock: AS5600 and TCA9548A both allow fast mode.
constexpr uint32_t kI2cTimeoutUs = 1000;  // [us] A bus that hangs longer counts as a failed read.
constexpr uint8_t kAnalogPin[9] = {54, 55, 56, 57, 58, 59, 60, 61, 62};  // The encoders' OUT pins on analog inputs, read only when built with -DMR_ENCODERS_ANALOG=1.
constexpr int8_t kEncoderSign[9] = {1, 1, 1, 1, 1, 1, 1, 1, 1};  // -1 where the angle decreases as the corner lowers.
constexpr uint8_t kBenchPin = 31;  // Pulled low at boot (a jumper to GND, or the AVR simulator's harness): the actuators are external and the clock simulated; left open: the rig.
constexpr uint8_t kProbeControllerPin = 32;  // High while a received byte is handled (the byte that completes an object_position frame runs the controller).
constexpr uint8_t kProbeActuatorPin = 33;  // High while the actuator loops run.
constexpr uint8_t kProbeLoopPin = 34;  // Toggles once per main-loop pass.

}  // namespace board
}  // namespace mr
