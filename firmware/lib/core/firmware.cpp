// Frame dispatch, replies, duplicate suppression and telemetry.
#include "firmware.h"

#include "rig_config.h"  // firmware version

namespace mr {

namespace {

using proto::ErrorCode;

// Physical value -> int16 wire value: times per_unit (1 / the field's scale: a product, not a division, in every
// frame), rounded, saturated; NaN -> 0.
int16_t to_wire_i16(float value, float per_unit) {
  const float raw = value * per_unit;
  if (!(raw == raw)) return 0;
  if (raw >= 32767.0f) return 32767;
  if (raw <= -32768.0f) return -32768;
  return static_cast<int16_t>(raw >= 0.0f ? raw + 0.5f : raw - 0.5f);
}

template <typename Msg>
Msg decoded(const uint8_t* payload) {
  Msg msg;
  proto::decode(payload, msg);
  return msg;
}

}  // namespace

void Firmware::boot(proto::ResetCause cause, bool estop) {
  if (estop) supervisor_.emergency_stop();
  apply_outputs();
  proto::Boot msg{static_cast<uint8_t>(cause)};
  uint8_t payload[proto::Boot::kSize];
  proto::encode(msg, payload);
  send(proto::Boot::kId, payload, sizeof payload);
  last_telemetry_us_ = clock_us_ = hal_.now_us();
  clock_ms_ = clock_us_ / 1000u;
  clock_rest_us_ = static_cast<uint16_t>(clock_us_ % 1000u);
}

uint32_t Firmware::millis(uint32_t now_us) {
  const uint32_t elapsed_us = now_us - clock_us_ + clock_rest_us_;  // unsigned: right across the us wrap
  clock_us_ = now_us;
  clock_ms_ += elapsed_us / 1000u;
  clock_rest_us_ = static_cast<uint16_t>(elapsed_us % 1000u);
  return clock_ms_;
}

void Firmware::rx_byte(uint8_t byte) {
  if (decoder_.push(byte) == FrameDecoder::Result::kFrame) dispatch();
}

void Firmware::poll() {
  const uint32_t now = hal_.now_us();
  millis(now);
  supervisor_.tick(now);
  const uint16_t actuator_faults = hal_.actuator_faults().bits;
  if (actuator_faults & ~supervisor_.faults()) supervisor_.shutdown(actuator_faults);
  apply_outputs();
  const uint32_t period_us = static_cast<uint32_t>(supervisor_.config().telemetry_period) * 1000u;
  if (period_us != 0 && now - last_telemetry_us_ >= period_us) send_telemetry(now);
}

void Firmware::apply_outputs() {
  hal_.actuators_power(supervisor_.actuator_power());
  hal_.actuators_command(supervisor_.output().command);
}

void Firmware::dispatch() {
  const uint8_t id = decoder_.id();
  const uint8_t seq = decoder_.seq();
  const int8_t size = proto::host_to_mcu_size(id);
  if (size < 0) return send_reply(id, seq, ErrorCode::kUnknownMessage, proto::kNoField);
  if (size != decoder_.payload_len()) return send_reply(id, seq, ErrorCode::kBadLength, proto::kNoField);

  if (id == proto::Identify::kId) {
    last_command_.valid = last_position_.valid = false;  // a (re)connected host: its sequence numbers start afresh
    supervisor_.forget_positions();
    return send_identify_reply();
  }
  const bool position = id == proto::ObjectPosition::kId;
  Answered& last = position ? last_position_ : last_command_;
  // A copy of the last command (camera frames may have come since), or of the newest frame when it was a
  // position (after a newer command its telemetry would answer for another state): the same answer, applied once.
  const bool copy =
      last.valid && seq == last.seq && decoder_.crc() == last.crc && id == last.id && (!position || seq == newest_seq_);
  if (copy) return answer_again(last, id, seq);
  const bool any_taken = last_command_.valid || last_position_.valid;
  if (any_taken && static_cast<uint8_t>(newest_seq_ - seq) <= kStaleWindow) {  // wraps: 0 the newest, 1.. older
    return send_reply(id, seq, ErrorCode::kStaleSequence, proto::kNoField);
  }
  const uint32_t now = hal_.now_us();
  uint8_t field = proto::kNoField;
  ErrorCode code = proto::kStateError;  // a state the message is not taken in (schema.toml, its states): nothing runs
  if (proto::taken_in(id, supervisor_.state())) {
    code = position ? supervisor_.position(decoded<proto::ObjectPosition>(decoder_.payload()), now, field)
                    : handle_command(field);
  }
  apply_outputs();
  newest_seq_ = seq;
  last = Answered{true, id, seq, decoder_.crc(), code, field};
  if (position && code == ErrorCode::kOk) return send_telemetry(now);
  send_reply(id, seq, code, field);
}

void Firmware::answer_again(const Answered& last, uint8_t id, uint8_t seq) {
  if (id == proto::ObjectPosition::kId && last.code == ErrorCode::kOk) return send_telemetry(hal_.now_us());
  send_reply(id, seq, last.code, last.field);
}

ErrorCode Firmware::handle_command(uint8_t& field) {
  const uint8_t* payload = decoder_.payload();
  switch (decoder_.id()) {
    case proto::Configure::kId:
      return supervisor_.configure(decoded<proto::Configure>(payload), field);
    case proto::ConfigurePid::kId:
      return supervisor_.configure_pid(decoded<proto::ConfigurePid>(payload), field);
    case proto::ConfigureSchedule::kId:
      return supervisor_.configure_schedule(decoded<proto::ConfigureSchedule>(payload), field);
    case proto::ConfigureCascade::kId:
      return supervisor_.configure_cascade(decoded<proto::ConfigureCascade>(payload), field);
    case proto::SetTarget::kId:
      return supervisor_.set_target(decoded<proto::SetTarget>(payload), field);
    case proto::Start::kId:
      return supervisor_.start(hal_.now_us());
    case proto::Stop::kId:
      supervisor_.stop();
      return ErrorCode::kOk;
    case proto::EmergencyStop::kId:
      supervisor_.emergency_stop();
      return ErrorCode::kOk;
    case proto::Jog::kId:
      return supervisor_.jog(decoded<proto::Jog>(payload), field);
    case proto::Zero::kId: {
      const proto::Zero msg = decoded<proto::Zero>(payload);
      const ErrorCode code = supervisor_.zero(msg, field);
      if (code == ErrorCode::kOk) hal_.actuators_zero(msg.actuators);
      return code;
    }
    case proto::SimClock::kId: {
      const ErrorCode code = hal_.sim_clock_set(decoded<proto::SimClock>(payload).now);
      if (code == ErrorCode::kOk) poll();  // what is due at the new time happens before the ack
      if (code == ErrorCode::kOutOfRange) field = proto::SimClock::kFieldNow;  // it went backwards
      return code;
    }
    default:
      return ErrorCode::kUnknownMessage;
  }
}

void Firmware::send(uint8_t id, const uint8_t* payload, uint8_t len) {
  uint8_t wire[proto::kMaxWire];
  const uint8_t n = frame_encode(id, tx_seq_++, payload, len, wire);
  hal_.serial_write(wire, n);
}

void Firmware::send_reply(uint8_t ref_id, uint8_t ref_seq, ErrorCode code, uint8_t field) {
  if (code == ErrorCode::kOk) {
    const proto::Ack ack{ref_id, ref_seq};
    uint8_t payload[proto::Ack::kSize];
    proto::encode(ack, payload);
    return send(proto::Ack::kId, payload, sizeof payload);
  }
  const proto::Nack nack{ref_id, ref_seq, static_cast<uint8_t>(code), field};
  uint8_t payload[proto::Nack::kSize];
  proto::encode(nack, payload);
  send(proto::Nack::kId, payload, sizeof payload);
}

void Firmware::send_identify_reply() {
  // The rig constants it was built with (protocol/rig.toml), for the host to compare with its own.
  const proto::IdentifyReply reply{proto::kProtocolVersion,
                                   kFirmwareMajor,
                                   kFirmwareMinor,
                                   kFirmwarePatch,
                                   proto::kSchemaHash,
                                   proto::kMaxWire,
                                   static_cast<uint8_t>(hal_.clock_kind()),
                                   kActuatorCount,
                                   kActuatorRangeM,
                                   kEncoderCounts,
                                   kPulleyCircumferenceM,
                                   kActuatorPeriodUs,
                                   kModulesX,
                                   kModulesY,
                                   proto::kBootGainsCrc};
  uint8_t payload[proto::IdentifyReply::kSize];
  proto::encode(reply, payload);
  send(proto::IdentifyReply::kId, payload, sizeof payload);
}

void Firmware::send_telemetry(uint32_t now_us) {
  using T = proto::Telemetry;
  const ControllerOutput& out = supervisor_.output();
  proto::ArrayCommands all{};  // an array's: every actuator's command, sent first (telemetry shows one module's four)
  if (kModuleCount > 1) {
    for (uint8_t i = 0; i < kActuatorCount; ++i) all.command[i] = to_wire_i16(out.command[i], 1.0f / T::kCommandScale);
    uint8_t payload[proto::ArrayCommands::kSize];
    proto::encode(all, payload);
    send(proto::ArrayCommands::kId, payload, sizeof payload);
  }
  float measured[kActuatorCount];
  hal_.actuators_measured(measured);
  T t;
  t.time = millis(now_us);
  t.state = static_cast<uint8_t>(supervisor_.state());
  t.faults = supervisor_.faults();
  t.position_frame = supervisor_.last_frame();
  t.position_age = supervisor_.position_age_ms(now_us);
  t.tilt_zx = to_wire_i16(out.tilt_zx, 1.0f / T::kTiltZxScale);
  t.tilt_zy = to_wire_i16(out.tilt_zy, 1.0f / T::kTiltZyScale);
  t.module = out.module;
  for (uint8_t c = 0; c < kCorners; ++c) {
    const uint8_t i = corner_actuator(t.module, c);
    t.command[c] = kModuleCount > 1 ? all.command[i] : to_wire_i16(out.command[i], 1.0f / T::kCommandScale);
    t.measured[c] = to_wire_i16(measured[i], 1.0f / T::kMeasuredScale);
  }
  t.crc_errors = decoder_.crc_errors();
  t.frame_errors = decoder_.frame_errors();
  const uint32_t overruns = hal_.actuator_overruns();
  t.loop_overruns = overruns > 0xFFFFu ? 0xFFFF : static_cast<uint16_t>(overruns);
  t.fault_actuator = hal_.actuator_faults().actuator;
  uint8_t payload[T::kSize];
  proto::encode(t, payload);
  send(T::kId, payload, sizeof payload);
  last_telemetry_us_ = now_us;
}

}  // namespace mr
