// The Arduino firmware's ELF (Uno or Mega 2560, as its rig says) in simavr, cycle-accurate, its UART bridged to a pty;
// probe timing and stack use on exit.
//
// Usage: mantaray-simavr FIRMWARE.elf [--bench] [--realtime] [--paint-from ADDR] [--stats FILE] [--run-for S]
// Prints "pty PATH" on stdout once the serial port exists; the host talks to the firmware there. SIGUSR1 pulls the
// reset pin, as a host opening the Uno's port does through DTR: the MCU restarts with MCUSR's EXTRF set and its
// RAM as it was (the pty, the modelled motors and the probe statistics carry on).
//   --bench       hold the bench pin low: external actuators and a simulated clock (protocol/rig.toml);
//                 without it the pin is held high, as the board's pull-up leaves it on the rig
//   --realtime    never let simulated time run ahead of the wall clock (simavr is faster than the Uno):
//                 a wall-clock firmware then keeps the host's time, as a board does
//   --paint-from  fill RAM from ADDR (the ELF's _end) up to RAMEND with 0xC5 before the firmware starts,
//                 so the untouched bytes above the data show the stack's high-water mark
//   --stats FILE  on exit (SIGTERM, SIGINT, or --run-for elapsed), write the probe statistics as JSON
//   --run-for S   stop after S seconds of simulated time
// The probes are the firmware's timing pins (protocol/rig.toml, rig_gen.h): the controller probe high while a
// received byte is handled (the byte that completes an object_position frame runs the controller), the actuator
// probe high while the four actuator loops run, the loop probe toggled once per main-loop pass.
// On the rig side (no --bench) the harness also plays the board's hardware (rig_gen.h): a TCA9548A multiplexer
// with an AS5600 encoder on each actuator's channel, and four geared motors whose shafts turn at the motor speed
// times the PWM duty of the PWM pins, in the direction of the direction pins (HIGH: +).
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "avr_ioport.h"
#include "avr_twi.h"
#include "sim_cycle_timers.h"
#include "sim_time.h"
#include "sim_avr.h"
#include "sim_elf.h"
#include "uart_pty.h"

#include "simavr_gen.h"  // MCU_NAME, kPwmPin, kDirPin, kMuxAddress, kBenchPin, ... (the rig file; firmware/rigs/NAME/)

#define PAINT 0xC5  // stack paint byte

typedef struct {
  const char* name;
  avr_cycle_count_t since;  // cycle of the last rising edge (or toggle)
  int high;
  unsigned long count;
  avr_cycle_count_t min, max, sum;
} probe_t;

// ---------------------------------------------------------------- the rig's hardware, modelled
// Its addresses, pins and motor speed are the board's: simavr_gen.h is written from the rig file.
#define MOTOR_STEP_US 500  // [us] motor model update period

#define MUX_BASE 0x70  // TCA9548A: 0x70..0x77 by its A0..A2 pins

typedef struct {
  avr_irq_t* irq;                    // [0] from the master (TWI_IRQ_OUTPUT), [1] to it (TWI_IRQ_INPUT)
  int selected;                      // 0 none, 1 a multiplexer, 2 an encoder
  int mux;                           // the multiplexer selected (its address - MUX_BASE)
  uint8_t mux_mask[8];               // channels each multiplexer connects
  uint8_t pointer[ACTUATOR_COUNT];   // each AS5600's register pointer
  int read_index;                    // byte of the current read
  double angle_rev[ACTUATOR_COUNT];  // shaft angles [rev]
} rig_t;

static rig_t g_rig;

static int is_mux(uint8_t device) {  // one of the rig's multiplexers
  for (int i = 0; i < ACTUATOR_COUNT; ++i) {
    if (kMuxAddress[i] == device) return 1;
  }
  return 0;
}

static int encoder_connected(void) {  // the one actuator whose encoder the multiplexers connect, or -1
  int actuator = -1;
  for (int i = 0; i < ACTUATOR_COUNT; ++i) {
    if (g_rig.mux_mask[kMuxAddress[i] - MUX_BASE] & (1u << kMuxChannel[i])) {
      if (actuator >= 0) return -1;  // two AS5600 on the bus at once: both answer, garbage
      actuator = i;
    }
  }
  return actuator;
}

static uint16_t encoder_angle(int actuator) {
  double turns = g_rig.angle_rev[actuator] - floor(g_rig.angle_rev[actuator]);
  return (uint16_t)(turns * ENCODER_COUNTS) & (ENCODER_COUNTS - 1);
}

static void answer(uint8_t msg, uint8_t addr, uint8_t data) {
  avr_raise_irq(g_rig.irq + 1, avr_twi_irq_msg(msg, addr, data));
}

// The bus as the devices see it: START with an address, data bytes written or read, STOP.
static void on_twi(struct avr_irq_t* irq, uint32_t value, void* param) {
  (void)irq;
  (void)param;
  avr_twi_msg_irq_t v;
  v.u.v = value;
  if (v.u.twi.msg & TWI_COND_STOP) g_rig.selected = 0;
  if (v.u.twi.msg & TWI_COND_START) {
    const uint8_t device = v.u.twi.addr >> 1;
    g_rig.selected = 0;
    g_rig.read_index = 0;
    if (is_mux(device)) {
      g_rig.selected = 1;
      g_rig.mux = device - MUX_BASE;
    } else if (device == ENCODER_ADDRESS && encoder_connected() >= 0) {
      g_rig.selected = 2;
    }
    if (g_rig.selected) answer(TWI_COND_ACK, v.u.twi.addr, 1);
    return;
  }
  if (!g_rig.selected) return;
  if (v.u.twi.msg & TWI_COND_WRITE) {
    if (g_rig.selected == 1) {
      g_rig.mux_mask[g_rig.mux] = v.u.twi.data;
    } else {
      g_rig.pointer[encoder_connected()] = v.u.twi.data;
    }
    answer(TWI_COND_ACK, v.u.twi.addr, 1);
  }
  if ((v.u.twi.msg & TWI_COND_READ) && g_rig.selected == 2) {
    const int actuator = encoder_connected();
    const uint16_t angle = g_rig.pointer[actuator] == ANGLE_REGISTER ? encoder_angle(actuator) : 0;
    const uint8_t data = g_rig.read_index++ == 0 ? (uint8_t)(angle >> 8) : (uint8_t)(angle & 0xFF);
    answer(TWI_COND_READ, v.u.twi.addr, data);
  }
}

// Duty 0..1 of a PWM pin: its compare register while the timer drives the pin, else the pin's level.
static double duty(avr_t* avr, const pwm_pin_t* p) {
  if (avr->data[p->tccr] & p->com_bit) return avr->data[p->ocr] / (double)PWM_MAX;
  return (avr->data[p->pin.data] & (1u << p->pin.bit)) ? 1.0 : 0.0;
}

static avr_cycle_count_t step_motors(avr_t* avr, avr_cycle_count_t when, void* param) {
  (void)param;
  for (int i = 0; i < ACTUATOR_COUNT; ++i) {
    const int high = avr->data[kDirPin[i].data] & (1u << kDirPin[i].bit);
    g_rig.angle_rev[i] += (high ? 1.0 : -1.0) * duty(avr, &kPwmPin[i]) * MOTOR_REV_PER_S * MOTOR_STEP_US * 1e-6;
  }
  return when + avr_usec_to_cycles(avr, MOTOR_STEP_US);
}

static void (*g_core_reset)(avr_t* avr);  // the MCU's own reset hook

// Every reset (the reset pin's, the watchdog's) clears simavr's cycle timers and PIN registers, though the motors
// go on turning and the pull-up goes on holding the bench pin high: the motors' timer is set again, the pin put back.
static void rig_reset(avr_t* avr) {
  g_core_reset(avr);
  avr_cycle_timer_register_usec(avr, MOTOR_STEP_US, step_motors, NULL);
  avr->data[kBenchPin.data - 2] |= 1u << kBenchPin.bit;  // PINx lies two below PORTx
}

static void rig_attach(avr_t* avr) {
  static const char* names[2] = {"32<rig.twi_in", "8>rig.twi_out"};
  memset(&g_rig, 0, sizeof g_rig);
  for (int i = 0; i < ACTUATOR_COUNT; ++i) g_rig.angle_rev[i] = 0.1 + 0.2 * i;  // arbitrary magnet positions
  g_rig.irq = avr_alloc_irq(&avr->irq_pool, 0, 2, names);
  avr_irq_register_notify(g_rig.irq + 0, on_twi, NULL);
  avr_connect_irq(avr_io_getirq(avr, AVR_IOCTL_TWI_GETIRQ(0), TWI_IRQ_OUTPUT), g_rig.irq + 0);
  avr_connect_irq(g_rig.irq + 1, avr_io_getirq(avr, AVR_IOCTL_TWI_GETIRQ(0), TWI_IRQ_INPUT));
  avr_cycle_timer_register_usec(avr, MOTOR_STEP_US, step_motors, NULL);
  g_core_reset = avr->reset;
  avr->reset = rig_reset;
}

// ---------------------------------------------------------------- harness
static volatile sig_atomic_t g_stop = 0;
static volatile sig_atomic_t g_reset_pin = 0;  // SIGUSR1 came: pull the reset pin between two runs
static avr_t* g_avr;
static probe_t g_frame = {.name = "byte_handling"}, g_actuators = {.name = "actuator_loops"},
               g_pass = {.name = "main_loop_pass"};

static void on_signal(int sig) {
  (void)sig;
  g_stop = 1;
}

static void on_reset_signal(int sig) {
  (void)sig;
  g_reset_pin = 1;
}

static void record(probe_t* p, avr_cycle_count_t width) {
  if (p->count == 0 || width < p->min) p->min = width;
  if (width > p->max) p->max = width;
  p->sum += width;
  p->count++;
}

// High-while-working probes: a pulse's width is the work's cycle count.
static void on_pulse(struct avr_irq_t* irq, uint32_t value, void* param) {
  (void)irq;
  probe_t* p = param;
  if (value && !p->high) {
    p->since = g_avr->cycle;
  } else if (!value && p->high) {
    record(p, g_avr->cycle - p->since);
  }
  p->high = value != 0;
}

// Toggled probe: every edge ends one main-loop pass.
static void on_toggle(struct avr_irq_t* irq, uint32_t value, void* param) {
  (void)irq;
  (void)value;
  probe_t* p = param;
  if (p->high) record(p, g_avr->cycle - p->since);
  p->high = 1;
  p->since = g_avr->cycle;
}

static void watch(pin_t pin, avr_irq_notify_t hook, probe_t* probe) {
  avr_irq_register_notify(avr_io_getirq(g_avr, AVR_IOCTL_IOPORT_GETIRQ(pin.port), pin.bit), hook, probe);
}

static void write_probe(FILE* f, const probe_t* p, const char* tail) {
  fprintf(f, "  \"%s\": {\"count\": %lu, \"min_cycles\": %llu, \"max_cycles\": %llu, \"mean_cycles\": %.1f}%s\n",
          p->name, p->count, (unsigned long long)p->min, (unsigned long long)p->max,
          p->count ? (double)p->sum / (double)p->count : 0.0, tail);
}

int main(int argc, char** argv) {
  const char* elf = NULL;
  const char* stats = NULL;
  long paint_from = -1;
  double run_for_s = -1.0;
  int bench = 0;
  int realtime = 0;
  for (int i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "--bench")) {
      bench = 1;
    } else if (!strcmp(argv[i], "--realtime")) {
      realtime = 1;
    } else if (!strcmp(argv[i], "--stats") && i + 1 < argc) {
      stats = argv[++i];
    } else if (!strcmp(argv[i], "--paint-from") && i + 1 < argc) {
      paint_from = strtol(argv[++i], NULL, 0);
    } else if (!strcmp(argv[i], "--run-for") && i + 1 < argc) {
      run_for_s = atof(argv[++i]);
    } else if (argv[i][0] != '-' && !elf) {
      elf = argv[i];
    } else {
      fprintf(stderr,
              "usage: %s FIRMWARE.elf [--bench] [--realtime] [--paint-from ADDR] [--stats FILE] "
              "[--run-for S]\n",
              argv[0]);
      return 2;
    }
  }
  if (!elf) {
    fprintf(stderr, "mantaray-simavr: no firmware ELF given\n");
    return 2;
  }

  elf_firmware_t firmware;
  memset(&firmware, 0, sizeof firmware);
  if (elf_read_firmware(elf, &firmware) != 0) {
    fprintf(stderr, "mantaray-simavr: cannot read %s\n", elf);
    return 1;
  }
  g_avr = avr_make_mcu_by_name(MCU_NAME);
  if (!g_avr) {
    fprintf(stderr, "mantaray-simavr: simavr has no %s\n", MCU_NAME);
    return 1;
  }
  avr_init(g_avr);
  g_avr->frequency = 16000000;  // [Hz] the Uno's and the Mega 2560's crystal
  avr_load_firmware(g_avr, &firmware);
  if (paint_from >= 0) {
    for (long a = paint_from; a <= g_avr->ramend; ++a) g_avr->data[a] = PAINT;
  }

  // The bench pin, held by a jumper (low) or left to the pull-up (high): an external level that the
  // firmware's own pin settings do not override.
  const uint8_t bench_mask = 1u << kBenchPin.bit;
  avr_ioport_external_t bench_pin = {.name = kBenchPin.port, .mask = bench_mask, .value = bench ? 0u : bench_mask};
  avr_ioctl(g_avr, AVR_IOCTL_IOPORT_SET_EXTERNAL(kBenchPin.port), &bench_pin);
  if (!bench) rig_attach(g_avr);
  watch(kProbeControllerPin, on_pulse, &g_frame);
  watch(kProbeActuatorPin, on_pulse, &g_actuators);
  watch(kProbeLoopPin, on_toggle, &g_pass);

  uart_pty_t pty;
  uart_pty_init(g_avr, &pty);
  uart_pty_connect(&pty, '0');
  printf("pty %s\n", pty.pty.slavename);
  fflush(stdout);

  signal(SIGTERM, on_signal);
  signal(SIGINT, on_signal);
  signal(SIGUSR1, on_reset_signal);
  const avr_cycle_count_t limit = run_for_s >= 0 ? (avr_cycle_count_t)(run_for_s * g_avr->frequency) : 0;
  int state = cpu_Running;
  struct timespec t0;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  const avr_cycle_count_t pace_every = g_avr->frequency / 1000;  // check the wall clock every 1 ms simulated
  avr_cycle_count_t next_pace = pace_every;
  while (!g_stop && state != cpu_Done && state != cpu_Crashed) {
    if (g_reset_pin) {
      g_reset_pin = 0;
      avr_reset(g_avr);  // registers and I/O to their reset values, the program counter to 0; RAM stays
      avr_regbit_set(g_avr, g_avr->reset_flags.extrf);
    }
    state = avr_run(g_avr);
    if (limit && g_avr->cycle >= limit) break;
    if (realtime && g_avr->cycle >= next_pace) {
      next_pace += pace_every;
      struct timespec now;
      clock_gettime(CLOCK_MONOTONIC, &now);
      const double wall_s = (double)(now.tv_sec - t0.tv_sec) + 1e-9 * (double)(now.tv_nsec - t0.tv_nsec);
      const double ahead_s = (double)g_avr->cycle / g_avr->frequency - wall_s;
      if (ahead_s > 0) usleep((useconds_t)(ahead_s * 1e6));
    }
  }

  if (stats) {
    FILE* f = fopen(stats, "w");
    if (!f) {
      fprintf(stderr, "mantaray-simavr: cannot write %s: %s\n", stats, strerror(errno));
      return 1;
    }
    long untouched = 0;
    if (paint_from >= 0) {
      for (long a = paint_from; a <= g_avr->ramend && g_avr->data[a] == PAINT; ++a) untouched++;
    }
    fprintf(f, "{\n  \"cycles\": %llu,\n  \"frequency_hz\": %u,\n  \"state\": %d,\n", (unsigned long long)g_avr->cycle,
            g_avr->frequency, state);
    fprintf(f, "  \"never_used_ram_bytes\": %ld,\n", paint_from >= 0 ? untouched : -1L);
    write_probe(f, &g_frame, ",");
    write_probe(f, &g_actuators, ",");
    write_probe(f, &g_pass, "");
    fprintf(f, "}\n");
    fclose(f);
  }
  // No uart_pty_stop(): it joins the pty's reader thread, which may sit in a read; exiting ends it.
  return state == cpu_Crashed ? 1 : 0;
}
