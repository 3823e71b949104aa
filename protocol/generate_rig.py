"""Write each committed rig's constants (firmware core, board pins, AVR simulator harness) from its rig file.

Called by protocol/generate.py, which writes every generated file and checks them in CI. protocol/rig.py reads and
checks every committed rig file (protocol/rig.toml, protocol/rigs/*.toml); here each is also checked against
schema.toml's rig-derived defaults and bounds (RigDescriptionError says what disagrees). A rig's headers go to
firmware/rigs/NAME/ (NAME: "module" for the default rig, else the file's stem), which its builds put on the include
path: rig_gen.h for the core, board_gen.h for the board layer (firmware/arduino), simavr_gen.h for the harness.
"""

from __future__ import annotations

import math
from pathlib import Path

if __package__ in (None, ""):
    from codegen import TYPES, camel, f32_literal
    from rig import MAX_ACTUATORS, ONE_OR_PER_ACTUATOR, RigDescription, RigDescriptionError, committed
else:
    from .codegen import TYPES, camel, f32_literal
    from .rig import MAX_ACTUATORS, ONE_OR_PER_ACTUATOR, RigDescription, RigDescriptionError, committed

__all__ = ["RigDescriptionError", "check_schema", "outputs"]

ROOT = Path(__file__).resolve().parent.parent
RIGS_OUT = ROOT / "firmware" / "rigs"  # one folder per rig


def _header(rig: RigDescription) -> str:
    source = rig.path.resolve().relative_to(ROOT).as_posix()
    return f"Generated from {source} by protocol/generate.py; do not edit."


def _fields(schema: dict, message: str) -> dict:
    return {f["name"]: f for m in schema["messages"] if m["name"] == message for f in m["fields"]}


def check_schema(rig: RigDescription, schema: dict) -> None:
    """The rig's reported constants are identify_reply fields; schema.toml's defaults and bounds that follow from a
    rig (the module size, the tilt limit atan(range / ((m + n) / 2)), the noise bound, the actuators jog and zero
    address) agree with it. Raises RigDescriptionError on the first disagreement."""
    where = rig.path.name
    reply = _fields(schema, "identify_reply")
    for key, entry in rig.core.items():
        name = entry.get("identify")
        if name is not None and (name not in reply or reply[name]["type"] != entry["type"]):
            raise RigDescriptionError(
                f"{where} {key}: identify_reply has no {entry['type']} field {name!r} (schema.toml)"
            )
    configure = _fields(schema, "configure")
    mx, my, travel = rig.module_size_x_m, rig.module_size_y_m, rig.actuator_range_m
    tilt_deg = round(math.degrees(math.atan(travel / ((mx + my) / 2))), 6)
    for field, key, expected in (
        ("module_x", "default", mx),
        ("module_y", "default", my),
        ("tilt_limit", "default", tilt_deg),
        ("noise_amplitude", "max", travel),
    ):
        if configure[field][key] != expected:
            raise RigDescriptionError(
                f"schema.toml configure.{field} {key} is {configure[field][key]}; {where} makes it {expected}"
            )
    jog, zero = _fields(schema, "jog")["actuator"], _fields(schema, "zero")["actuators"]
    if jog["max"] != MAX_ACTUATORS - 1 or TYPES[zero["type"]][0] * 8 != MAX_ACTUATORS:
        raise RigDescriptionError(
            f"schema.toml jog.actuator and zero.actuators must address {MAX_ACTUATORS} actuators (protocol/rig.py)"
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
        if key in ONE_OR_PER_ACTUATOR:  # one accessor, whether the rig gives one value or one per actuator
            each = isinstance(v, list)
            value = f"k{camel(key)}[actuator]" if each else f"k{camel(key)}"
            out.append(f"constexpr {ctype} {key}(uint8_t{' actuator' if each else ''}) {{ return {value}; }}")
            distinct = len(set(v)) if isinstance(v, list) else 1
            out.append(f"constexpr uint8_t k{camel(key)}Count = {distinct};  // distinct values")
    return out


def render_core(rig: RigDescription) -> str:
    return "\n".join(
        [
            f"// The rig's constants every build of the firmware core shares ({rig.describe()}). {_header(rig)}",
            "#pragma once",
            "",
            "#include <stdint.h>  // uint8_t..uint32_t",
            "",
            "namespace mr {",
            "",
            *_cpp_constants(rig.core),
            "",
            "}  // namespace mr",
            "",
        ]
    )


def render_board(rig: RigDescription) -> str:
    return "\n".join(
        [
            f"// The {rig.board.name}'s pin map and bus addresses (wiring: firmware/README.md). {_header(rig)}",
            "#pragma once",
            "",
            "#include <stdint.h>  // uint8_t, int8_t, uint32_t",
            "",
            "namespace mr {",
            "namespace board {",
            "",
            *_cpp_constants(rig.board_entries),
            "",
            "}  // namespace board",
            "}  // namespace mr",
            "",
        ]
    )


def render_simavr(rig: RigDescription) -> str:
    """C for the harness: the same hardware as the board's, placed on its MCU's registers."""
    v, board = rig.value, rig.board

    def c_pin(pin: int) -> str:
        port, bit = board.pins[pin]
        return f"{{'{port}', {bit}, 0x{board.port_address[port]:02X}}}"

    def c_pwm(pin: int) -> str:
        t = board.timer_outputs[board.pwm[pin]]
        return f"{{0x{t.tccr:02X}, 1u << {t.com_bit}, 0x{t.ocr:02X}, {c_pin(pin)}}}"

    count = rig.actuator_count
    mux = v("mux_address") if isinstance(v("mux_address"), list) else [v("mux_address")] * count
    out = [
        f"// The rig's hardware as the AVR simulator's harness plays it. {_header(rig)}",
        "#pragma once",
        "",
        "#include <stdint.h>  // uint8_t",
        "",
        f'#define MCU_NAME "{board.mcu}"',
        f"#define ACTUATOR_COUNT {count}",
        f"#define ENCODER_ADDRESS 0x{v('encoder_address'):02X} // AS5600",
        f"#define ANGLE_REGISTER 0x{v('encoder_angle_register'):02X}  // AS5600 ANGLE, 12 bits, high byte first",
        f"#define ENCODER_COUNTS {v('encoder_counts')}  // [counts/rev]",
        f"#define PWM_MAX {v('pwm_max')}  // a compare register's full scale",
        f"#define MOTOR_REV_PER_S {rig.motor_speed_rpm / 60.0!r}  // [rev/s] motor_speed_rpm / 60, at full drive",
        "",
        "// A pin: its port letter, bit and the port's data-space address (PORTx).",
        "typedef struct { char port; uint8_t bit; int data; } pin_t;",
        "// A PWM pin: its timer's control register, the compare-output bit that connects it, its compare register.",
        "typedef struct { int tccr; uint8_t com_bit; int ocr; pin_t pin; } pwm_pin_t;",
        "",
        f"static const pwm_pin_t kPwmPin[ACTUATOR_COUNT] = {{{', '.join(c_pwm(p) for p in v('pwm_pin'))}}};"
        f"  // pins {', '.join(map(str, v('pwm_pin')))}: {', '.join(board.pwm[p] for p in v('pwm_pin'))}",
        f"static const pin_t kDirPin[ACTUATOR_COUNT] = {{{', '.join(c_pin(p) for p in v('dir_pin'))}}};"
        f"  // pins {', '.join(map(str, v('dir_pin')))}: HIGH lowers the corner",
        f"static const uint8_t kMuxAddress[ACTUATOR_COUNT] = {{{', '.join(f'0x{a:02X}' for a in mux)}}};  // TCA9548A",
        f"static const uint8_t kMuxChannel[ACTUATOR_COUNT] = {{{', '.join(map(str, v('mux_channel')))}}};",
    ]
    for key in ("bench_pin", "probe_controller_pin", "probe_actuator_pin", "probe_loop_pin"):
        out.append(f"static const pin_t k{camel(key)} = {c_pin(v(key))};  // D{v(key)}")
    return "\n".join(out + [""])


def outputs(schema: dict) -> dict[Path, str]:
    out = {}
    for rig in committed():
        check_schema(rig, schema)
        folder = RIGS_OUT / rig.name
        out[folder / "rig_gen.h"] = render_core(rig)
        out[folder / "board_gen.h"] = render_board(rig)
        out[folder / "simavr_gen.h"] = render_simavr(rig)
    return out
