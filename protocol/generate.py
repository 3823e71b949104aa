"""Generate the C++ and Python protocol code from schema.toml, the rig's constants from rig.toml (generate_rig.py)
and the C++ test vectors from vectors.json.

Usage:  python protocol/generate.py           write the generated files
        python protocol/generate.py --check   exit 1 if any generated file is stale (CI runs this)
"""

from __future__ import annotations

import argparse
import json
import math
import struct
import sys
import tomllib
import zlib
from pathlib import Path

if __package__ in (None, ""):  # run as a script (CI, setup.sh), also from a copy of the tree
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import generate_rig  # noqa: E402
    from codegen import TYPES, camel, f32_literal  # noqa: E402
else:
    from . import generate_rig
    from .codegen import TYPES, camel, f32_literal

ROOT = Path(__file__).resolve().parent.parent
SCHEMA = ROOT / "protocol" / "schema.toml"
VECTORS = ROOT / "protocol" / "vectors.json"
CPP_OUT = ROOT / "firmware" / "lib" / "core" / "protocol_gen.h"
PY_OUT = ROOT / "protocol" / "messages.py"
SPEC = ROOT / "protocol" / "PROTOCOL.md"
SPEC_BEGIN = "<!-- BEGIN GENERATED REFERENCE: protocol/generate.py writes this part from schema.toml -->"
SPEC_END = "<!-- END GENERATED REFERENCE -->"
CPP_VECTORS_OUT = ROOT / "firmware" / "tests" / "test_core" / "vectors_gen.h"

HEADER = "Generated from protocol/schema.toml by protocol/generate.py; do not edit."


def load_schema(path: Path = SCHEMA) -> dict:
    with open(path, "rb") as f:
        schema = tomllib.load(f)
    check_behaviour(schema)
    return schema


class SchemaError(Exception):
    """schema.toml names a state, axis, message or field that it does not define."""


def check_behaviour(schema: dict) -> None:
    """The message states and the controller tables name only what the schema defines, and cover all of it."""
    states = schema["enums"]["state"]["values"]
    if schema["protocol"]["state_error"] not in {e["name"] for e in schema["errors"]}:
        raise SchemaError(f"[protocol] state_error {schema['protocol']['state_error']!r} is no error")
    for msg in schema["messages"]:
        taken = msg.get("states")
        if msg["direction"] == "host_to_mcu" and not taken:
            raise SchemaError(f"message {msg['name']} lacks states (the supervisor states it is taken in)")
        if msg["direction"] != "host_to_mcu" and taken is not None:
            raise SchemaError(f"message {msg['name']} travels to the host: the firmware takes it in no state")
        if unknown := set(taken or ()) - set(states):
            raise SchemaError(f"message {msg['name']}: states {sorted(unknown)} are no enums.state values")
    controllers = schema["controllers"]
    if set(controllers) != set(schema["enums"]["controller"]["values"]):
        raise SchemaError("[controllers] must have one table per enums.controller value")
    host_messages = {msg["name"] for msg in schema["messages"] if msg["direction"] == "host_to_mcu"}
    configure = next(msg for msg in schema["messages"] if msg["name"] == "configure")
    known = {
        "axes": set(schema["enums"]["axis"]["values"]),
        "settings": host_messages,
        "configure": {f["name"] for f in configure["fields"]},
    }
    for name, table in controllers.items():
        if set(table) != {*known, "paper"} or not isinstance(table["paper"], bool):
            raise SchemaError(f"controllers.{name} must have axes, settings, configure and paper (true or false)")
        for key, allowed in known.items():
            if unknown := set(table[key]) - allowed:
                raise SchemaError(f"controllers.{name}.{key}: {sorted(unknown)} not in the schema")


def canonical(schema: dict) -> bytes:
    """The schema without its prose and its behaviour (message states, controller tables, the PIDs' boot gains): what
    two ends must agree on byte for byte. The boot gains cross no wire; identify reports them (boot_gains_crc)."""

    def strip(obj):
        if isinstance(obj, dict):
            return {k: strip(v) for k, v in obj.items() if k not in ("doc", "unit", "reply", "default", "states")}
        if isinstance(obj, list):
            return [strip(v) for v in obj]
        return obj

    layout = {k: v for k, v in schema.items() if k not in ("controllers", "pid_defaults")}
    layout["protocol"] = {k: v for k, v in schema["protocol"].items() if k != "state_error"}
    return json.dumps(strip(layout), sort_keys=True, separators=(",", ":")).encode()


def schema_hash(schema: dict) -> int:
    """CRC-32 (zlib) of the canonical schema."""
    return zlib.crc32(canonical(schema))


def boot_gains_crc(schema: dict) -> int:
    """CRC-32 (zlib) of every PID's boot gains as the firmware holds them: kp, ki, kd, integral_limit as f32
    little-endian, the PIDs in Axis order. identify_reply reports it, so a host can tell which gains a PID it does not
    set runs, without a retuned default making it refuse the board."""
    axes = sorted(schema["enums"]["axis"]["values"].items(), key=lambda kv: kv[1])
    names = ("kp", "ki", "kd", "integral_limit")
    return zlib.crc32(b"".join(struct.pack("<4f", *(schema["pid_defaults"][a][n] for n in names)) for a, _ in axes))


def payload_size(msg: dict) -> int:
    return sum(TYPES[f["type"]][0] * f.get("count", 1) for f in msg["fields"])


def enum_default(schema: dict, field: dict) -> int:
    value = field.get("default", 0)
    if isinstance(value, str):
        return schema["enums"][field["enum"]]["values"][value]
    return value


def state_mask(schema: dict, msg: dict) -> int:
    """Bit i set: the firmware takes the message in the supervisor state whose value is i."""
    values = schema["enums"]["state"]["values"]
    return sum(1 << values[state] for state in msg.get("states", ()))


def field_comment(field: dict) -> str:
    unit = f"[{field['unit']}] " if "unit" in field else ""
    extra = ""
    if "scale" in field:
        extra += f" (wire = value / {field['scale']!r})"
    if "enum" in field:
        extra += f" (enum {field['enum']})"
    if "flags" in field:
        extra += f" (flags {field['flags']})"
    return f"{unit}{field['doc']}{extra}"


# ------------------------------------------------------------------------------------------------ C++


def cpp_scalar_put(field: dict, expr: str, offset: str) -> str:
    return f"put_{field['type']}(out + {offset}, {expr});"


def cpp_scalar_get(field: dict, expr: str, offset: str) -> str:
    return f"{expr} = get_{field['type']}(in + {offset});"


def cpp_message(schema: dict, msg: dict) -> list[str]:
    name = camel(msg["name"])
    lines = [
        f"// {msg['doc']}",
        f"struct {name} {{",
        f"  static constexpr uint8_t kId = 0x{msg['id']:02X};",
        f"  static constexpr uint8_t kSize = {payload_size(msg)};  // [bytes] payload",
    ]
    for field in msg["fields"]:
        ctype = TYPES[field["type"]][1]
        dim = f"[{field['count']}]" if "count" in field else ""
        lines.append(f"  {ctype} {field['name']}{dim};  // {field_comment(field)}")
    for index, field in enumerate(msg["fields"]):  # what nack.field names, for the checks the schema cannot say
        lines.append(f"  static constexpr uint8_t kField{camel(field['name'])} = {index};")
    for field in msg["fields"]:
        if "scale" in field:
            lines.append(
                f"  static constexpr float k{camel(field['name'])}Scale = {f32_literal(field['scale'])};"
                f"  // [{field['unit']}] per wire unit"
            )
    lines.append("};")

    enc, dec = [], []
    offset = 0
    for field in msg["fields"]:
        size = TYPES[field["type"]][0]
        if "count" in field:
            for i in range(field["count"]):
                enc.append("  " + cpp_scalar_put(field, f"m.{field['name']}[{i}]", str(offset)))
                dec.append("  " + cpp_scalar_get(field, f"m.{field['name']}[{i}]", str(offset)))
                offset += size
        else:
            enc.append("  " + cpp_scalar_put(field, f"m.{field['name']}", str(offset)))
            dec.append("  " + cpp_scalar_get(field, f"m.{field['name']}", str(offset)))
            offset += size
    if msg["fields"]:
        lines.append(f"inline void encode(const {name}& m, uint8_t* out) {{")
        lines += enc
        lines.append("}")
        lines.append(f"inline void decode(const uint8_t* in, {name}& m) {{")
        lines += dec
        lines.append("}")
    else:
        lines.append(f"inline void encode(const {name}&, uint8_t*) {{}}")
        lines.append(f"inline void decode(const uint8_t*, {name}&) {{}}")

    if msg["direction"] == "host_to_mcu":
        checks = []
        for index, field in enumerate(msg["fields"]):
            ref = f"m.{field['name']}"
            if field["type"] == "f32":
                checks.append(f"  if (!is_finite({ref})) {{ field = {index}; return ErrorCode::kNotFinite; }}")
            conds = []
            if "enum" in field:
                values = schema["enums"][field["enum"]]["values"].values()
                conds.append(" && ".join(f"{ref} != {v}" for v in sorted(values)))
            fmt = f32_literal if field["type"] == "f32" else (lambda v: str(int(v)))
            if "min" in field and not (field["type"] != "f32" and field["min"] == 0):
                conds.append(f"{ref} < {fmt(field['min'])}")
            if "max" in field:
                conds.append(f"{ref} > {fmt(field['max'])}")
            if conds:
                cond = " || ".join(f"({c})" for c in conds)
                checks.append(f"  if ({cond}) {{ field = {index}; return ErrorCode::kOutOfRange; }}")
        lines.append(
            "// Field-local checks from the schema (NaN/inf, bounds, enum values); field = index of the first bad one."
        )
        sig_m = " m" if checks else " /*m*/"
        sig_f = " field" if checks else " /*field*/"
        lines.append(f"inline ErrorCode validate(const {name}&{sig_m}, uint8_t&{sig_f}) {{")
        lines += checks
        lines.append("  return ErrorCode::kOk;")
        lines.append("}")

    if any("default" in f for f in msg["fields"]):
        lines.append("// Boot values from the schema.")
        lines.append(f"inline void set_defaults({name}& m) {{")
        for field in msg["fields"]:
            if "default" not in field:
                continue
            if field["type"] == "f32":
                lines.append(f"  m.{field['name']} = {f32_literal(field['default'])};")
            else:
                lines.append(f"  m.{field['name']} = {enum_default(schema, field)};")
        lines.append("}")
    return lines


def cpp_size_switch(schema: dict, direction: str, meaning: str) -> list[str]:
    """The C++ function {direction}_size(id): the payload size of each message travelling that way."""
    lines = [
        f"// Payload size [bytes] of a message id travelling {meaning}.",
        f"inline int8_t {direction}_size(uint8_t id) {{",
        "  switch (id) {",
    ]
    lines += [
        f"    case {camel(msg['name'])}::kId: return {camel(msg['name'])}::kSize;"
        for msg in schema["messages"]
        if msg["direction"] == direction
    ]
    return lines + ["    default: return -1;", "  }", "}", ""]


def render_cpp(schema: dict) -> str:
    proto = schema["protocol"]
    out = [
        f"// {HEADER}",
        "#pragma once",
        "",
        "#include <stdint.h>  // fixed-width wire types",
        "",
        '#include "wire.h"  // put_*/get_* little-endian helpers, is_finite',
        "",
        "namespace mr {",
        "namespace proto {",
        "",
        f"constexpr uint16_t kProtocolVersion = {proto['version']};",
        f"constexpr uint32_t kSchemaHash = 0x{schema_hash(schema):08X}u;",
        f"constexpr uint32_t kBootGainsCrc = 0x{boot_gains_crc(schema):08X}u;  // of kPidDefaults, for identify",
        f"constexpr uint8_t kMaxPacket = {proto['max_packet']};  // [bytes] id + seq + payload + CRC",
        f"constexpr uint8_t kMaxWire = {proto['max_wire']};  // [bytes] COBS packet + delimiter",
        "constexpr uint8_t kNoField = 255;  // nack.field when no single field is at fault",
        "",
        "enum class ErrorCode : uint8_t {",
        "  kOk = 0,",
    ]
    for err in schema["errors"]:
        out.append(f"  k{camel(err['name'])} = {err['code']},  // {err['doc']}")
    out.append("};")
    out.append(
        f"constexpr uint8_t kLastErrorCode = {max(e['code'] for e in schema['errors'])};  // nack.code is 1..this"
    )
    most = max(len(msg["fields"]) for msg in schema["messages"] if msg["direction"] == "host_to_mcu")
    out.append(
        f"constexpr uint8_t kMostFields = {most};  // fields of the widest host -> MCU message: nack.field "
        f"is below this or kNoField"
    )
    out.append("")
    for name, enum in schema["enums"].items():
        out.append(f"// {enum['doc']}")
        out.append(f"enum class {camel(name)} : uint8_t {{")
        for vname, value in enum["values"].items():
            out.append(f"  k{camel(vname)} = {value},")
        out.append("};")
        out.append(
            f"constexpr uint8_t k{camel(name)}Count = {max(enum['values'].values()) + 1};  // values 0..this - 1"
        )
        out.append("")
    for name, flags in schema["flags"].items():
        out.append(f"// {flags['doc']}")
        out.append(f"namespace {name} {{")
        for vname, bit in flags["values"].items():
            out.append(f"constexpr uint16_t k{camel(vname)} = 1u << {bit};")
        out.append(f"}}  // namespace {name}")
        out.append("")
    out.append(
        "// Boot gains of each PID, indexed by Axis: {kp [deg/m], ki [deg/(m s)], kd [deg s/m], integral_limit [deg]}."
    )
    out.append("struct PidDefaults { float kp, ki, kd, integral_limit; };")
    out.append("constexpr PidDefaults kPidDefaults[] = {")
    for axis, _ in sorted(schema["enums"]["axis"]["values"].items(), key=lambda kv: kv[1]):
        g = schema["pid_defaults"][axis]
        out.append(
            f"    {{{f32_literal(g['kp'])}, {f32_literal(g['ki'])}, {f32_literal(g['kd'])}, "
            f"{f32_literal(g['integral_limit'])}}},  // {axis}"
        )
    out.append("};")
    out.append("")
    for msg in schema["messages"]:
        out += cpp_message(schema, msg)
        out.append("")
    out += cpp_size_switch(schema, "host_to_mcu", "host -> MCU, or -1 if the MCU handles no such id")
    out += cpp_size_switch(schema, "mcu_to_host", "MCU -> host, or -1 if the MCU sends no such id")
    groups: dict[int, list[dict]] = {}  # kStates -> the messages with it
    for msg in schema["messages"]:
        if msg["direction"] == "host_to_mcu":
            if msg["id"] >= 32:
                raise SchemaError(f"message {msg['name']}: a host -> MCU id must be below 32 (a bit of a uint32_t)")
            groups.setdefault(state_mask(schema, msg), []).append(msg)
    out += [
        "// Supervisor states a host -> MCU message is taken in (bit i: State i); 0 for an id the MCU handles not.",
        "// Bit tests on the id, not a switch: avr-gcc would make that a lookup table in the Uno's RAM.",
        "inline uint8_t host_to_mcu_states(uint8_t id) {",
        "  if (id >= 32) return 0;",
        "  const uint32_t bit = static_cast<uint32_t>(1) << id;",
    ]
    for mask, msgs in groups.items():
        ids = sum(1 << msg["id"] for msg in msgs)
        names = ", ".join(msg["name"] for msg in msgs)
        out.append(f"  if (bit & 0x{ids:08X}u) return 0x{mask:02X};  // {names}")
    out += ["  return 0;", "}", ""]
    out += [
        "// nack.code of a command sent in a state its message is not taken in, before any field is looked at.",
        f"constexpr ErrorCode kStateError = ErrorCode::k{camel(proto['state_error'])};",
        "// Whether the firmware takes message id in state (schema.toml, the message's states).",
        "inline bool taken_in(uint8_t id, State state) {",
        "  return (host_to_mcu_states(id) >> static_cast<uint8_t>(state)) & 1u;",
        "}",
        "",
    ]
    host_ids = ", ".join(
        f"{camel(msg['name'])}::kId" for msg in schema["messages"] if msg["direction"] == "host_to_mcu"
    )
    out.append(
        "// Every message id travelling host -> MCU, in schema order (for the fuzzer and the tests: no hand-kept list)."
    )
    out.append(f"constexpr uint8_t kHostToMcuIds[] = {{{host_ids}}};")
    out += ["", "}  // namespace proto", "}  // namespace mr", ""]
    return "\n".join(out)


# --------------------------------------------------------------------------------------------- Python


def py_default(schema: dict, field: dict) -> str:
    if "enum" in field:
        enum = schema["enums"][field["enum"]]
        value = enum_default(schema, field)
        member = next(k for k, v in enum["values"].items() if v == value) if value in enum["values"].values() else None
        return f"{camel(field['enum'])}.{member.upper()}" if member else str(value)
    if "flags" in field:
        return f"{camel(field['flags'])}(0)"
    if "count" in field:
        zero = "0.0" if field["type"] == "f32" or "scale" in field else "0"
        return "(" + ", ".join([zero] * field["count"]) + ")"
    if "default" in field:
        return repr(float(field["default"])) if field["type"] == "f32" else str(int(field["default"]))
    return "0.0" if field["type"] == "f32" or "scale" in field else "0"


def py_annotation(field: dict) -> str:
    base = "float" if field["type"] == "f32" or "scale" in field else "int"
    if "enum" in field:
        base = camel(field["enum"])
    if "flags" in field:
        base = camel(field["flags"])
    return f"tuple[{base}, ...]" if "count" in field else base


def render_py(schema: dict) -> str:
    proto = schema["protocol"]
    out = [
        f'"""Protocol messages, enums and error codes. {HEADER}"""',
        "",
        "from __future__ import annotations",
        "",
        "import enum",
        "from dataclasses import dataclass",
        "from typing import ClassVar",
        "",
        "from .codec import FieldSpec, Message",
        "",
        f"PROTOCOL_VERSION = {proto['version']}",
        f"SCHEMA_HASH = 0x{schema_hash(schema):08X}",
        f"BOOT_GAINS_CRC = 0x{boot_gains_crc(schema):08X}  # of PID_DEFAULTS, as identify_reply reports the board's",
        f"MAX_PACKET = {proto['max_packet']}  # [bytes] id + seq + payload + CRC",
        f"MAX_WIRE = {proto['max_wire']}  # [bytes] COBS packet + delimiter",
        "NO_FIELD = 255",
        "",
        "",
        "class ErrorCode(enum.IntEnum):",
        '    """nack.code values."""',
        "",
        "    OK = 0",
    ]
    for err in schema["errors"]:
        out.append(f"    {err['name'].upper()} = {err['code']}")
    out += ["", "", "ERROR_DOCS = {"]
    for err in schema["errors"]:
        out.append(f"    ErrorCode.{err['name'].upper()}: {err['doc']!r},")
    out.append("}")
    for name, enum in schema["enums"].items():
        out += ["", "", f"class {camel(name)}(enum.IntEnum):", f'    """{enum["doc"]}"""', ""]
        for vname, value in enum["values"].items():
            out.append(f"    {vname.upper()} = {value}")
    for name, flags in schema["flags"].items():
        out += ["", "", f"class {camel(name)}(enum.IntFlag):", f'    """{flags["doc"]}"""', ""]
        for vname, bit in flags["values"].items():
            out.append(f"    {vname.upper()} = 1 << {bit}")
    out += [
        "",
        "",
        "# Boot gains of each PID: kp [deg/m], ki [deg/(m s)], kd [deg s/m], integral_limit [deg].",
        "PID_DEFAULTS = {",
    ]
    for axis in schema["enums"]["axis"]["values"]:
        g = schema["pid_defaults"][axis]
        out.append(
            f"    Axis.{axis.upper()}: {{'kp': {g['kp']!r}, 'ki': {g['ki']!r}, 'kd': {g['kd']!r}, "
            f"'integral_limit': {g['integral_limit']!r}}},"
        )
    out.append("}")
    names = []
    for msg in schema["messages"]:
        cls = camel(msg["name"])
        names.append(cls)
        out += [
            "",
            "",
            "@dataclass(frozen=True)",
            f"class {cls}(Message):",
            f'    """{msg["doc"]}"""',
            "",
            f"    ID: ClassVar[int] = 0x{msg['id']:02X}",
            f"    NAME: ClassVar[str] = {msg['name']!r}",
            f"    DIRECTION: ClassVar[str] = {msg['direction']!r}",
            f"    REPLY: ClassVar[str | None] = {msg.get('reply')!r}",
            f"    SIZE: ClassVar[int] = {payload_size(msg)}  # [bytes] payload",
            "    STATES: ClassVar[frozenset[int]] = "
            + (
                "frozenset({" + ", ".join(f"State.{s.upper()}" for s in msg["states"]) + "})"
                if "states" in msg
                else "frozenset()"
            ),
            "    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (",
        ]
        for field in msg["fields"]:
            kind = camel(field["enum"]) if "enum" in field else camel(field["flags"]) if "flags" in field else "None"
            out.append(
                f"        FieldSpec({field['name']!r}, {TYPES[field['type']][2]!r}, {field.get('count', 1)}, "
                f"{field.get('scale')!r}, {kind}, {field.get('min')!r}, {field.get('max')!r}, "
                f"{field.get('unit', '')!r}),"
            )
        out.append("    )")
        if msg["fields"]:
            out.append("")
        for field in msg["fields"]:
            out.append(
                f"    {field['name']}: {py_annotation(field)} = {py_default(schema, field)}  # {field_comment(field)}"
            )
    out += ["", "", "MESSAGES: dict[int, type[Message]] = {m.ID: m for m in (" + ", ".join(names) + ")}"]
    out += py_controllers(schema)
    return "\n".join(out)


def py_controllers(schema: dict) -> list[str]:
    """The [controllers] tables, and the nack.code of a command outside its message's STATES."""
    controllers = schema["controllers"]
    settings = [
        msg["name"] for msg in schema["messages"] if any(msg["name"] in c["settings"] for c in controllers.values())
    ]
    paper = [
        a for a in schema["enums"]["axis"]["values"] if any(a in c["axes"] for c in controllers.values() if c["paper"])
    ]

    def py_tuple(items: list[str]) -> str:
        return f"({items[0]},)" if len(items) == 1 else "(" + ", ".join(items) + ")"

    def axes(names) -> str:
        return py_tuple([f"Axis.{a.upper()}" for a in names])

    def classes(names) -> str:
        return py_tuple([camel(n) for n in names])

    def strings(names) -> str:
        return py_tuple([repr(n) for n in names])

    out = [
        "",
        f"STATE_ERROR = ErrorCode.{schema['protocol']['state_error'].upper()}  # nack.code outside a message's STATES",
        "",
        "# What each controller reads (schema.toml, [controllers]): the PIDs it runs, the messages with its own settings,",
        "# the configure fields that are its settings.",
        "CONTROLLER_AXES: dict[Controller, tuple[Axis, ...]] = {",
    ]
    out += [f"    Controller.{name.upper()}: {axes(c['axes'])}," for name, c in controllers.items()]
    out += ["}", "CONTROLLER_SETTINGS: dict[Controller, tuple[type[Message], ...]] = {"]
    out += [f"    Controller.{name.upper()}: {classes(c['settings'])}," for name, c in controllers.items()]
    out += ["}", "CONTROLLER_CONFIGURE: dict[Controller, tuple[str, ...]] = {"]
    out += [f"    Controller.{name.upper()}: {strings(c['configure'])}," for name, c in controllers.items()]
    out += [
        "}",
        f"SETTINGS_MESSAGES: tuple[type[Message], ...] = {classes(settings)}  # every controller's, in schema order",
        f"PAPER_AXES: tuple[Axis, ...] = {axes(paper)}  # the PIDs of the paper's controllers, whose gains it gives",
        "",
    ]
    return out


# ------------------------------------------------------------------------------- PROTOCOL.md reference


def md_bounds(field: dict) -> str:
    parts = []
    if "min" in field or "max" in field:
        parts.append(f"{field.get('min', '')} .. {field.get('max', '')}")
    if "default" in field:
        parts.append(f"default {field['default']}")
    return "; ".join(parts)


def render_md(schema: dict) -> str:
    out = [
        SPEC_BEGIN,
        "",
        f"Schema hash of this version: `0x{schema_hash(schema):08X}`.",
        "",
        "### Error codes (`nack.code`)",
        "",
        "| code | name | meaning |",
        "|---|---|---|",
    ]
    for err in schema["errors"]:
        out.append(f"| {err['code']} | `{err['name']}` | {err['doc']} |")
    out += ["", "### Enums and flags", ""]
    for name, enum in schema["enums"].items():
        values = ", ".join(f"{v} = `{k}`" for k, v in enum["values"].items())
        out.append(f"- **{name}** ({enum['doc']}): {values}")
    for name, flags in schema["flags"].items():
        values = ", ".join(f"bit {v} = `{k}`" for k, v in flags["values"].items())
        out.append(f"- **{name}** ({flags['doc']}): {values}")
    out += [
        "",
        "### Messages",
        "",
        "Offsets are into the payload (after id and seq); all fields little-endian; f32 is IEEE-754 binary32.",
        "A scaled field carries round(value / scale) saturated to its integer range.",
        "",
    ]
    for msg in schema["messages"]:
        arrow = "host → firmware" if msg["direction"] == "host_to_mcu" else "firmware → host"
        reply = f"; answered by `{msg['reply']}`" if "reply" in msg else ""
        taken = ""
        if len(msg.get("states", ())) == len(schema["enums"]["state"]["values"]):
            taken = " Taken in every state."
        elif "states" in msg:
            taken = (
                f" Taken in {', '.join(f'`{s}`' for s in msg['states'])}; in any other state refused with "
                f"`{schema['protocol']['state_error']}`."
            )
        size = payload_size(msg)
        out += [
            f"#### `{msg['name']}` — id 0x{msg['id']:02X}, {arrow}{reply}",
            "",
            f"{msg['doc']}{taken} Payload {size} bytes; frame on the wire {cobs_wire_size(size)} bytes.",
            "",
        ]
        if not msg["fields"]:
            continue
        out += ["| offset | field | type | unit | scale | bounds, default | meaning |", "|---|---|---|---|---|---|---|"]
        offset = 0
        for field in msg["fields"]:
            count = field.get("count", 1)
            ftype = field["type"] + (f"[{count}]" if count > 1 else "")
            kind = (
                f" (enum `{field['enum']}`)"
                if "enum" in field
                else f" (flags `{field['flags']}`)"
                if "flags" in field
                else ""
            )
            out.append(
                f"| {offset} | `{field['name']}` | {ftype} | {field.get('unit', '')} | {field.get('scale', '')} | "
                f"{md_bounds(field)} | {field['doc']}{kind} |"
            )
            offset += TYPES[field["type"]][0] * count
        out.append("")
    out.append(SPEC_END)
    return "\n".join(out)


def cobs_wire_size(payload: int) -> int:
    """[bytes] on the wire: id + seq + payload + CRC, one COBS code byte (packets < 254 bytes), delimiter."""
    return payload + 4 + 1 + 1


def splice_spec(text: str, reference: str) -> str:
    if SPEC_BEGIN not in text or SPEC_END not in text:
        raise SystemExit(f"{SPEC} lacks the generated-reference markers")
    head, rest = text.split(SPEC_BEGIN, 1)
    tail = rest.split(SPEC_END, 1)[1]
    return head + reference + tail


# ------------------------------------------------------------------------------------- C++ test vectors


def cpp_field_checks(schema: dict, msg: dict, fields: dict) -> list[str]:
    checks = []
    for field in msg["fields"]:
        values = fields[field["name"]]
        values = values if "count" in field else [values]
        for i, value in enumerate(values):
            ref = f"m.{field['name']}" + (f"[{i}]" if "count" in field else "")
            if "enum" in field and isinstance(value, str):
                value = schema["enums"][field["enum"]]["values"][value]
            if field["type"] == "f32":
                value = float(value)
                if math.isnan(value):
                    checks.append(f"{ref} != {ref}")
                else:
                    checks.append(f"{ref} == {f32_literal(value)}")
            elif "scale" in field:
                checks.append(f"{ref} == {round(value / field['scale'])}")
            else:
                checks.append(f"{ref} == {int(value)}u" if int(value) >= 0 else f"{ref} == {int(value)}")
    return checks


def render_cpp_vectors(schema: dict, vectors: list[dict]) -> str:
    by_name = {m["name"]: m for m in schema["messages"]}
    out = [
        f"// Test vectors from protocol/vectors.json. {HEADER}",
        "#pragma once",
        "",
        "#include <stdint.h>  // uint8_t",
        "",
        '#include "protocol_gen.h"  // message structs and decode()',
        "",
        "namespace vectors {",
        "",
        "enum class Yield : uint8_t { kFrame, kCrcError, kFrameError };",
        "",
        "struct Expected {",
        "  Yield yield;",
        "  uint8_t id, seq;",
        "  const uint8_t* payload;",
        "  uint8_t payload_len;",
        "  bool (*fields_ok)(const uint8_t* payload);  // null when the vector names no fields",
        "};",
        "",
        "struct Vector {",
        "  const char* name;",
        "  const uint8_t* wire;",
        "  uint16_t wire_len;",
        "  const Expected* expected;",
        "  uint8_t expected_len;",
        "};",
        "",
    ]
    table = []
    for vi, vec in enumerate(vectors):
        wire = bytes.fromhex(vec["wire"])
        out.append(f"// {vec['name']}")
        out.append(f"const uint8_t wire_{vi}[] = {{{', '.join(f'0x{b:02X}' for b in wire) or '0'}}};")
        exp_rows = []
        for yi, y in enumerate(vec["yields"]):
            if y["yield"] == "frame":
                payload = bytes.fromhex(y["payload"])
                out.append(
                    f"const uint8_t payload_{vi}_{yi}[] = {{{', '.join(f'0x{b:02X}' for b in payload) or '0'}}};"
                )
                check = "nullptr"
                if "fields" in y:
                    msg = by_name[y["message"]]
                    checks = cpp_field_checks(schema, msg, y["fields"])
                    out.append(f"inline bool fields_ok_{vi}_{yi}(const uint8_t* p) {{")
                    out.append(f"  mr::proto::{camel(msg['name'])} m;")
                    out.append("  mr::proto::decode(p, m);")
                    out.append("  return " + (" &&\n         ".join(checks) if checks else "true") + ";")
                    out.append("}")
                    check = f"fields_ok_{vi}_{yi}"
                exp_rows.append(
                    f"{{Yield::kFrame, 0x{y['id']:02X}, {y['seq']}, payload_{vi}_{yi}, {len(payload)}, {check}}}"
                )
            else:
                kind = {"crc_error": "kCrcError", "frame_error": "kFrameError"}[y["yield"]]
                exp_rows.append(f"{{Yield::{kind}, 0, 0, nullptr, 0, nullptr}}")
        if exp_rows:
            out.append(f"const Expected expected_{vi}[] = {{{', '.join(exp_rows)}}};")
        table.append(
            f"    {{{json.dumps(vec['name'])}, wire_{vi}, {len(wire)}, "
            f"{f'expected_{vi}' if exp_rows else 'nullptr'}, {len(exp_rows)}}},"
        )
        out.append("")
    out.append("const Vector kAll[] = {")
    out += table
    out.append("};")
    out += ["", "}  // namespace vectors", ""]
    return "\n".join(out)


def outputs() -> dict[Path, str]:
    schema = load_schema()
    files = {
        CPP_OUT: render_cpp(schema),
        PY_OUT: render_py(schema),
        SPEC: splice_spec(SPEC.read_text(), render_md(schema)),
        **generate_rig.outputs(schema),
    }
    if VECTORS.exists():
        try:
            files[CPP_VECTORS_OUT] = render_cpp_vectors(schema, json.loads(VECTORS.read_text())["vectors"])
        except KeyError as exc:  # a field the schema gained: make_vectors.py writes it, from messages.py
            raise StaleVectors(
                f"vectors.json has no field {exc} the schema now has (messages.py and protocol_gen.h are "
                f"written): "
                f"run python protocol/make_vectors.py, then this again"
            ) from None
    return files


class StaleVectors(Exception):
    """vectors.json predates a schema change (a new field); the code it is generated from must come first."""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--check", action="store_true", help="fail if a generated file differs from the schema")
    args = parser.parse_args(argv)
    stale = []
    try:
        files = outputs()
    except generate_rig.RigDescriptionError as exc:
        print(exc, file=sys.stderr)
        return 1
    except StaleVectors as exc:
        if not args.check:
            schema = load_schema()
            PY_OUT.write_text(render_py(schema))
            CPP_OUT.write_text(render_cpp(schema))
        print(exc, file=sys.stderr)
        return 1
    for path, text in files.items():
        if args.check:
            if not path.exists() or path.read_text() != text:
                stale.append(path.relative_to(ROOT))
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text)
    if stale:
        print(
            "stale generated files (run: python protocol/generate.py): " + ", ".join(map(str, stale)), file=sys.stderr
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
