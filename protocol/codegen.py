"""What the two code generators (generate.py for the protocol, generate_rig.py for the rig) write alike: types, names, literals."""

from __future__ import annotations

import math

# wire type -> (size [bytes], C++ type, struct format char)
TYPES = {
    "u8": (1, "uint8_t", "B"),
    "i8": (1, "int8_t", "b"),
    "u16": (2, "uint16_t", "H"),
    "u32": (4, "uint32_t", "I"),
    "i16": (2, "int16_t", "h"),
    "f32": (4, "float", "f"),
}


def camel(name: str) -> str:
    return "".join(p.capitalize() for p in name.split("_"))


def f32_literal(value: float) -> str:
    if math.isnan(value):
        return "(0.0f / 0.0f)"
    if math.isinf(value):
        return "(1.0f / 0.0f)" if value > 0 else "(-1.0f / 0.0f)"
    return f"{float(value)!r}f"
