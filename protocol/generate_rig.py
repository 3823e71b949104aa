"""Write the rig's constants (firmware core, Uno board, AVR simulator harness, Python) from protocol/rig.toml.

Called by protocol/generate.py, which writes every generated file and checks them in CI; the description is checked
against itself and against schema.toml's rig-derived defaults first (RigDescriptionError says what disagrees).
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

if __package__ in (None, ""):
    from codegen import TYPES, camel, f32_literal
else:
    from .codegen import TYPES, camel, f32_literal

ROOT = Path(__file__).resolve().parent.parent
RIG = ROOT / "protocol" / "rig.toml"
CORE_OUT = ROOT / "firmware" / "lib" / "core" / "rig_gen.h"
BOARD_OUT = ROOT / "firmware" / "uno" / "board_gen.h"
SIMAVR_OUT = ROOT / "firmware" / "simavr" / "rig_gen.h"
PY_OUT = ROOT / "protocol" / "rig.py"
HEADER = "Generated from protocol/rig.toml by protocol/generate.py; do not edit."

# The ATmega328P behind the Uno's pin numbers (its datasheet): data-space addresses of the port registers, each
# digital pin's port and bit, and each PWM pin's timer (control register, its compare-output bit, compare register).
PORT_ADDRESS = {"B": 0x25, "C": 0x28, "D": 0x2B}
UNO_PINS = {
    **{p: ("D", p) for p in range(8)},
    **{p: ("B", p - 8) for p in range(8, 14)},
    **{p: ("C", p - 14) for p in range(14, 20)},
}
UNO_PWM = {
    3: ("OC2B", 0xB0, 5, 0xB4),
    5: ("OC0B", 0x44, 5, 0x48),
    6: ("OC0A", 0x44, 7, 0x47),
    9: ("OC1A", 0x80, 7, 0x88),
    10: ("OC1B", 0x80, 5, 0x8A),
    11: ("OC2A", 0xB0, 7, 0xB3),
}
PER_ACTUATOR = ("pwm_pin", "dir_pin", "motor_sign", "mux_channel", "analog_pin", "encoder_sign")
PINS = ("pwm_pin", "dir_pin", "analog_pin", "bench_pin", "probe_controller_pin", "probe_actuator_pin", "probe_loop_pin")


class RigDescriptionError(ValueError):
    """rig.toml contradicts itself, the Uno, or schema.toml."""


def load_rig(path: Path = RIG) -> dict:
    with open(path, "rb") as f:
        return tomllib.load(f)


def value(rig: dict, key: str):
    section = "core" if key in rig["core"] else "board"
    return rig[section][key]["value"]


def _pins(rig: dict, key: str) -> list[int]:
    """The pins an entry names: one, or one per actuator."""
    pins = value(rig, key)
    return pins if isinstance(pins, list) else [pins]


def check(rig: dict, schema: dict) -> None:
    """Raises RigDescriptionError on the first disagreement found."""
    for section in ("core", "board"):
        for key, entry in rig[section].items():
            if entry.get("type") not in TYPES or "doc" not in entry or "value" not in entry:
                raise RigDescriptionError(
                    f"rig.toml [{section}] {key}: needs value, doc and a type of {', '.join(TYPES)}"
                )
    count = value(rig, "actuator_count")
    for key in PER_ACTUATOR:
        if len(value(rig, key)) != count:
            raise RigDescriptionError(f"rig.toml {key}: {len(value(rig, key))} values for {count} actuators")
    for key in PINS:
        for pin in _pins(rig, key):
            if pin not in UNO_PINS:
                raise RigDescriptionError(f"rig.toml {key}: the Uno has no pin {pin} (0..19)")
    for pin in value(rig, "pwm_pin"):
        if pin not in UNO_PWM:
            raise RigDescriptionError(f"rig.toml pwm_pin: pin {pin} has no PWM on the Uno ({sorted(UNO_PWM)})")
    used = [pin for key in PINS for pin in _pins(rig, key)]
    if len(set(used)) != len(used):
        raise RigDescriptionError(
            f"rig.toml: a pin is used twice ({sorted(p for p in set(used) if used.count(p) > 1)})"
        )
    reply = {f["name"]: f for m in schema["messages"] if m["name"] == "identify_reply" for f in m["fields"]}
    for key, entry in rig["core"].items():
        name = entry.get("identify")
        if name is not None and (name not in reply or reply[name]["type"] != entry["type"]):
            raise RigDescriptionError(
                f"rig.toml {key}: identify_reply has no {entry['type']} field {name!r} (schema.toml)"
            )
    configure = {f["name"]: f for m in schema["messages"] if m["name"] == "configure" for f in m["fields"]}
    mx, my, travel = value(rig, "module_size_x_m"), value(rig, "module_size_y_m"), value(rig, "actuator_range_m")
    tilt_deg = round(math.degrees(math.atan(travel / ((mx + my) / 2))), 6)
    for field, key, expected in (
        ("module_x", "default", mx),
        ("module_y", "default", my),
        ("tilt_limit", "default", tilt_deg),
        ("noise_amplitude", "max", travel),
    ):
        if configure[field][key] != expected:
            raise RigDescriptionError(
                f"schema.toml configure.{field} {key} is {configure[field][key]}; rig.toml makes it {expected}"
            )


def _c_value(key: str, entry: dict, v) -> str:
    if entry["type"] == "f32":
        return f32_literal(v)
    return f"0x{v:02X}" if key.endswith(("_address", "_register")) else str(v)  # bus addresses as datasheets write them


def _comment(entry: dict) -> str:
    unit = f"[{entry['unit']}] " if "unit" in entry else ""
    reported = f" (identify_reply.{entry['identify']})" if "identify" in entry else ""
    return f"{unit}{entry['doc']}{reported}"


def _cpp_constants(section: dict) -> list[str]:
    out = []
    for key, entry in section.items():
        ctype, v = TYPES[entry["type"]][1], entry["value"]
        if isinstance(v, list):
            out.append(
                f"constexpr {ctype} k{camel(key)}[{len(v)}] = {{{', '.join(_c_value(key, entry, x) for x in v)}}};"
                f"  // {_comment(entry)}"
            )
        else:
            out.append(f"constexpr {ctype} k{camel(key)} = {_c_value(key, entry, v)};  // {_comment(entry)}")
    return out


def render_core(rig: dict) -> str:
    return "\n".join(
        [
            f"// The rig's constants every build of the firmware core shares. {HEADER}",
            "#pragma once",
            "",
            "#include <stdint.h>  // uint8_t..uint32_t",
            "",
            "namespace mr {",
            "",
            *_cpp_constants(rig["core"]),
            "",
            "}  // namespace mr",
            "",
        ]
    )


def render_board(rig: dict) -> str:
    return "\n".join(
        [
            f"// The Uno's pin map and bus addresses (wiring: firmware/README.md). {HEADER}",
            "#pragma once",
            "",
            "#include <stdint.h>  // uint8_t, int8_t, uint32_t",
            "",
            "namespace mr {",
            "namespace board {",
            "",
            *_cpp_constants(rig["board"]),
            "",
            "}  // namespace board",
            "}  // namespace mr",
            "",
        ]
    )


def _c_pin(pin: int) -> str:
    port, bit = UNO_PINS[pin]
    return f"{{'{port}', {bit}, 0x{PORT_ADDRESS[port]:02X}}}"


def render_simavr(rig: dict) -> str:
    """C for the harness: the same hardware as the board's, placed on the ATmega328P's registers."""

    def v(key: str):
        return value(rig, key)

    pwm = [
        f"{{0x{UNO_PWM[p][1]:02X}, 1u << {UNO_PWM[p][2]}, 0x{UNO_PWM[p][3]:02X}, {_c_pin(p)}}}" for p in v("pwm_pin")
    ]
    out = [
        f"// The rig's hardware as the AVR simulator's harness plays it. {HEADER}",
        "#pragma once",
        "",
        "#include <stdint.h>  // uint8_t",
        "",
        f"#define ACTUATOR_COUNT {v('actuator_count')}",
        f"#define MUX_ADDRESS 0x{v('mux_address'):02X}     // TCA9548A",
        f"#define ENCODER_ADDRESS 0x{v('encoder_address'):02X} // AS5600",
        f"#define ANGLE_REGISTER 0x{v('encoder_angle_register'):02X}  // AS5600 ANGLE, 12 bits, high byte first",
        f"#define ENCODER_COUNTS {v('encoder_counts')}  // [counts/rev]",
        f"#define PWM_MAX {v('pwm_max')}  // a compare register's full scale",
        f"#define MOTOR_REV_PER_S {v('motor_speed_rpm') / 60.0!r}  // [rev/s] motor_speed_rpm / 60, at full drive",
        "",
        "// A pin: its port letter, bit and the port's data-space address (PORTx).",
        "typedef struct { char port; uint8_t bit; int data; } pin_t;",
        "// A PWM pin: its timer's control register, the compare-output bit that connects it, its compare register.",
        "typedef struct { int tccr; uint8_t com_bit; int ocr; pin_t pin; } pwm_pin_t;",
        "",
        f"static const pwm_pin_t kPwmPin[ACTUATOR_COUNT] = {{{', '.join(pwm)}}};"
        f"  // pins {', '.join(map(str, v('pwm_pin')))}: {', '.join(UNO_PWM[p][0] for p in v('pwm_pin'))}",
        f"static const pin_t kDirPin[ACTUATOR_COUNT] = {{{', '.join(_c_pin(p) for p in v('dir_pin'))}}};"
        f"  // pins {', '.join(map(str, v('dir_pin')))}: HIGH lowers the corner",
    ]
    for key in ("bench_pin", "probe_controller_pin", "probe_actuator_pin", "probe_loop_pin"):
        out.append(f"static const pin_t k{camel(key)} = {_c_pin(v(key))};  // D{v(key)}")
    return "\n".join(out + [""])


def render_py(rig: dict) -> str:
    out = [f'"""The rig\'s constants for the host and the simulation. {HEADER}"""', ""]
    for key, entry in rig["core"].items():
        out.append(f"{key.upper()} = {entry['value']!r}  # {_comment(entry)}")
    out += ["", "# What the firmware reports at identify (identify_reply field -> this description's value)."]
    out.append(
        "REPORTED = {"
        + ", ".join(f"{e['identify']!r}: {k.upper()}" for k, e in rig["core"].items() if "identify" in e)
        + "}"
    )
    units = {e["identify"]: e.get("unit", "") for e in rig["core"].values() if "identify" in e}
    out.append(f"REPORTED_UNITS = {units!r}")
    return "\n".join(out + [""])


def outputs(schema: dict) -> dict[Path, str]:
    rig = load_rig()
    check(rig, schema)
    return {
        CORE_OUT: render_core(rig),
        BOARD_OUT: render_board(rig),
        SIMAVR_OUT: render_simavr(rig),
        PY_OUT: render_py(rig),
    }
