// Test vectors from protocol/vectors.json. Generated from protocol/schema.toml by protocol/generate.py; do not edit.
#pragma once

#include <stdint.h>  // uint8_t

#include "protocol_gen.h"  // message structs and decode()

namespace vectors {

enum class Yield : uint8_t { kFrame, kCrcError, kFrameError };

struct Expected {
  Yield yield;
  uint8_t id, seq;
  const uint8_t* payload;
  uint8_t payload_len;
  bool (*fields_ok)(const uint8_t* payload);  // null when the vector names no fields
};

struct Vector {
  const char* name;
  const uint8_t* wire;
  uint16_t wire_len;
  const Expected* expected;
  uint8_t expected_len;
};

// identify, seq 1
const uint8_t wire_0[] = {0x05, 0x01, 0x01, 0x1F, 0x3E, 0x00};
const uint8_t payload_0_0[] = {0};
inline bool fields_ok_0_0(const uint8_t* p) {
  mr::proto::Identify m;
  mr::proto::decode(p, m);
  return true;
}
const Expected expected_0[] = {{Yield::kFrame, 0x01, 1, payload_0_0, 0, fields_ok_0_0}};

// configure, the paper's defaults
const uint8_t wire_1[] = {0x03, 0x02, 0x02, 0x01, 0x01, 0x01, 0x02, 0x3F, 0x01, 0x01, 0x0A, 0x3F, 0x39, 0x85, 0xD4, 0x41, 0x0A, 0xD7, 0xA3, 0x3C, 0x01, 0x01, 0x01, 0x02, 0x01, 0x01, 0x01, 0x04, 0xF4, 0x01, 0x64, 0x07, 0xCD, 0xCC, 0x4C, 0x3D, 0x69, 0xBD, 0x00};
const uint8_t payload_1_0[] = {0x00, 0x00, 0x00, 0x00, 0x3F, 0x00, 0x00, 0x00, 0x3F, 0x39, 0x85, 0xD4, 0x41, 0x0A, 0xD7, 0xA3, 0x3C, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0xF4, 0x01, 0x64, 0x00, 0xCD, 0xCC, 0x4C, 0x3D};
inline bool fields_ok_1_0(const uint8_t* p) {
  mr::proto::Configure m;
  mr::proto::decode(p, m);
  return m.controller == 0u &&
         m.module_x == 0.5f &&
         m.module_y == 0.5f &&
         m.tilt_limit == 26.56505012512207f &&
         m.tolerance == 0.019999999552965164f &&
         m.noise_amplitude == 0.0f &&
         m.noise_seed == 1u &&
         m.deadman == 500u &&
         m.telemetry_period == 100u &&
         m.velocity_filter == 0.05000000074505806f;
}
const Expected expected_1[] = {{Yield::kFrame, 0x02, 2, payload_1_0, 33, fields_ok_1_0}};

// configure, euclidean with noise
const uint8_t wire_2[] = {0x04, 0x02, 0x03, 0x01, 0x01, 0x03, 0x40, 0x3F, 0x01, 0x01, 0x02, 0x3F, 0x01, 0x10, 0xA0, 0x41, 0x0A, 0xD7, 0x23, 0x3C, 0xCD, 0xCC, 0x4C, 0x3D, 0xEF, 0xBE, 0xAD, 0xDE, 0xFA, 0x01, 0x01, 0x07, 0xCD, 0xCC, 0x4C, 0x3D, 0x33, 0x50, 0x00};
const uint8_t payload_2_0[] = {0x01, 0x00, 0x00, 0x40, 0x3F, 0x00, 0x00, 0x00, 0x3F, 0x00, 0x00, 0xA0, 0x41, 0x0A, 0xD7, 0x23, 0x3C, 0xCD, 0xCC, 0x4C, 0x3D, 0xEF, 0xBE, 0xAD, 0xDE, 0xFA, 0x00, 0x00, 0x00, 0xCD, 0xCC, 0x4C, 0x3D};
inline bool fields_ok_2_0(const uint8_t* p) {
  mr::proto::Configure m;
  mr::proto::decode(p, m);
  return m.controller == 1u &&
         m.module_x == 0.75f &&
         m.module_y == 0.5f &&
         m.tilt_limit == 20.0f &&
         m.tolerance == 0.009999999776482582f &&
         m.noise_amplitude == 0.05000000074505806f &&
         m.noise_seed == 3735928559u &&
         m.deadman == 250u &&
         m.telemetry_period == 0u &&
         m.velocity_filter == 0.05000000074505806f;
}
const Expected expected_2[] = {{Yield::kFrame, 0x02, 3, payload_2_0, 33, fields_ok_2_0}};

// configure_pid x, paper gains
const uint8_t wire_3[] = {0x03, 0x03, 0x04, 0x13, 0x33, 0x33, 0xF7, 0x41, 0x71, 0x3D, 0xD6, 0x41, 0x33, 0x33, 0x77, 0x41, 0x39, 0x85, 0xD4, 0x41, 0xED, 0xE5, 0x00};
const uint8_t payload_3_0[] = {0x00, 0x33, 0x33, 0xF7, 0x41, 0x71, 0x3D, 0xD6, 0x41, 0x33, 0x33, 0x77, 0x41, 0x39, 0x85, 0xD4, 0x41};
inline bool fields_ok_3_0(const uint8_t* p) {
  mr::proto::ConfigurePid m;
  mr::proto::decode(p, m);
  return m.axis == 0u &&
         m.kp == 30.899999618530273f &&
         m.ki == 26.780000686645508f &&
         m.kd == 15.449999809265137f &&
         m.integral_limit == 26.56505012512207f;
}
const Expected expected_3[] = {{Yield::kFrame, 0x03, 4, payload_3_0, 17, fields_ok_3_0}};

// configure_pid radial, paper gains
const uint8_t wire_4[] = {0x10, 0x03, 0x05, 0x02, 0xA4, 0x70, 0xAD, 0x42, 0xAE, 0x47, 0xDF, 0x41, 0x3D, 0x0A, 0x23, 0x41, 0x01, 0x05, 0x20, 0x41, 0x33, 0x04, 0x00};
const uint8_t payload_4_0[] = {0x02, 0xA4, 0x70, 0xAD, 0x42, 0xAE, 0x47, 0xDF, 0x41, 0x3D, 0x0A, 0x23, 0x41, 0x00, 0x00, 0x20, 0x41};
inline bool fields_ok_4_0(const uint8_t* p) {
  mr::proto::ConfigurePid m;
  mr::proto::decode(p, m);
  return m.axis == 2u &&
         m.kp == 86.72000122070312f &&
         m.ki == 27.90999984741211f &&
         m.kd == 10.1899995803833f &&
         m.integral_limit == 10.0f;
}
const Expected expected_4[] = {{Yield::kFrame, 0x03, 5, payload_4_0, 17, fields_ok_4_0}};

// set_target (0.125, -0.0625)
const uint8_t wire_5[] = {0x03, 0x04, 0x06, 0x01, 0x01, 0x02, 0x3E, 0x01, 0x05, 0x80, 0xBD, 0x2C, 0xB8, 0x00};
const uint8_t payload_5_0[] = {0x00, 0x00, 0x00, 0x3E, 0x00, 0x00, 0x80, 0xBD};
inline bool fields_ok_5_0(const uint8_t* p) {
  mr::proto::SetTarget m;
  mr::proto::decode(p, m);
  return m.x == 0.125f &&
         m.y == -0.0625f;
}
const Expected expected_5[] = {{Yield::kFrame, 0x04, 6, payload_5_0, 8, fields_ok_5_0}};

// set_target NaN x (frame-valid; the firmware refuses it)
const uint8_t wire_6[] = {0x03, 0x04, 0x07, 0x01, 0x03, 0xC0, 0x7F, 0x01, 0x01, 0x01, 0x03, 0xE8, 0x3B, 0x00};
const uint8_t payload_6_0[] = {0x00, 0x00, 0xC0, 0x7F, 0x00, 0x00, 0x00, 0x00};
inline bool fields_ok_6_0(const uint8_t* p) {
  mr::proto::SetTarget m;
  mr::proto::decode(p, m);
  return m.x != m.x &&
         m.y == 0.0f;
}
const Expected expected_6[] = {{Yield::kFrame, 0x04, 7, payload_6_0, 8, fields_ok_6_0}};

// start
const uint8_t wire_7[] = {0x05, 0x05, 0x08, 0xF2, 0x63, 0x00};
const uint8_t payload_7_0[] = {0};
inline bool fields_ok_7_0(const uint8_t* p) {
  mr::proto::Start m;
  mr::proto::decode(p, m);
  return true;
}
const Expected expected_7[] = {{Yield::kFrame, 0x05, 8, payload_7_0, 0, fields_ok_7_0}};

// stop
const uint8_t wire_8[] = {0x05, 0x06, 0x09, 0x80, 0x26, 0x00};
const uint8_t payload_8_0[] = {0};
inline bool fields_ok_8_0(const uint8_t* p) {
  mr::proto::Stop m;
  mr::proto::decode(p, m);
  return true;
}
const Expected expected_8[] = {{Yield::kFrame, 0x06, 9, payload_8_0, 0, fields_ok_8_0}};

// emergency_stop, seq wraps to 0
const uint8_t wire_9[] = {0x02, 0x07, 0x03, 0x98, 0x84, 0x00};
const uint8_t payload_9_0[] = {0};
inline bool fields_ok_9_0(const uint8_t* p) {
  mr::proto::EmergencyStop m;
  mr::proto::decode(p, m);
  return true;
}
const Expected expected_9[] = {{Yield::kFrame, 0x07, 0, payload_9_0, 0, fields_ok_9_0}};

// jog actuator 3 to -0.1 m
const uint8_t wire_10[] = {0x0A, 0x08, 0x0A, 0x03, 0xCD, 0xCC, 0xCC, 0xBD, 0x48, 0xF6, 0x00};
const uint8_t payload_10_0[] = {0x03, 0xCD, 0xCC, 0xCC, 0xBD};
inline bool fields_ok_10_0(const uint8_t* p) {
  mr::proto::Jog m;
  mr::proto::decode(p, m);
  return m.actuator == 3u &&
         m.position == -0.10000000149011612f;
}
const Expected expected_10[] = {{Yield::kFrame, 0x08, 10, payload_10_0, 5, fields_ok_10_0}};

// zero actuators 0 and 2 (homing)
const uint8_t wire_11[] = {0x04, 0x0A, 0x09, 0x05, 0x03, 0x0F, 0x8D, 0x00};
const uint8_t payload_11_0[] = {0x05, 0x00};
inline bool fields_ok_11_0(const uint8_t* p) {
  mr::proto::Zero m;
  mr::proto::decode(p, m);
  return m.actuators == 5u;
}
const Expected expected_11[] = {{Yield::kFrame, 0x0A, 9, payload_11_0, 2, fields_ok_11_0}};

// zero actuators 0 and 8 (an array's)
const uint8_t wire_12[] = {0x07, 0x0A, 0x10, 0x01, 0x01, 0x18, 0x8C, 0x00};
const uint8_t payload_12_0[] = {0x01, 0x01};
inline bool fields_ok_12_0(const uint8_t* p) {
  mr::proto::Zero m;
  mr::proto::decode(p, m);
  return m.actuators == 257u;
}
const Expected expected_12[] = {{Yield::kFrame, 0x0A, 16, payload_12_0, 2, fields_ok_12_0}};

// configure_schedule, a schedule that acts
const uint8_t wire_13[] = {0x07, 0x0B, 0x0E, 0x0A, 0xD7, 0xA3, 0x3D, 0x01, 0x01, 0x02, 0x3F, 0x01, 0x03, 0x80, 0x3E, 0x01, 0x01, 0x08, 0x40, 0x9A, 0x99, 0x99, 0x3E, 0x41, 0xBA, 0x00};
const uint8_t payload_13_0[] = {0x0A, 0xD7, 0xA3, 0x3D, 0x00, 0x00, 0x00, 0x3F, 0x00, 0x00, 0x80, 0x3E, 0x00, 0x00, 0x00, 0x40, 0x9A, 0x99, 0x99, 0x3E};
inline bool fields_ok_13_0(const uint8_t* p) {
  mr::proto::ConfigureSchedule m;
  mr::proto::decode(p, m);
  return m.edge_zone == 0.07999999821186066f &&
         m.edge_gain == 0.5f &&
         m.edge_tilt == 0.25f &&
         m.edge_brake == 2.0f &&
         m.brake_speed == 0.30000001192092896f;
}
const Expected expected_13[] = {{Yield::kFrame, 0x0B, 14, payload_13_0, 20, fields_ok_13_0}};

// configure_cascade
const uint8_t wire_14[] = {0x03, 0x0C, 0x0F, 0x01, 0x03, 0x80, 0x40, 0x01, 0x01, 0x04, 0x3E, 0xC6, 0x8C, 0x00};
const uint8_t payload_14_0[] = {0x00, 0x00, 0x80, 0x40, 0x00, 0x00, 0x00, 0x3E};
inline bool fields_ok_14_0(const uint8_t* p) {
  mr::proto::ConfigureCascade m;
  mr::proto::decode(p, m);
  return m.position_gain == 4.0f &&
         m.speed_limit == 0.125f;
}
const Expected expected_14[] = {{Yield::kFrame, 0x0C, 15, payload_14_0, 8, fields_ok_14_0}};

// sim_clock 83333 us
const uint8_t wire_15[] = {0x06, 0x09, 0x0B, 0x85, 0x45, 0x01, 0x03, 0x1C, 0x0E, 0x00};
const uint8_t payload_15_0[] = {0x85, 0x45, 0x01, 0x00};
inline bool fields_ok_15_0(const uint8_t* p) {
  mr::proto::SimClock m;
  mr::proto::decode(p, m);
  return m.now == 83333u;
}
const Expected expected_15[] = {{Yield::kFrame, 0x09, 11, payload_15_0, 4, fields_ok_15_0}};

// object_position visible
const uint8_t wire_16[] = {0x08, 0x10, 0x0C, 0x01, 0x02, 0x87, 0xD6, 0x12, 0x01, 0x01, 0x01, 0x06, 0xBD, 0xCD, 0xCC, 0x4C, 0x3E, 0x03, 0xC0, 0xC4, 0x00};
const uint8_t payload_16_0[] = {0x01, 0x02, 0x87, 0xD6, 0x12, 0x00, 0x00, 0x00, 0x00, 0xBD, 0xCD, 0xCC, 0x4C, 0x3E, 0x00};
inline bool fields_ok_16_0(const uint8_t* p) {
  mr::proto::ObjectPosition m;
  mr::proto::decode(p, m);
  return m.frame == 513u &&
         m.capture_time == 1234567u &&
         m.x == -0.03125f &&
         m.y == 0.20000000298023224f &&
         m.flags == 0u;
}
const Expected expected_16[] = {{Yield::kFrame, 0x10, 12, payload_16_0, 15, fields_ok_16_0}};

// object_position not visible
const uint8_t wire_17[] = {0x08, 0x10, 0x0D, 0x02, 0x02, 0x0C, 0x1C, 0x14, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x04, 0x01, 0x05, 0x60, 0x00};
const uint8_t payload_17_0[] = {0x02, 0x02, 0x0C, 0x1C, 0x14, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01};
inline bool fields_ok_17_0(const uint8_t* p) {
  mr::proto::ObjectPosition m;
  mr::proto::decode(p, m);
  return m.frame == 514u &&
         m.capture_time == 1317900u &&
         m.x == 0.0f &&
         m.y == 0.0f &&
         m.flags == 1u;
}
const Expected expected_17[] = {{Yield::kFrame, 0x10, 13, payload_17_0, 15, fields_ok_17_0}};

// identify_reply
const uint8_t wire_18[] = {0x02, 0x81, 0x02, 0x02, 0x01, 0x02, 0x01, 0x08, 0xED, 0x63, 0xED, 0xFD, 0x2E, 0x01, 0x04, 0x01, 0x03, 0x80, 0x3E, 0x08, 0x10, 0x0A, 0xD7, 0x23, 0x3D, 0xA0, 0x0F, 0x01, 0x03, 0x01, 0x01, 0x01, 0x01, 0x01, 0x03, 0x2E, 0x06, 0x00};
const uint8_t payload_18_0[] = {0x02, 0x00, 0x00, 0x01, 0x00, 0xED, 0x63, 0xED, 0xFD, 0x2E, 0x01, 0x04, 0x00, 0x00, 0x80, 0x3E, 0x00, 0x10, 0x0A, 0xD7, 0x23, 0x3D, 0xA0, 0x0F, 0x00, 0x00, 0x01, 0x01, 0x00, 0x00, 0x00, 0x00};
inline bool fields_ok_18_0(const uint8_t* p) {
  mr::proto::IdentifyReply m;
  mr::proto::decode(p, m);
  return m.protocol_version == 2u &&
         m.firmware_major == 0u &&
         m.firmware_minor == 1u &&
         m.firmware_patch == 0u &&
         m.schema_hash == 4260193261u &&
         m.max_wire == 46u &&
         m.clock == 1u &&
         m.actuator_count == 4u &&
         m.actuator_range == 0.25f &&
         m.encoder_counts == 4096u &&
         m.pulley_circumference == 0.03999999910593033f &&
         m.actuator_period == 4000u &&
         m.modules_x == 1u &&
         m.modules_y == 1u &&
         m.boot_gains_crc == 0u;
}
const Expected expected_18[] = {{Yield::kFrame, 0x81, 0, payload_18_0, 32, fields_ok_18_0}};

// ack of set_target seq 6
const uint8_t wire_19[] = {0x07, 0x82, 0x01, 0x04, 0x06, 0xA2, 0x2F, 0x00};
const uint8_t payload_19_0[] = {0x04, 0x06};
inline bool fields_ok_19_0(const uint8_t* p) {
  mr::proto::Ack m;
  mr::proto::decode(p, m);
  return m.ref_id == 4u &&
         m.ref_seq == 6u;
}
const Expected expected_19[] = {{Yield::kFrame, 0x82, 1, payload_19_0, 2, fields_ok_19_0}};

// nack out_of_range field 3
const uint8_t wire_20[] = {0x09, 0x83, 0x02, 0x02, 0x03, 0x04, 0x03, 0xCC, 0x18, 0x00};
const uint8_t payload_20_0[] = {0x02, 0x03, 0x04, 0x03};
inline bool fields_ok_20_0(const uint8_t* p) {
  mr::proto::Nack m;
  mr::proto::decode(p, m);
  return m.ref_id == 2u &&
         m.ref_seq == 3u &&
         m.code == 4u &&
         m.field == 3u;
}
const Expected expected_20[] = {{Yield::kFrame, 0x83, 2, payload_20_0, 4, fields_ok_20_0}};

// telemetry running
const uint8_t wire_21[] = {0x06, 0x84, 0x03, 0x40, 0xE2, 0x01, 0x02, 0x01, 0x01, 0x04, 0x01, 0x02, 0x2A, 0x05, 0x35, 0x01, 0xA0, 0xF5, 0x01, 0x08, 0x39, 0x30, 0x58, 0x9E, 0xA8, 0x61, 0x01, 0x08, 0x34, 0x30, 0x62, 0x9E, 0xA8, 0x61, 0x02, 0x04, 0xFF, 0xFF, 0x07, 0x05, 0x03, 0xFF, 0x4F, 0xF3, 0x00};
const uint8_t payload_21_0[] = {0x40, 0xE2, 0x01, 0x00, 0x01, 0x00, 0x00, 0x01, 0x02, 0x2A, 0x00, 0x35, 0x01, 0xA0, 0xF5, 0x00, 0x00, 0x39, 0x30, 0x58, 0x9E, 0xA8, 0x61, 0x01, 0x00, 0x34, 0x30, 0x62, 0x9E, 0xA8, 0x61, 0x02, 0x00, 0xFF, 0xFF, 0x07, 0x00, 0x03, 0xFF};
inline bool fields_ok_21_0(const uint8_t* p) {
  mr::proto::Telemetry m;
  mr::proto::decode(p, m);
  return m.time == 123456u &&
         m.state == 1u &&
         m.faults == 0u &&
         m.position_frame == 513u &&
         m.position_age == 42u &&
         m.tilt_zx == 309 &&
         m.tilt_zy == -2656 &&
         m.command[0] == 0 &&
         m.command[1] == 12345 &&
         m.command[2] == -25000 &&
         m.command[3] == 25000 &&
         m.measured[0] == 1 &&
         m.measured[1] == 12340 &&
         m.measured[2] == -24990 &&
         m.measured[3] == 25000 &&
         m.crc_errors == 2u &&
         m.frame_errors == 65535u &&
         m.loop_overruns == 7u &&
         m.module == 3u &&
         m.fault_actuator == 255u;
}
const Expected expected_21[] = {{Yield::kFrame, 0x84, 3, payload_21_0, 39, fields_ok_21_0}};

// telemetry estop
const uint8_t wire_22[] = {0x03, 0x84, 0x04, 0x01, 0x01, 0x01, 0x03, 0x04, 0x07, 0x01, 0x01, 0x03, 0xFF, 0xFF, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x04, 0x02, 0x0F, 0xD8, 0x00};
const uint8_t payload_22_0[] = {0x00, 0x00, 0x00, 0x00, 0x04, 0x07, 0x00, 0x00, 0x00, 0xFF, 0xFF, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02};
inline bool fields_ok_22_0(const uint8_t* p) {
  mr::proto::Telemetry m;
  mr::proto::decode(p, m);
  return m.time == 0u &&
         m.state == 4u &&
         m.faults == 7u &&
         m.position_frame == 0u &&
         m.position_age == 65535u &&
         m.tilt_zx == 0 &&
         m.tilt_zy == 0 &&
         m.command[0] == 0 &&
         m.command[1] == 0 &&
         m.command[2] == 0 &&
         m.command[3] == 0 &&
         m.measured[0] == 0 &&
         m.measured[1] == 0 &&
         m.measured[2] == 0 &&
         m.measured[3] == 0 &&
         m.crc_errors == 0u &&
         m.frame_errors == 0u &&
         m.loop_overruns == 0u &&
         m.module == 0u &&
         m.fault_actuator == 2u;
}
const Expected expected_22[] = {{Yield::kFrame, 0x84, 4, payload_22_0, 39, fields_ok_22_0}};

// boot after watchdog
const uint8_t wire_23[] = {0x02, 0x85, 0x04, 0x03, 0x55, 0x2C, 0x00};
const uint8_t payload_23_0[] = {0x03};
inline bool fields_ok_23_0(const uint8_t* p) {
  mr::proto::Boot m;
  mr::proto::decode(p, m);
  return m.reset_cause == 3u;
}
const Expected expected_23[] = {{Yield::kFrame, 0x85, 0, payload_23_0, 1, fields_ok_23_0}};

// array_commands of a 2 x 2 array
const uint8_t wire_24[] = {0x09, 0x86, 0x05, 0xD4, 0x30, 0x58, 0x9E, 0xA8, 0x61, 0x01, 0x06, 0x96, 0xE7, 0x10, 0x27, 0x01, 0x05, 0xFF, 0xFF, 0x20, 0x4E, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x03, 0xA0, 0x2B, 0x00};
const uint8_t payload_24_0[] = {0xD4, 0x30, 0x58, 0x9E, 0xA8, 0x61, 0x00, 0x00, 0x96, 0xE7, 0x10, 0x27, 0x01, 0x00, 0xFF, 0xFF, 0x20, 0x4E, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00};
inline bool fields_ok_24_0(const uint8_t* p) {
  mr::proto::ArrayCommands m;
  mr::proto::decode(p, m);
  return m.command[0] == 12500 &&
         m.command[1] == -25000 &&
         m.command[2] == 25000 &&
         m.command[3] == 0 &&
         m.command[4] == -6250 &&
         m.command[5] == 10000 &&
         m.command[6] == 1 &&
         m.command[7] == -1 &&
         m.command[8] == 20000 &&
         m.command[9] == 0 &&
         m.command[10] == 0 &&
         m.command[11] == 0 &&
         m.command[12] == 0 &&
         m.command[13] == 0 &&
         m.command[14] == 0 &&
         m.command[15] == 0;
}
const Expected expected_24[] = {{Yield::kFrame, 0x86, 5, payload_24_0, 32, fields_ok_24_0}};

// set_target with one flipped bit -> crc_error
const uint8_t wire_25[] = {0x03, 0x04, 0x06, 0x01, 0x01, 0x03, 0x3E, 0x01, 0x05, 0x80, 0xBD, 0x2C, 0xB8, 0x00};
const Expected expected_25[] = {{Yield::kCrcError, 0, 0, nullptr, 0, nullptr}};

// set_target truncated before its CRC -> crc_error or frame_error
const uint8_t wire_26[] = {0x03, 0x04, 0x06, 0x01, 0x01, 0x02, 0x3E, 0x01, 0x00};
const Expected expected_26[] = {{Yield::kCrcError, 0, 0, nullptr, 0, nullptr}};

// too short: 3 bytes -> frame_error
const uint8_t wire_27[] = {0x04, 0x01, 0x02, 0x03, 0x00};
const Expected expected_27[] = {{Yield::kFrameError, 0, 0, nullptr, 0, nullptr}};

// malformed COBS: code past the end -> frame_error
const uint8_t wire_28[] = {0x0A, 0x01, 0x02, 0x03, 0x04, 0x00};
const Expected expected_28[] = {{Yield::kFrameError, 0, 0, nullptr, 0, nullptr}};

// oversized: 60 non-zero bytes -> one frame_error
const uint8_t wire_29[] = {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x00};
const Expected expected_29[] = {{Yield::kFrameError, 0, 0, nullptr, 0, nullptr}};

// idle delimiters yield nothing
const uint8_t wire_30[] = {0x00, 0x00, 0x00};

// garbage, then a frame: resynchronised
const uint8_t wire_31[] = {0xFF, 0x13, 0x37, 0x7E, 0x00, 0x05, 0x01, 0x01, 0x1F, 0x3E, 0x00};
const uint8_t payload_31_1[] = {0};
inline bool fields_ok_31_1(const uint8_t* p) {
  mr::proto::Identify m;
  mr::proto::decode(p, m);
  return true;
}
const Expected expected_31[] = {{Yield::kFrameError, 0, 0, nullptr, 0, nullptr}, {Yield::kFrame, 0x01, 1, payload_31_1, 0, fields_ok_31_1}};

// oversized garbage then a frame
const uint8_t wire_32[] = {0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x00, 0x05, 0x01, 0x01, 0x1F, 0x3E, 0x00};
const uint8_t payload_32_1[] = {0};
inline bool fields_ok_32_1(const uint8_t* p) {
  mr::proto::Identify m;
  mr::proto::decode(p, m);
  return true;
}
const Expected expected_32[] = {{Yield::kFrameError, 0, 0, nullptr, 0, nullptr}, {Yield::kFrame, 0x01, 1, payload_32_1, 0, fields_ok_32_1}};

// unknown id 0x7F, valid CRC: a frame (the firmware nacks unknown_message)
const uint8_t wire_33[] = {0x05, 0x7F, 0x05, 0xCD, 0x55, 0x00};
const uint8_t payload_33_0[] = {0};
const Expected expected_33[] = {{Yield::kFrame, 0x7F, 5, payload_33_0, 0, nullptr}};

// set_target with a 4-byte payload, valid CRC: a frame (the firmware nacks bad_length)
const uint8_t wire_34[] = {0x03, 0x04, 0x06, 0x01, 0x05, 0x80, 0x3E, 0x31, 0x09, 0x00};
const uint8_t payload_34_0[] = {0x00, 0x00, 0x80, 0x3E};
const Expected expected_34[] = {{Yield::kFrame, 0x04, 6, payload_34_0, 4, nullptr}};

const Vector kAll[] = {
    {"identify, seq 1", wire_0, 6, expected_0, 1},
    {"configure, the paper's defaults", wire_1, 39, expected_1, 1},
    {"configure, euclidean with noise", wire_2, 39, expected_2, 1},
    {"configure_pid x, paper gains", wire_3, 23, expected_3, 1},
    {"configure_pid radial, paper gains", wire_4, 23, expected_4, 1},
    {"set_target (0.125, -0.0625)", wire_5, 14, expected_5, 1},
    {"set_target NaN x (frame-valid; the firmware refuses it)", wire_6, 14, expected_6, 1},
    {"start", wire_7, 6, expected_7, 1},
    {"stop", wire_8, 6, expected_8, 1},
    {"emergency_stop, seq wraps to 0", wire_9, 6, expected_9, 1},
    {"jog actuator 3 to -0.1 m", wire_10, 11, expected_10, 1},
    {"zero actuators 0 and 2 (homing)", wire_11, 8, expected_11, 1},
    {"zero actuators 0 and 8 (an array's)", wire_12, 8, expected_12, 1},
    {"configure_schedule, a schedule that acts", wire_13, 26, expected_13, 1},
    {"configure_cascade", wire_14, 14, expected_14, 1},
    {"sim_clock 83333 us", wire_15, 10, expected_15, 1},
    {"object_position visible", wire_16, 21, expected_16, 1},
    {"object_position not visible", wire_17, 21, expected_17, 1},
    {"identify_reply", wire_18, 38, expected_18, 1},
    {"ack of set_target seq 6", wire_19, 8, expected_19, 1},
    {"nack out_of_range field 3", wire_20, 10, expected_20, 1},
    {"telemetry running", wire_21, 45, expected_21, 1},
    {"telemetry estop", wire_22, 45, expected_22, 1},
    {"boot after watchdog", wire_23, 7, expected_23, 1},
    {"array_commands of a 2 x 2 array", wire_24, 38, expected_24, 1},
    {"set_target with one flipped bit -> crc_error", wire_25, 14, expected_25, 1},
    {"set_target truncated before its CRC -> crc_error or frame_error", wire_26, 9, expected_26, 1},
    {"too short: 3 bytes -> frame_error", wire_27, 5, expected_27, 1},
    {"malformed COBS: code past the end -> frame_error", wire_28, 6, expected_28, 1},
    {"oversized: 60 non-zero bytes -> one frame_error", wire_29, 61, expected_29, 1},
    {"idle delimiters yield nothing", wire_30, 3, nullptr, 0},
    {"garbage, then a frame: resynchronised", wire_31, 11, expected_31, 2},
    {"oversized garbage then a frame", wire_32, 107, expected_32, 2},
    {"unknown id 0x7F, valid CRC: a frame (the firmware nacks unknown_message)", wire_33, 6, expected_33, 1},
    {"set_target with a 4-byte payload, valid CRC: a frame (the firmware nacks bad_length)", wire_34, 10, expected_34, 1},
};

}  // namespace vectors
