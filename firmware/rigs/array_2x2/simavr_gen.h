// The rig's hardware as the AVR simulator's harness plays it. Generated from protocol/rigs/array_2x2.toml by protocol/generate.py; do not edit.
#pragma once

#include <stdint.h>  // uint8_t

#define MCU_NAME "atmega2560"
#define ACTUATOR_COUNT 9
#define ENCODER_ADDRESS 0x36 // AS5600
#define ANGLE_REGISTER 0x0E  // AS5600 ANGLE, 12 bits, high byte first
#define ENCODER_COUNTS 4096  // [counts/rev]
#define PWM_MAX 255  // a compare register's full scale
#define MOTOR_REV_PER_S 2.0  // [rev/s] motor_speed_rpm / 60, at full drive

// A pin: its port letter, bit and the port's data-space address (PORTx).
typedef struct { char port; uint8_t bit; int data; } pin_t;
// A PWM pin: its timer's control register, the compare-output bit that connects it, its compare register.
typedef struct { int tccr; uint8_t com_bit; int ocr; pin_t pin; } pwm_pin_t;

static const pwm_pin_t kPwmPin[ACTUATOR_COUNT] = {{0x90, 1u << 5, 0x9A, {'E', 4, 0x2E}}, {0x90, 1u << 3, 0x9C, {'E', 5, 0x2E}}, {0x90, 1u << 7, 0x98, {'E', 3, 0x2E}}, {0xA0, 1u << 7, 0xA8, {'H', 3, 0x102}}, {0xA0, 1u << 5, 0xAA, {'H', 4, 0x102}}, {0xA0, 1u << 3, 0xAC, {'H', 5, 0x102}}, {0x120, 1u << 3, 0x12C, {'L', 5, 0x10B}}, {0x120, 1u << 5, 0x12A, {'L', 4, 0x10B}}, {0x120, 1u << 7, 0x128, {'L', 3, 0x10B}}};  // pins 2, 3, 5, 6, 7, 8, 44, 45, 46: OC3B, OC3C, OC3A, OC4A, OC4B, OC4C, OC5C, OC5B, OC5A
static const pin_t kDirPin[ACTUATOR_COUNT] = {{'A', 0, 0x22}, {'A', 1, 0x22}, {'A', 2, 0x22}, {'A', 3, 0x22}, {'A', 4, 0x22}, {'A', 5, 0x22}, {'A', 6, 0x22}, {'A', 7, 0x22}, {'C', 7, 0x28}};  // pins 22, 23, 24, 25, 26, 27, 28, 29, 30: HIGH lowers the corner
static const uint8_t kMuxAddress[ACTUATOR_COUNT] = {0x70, 0x70, 0x70, 0x70, 0x70, 0x70, 0x70, 0x70, 0x71};  // TCA9548A
static const uint8_t kMuxChannel[ACTUATOR_COUNT] = {0, 1, 2, 3, 4, 5, 6, 7, 0};
static const pin_t kBenchPin = {'C', 6, 0x28};  // D31
static const pin_t kProbeControllerPin = {'C', 5, 0x28};  // D32
static const pin_t kProbeActuatorPin = {'C', 4, 0x28};  // D33
static const pin_t kProbeLoopPin = {'C', 3, 0x28};  // D34
