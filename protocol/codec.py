"""Payload codec: turns a message dataclass into payload bytes and back, driven by the generated FIELDS tables."""
from __future__ import annotations

import enum
import math
import struct
from dataclasses import dataclass, fields as dc_fields
from typing import Any, ClassVar

F32_MAX = 3.4028234663852886e38
INT_RANGES = {"B": (0, 0xFF), "H": (0, 0xFFFF), "I": (0, 0xFFFFFFFF), "h": (-0x8000, 0x7FFF)}


class CodecError(ValueError):
    """A payload or value that cannot be encoded or decoded."""


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

    @classmethod
    def decode_payload(cls, payload: bytes) -> "Message":
        if len(payload) != cls.SIZE:
            raise CodecError(f"{cls.NAME}: payload is {len(payload)} bytes, expected {cls.SIZE}")
        raw = struct.unpack(cls.struct_format(), payload)
        kwargs, i = {}, 0
        for spec in cls.FIELDS:
            elements = [_from_wire(spec, r) for r in raw[i:i + spec.count]]
            kwargs[spec.name] = tuple(elements) if spec.count > 1 else elements[0]
            i += spec.count
        return cls(**kwargs)

    def as_dict(self) -> dict[str, Any]:
        """Field values as plain JSON-friendly Python values (enum members by name, flag sets as ints)."""
        out = {}
        for f in dc_fields(self):
            value = getattr(self, f.name)
            if isinstance(value, enum.IntFlag):
                value = int(value)
            elif isinstance(value, enum.IntEnum):
                value = value.name.lower()
            out[f.name] = list(value) if isinstance(value, tuple) else value
        return out
