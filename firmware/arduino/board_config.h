// The Uno board's settings: encoder source, the actuator loops' gains and limits (its pins: board_gen.h).
#pragma once

#include <stdint.h>  // uint8_t, uint32_t

#include "actuator.h"   // ActuatorConfig
#include "board_gen.h"  // pin map, signs, bus addresses (protocol/rig.toml)
#include "rig_gen.h"    // kPulleyCircumferenceM, kEncoderCounts, kActuatorPeriodUs (protocol/rig.toml)

namespace mr {
namespace board {

// Pins, signs and bus addresses are in board_gen.h, written from protocol/rig.toml (edit that, then run
// python3 protocol/generate.py). Actuator i sits at corner i of PROTOCOL.md §5: 0 (-x,-y), 1 (+x,-y), 2 (-x,+y), 3
// (+x,+y).

// ---------------------------------------------------------------- encoders (AS5600, 12 bit)
enum class EncoderSource : uint8_t { kI2cMux, kAnalog };
// All AS5600 answer at one I2C address, so by default each sits on its own channel of a TCA9548A
// multiplexer (SDA A4, SCL A5). kAnalog reads their OUT pins (analog mode) with the ADC instead.
#ifndef MR_ENCODERS_ANALOG
#define MR_ENCODERS_ANALOG 0  // build flag -DMR_ENCODERS_ANALOG=1 selects the ADC
#endif
constexpr EncoderSource kEncoderSource = MR_ENCODERS_ANALOG ? EncoderSource::kAnalog : EncoderSource::kI2cMux;

// ---------------------------------------------------------------- actuator loops
constexpr ActuatorConfig kActuator = {
    kPulleyCircumferenceM / kEncoderCounts,  // metres_per_count [m/count]
    40.0f,                                   // kp [1/m]: full drive beyond 2.5 cm of error
    20.0f,                                   // ki [1/(m s)]
    0.5f,                                    // kd [s/m]
    1.0f,                                    // max_duty [-]
    0.0005f,                                 // deadband_m [m]: 0.5 mm, about 50 encoder counts
    kActuatorRangeM,                         // soft_limit_m [m]: the actuator range
    0.5f,                                    // stall_duty [-]: driving at least half power ...
    0.002f,                                  // stall_travel_m [m]: ... must move 2 mm ...
    0.5f,                                    // stall_time_s [s]: ... within 0.5 s
};

}  // namespace board
}  // namespace mr
