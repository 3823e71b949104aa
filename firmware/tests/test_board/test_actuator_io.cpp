// The Uno's actuator stack on the host: the board I/O (actuator_io.cpp) and the core's loops against modelled motors.
#include <doctest/doctest.h>

#include <math.h>  // fabs

#include "Arduino.h"
#include "Wire.h"
#include "actuators.h"
#include "board_config.h"
#include "protocol_gen.h"
#include "actuator_io.h"

namespace {

using mr::ActuatorBank;
using mr::board::kActuator;

// A geared DC motor on an H-bridge turning an AS5600's magnet: speed follows the PWM with a time constant.
struct Rig {
  static constexpr float kTopSpeedRevPerS = 2.0f;  // [rev/s] 120 rev/min at full drive
  static constexpr float kTimeConstantS = 0.03f;   // [s]
  float angle_rev[4] = {};                         // shaft angle [rev] since the start
  float speed_rev_per_s[4] = {};
  bool blocked[4] = {};
  uint16_t offset_counts[4] = {};  // encoder reading at angle 0

  explicit Rig(uint16_t offset = 1000) {
    fake::reset();
    for (int i = 0; i < 4; ++i) offset_counts[i] = static_cast<uint16_t>(offset + 700 * i);
    publish();
  }

  float duty(int i) const {
    const int pwm = fake::pins.pwm[mr::board::kPwmPin[i]];
    const float sign = fake::pins.digital[mr::board::kDirPin[i]] == HIGH ? 1.0f : -1.0f;
    return sign * static_cast<float>(pwm) / mr::board::kPwmMax;
  }

  void publish() {
    for (int i = 0; i < 4; ++i) {
      const float counts = angle_rev[i] * mr::kEncoderCounts + offset_counts[i];
      long wrapped = static_cast<long>(floorf(counts)) % mr::kEncoderCounts;
      if (wrapped < 0) wrapped += mr::kEncoderCounts;
      fake::bus.angle[mr::board::kMuxChannel[i]] = static_cast<uint16_t>(wrapped);
      fake::pins.analog_in[mr::board::kAnalogPin[i]] = static_cast<int>(wrapped * 1023 / (mr::kEncoderCounts - 1));
    }
  }

  void advance(float dt_s) {
    for (int i = 0; i < 4; ++i) {
      const float target = blocked[i] ? 0.0f : duty(i) * kTopSpeedRevPerS;
      speed_rev_per_s[i] += (target - speed_rev_per_s[i]) * dt_s / kTimeConstantS;
      angle_rev[i] += speed_rev_per_s[i] * dt_s;
    }
    publish();
  }

  float position_m(int i) const { return angle_rev[i] * mr::kPulleyCircumferenceM; }
  bool all_pwm_zero() const {
    for (int i = 0; i < 4; ++i) {
      if (fake::pins.pwm[mr::board::kPwmPin[i]] != 0) return false;
    }
    return true;
  }
};

// How far the measured position may trail the shaft: two counts, or one ADC step (4 counts) read in analog mode.
const float kReadingTolM =
    (mr::board::kEncoderSource == mr::board::EncoderSource::kAnalog ? 5 : 2) * kActuator.metres_per_count + 1e-6f;

struct Stack {
  Rig rig;
  mr::board::ArduinoActuatorIo io;
  ActuatorBank bank{io, kActuator, mr::kActuatorPeriodUs};

  explicit Stack(uint16_t offset = 1000) : rig(offset) {
    io.begin();
    bank.begin(fake::now_us);
  }
  // Runs the main loop for s seconds in 250 us passes, the motors following the PWM.
  void run(float s) {
    const uint32_t end = fake::now_us + static_cast<uint32_t>(s * 1e6f);
    while (fake::now_us < end) {
      bank.tick(fake::now_us);
      rig.advance(250e-6f);
      fake::now_us += 250;
    }
  }
  // Sends the carriages toward +-0.2 m and runs 0.2 s: the motors are driven.
  void drive_away() {
    const float setpoints[4] = {0.2f, -0.2f, 0.2f, -0.2f};
    bank.set_setpoints(setpoints);
    run(0.2f);
    CHECK_FALSE(rig.all_pwm_zero());
  }
  float measured(int i) const {
    float m[4];
    bank.measured(m);
    return m[i];
  }
};

}  // namespace

TEST_CASE("the loops bring every carriage to its setpoint and hold it within the deadband") {
  Stack s;
  const float setpoints[4] = {0.1f, -0.05f, 0.2f, -0.15f};
  s.bank.set_setpoints(setpoints);
  s.run(4.0f);
  for (int i = 0; i < 4; ++i) {
    CHECK(fabs(s.rig.position_m(i) - setpoints[i]) < 0.002f);
    CHECK(fabs(s.measured(i) - s.rig.position_m(i)) < kReadingTolM);
  }
  CHECK(s.bank.faults() == 0);
  CHECK(s.bank.overruns() == 0);
}

TEST_CASE("a positive duty lowers the corner: DIR high, encoder counting up, measured position positive") {
  Stack s;
  const float down[4] = {0.05f, 0.0f, 0.0f, 0.0f};
  s.bank.set_setpoints(down);
  s.run(0.05f);
  CHECK(fake::pins.digital[mr::board::kDirPin[0]] == HIGH);
  CHECK(fake::pins.pwm[mr::board::kPwmPin[0]] > 0);
  s.run(2.0f);
  CHECK(s.measured(0) > 0.045f);
}

TEST_CASE("unwrapping stays right over many turns, across the wrap point, both ways") {
  Stack s(4090);                                        // the encoder starts six counts below its wrap
  const float far[4] = {0.24f, -0.24f, 0.24f, -0.24f};  // 6 turns of the 0.04 m pulley each way
  s.bank.set_setpoints(far);
  s.run(8.0f);
  for (int i = 0; i < 4; ++i) {
    CHECK(fabs(s.rig.angle_rev[i]) > 5.5f);
    CHECK(fabs(s.measured(i) - s.rig.position_m(i)) < kReadingTolM);
  }
  const float home[4] = {};
  s.bank.set_setpoints(home);
  s.run(8.0f);
  for (int i = 0; i < 4; ++i) CHECK(fabs(s.rig.position_m(i)) < 0.002f);
}

TEST_CASE("EncoderUnwrap: every step under half a turn is counted exactly, wherever the wrap falls") {
  mr::EncoderUnwrap u;
  u.reset(4095);
  long expected = 0;
  uint16_t raw = 4095;
  const int steps[] = {1, -1, -2, 3, 2047, -2047, 1500, 1500, 1500, -800, 5, -4000 % 2048};
  for (int round = 0; round < 200; ++round) {
    for (int step : steps) {
      raw = static_cast<uint16_t>((raw + step + 4096) % 4096);
      expected += step;
      CHECK(u.update(raw) == expected);
    }
  }
}

TEST_CASE("a blocked carriage is a stall: fault latched and every PWM at zero") {
  Stack s;
  s.rig.blocked[2] = true;
  const float setpoints[4] = {0.05f, 0.05f, 0.05f, 0.05f};
  s.bank.set_setpoints(setpoints);
  s.run(kActuator.stall_time_s * 0.5f);
  CHECK(s.bank.faults() == 0);
  s.run(kActuator.stall_time_s);
  CHECK((s.bank.faults() & mr::proto::faults::kStall) != 0);
  CHECK(s.rig.all_pwm_zero());
  s.run(0.5f);
  CHECK(s.rig.all_pwm_zero());
}

// An ADC always answers: only an I2C encoder can fall silent.
TEST_CASE("a silent encoder is an encoder fault after three missed readings, and cuts every motor" *
          doctest::skip(mr::board::kEncoderSource == mr::board::EncoderSource::kAnalog)) {
  Stack s;
  const float setpoints[4] = {0.05f, 0.05f, 0.05f, 0.05f};
  s.bank.set_setpoints(setpoints);
  s.run(0.1f);
  fake::bus.silent[mr::board::kMuxChannel[1]] = true;
  int periods = 0;
  while (s.bank.faults() == 0 && periods < 10) {
    s.run(1e-6f * mr::kActuatorPeriodUs);  // one loop run per period
    ++periods;
  }
  CHECK(periods == ActuatorBank::kReadFailuresForFault);
  CHECK((s.bank.faults() & mr::proto::faults::kEncoder) != 0);
  CHECK(s.rig.all_pwm_zero());
}

TEST_CASE("the emergency-stop path (power off) zeroes every PWM at once and keeps them there") {
  Stack s;
  s.drive_away();
  s.bank.power(false);
  CHECK(s.rig.all_pwm_zero());  // before any further loop run
  s.run(1.0f);
  CHECK(s.rig.all_pwm_zero());
  s.bank.power(true);
  s.run(0.1f);
  CHECK_FALSE(s.rig.all_pwm_zero());
}

TEST_CASE("the watchdog interrupt's path zeroes every PWM and marks the reset it precedes") {
  Stack s;
  s.drive_away();
  mr::board::ResetMark survives{0x1234, 0x0000};  // whatever RAM held
  mr::board::on_watchdog_timeout(survives);
  CHECK(s.rig.all_pwm_zero());
  // the stock bootloader clears MCUSR: the mark alone says watchdog, once
  CHECK(mr::board::reset_cause(0, survives) == mr::proto::ResetCause::kWatchdog);
  CHECK(mr::board::reset_cause(0, survives) == mr::proto::ResetCause::kUnknown);
}

TEST_CASE("the reset cause: power-on first, then the watchdog, brown-out and external") {
  using mr::proto::ResetCause;
  mr::board::ResetMark none{0, 0};
  CHECK(mr::board::reset_cause(0x01 | 0x04, none) == ResetCause::kPowerOn);  // a power-on ramp trips BOR too
  CHECK(mr::board::reset_cause(0x08, none) == ResetCause::kWatchdog);
  CHECK(mr::board::reset_cause(0x04, none) == ResetCause::kBrownOut);
  CHECK(mr::board::reset_cause(0x02, none) == ResetCause::kExternal);
  mr::board::ResetMark marked{mr::board::kWatchdogMark, static_cast<uint16_t>(~mr::board::kWatchdogMark)};
  CHECK(mr::board::reset_cause(0x01, marked) == ResetCause::kPowerOn);  // RAM is random at power-on
  mr::board::ResetMark half{mr::board::kWatchdogMark, 0};               // the mark without its complement
  CHECK(mr::board::reset_cause(0x02, half) == ResetCause::kExternal);
}

TEST_CASE("the emergency stop's mark survives every reset but a power-on, and only while latched") {
  mr::board::ResetMark survives{0x1234, 0x0000};  // whatever RAM held
  CHECK_FALSE(mr::board::estop_survived(0, survives));
  mr::board::keep_estop(survives, true);
  CHECK(mr::board::estop_survived(0x02, survives));        // reset pin, or the host opening the port
  CHECK(mr::board::estop_survived(0x08, survives));        // watchdog
  CHECK(mr::board::estop_survived(0x04, survives));        // brown-out
  CHECK(mr::board::estop_survived(0, survives));           // behind the stock bootloader, which clears MCUSR
  CHECK_FALSE(mr::board::estop_survived(0x01, survives));  // power-on: RAM is random
  mr::board::keep_estop(survives, false);                  // the host's stop cleared it
  CHECK_FALSE(mr::board::estop_survived(0x02, survives));
  mr::board::ResetMark watchdog{0, 0};
  mr::board::on_watchdog_timeout(watchdog);
  CHECK_FALSE(mr::board::estop_survived(0x08, watchdog));  // the watchdog's mark is not the emergency stop's
}

TEST_CASE("soft limits: a setpoint beyond the travel stops the carriage at the limit") {
  Stack s;
  const float beyond[4] = {0.4f, -0.4f, 0.3f, -0.3f};
  s.bank.set_setpoints(beyond);
  s.run(6.0f);
  for (int i = 0; i < 4; ++i) CHECK(fabs(s.rig.position_m(i)) < kActuator.soft_limit_m + 0.003f);
  CHECK(s.bank.faults() == 0);
}

TEST_CASE("zeroing: the masked actuators' present positions become 0 m") {
  Stack s;
  const float setpoints[4] = {0.1f, 0.1f, 0.1f, 0.1f};
  s.bank.set_setpoints(setpoints);
  s.run(3.0f);
  s.bank.zero(0b0101);
  CHECK(fabs(s.measured(0)) < 1e-6f);
  CHECK(fabs(s.measured(2)) < 1e-6f);
  CHECK(s.measured(1) > 0.09f);
}
