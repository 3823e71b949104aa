"""Frame layer: CRC-16/CCITT-FALSE, COBS, and a resynchronising stream decoder (PROTOCOL.md, "Framing")."""

from __future__ import annotations

from dataclasses import dataclass

from .codec import CodecError, Message
from .messages import MAX_PACKET, MAX_WIRE, MESSAGES

MIN_PACKET = 4  # [bytes] id + seq + CRC with an empty payload


def crc16(data: bytes, crc: int = 0xFFFF) -> int:
    """CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, no reflection, no final xor; "123456789" -> 0x29B1."""
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else (crc << 1)
            crc &= 0xFFFF
    return crc


def cobs_encode(data: bytes) -> bytes:
    """Consistent Overhead Byte Stuffing: the result holds no 0x00 (the delimiter is not appended)."""
    out = bytearray()
    block = bytearray()
    for byte in data:
        if byte == 0:
            out.append(len(block) + 1)
            out += block
            block.clear()
        else:
            block.append(byte)
            if len(block) == 254:
                out.append(255)
                out += block
                block.clear()
    out.append(len(block) + 1)
    out += block
    return bytes(out)


def cobs_decode(data: bytes) -> bytes:
    """Inverse of cobs_encode; raises ValueError on a malformed block (0x00 inside, or a code past the end)."""
    out = bytearray()
    i, n = 0, len(data)
    while i < n:
        code = data[i]
        if code == 0 or i + code > n:
            raise ValueError("malformed COBS block")
        block = data[i + 1 : i + code]
        if 0 in block:
            raise ValueError("0x00 inside a COBS block")
        out += block
        i += code
        if code != 255 and i < n:
            out.append(0)
    return bytes(out)


def encode_packet(message_id: int, seq: int, payload: bytes) -> bytes:
    """Wire bytes of one frame: COBS(id, seq, payload, CRC16 little-endian) + 0x00."""
    body = bytes([message_id & 0xFF, seq & 0xFF]) + payload
    packet = body + crc16(body).to_bytes(2, "little")
    if len(packet) > MAX_PACKET:
        raise CodecError(f"packet of {len(packet)} bytes exceeds the {MAX_PACKET}-byte maximum")
    return cobs_encode(packet) + b"\x00"


def encode_frame(message: Message, seq: int) -> bytes:
    return encode_packet(message.ID, seq, message.encode_payload())


@dataclass(frozen=True)
class Frame:
    """A frame whose CRC checked out; payload not yet interpreted."""

    id: int
    seq: int
    payload: bytes

    def message(self) -> Message:
        """Decode the payload; raises CodecError for an unknown id or a wrong length."""
        cls = MESSAGES.get(self.id)
        if cls is None:
            raise CodecError(f"unknown message id 0x{self.id:02X}")
        return cls.decode_payload(self.payload)


@dataclass(frozen=True)
class FrameError:
    """A dropped frame: kind is 'crc_error' or 'frame_error' (bad COBS, oversize or too short)."""

    kind: str


class FrameDecoder:
    """Feeds on arbitrary byte chunks; yields a Frame or FrameError at each delimiter.

    Never holds more than MAX_WIRE bytes: a frame that grows past that is dropped as one
    frame_error and the decoder resynchronises on the next 0x00.
    """

    def __init__(self) -> None:
        self._buf = bytearray()
        self._overflow = False
        self.crc_errors = 0
        self.frame_errors = 0

    def feed(self, data: bytes) -> list[Frame | FrameError]:
        out: list[Frame | FrameError] = []
        for byte in data:
            if byte != 0:
                if len(self._buf) < MAX_WIRE - 1:
                    self._buf.append(byte)
                else:
                    self._overflow = True
                continue
            result = self._finish()
            if result is not None:
                out.append(result)
        return out

    def _finish(self) -> Frame | FrameError | None:
        encoded, overflow = bytes(self._buf), self._overflow
        self._buf.clear()
        self._overflow = False
        if overflow:
            return self._error("frame_error")
        if not encoded:
            return None  # back-to-back delimiters: idle line or a resync
        try:
            packet = cobs_decode(encoded)
        except ValueError:
            return self._error("frame_error")
        if len(packet) < MIN_PACKET:  # COBS never decodes MAX_WIRE - 1 bytes to more than MAX_PACKET
            return self._error("frame_error")
        if crc16(packet[:-2]) != int.from_bytes(packet[-2:], "little"):
            return self._error("crc_error")
        return Frame(packet[0], packet[1], packet[2:-2])

    def _error(self, kind: str) -> FrameError:
        if kind == "crc_error":
            self.crc_errors += 1
        else:
            self.frame_errors += 1
        return FrameError(kind)
