"""The boards a rig can be built for: the MCU, its clock and memories, how PlatformIO names it, and each Arduino pin's
port and bit, its PWM output and timer registers. The one board table: scripts/avr_build.py, host/avr_image.py, the
simavr benchmarks and tests read it, and tests/test_avr_build.py checks platformio.ini against it.

Sources: PlatformIO's board JSON (platform-atmelavr boards/uno.json, megaatmega2560.json: build.mcu, f_cpu,
extra_flags, variant; upload.maximum_size, maximum_ram_size), the ATmega328P and ATmega2560 datasheets (register
addresses in data space, as avr-libc's io headers give them: an I/O address + 0x20) and Arduino's variant files
(variants/standard and variants/mega, pins_arduino.h: which port bit and which timer output each Arduino pin number
is). protocol/rig.py checks a rig's pins against these; protocol/generate_rig.py places them on the registers for the
AVR simulator's harness.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class TimerOutput:
    """A timer's output-compare channel: its control register, the bit that connects the pin, its compare register."""

    tccr: int  # data-space address of TCCRnA
    com_bit: int  # COMnx1: the bit of TCCRnA that connects the output (non-inverting PWM)
    ocr: int  # data-space address of OCRnx (its low byte where 16 bits wide)


@dataclass(frozen=True)
class Board:
    """One Arduino board: what an Arduino pin number means on its MCU."""

    name: str  # as rig files name it
    mcu: str  # avr-gcc's -mmcu, simavr's -m
    pio_board: str  # platformio.ini's board = (its board JSON's name)
    pio_prefix: str  # a rig's PlatformIO environment is PREFIX_RIG (the Uno's one-module environment is plain uno)
    arduino_define: str  # the board JSON's build.extra_flags: -D this
    variant: str  # the Arduino core's variants/ folder for its pins
    flash_bytes: int  # [bytes] upload.maximum_size: flash less the bootloader
    ram_bytes: int  # [bytes] upload.maximum_ram_size
    port_address: dict[str, int]  # port letter -> data-space address of PORTx
    pins: dict[int, tuple[str, int]]  # Arduino pin number -> (port letter, bit)
    pwm: dict[int, str]  # Arduino pin number -> the timer output driving it (analogWrite)
    timer_outputs: dict[str, TimerOutput]  # timer output name -> its registers
    reserved: dict[int, str]  # pins the firmware's own peripherals use (serial link, I2C bus) -> what for

    f_cpu_hz: int = 16_000_000  # [Hz] the crystal: the board JSON's f_cpu, simavr's -f

    def pin_range(self) -> str:
        return f"0..{max(self.pins)}"


def _port_pins(layout: str) -> dict[int, tuple[str, int]]:
    """Pins numbered in order from a layout "PE0 PE1 PE4 ..." (Arduino's digital_pin_to_port and _bit_mask)."""
    return {pin: (name[1], int(name[2])) for pin, name in enumerate(layout.split())}


# Timers 0, 1 and 2 sit at the same addresses on both MCUs (the ATmega2560 adds 3, 4 and 5).
TIMERS_0_TO_2 = {
    "OC0A": TimerOutput(0x44, 7, 0x47),
    "OC0B": TimerOutput(0x44, 5, 0x48),
    "OC1A": TimerOutput(0x80, 7, 0x88),
    "OC1B": TimerOutput(0x80, 5, 0x8A),
    "OC2A": TimerOutput(0xB0, 7, 0xB3),
    "OC2B": TimerOutput(0xB0, 5, 0xB4),
}

UNO = Board(
    name="uno",
    mcu="atmega328p",
    pio_board="uno",
    pio_prefix="uno",
    arduino_define="ARDUINO_AVR_UNO",
    variant="standard",
    flash_bytes=32256,
    ram_bytes=2048,
    port_address={"B": 0x25, "C": 0x28, "D": 0x2B},
    pins=_port_pins("PD0 PD1 PD2 PD3 PD4 PD5 PD6 PD7 PB0 PB1 PB2 PB3 PB4 PB5 PC0 PC1 PC2 PC3 PC4 PC5"),
    pwm={3: "OC2B", 5: "OC0B", 6: "OC0A", 9: "OC1A", 10: "OC1B", 11: "OC2A"},
    timer_outputs=TIMERS_0_TO_2,
    reserved={0: "the serial link (RX)", 1: "the serial link (TX)", 18: "I2C (SDA)", 19: "I2C (SCL)"},
)

MEGA2560 = Board(
    name="mega2560",
    mcu="atmega2560",
    pio_board="megaatmega2560",
    pio_prefix="mega",
    arduino_define="ARDUINO_AVR_MEGA2560",
    variant="mega",
    flash_bytes=253952,
    ram_bytes=8192,
    port_address={
        "A": 0x22,
        "B": 0x25,
        "C": 0x28,
        "D": 0x2B,
        "E": 0x2E,
        "F": 0x31,
        "G": 0x34,
        "H": 0x102,
        "J": 0x105,
        "K": 0x108,
        "L": 0x10B,
    },
    pins=_port_pins(
        "PE0 PE1 PE4 PE5 PG5 PE3 PH3 PH4 PH5 PH6 PB4 PB5 PB6 PB7 PJ1 PJ0 PH1 PH0 PD3 PD2 PD1 PD0 "  # 0..21
        "PA0 PA1 PA2 PA3 PA4 PA5 PA6 PA7 PC7 PC6 PC5 PC4 PC3 PC2 PC1 PC0 PD7 PG2 PG1 PG0 "  # 22..41
        "PL7 PL6 PL5 PL4 PL3 PL2 PL1 PL0 PB3 PB2 PB1 PB0 "  # 42..53
        "PF0 PF1 PF2 PF3 PF4 PF5 PF6 PF7 PK0 PK1 PK2 PK3 PK4 PK5 PK6 PK7"  # 54..69: A0..A15
    ),
    pwm={
        2: "OC3B",
        3: "OC3C",
        4: "OC0B",
        5: "OC3A",
        6: "OC4A",
        7: "OC4B",
        8: "OC4C",
        9: "OC2B",
        10: "OC2A",
        11: "OC1A",
        12: "OC1B",
        13: "OC0A",
        44: "OC5C",
        45: "OC5B",
        46: "OC5A",
    },
    timer_outputs={
        **TIMERS_0_TO_2,
        "OC3A": TimerOutput(0x90, 7, 0x98),
        "OC3B": TimerOutput(0x90, 5, 0x9A),
        "OC3C": TimerOutput(0x90, 3, 0x9C),
        "OC4A": TimerOutput(0xA0, 7, 0xA8),
        "OC4B": TimerOutput(0xA0, 5, 0xAA),
        "OC4C": TimerOutput(0xA0, 3, 0xAC),
        "OC5A": TimerOutput(0x120, 7, 0x128),
        "OC5B": TimerOutput(0x120, 5, 0x12A),
        "OC5C": TimerOutput(0x120, 3, 0x12C),
    },
    reserved={0: "the serial link (RX)", 1: "the serial link (TX)", 20: "I2C (SDA)", 21: "I2C (SCL)"},
)

BOARDS = {board.name: board for board in (UNO, MEGA2560)}
PIO_BOARDS = {board.pio_board: board for board in BOARDS.values()}  # by platformio.ini's board =
