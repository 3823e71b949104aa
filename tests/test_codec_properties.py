"""Property tests of codec + framing: message round trips, garbage tolerance, resynchronisation, bit-flip detection."""

from __future__ import annotations

import enum
import math
import struct

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from mantaray.protocol import messages as m
from mantaray.protocol.codec import INT_RANGES, CodecError, FieldSpec, Message
from mantaray.protocol.framing import Frame, FrameDecoder, FrameError, cobs_decode, encode_frame

FAST = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
MESSAGE_CLASSES = sorted(m.MESSAGES.values(), key=lambda cls: cls.ID)


def f32(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


def element_strategy(spec: FieldSpec) -> st.SearchStrategy:
    """One wire element's value in physical units, anywhere the wire type can carry it."""
    if spec.scale is not None:
        lo, hi = INT_RANGES[spec.fmt]
        return st.floats(min_value=lo * spec.scale, max_value=hi * spec.scale, allow_nan=False)
    if spec.fmt == "f":
        anything = st.floats(width=32)  # NaN and +-inf included: the codec carries them, the firmware refuses
        if spec.min is not None and spec.max is not None:
            in_range = st.floats(min_value=f32(spec.min), max_value=f32(spec.max), width=32)
            return st.one_of(in_range, anything)
        return anything
    lo, hi = INT_RANGES[spec.fmt]
    if spec.kind is not None:
        if issubclass(spec.kind, enum.IntFlag):
            return st.integers(lo, hi).map(spec.kind)  # undefined bits too: the codec keeps them
        return st.sampled_from(list(spec.kind))
    return st.integers(lo, hi)


def field_strategy(spec: FieldSpec) -> st.SearchStrategy:
    one = element_strategy(spec)
    if spec.count > 1:
        return st.tuples(*[one] * spec.count)
    return one


@st.composite
def messages(draw, classes=tuple(MESSAGE_CLASSES)) -> Message:
    cls = draw(st.sampled_from(classes))
    return cls(**{spec.name: draw(field_strategy(spec)) for spec in cls.FIELDS})


def assert_same_element(spec: FieldSpec, got, sent) -> None:
    if spec.scale is not None:
        lo, hi = INT_RANGES[spec.fmt]
        assert lo * spec.scale <= got <= hi * spec.scale
        assert abs(got - sent) <= spec.scale / 2 * (1 + 1e-9), (spec.name, got, sent)
    elif spec.fmt == "f":
        if math.isnan(sent):
            assert math.isnan(got), (spec.name, got)
        else:
            assert got == sent and math.copysign(1, got) == math.copysign(1, sent), (spec.name, got, sent)
    else:
        assert got == sent and int(got) == int(sent), (spec.name, got, sent)
        if spec.kind is not None:
            assert isinstance(got, spec.kind)


def assert_same_message(got: Message, sent: Message) -> None:
    assert type(got) is type(sent)
    for spec in sent.FIELDS:
        g, s = getattr(got, spec.name), getattr(sent, spec.name)
        if spec.count > 1:
            assert isinstance(g, tuple) and len(g) == spec.count
            for ge, se in zip(g, s, strict=True):
                assert_same_element(spec, ge, se)
        else:
            assert_same_element(spec, g, s)


# ------------------------------------------------------------------------------------ round trips
@FAST
@given(msg=messages(), seq=st.integers(0, 255))
def test_every_message_round_trips(msg, seq):
    wire = encode_frame(msg, seq)
    assert len(wire) <= m.MAX_WIRE
    assert wire.count(0) == 1 and wire[-1] == 0
    decoder = FrameDecoder()
    out = decoder.feed(wire)
    assert len(out) == 1
    frame = out[0]
    assert isinstance(frame, Frame)
    assert (frame.id, frame.seq, len(frame.payload)) == (msg.ID, seq, msg.SIZE)
    assert_same_message(frame.message(), msg)
    assert decoder.crc_errors == decoder.frame_errors == 0


@pytest.mark.parametrize("cls", MESSAGE_CLASSES, ids=lambda c: c.NAME)
def test_every_message_type_round_trips(cls):
    """Each type on its own, so a rarely drawn type still gets its share of examples."""

    @settings(max_examples=25, deadline=None)
    @given(msg=messages(classes=(cls,)), seq=st.integers(0, 255))
    def check(msg, seq):
        (frame,) = FrameDecoder().feed(encode_frame(msg, seq))
        assert_same_message(frame.message(), msg)
        assert frame.message().encode_payload() == msg.encode_payload()

    check()


@FAST
@given(msg=messages(), seq=st.integers(0, 255), chunks=st.lists(st.integers(1, 8), min_size=1, max_size=20))
def test_round_trip_in_arbitrary_chunks(msg, seq, chunks):
    wire = encode_frame(msg, seq) * 2
    decoder, out, i, k = FrameDecoder(), [], 0, 0
    while i < len(wire):
        n = chunks[k % len(chunks)]
        out += decoder.feed(wire[i : i + n])
        i, k = i + n, k + 1
    assert len(out) == 2 and out[0] == out[1]
    assert_same_message(out[0].message(), msg)


# ------------------------------------------------------------------------------------- garbage
@FAST
@given(
    garbage=st.one_of(
        st.binary(max_size=400), st.lists(st.sampled_from([0, 1, 2, 0xFF, 0x7F, 0x10]), max_size=300).map(bytes)
    ),
    chunks=st.lists(st.integers(1, 64), min_size=1, max_size=30),
)
def test_garbage_never_raises_and_yields_at_most_one_item_per_delimiter(garbage, chunks):
    decoder, out, i, k = FrameDecoder(), [], 0, 0
    while i < len(garbage):
        n = chunks[k % len(chunks)]
        out += decoder.feed(garbage[i : i + n])
        assert len(decoder._buf) <= m.MAX_WIRE - 1  # bounded, as the Uno's buffer is
        i, k = i + n, k + 1
    assert len(out) <= garbage.count(0)
    assert all(isinstance(item, (Frame, FrameError)) for item in out)
    errors = [item for item in out if isinstance(item, FrameError)]
    assert decoder.crc_errors + decoder.frame_errors == len(errors)
    assert {e.kind for e in errors} <= {"crc_error", "frame_error"}
    for item in out:
        if isinstance(item, Frame):
            assert len(item.payload) <= m.MAX_PACKET - 4
            try:
                item.message()
            except CodecError:
                pass  # an unknown id or a wrong length is the firmware's to nack, not the decoder's to raise


@FAST
@given(garbage=st.binary(max_size=200), msg=messages(), seq=st.integers(0, 255), chunk=st.integers(1, 50))
@example(garbage=b"\x01" * 120, msg=m.Identify(), seq=1, chunk=7)  # an oversized run first
@example(garbage=b"\x05\x01", msg=m.Stop(), seq=0, chunk=1)  # a COBS code pointing past the end
def test_a_frame_after_garbage_and_one_delimiter_is_recovered(garbage, msg, seq, chunk):
    stream = garbage + b"\x00" + encode_frame(msg, seq)
    decoder = FrameDecoder()
    out = []
    for i in range(0, len(stream), chunk):
        out += decoder.feed(stream[i : i + chunk])
    assert out, "the frame was lost"
    last = out[-1]
    assert isinstance(last, Frame)
    assert (last.id, last.seq) == (msg.ID, seq)
    assert last.payload == msg.encode_payload()
    assert_same_message(last.message(), msg)


# ------------------------------------------------------------------------------------- bit flips
def cobs_code_positions(encoded: bytes) -> set[int]:
    """Indexes of the COBS code bytes of one encoded packet (no delimiter)."""
    positions, i = set(), 0
    while i < len(encoded):
        positions.add(i)
        i += encoded[i]
    return positions


def flipped(wire: bytes, bit: int) -> bytes:
    out = bytearray(wire)
    out[bit // 8] ^= 1 << (bit % 8)
    return bytes(out)


@settings(max_examples=60, deadline=None)
@given(msg=messages(), seq=st.integers(0, 255))
def test_every_single_bit_flip_of_a_data_byte_is_a_crc_error(msg, seq):
    """A flip that leaves the COBS structure alone is a one-bit error in the packet: CRC-16 always catches it."""
    wire = encode_frame(msg, seq)
    codes = cobs_code_positions(wire[:-1])
    checked = 0
    for bit in range((len(wire) - 1) * 8):
        if bit // 8 in codes:
            continue
        bad = flipped(wire, bit)
        if bad[bit // 8] == 0:
            continue  # a new delimiter: structural, see below
        assert FrameDecoder().feed(bad) == [FrameError("crc_error")]
        checked += 1
    assert checked > 0


# Any single flip, including ones that hit a COBS code byte or create or destroy a delimiter. Those rebuild
# the packet into other bytes, and then a CRC-16 misses with probability 2^-16 per resulting packet, not 0:
# over ~350 000 such flips of random frames one wrong frame appeared (pinned in the next test). The
# examples are derandomised so this test is reproducible; it checks the common case, not a guarantee.
@settings(max_examples=300, deadline=None, derandomize=True)
@given(msg=messages(), seq=st.integers(0, 255), where=st.floats(0, 1, exclude_max=True), trailer=st.booleans())
def test_single_bit_flip_never_yields_a_wrong_frame(msg, seq, where, trailer):
    wire = encode_frame(msg, seq)
    bit = int(where * len(wire) * 8)
    bad = flipped(wire, bit) + (b"\x00" if trailer else b"")  # the trailer ends a frame whose delimiter died
    out = FrameDecoder().feed(bad)
    assert len(out) <= bad.count(0)
    assert not any(isinstance(item, Frame) for item in out), out
    if bit // 8 != len(wire) - 1 and bad[bit // 8] != 0 and bit // 8 not in cobs_code_positions(wire[:-1]):
        assert out == [FrameError("crc_error")]


def test_known_structural_flip_that_crc16_misses():
    """The one escape found: a flip that creates a 0x00 splits the frame and the tail's CRC happens to match.

    The decoder yields a frame that is not the one sent; its payload length is wrong for its id, so
    Frame.message() refuses it and the firmware would nack bad_length. Kept as a record of what the
    frame layer can and cannot promise (CRC-16 catches a random corruption with probability 1 - 2^-16).
    """
    wire = bytes.fromhex("0410a7f60102020502833502010401a6020304bf00")
    (sent,) = FrameDecoder().feed(wire)
    assert isinstance(sent, Frame) and sent.id == m.ObjectPosition.ID
    out = FrameDecoder().feed(flipped(wire, 32))
    frames = [item for item in out if isinstance(item, Frame)]
    assert frames == [Frame(2, 0, bytes.fromhex("02833502000001a60200"))]
    with pytest.raises(CodecError):
        frames[0].message()
    assert cobs_decode(wire[:-1])[0] == m.ObjectPosition.ID
