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

  // Announces the start to the host (boot message) and levels the surface.
  void boot(proto::ResetCause cause);
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
  uint32_t clock_us_ = 0;      // [us] firmware clock at the last millis()
  uint32_t clock_ms_ = 0;      // [ms] accumulated
  uint16_t clock_rest_us_ = 0; // [us] below a millisecond, carried
  // The last command answered, to answer a retransmission again without applying it twice.
  bool has_last_ = false;
  uint8_t last_id_ = 0;
  uint8_t last_seq_ = 0;
  uint16_t last_crc_ = 0;
  proto::ErrorCode last_code_ = proto::ErrorCode::kOk;
  uint8_t last_field_ = proto::kNoField;
};

}  // namespace mr
