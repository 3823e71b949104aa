"""Payload codec: turns a message dataclass into payload bytes and back, driven by the generated FIELDS tables."""

from __future__ import annotations

import enum
import math
import struct
from dataclasses import dataclass
from dataclasses import fields as dc_fields
from typing import Any, ClassVar

F32_MAX = 3.4028234663852886e38
INT_RANGES = {"B": (0, 0xFF), "H": (0, 0xFFFF), "I": (0, 0xFFFFFFFF), "h": (-0x8000, 0x7FFF)}


class CodecError(ValueError):
    """A payload or value that cannot be encoded or decoded."""


def choices(kind: type[enum.Enum]) -> list[str]:
    """An enum's member names as the command lines, the JSON and the error messages spell them: lower case."""
    return [member.name.lower() for member in kind]


def bounds_text(message: type[Message], field: str) -> str:
    """A field's bounds as the schema declares them, for help texts: "0.001..0.5 m"."""
    spec = next(f for f in message.FIELDS if f.name == field)
    unit = f" {spec.unit}" if spec.unit else ""
    return f"{spec.min:g}..{spec.max:g}{unit}"


class FieldRefused(ValueError):
    """A field the firmware would refuse by the schema's field-local rules; code and field as its nack would say."""

    def __init__(self, message: Message, field: str, code: str, text: str) -> None:
        self.message_name, self.field, self.code = message.NAME, field, code  # code: not_finite | out_of_range
        self.reason = text
        super().__init__(f"{message.NAME}.{field}: {text}")


@dataclass(frozen=True)
class FieldSpec:
    """One field of a message as the schema defines it."""

    name: str
    fmt: str  # struct format character of one wire element
    count: int  # 1, or the length of a fixed array
    scale: float | None  # wire integer * scale = value [unit]
    kind: Any  # IntEnum / IntFlag class, or None
    min: float | None
    max: float | None
    unit: str


def _to_wire(spec: FieldSpec, value: Any) -> int | float:
    """One element in physical units -> the number struct packs (saturating, never raising on range)."""
    if spec.fmt == "f":
        value = float(value)
        if math.isfinite(value) and abs(value) > F32_MAX:
            return math.copysign(math.inf, value)
        return value
    if spec.scale is not None:
        value = float(value)
        if math.isnan(value):
            raise CodecError(f"{spec.name}: NaN cannot be sent in a scaled integer field")
        value = round(value / spec.scale) if math.isfinite(value) else math.copysign(1 << 40, value)
    lo, hi = INT_RANGES[spec.fmt]
    value = int(value)
    if spec.scale is not None:
        return min(max(value, lo), hi)
    if not lo <= value <= hi:
        raise CodecError(f"{spec.name}: {value} does not fit the wire type (range {lo}..{hi})")
    return value


def _as_f32(value: float) -> float:
    return struct.unpack("<f", struct.pack("<f", value))[0] if math.isfinite(value) and abs(value) <= F32_MAX else value


def _field_refusal(spec: FieldSpec, value: Any) -> tuple[str, str] | None:
    """(code, why) when the firmware's generated validate() refuses this element, else None.

    The same rules, in the same order, as protocol/generate.py writes into protocol_gen.h: an f32 must be finite,
    an enum value must be one of the enum's, and the value must lie within min..max (compared as float32)."""
    unit = f" {spec.unit}" if spec.unit else ""
    if spec.fmt == "f":
        value = float(value)
        if not math.isfinite(value):
            return "not_finite", f"must be a finite number, got {value}"
        value = _as_f32(value)
    if isinstance(spec.kind, type) and issubclass(spec.kind, enum.IntEnum) and not issubclass(spec.kind, enum.IntFlag):
        if int(value) not in spec.kind._value2member_map_:
            return "out_of_range", f"must be one of {', '.join(k.name.lower() for k in spec.kind)}, got {value!r}"
    lo = None if spec.min is None else (_as_f32(spec.min) if spec.fmt == "f" else spec.min)
    hi = None if spec.max is None else (_as_f32(spec.max) if spec.fmt == "f" else spec.max)
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        bounds = (
            f"{spec.min:g}..{spec.max:g}"
            if lo is not None and hi is not None
            else (f">= {spec.min:g}" if lo is not None else f"<= {spec.max:g}")
        )
        return "out_of_range", f"{value:g}{unit} is outside {bounds}{unit}"
    return None


def _from_wire(spec: FieldSpec, raw: int | float) -> Any:
    if spec.scale is not None:
        return raw * spec.scale
    if spec.kind is not None:
        try:
            return spec.kind(raw)
        except ValueError:
            return raw  # an unknown enum value from the other end stays a plain int
    return raw


class Message:
    """Base of every generated message: payload encoding by the FIELDS table."""

    ID: ClassVar[int]
    NAME: ClassVar[str]
    DIRECTION: ClassVar[str]
    REPLY: ClassVar[str | None]
    SIZE: ClassVar[int]
    FIELDS: ClassVar[tuple[FieldSpec, ...]]
    STATES: ClassVar[frozenset[int]]  # supervisor states (State values) the firmware takes it in; empty: MCU -> host

    @classmethod
    def struct_format(cls) -> str:
        return "<" + "".join(f.fmt * f.count for f in cls.FIELDS)

    def encode_payload(self) -> bytes:
        values: list[int | float] = []
        for spec in self.FIELDS:
            value = getattr(self, spec.name)
            elements = list(value) if spec.count > 1 else [value]
            if len(elements) != spec.count:
                raise CodecError(f"{spec.name}: expected {spec.count} values, got {len(elements)}")
            values += [_to_wire(spec, v) for v in elements]
        return struct.pack(self.struct_format(), *values)

    def check(self) -> Message:
        """Raise FieldRefused for the first field the firmware would refuse by the schema alone (bounds, finiteness,
        enum values); returns the message. Rules across fields (PROTOCOL.md) stay the firmware's to judge."""
        for spec in self.FIELDS:
            value = getattr(self, spec.name)
            for element in list(value) if spec.count > 1 else [value]:
                refusal = _field_refusal(spec, element)
                if refusal is not None:
                    raise FieldRefused(self, spec.name, *refusal)
        return self

    @classmethod
    def decode_payload(cls, payload: bytes) -> Message:
        if len(payload) != cls.SIZE:
            raise CodecError(f"{cls.NAME}: payload is {len(payload)} bytes, expected {cls.SIZE}")
        raw = struct.unpack(cls.struct_format(), payload)
        kwargs, i = {}, 0
        for spec in cls.FIELDS:
            elements = [_from_wire(spec, r) for r in raw[i : i + spec.count]]
            kwargs[spec.name] = tuple(elements) if spec.count > 1 else elements[0]
            i += spec.count
        return cls(**kwargs)

    def as_dict(self) -> dict[str, Any]:
        """Field values as plain JSON-friendly Python values (enum members by name, flag sets as ints)."""
        out = {}
        for f in dc_fields(self):  # type: ignore[arg-type]  # every Message subclass is a dataclass
            value = getattr(self, f.name)
            if isinstance(value, enum.IntFlag):
                value = int(value)
            elif isinstance(value, enum.IntEnum):
                value = value.name.lower()
            out[f.name] = list(value) if isinstance(value, tuple) else value
        return out
