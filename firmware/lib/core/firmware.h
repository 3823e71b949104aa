// The firmware's top level: bytes in -> frames -> supervisor -> replies and telemetry out; the same on every board.
//
// Scheduling contract (each board's main loop): call rx_byte() for every received byte as it arrives
// and poll() on every pass; neither blocks. poll() runs the deadman, sends periodic telemetry and hands
// the actuator setpoints to the HAL.
#pragma once

#include <stdint.h>  // uint8_t..uint32_t

#include "frame.h"         // FrameDecoder
#include "hal.h"           // Hal
#include "protocol_gen.h"  // proto messages
#include "supervisor.h"    // Supervisor

namespace mr {

class Firmware {
 public:
  // The board it runs on: every clock reading, byte out and actuator command goes through it.
  explicit Firmware(Hal& hal) : hal_(hal) {}

  // Announces the start to the host (boot message) and levels the surface. estop: the board kept an emergency stop
  // latched across its reset; it holds (actuator power cut) until the host's stop, as one sent now would.
  void boot(proto::ResetCause cause, bool estop = false);
  void rx_byte(uint8_t byte);
  void poll();

  const Supervisor& supervisor() const { return supervisor_; }

 private:
  void dispatch();
  proto::ErrorCode handle_command(uint8_t& field);
  void send(uint8_t id, const uint8_t* payload, uint8_t len);
  void send_reply(uint8_t ref_id, uint8_t ref_seq, proto::ErrorCode code, uint8_t field);
  void send_identify_reply();
  void send_telemetry(uint32_t now_us);
  void apply_outputs();
  // The telemetry's clock [ms]: the microsecond clock's elapsed time accumulated, so it wraps at 2^32 ms
  // (49.7 days), not with the microseconds (71.6 min); needs a call at least every 71 min (poll makes one).
  uint32_t millis(uint32_t now_us);

  Hal& hal_;
  FrameDecoder decoder_;
  Supervisor supervisor_;
  uint8_t tx_seq_ = 0;
  uint32_t last_telemetry_us_ = 0;
  uint32_t clock_us_ = 0;       // [us] firmware clock at the last millis()
  uint32_t clock_ms_ = 0;       // [ms] accumulated
  uint16_t clock_rest_us_ = 0;  // [us] below a millisecond, carried
  // What a frame was answered with, to answer a copy of it again without applying it twice.
  struct Answered {
    bool valid;
    uint8_t id, seq;
    uint16_t crc;
    proto::ErrorCode code;
    uint8_t field;
  };
  void answer_again(const Answered& last, uint8_t id, uint8_t seq);
  // Order (PROTOCOL.md section 3): a copy of the last command or of the last position is answered again; any
  // other frame 0..kStaleWindow sequence numbers behind the newest one taken is a late copy: refused as stale.
  static constexpr uint8_t kStaleWindow = 64;
  uint8_t newest_seq_ = 0;  // of the newest frame taken (the last command's or the last position's)
  Answered last_command_ = {false, 0, 0, 0, proto::ErrorCode::kOk, proto::kNoField};
  Answered last_position_ = {false, 0, 0, 0, proto::ErrorCode::kOk, proto::kNoField};
};

}  // namespace mr
