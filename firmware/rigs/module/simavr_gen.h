// The rig's hardware as the AVR simulator's harness plays it. Generated from protocol/rig.toml by protocol/generate.py; do not edit.
#pragma once

#include <stdint.h>  // uint8_t

#define MCU_NAME "atmega328p"
#define ACTUATOR_COUNT 4
#define ENCODER_ADDRESS 0x36 // AS5600
#define ANGLE_REGISTER 0x0E  // AS5600 ANGLE, 12 bits, high byte first
#define ENCODER_COUNTS 4096  // [counts/rev]
#define PWM_MAX 255  // a compare register's full scale
#define MOTOR_REV_PER_S 2.0  // [rev/s] motor_speed_rpm / 60, at full drive

// A pin: its port letter, bit and the port's data-space address (PORTx).
typedef struct { char port; uint8_t bit; int data; } pin_t;
// A PWM pin: its timer's control register, the compare-output bit that connects it, its compare register.
typedef struct { int tccr; uint8_t com_bit; int ocr; pin_t pin; } pwm_pin_t;

static const pwm_pin_t kPwmPin[ACTUATOR_COUNT] = {{0xB0, 1u << 5, 0xB4, {'D', 3, 0x2B}}, {0x44, 1u << 5, 0x48, {'D', 5, 0x2B}}, {0x44, 1u << 7, 0x47, {'D', 6, 0x2B}}, {0x80, 1u << 7, 0x88, {'B', 1, 0x25}}};  // pins 3, 5, 6, 9: OC2B, OC0B, OC0A, OC1A
static const pin_t kDirPin[ACTUATOR_COUNT] = {{'D', 4, 0x2B}, {'D', 7, 0x2B}, {'B', 0, 0x25}, {'B', 4, 0x25}};  // pins 4, 7, 8, 12: HIGH lowers the corner
static const uint8_t kMuxAddress[ACTUATOR_COUNT] = {0x70, 0x70, 0x70, 0x70};  // TCA9548A
static const uint8_t kMuxChannel[ACTUATOR_COUNT] = {0, 1, 2, 3};
static const pin_t kBenchPin = {'D', 2, 0x2B};  // D2
static const pin_t kProbeControllerPin = {'B', 5, 0x25};  // D13
static const pin_t kProbeActuatorPin = {'B', 2, 0x25};  // D10
static const pin_t kProbeLoopPin = {'B', 3, 0x25};  // D11
