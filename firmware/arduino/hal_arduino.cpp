// The Uno's HAL: micros() clock, the serial TX buffer, and the four actuator loops (or, in bench mode, none).
#include <Arduino.h>  // micros(), Serial, pinMode, digitalRead

#include "actuators.h"        // ActuatorBank
#include "board.h"            // this board's entry points (setup and loop)
#include "board_config.h"     // kActuator, kBenchPin (board_gen.h), kActuatorPeriodUs (rig_gen.h)
#include "hal.h"              // the interface implemented here
#include "ideal_actuators.h"  // IdealActuators, SimulatedClock: bench mode
#include "actuator_io.h"      // ArduinoActuatorIo

namespace mr {
namespace board {

namespace {

board::ArduinoActuatorIo g_io;
board::Probe g_probe_actuators;  // high while the four loops run
ActuatorBank g_bank(g_io, board::kActuator, kActuatorPeriodUs);
bool g_bench = false;        // bench mode: external actuators (setpoints reported back), simulated clock
IdealActuators g_external;   // bench mode's actuators
SimulatedClock g_sim_clock;  // bench mode's clock

// The one HAL of this board: micros() or the bench mode's simulated clock, Serial, the actuator bank.
class ArduinoHal final : public Hal {
 public:
  // micros() has a 4 us resolution at 16 MHz and wraps like the HAL's clock (2^32 us).
  uint32_t now_us() const override { return g_bench ? g_sim_clock.now_us() : micros(); }

  // A frame goes out only if the whole of it fits in the serial TX buffer (SERIAL_TX_BUFFER_SIZE bytes);
  // otherwise it is dropped, never waited for: a blocking write would stall the control loop.
  void serial_write(const uint8_t* data, uint8_t len) override {
    if (Serial.availableForWrite() < len) return;
    Serial.write(data, len);
  }

  void actuators_command(const float (&command)[kActuatorCount]) override {
    if (g_bench) return g_external.command(command);
    g_bank.set_setpoints(command);
  }

  void actuators_measured(float (&measured)[kActuatorCount]) const override {
    if (g_bench) return g_external.measured(measured);
    g_bank.measured(measured);
  }

  void actuators_power(bool on) override {
    if (g_bench) return g_external.power(on);
    g_bank.power(on);
  }

  void actuators_zero(uint16_t mask) override {
    if (g_bench) return g_external.zero(mask);
    g_bank.zero(mask);
  }

  ActuatorFaults actuator_faults() const override {
    return g_bench ? ActuatorFaults{0, kNoActuator} : ActuatorFaults{g_bank.faults(), g_bank.fault_actuator()};
  }
  uint32_t actuator_overruns() const override { return g_bank.overruns(); }

  proto::Clock clock_kind() const override { return g_bench ? proto::Clock::kSimulated : proto::Clock::kWall; }

  proto::ErrorCode sim_clock_set(uint32_t t_us) override {
    if (!g_bench) return proto::ErrorCode::kUnsupported;
    return g_sim_clock.set(t_us);
  }
};

ArduinoHal g_hal;

}  // namespace

bool begin() {
  pinMode(kBenchPin, INPUT_PULLUP);
  g_bench = digitalRead(kBenchPin) == LOW;
  g_probe_actuators.begin(kProbeActuatorPin);
  if (!g_bench) {
    g_io.begin();
    g_bank.begin(micros());
  }
  return g_bench;
}

void actuators_tick() {
  const uint32_t now = micros();
  if (g_bench || !g_bank.due(now)) return;
  g_probe_actuators.high();
  g_bank.tick(now);
  g_probe_actuators.low();
}

Hal& hal() { return g_hal; }

}  // namespace board
}  // namespace mr
