// The Uno board's pin map and the rig's constants, with units and documented defaults (wiring: firmware/README.md).
#pragma once

#include <stdint.h>  // uint8_t, uint32_t

#include "actuator.h"  // ActuatorConfig, kEncoderCounts

namespace mr {
namespace board {

// ---------------------------------------------------------------- motors (one H-bridge channel each)
// Actuator i sits at corner i of PROTOCOL.md §5: 0 (-x,-y), 1 (+x,-y), 2 (-x,+y), 3 (+x,+y).
constexpr uint8_t kPwmPin[4] = {3, 5, 6, 9};         // PWM (timers 2, 0, 0, 1: 490, 976, 976, 490 Hz)
constexpr uint8_t kDirPin[4] = {4, 7, 8, 12};        // direction: HIGH lowers the corner (before kMotorSign)
constexpr int8_t kMotorSign[4] = {1, 1, 1, 1};       // -1 where a motor is wired the other way round
constexpr uint8_t kPwmMax = 255;                     // analogWrite() full scale

// ---------------------------------------------------------------- encoders (AS5600, 12 bit)
enum class EncoderSource : uint8_t { kI2cMux, kAnalog };
// All AS5600 answer at one I2C address, so by default each sits on its own channel of a TCA9548A
// multiplexer (SDA A4, SCL A5). kAnalog reads their OUT pins (analog mode) with the ADC instead.
#ifndef MR_ENCODERS_ANALOG
#define MR_ENCODERS_ANALOG 0  // build flag -DMR_ENCODERS_ANALOG=1 selects the ADC
#endif
constexpr EncoderSource kEncoderSource = MR_ENCODERS_ANALOG ? EncoderSource::kAnalog : EncoderSource::kI2cMux;
constexpr uint8_t kMuxAddress = 0x70;                // TCA9548A with A0..A2 low
constexpr uint8_t kMuxChannel[4] = {0, 1, 2, 3};     // multiplexer channel of each actuator's encoder
constexpr uint8_t kEncoderAddress = 0x36;            // AS5600 (fixed)
constexpr uint8_t kEncoderAngleRegister = 0x0E;      // ANGLE, 12 bits, high byte first
constexpr uint32_t kI2cClockHz = 400000;             // [Hz] AS5600 and TCA9548A both allow fast mode
constexpr uint32_t kI2cTimeoutUs = 1000;             // [us] a bus that hangs longer counts as a failed read
constexpr uint8_t kAnalogPin[4] = {14, 15, 16, 17};  // A0..A3, used only with EncoderSource::kAnalog
constexpr int8_t kEncoderSign[4] = {1, 1, 1, 1};     // -1 where the angle decreases as the corner lowers

// ---------------------------------------------------------------- actuator loops
constexpr float kPulleyCircumferenceM = 0.040f;      // [m/rev] GT2 20-tooth pulley: measure yours
constexpr uint32_t kLoopPeriodUs = 4000;             // [us] 250 Hz position loops
constexpr ActuatorConfig kActuator = {
    kPulleyCircumferenceM / kEncoderCounts,  // metres_per_count [m/count]
    40.0f,                                   // kp [1/m]: full drive beyond 2.5 cm of error
    20.0f,                                   // ki [1/(m s)]
    0.5f,                                    // kd [s/m]
    1.0f,                                    // max_duty [-]
    0.0005f,                                 // deadband_m [m]: 0.5 mm, about 50 encoder counts
    0.25f,                                   // soft_limit_m [m]: the paper's travel
    0.5f,                                    // stall_duty [-]: driving at least half power ...
    0.002f,                                  // stall_travel_m [m]: ... must move 2 mm ...
    0.5f,                                    // stall_time_s [s]: ... within 0.5 s
};

// ---------------------------------------------------------------- bench mode, watchdog, probes
// Pulled low at boot (a jumper to GND, or the AVR simulator's harness): the actuators are external and the
// clock is simulated. The firmware then reports its setpoints as positions and drives no motor, and
// sim_clock sets its time, so a simulated rig can apply the setpoints in lock-step. Left open: the rig.
constexpr uint8_t kBenchPin = 2;
// Probe outputs, high while a piece of work runs, for timing in the AVR simulator or on a scope.
constexpr uint8_t kProbeControllerPin = 13;          // one object_position frame: controller step and reply
constexpr uint8_t kProbeActuatorPin = 10;            // one run of the four actuator loops
constexpr uint8_t kProbeLoopPin = 11;                // toggles once per main-loop pass

}  // namespace board
}  // namespace mr
