"""Conformance: the link layer — unknown ids, bad lengths, corrupt and oversize frames, garbage and resynchronisation."""

from __future__ import annotations

import random

import pytest

from mantaray.protocol import messages as m
from mantaray.protocol.conformance.harness import (
    ALT_CONFIG,
    BASE_CONFIG,
    DEFAULT_CONFIG,
    base_config_fingerprint,
    config_fingerprint,
    error_delta,
    packet_wire,
    reference_errors,
    reference_frames,
)
from mantaray.protocol.framing import Frame, cobs_encode, crc16, encode_frame

HOST_TO_MCU = [cls for cls in m.MESSAGES.values() if cls.DIRECTION == "host_to_mcu"]
KNOWN_IDS = {cls.ID for cls in HOST_TO_MCU}


def nacks_and_acks(msgs) -> list:
    return [x for x in msgs if isinstance(x, (m.Ack, m.Nack, m.IdentifyReply))]


def running(dut, x: float = 0.1, y: float = 0.0) -> m.Telemetry:
    """Running, steering from the centre towards (x, y)."""
    dut.set_target(x, y)
    dut.start()
    return dut.position(0.0, 0.0)


# ------------------------------------------------------------------------------------------ unknown ids
# The edges of the id space, the first id after the commands, and every firmware -> host id (no command either)
UNKNOWN_IDS = sorted(
    {
        0x00,
        0x0F,
        0x11,
        0x7F,
        0x80,
        0xFE,
        0xFF,
        max(i for i in KNOWN_IDS if i < 0x10) + 1,
        *(cls.ID for cls in m.MESSAGES.values() if cls.DIRECTION == "mcu_to_host"),
    }
    - KNOWN_IDS
)


@pytest.mark.parametrize("payload", [b"", b"\x01" * 8, bytes(range(40))], ids=["empty", "8-bytes", "40-bytes"])
@pytest.mark.parametrize("message_id", UNKNOWN_IDS, ids=lambda i: f"0x{i:02X}")
def test_unknown_message_id_is_nacked(dut, message_id, payload):
    assert message_id not in KNOWN_IDS
    seq = dut.next_seq()
    before, _ = dut.exchange(packet_wire(message_id, seq, payload))
    assert nacks_and_acks(before) == [m.Nack(message_id, seq, m.ErrorCode.UNKNOWN_MESSAGE, m.NO_FIELD)]


def test_unknown_message_changes_nothing(dut):
    before = running(dut)
    dut.exchange(packet_wire(0x7F, dut.next_seq(), b""))
    after = dut.probe()
    assert (after.state, after.faults, after.command) == (before.state, before.faults, before.command)


# ------------------------------------------------------------------------------------------- bad length
def _length_cases():
    for cls in HOST_TO_MCU:
        for size in sorted({cls.SIZE - 1, cls.SIZE + 1, 0, cls.SIZE + 8} - {cls.SIZE}):
            if 0 <= size <= m.MAX_PACKET - 4:
                yield pytest.param(cls, size, id=f"{cls.NAME}-{size}")


@pytest.mark.parametrize("cls,size", list(_length_cases()))
def test_wrong_payload_length_is_bad_length(dut, cls, size):
    seq = dut.next_seq()
    before, _ = dut.exchange(packet_wire(cls.ID, seq, bytes(range(1, size + 1))))
    assert nacks_and_acks(before) == [m.Nack(cls.ID, seq, m.ErrorCode.BAD_LENGTH, m.NO_FIELD)]
    assert not [x for x in before if isinstance(x, m.Telemetry)]


def test_bad_length_start_and_emergency_stop_change_nothing(dut):
    dut.set_target(0.1, 0.0)
    dut.exchange(packet_wire(m.Start.ID, dut.next_seq(), b"\x01"))
    assert dut.probe().state == m.State.IDLE
    before = running(dut)
    dut.exchange(packet_wire(m.EmergencyStop.ID, dut.next_seq(), b"\x01"))
    after = dut.probe()
    assert (after.state, after.faults) == (before.state, before.faults) == (m.State.RUNNING, 0)


@pytest.mark.parametrize("cut", [1, -1], ids=["truncated", "padded"])
def test_bad_length_configure_changes_nothing(dut, cut):
    reference = base_config_fingerprint(dut)
    dut.command(BASE_CONFIG)
    payload = ALT_CONFIG.encode_payload()
    payload = payload[:-1] if cut == 1 else payload + b"\x00"
    seq = dut.next_seq()
    before, _ = dut.exchange(packet_wire(m.Configure.ID, seq, payload))
    assert nacks_and_acks(before) == [m.Nack(m.Configure.ID, seq, m.ErrorCode.BAD_LENGTH, m.NO_FIELD)]
    assert config_fingerprint(dut) == reference


def far_ahead(dut, x: float = 0.0, y: float = 0.0) -> m.ObjectPosition:
    """A frame whose counter and capture time are still new after a few more probes."""
    return m.ObjectPosition(
        (dut.frame + 100) & 0xFFFF, (dut.capture_us + 1_000_000) & 0xFFFFFFFF, x, y, m.PositionFlags(0)
    )


def test_bad_length_position_is_nacked_and_enters_no_history(dut):
    msg = far_ahead(dut)
    seq = dut.next_seq()
    before, _ = dut.exchange(packet_wire(m.ObjectPosition.ID, seq, msg.encode_payload()[:-1]))
    assert nacks_and_acks(before) == [m.Nack(m.ObjectPosition.ID, seq, m.ErrorCode.BAD_LENGTH, m.NO_FIELD)]
    assert dut.send_position(msg).position_frame == msg.frame  # its counter is still new


# ------------------------------------------------------------------------------------ corrupted frames
def flipped_packets(msg, seq: int):
    """Every single-bit flip of the packet (id, seq, payload, CRC), COBS-encoded: a CRC error each."""
    body = bytes([msg.ID, seq]) + msg.encode_payload()
    packet = body + crc16(body).to_bytes(2, "little")
    for bit in range(len(packet) * 8):
        bad = bytearray(packet)
        bad[bit // 8] ^= 1 << (bit % 8)
        yield cobs_encode(bytes(bad)) + b"\x00"


@pytest.mark.parametrize("msg", [m.EmergencyStop(), m.Stop(), m.SetTarget(-0.2, -0.2)], ids=lambda x: x.NAME)
def test_bit_flips_in_the_packet_are_dropped_as_crc_errors(dut, msg):
    # Some 160 exchanges without a position: at 115200 baud that outlasts the default deadman on a
    # wall-clock firmware (a board, or the AVR simulator in real time), and this test is about CRCs.
    dut.configure(deadman=60000)
    before = running(dut, 0.2, 0.2)
    for frame in flipped_packets(msg, dut.next_seq()):
        replies, after = dut.exchange(frame)
        assert nacks_and_acks(replies) == []
        assert error_delta(before, after) == (1, 0)
        before = after
    assert (after.state, after.faults) == (m.State.RUNNING, 0)
    assert after.tilt_zx > 0 and after.tilt_zy > 0  # still steering to (0.2, 0.2)


def test_bit_flips_on_the_wire_are_dropped_and_counted(dut):
    """Any single-bit flip of the wire bytes (COBS codes included, never making a delimiter) drops the
    frame; it counts as the reference decoder counts it (crc_errors or frame_errors)."""
    dut.configure(deadman=60000)  # dozens of exchanges without a position (see the test above)
    dut.set_target(0.1, 0.0)
    before = running(dut)
    wire, _ = dut.frame_bytes(m.EmergencyStop())
    for i in range(len(wire) - 1):
        for bit in range(8):
            bad = bytearray(wire)
            bad[i] ^= 1 << bit
            if bad[i] == 0:
                continue
            expected = reference_errors(bytes(bad))
            assert not any(isinstance(x, Frame) for x in reference_frames(bytes(bad)))
            replies, after = dut.exchange(bytes(bad))
            assert nacks_and_acks(replies) == [], f"byte {i} bit {bit}"
            assert error_delta(before, after) == expected, f"byte {i} bit {bit}"
            before = after
    assert (after.state, after.faults) == (m.State.RUNNING, 0)


def test_corrupt_position_is_dropped_silently(dut):
    before = running(dut)
    msg = far_ahead(dut, 0.2, 0.0)  # past the target: it would reverse the tilt
    # one payload bit flipped under the original CRC, then framed: a CRC error whatever the bytes are (a flip
    # of the COBS bytes themselves can be a framing error instead, depending on the capture time's value)
    body = bytes([m.ObjectPosition.ID, dut.next_seq()]) + msg.encode_payload()
    damaged = bytearray(body)
    damaged[4] ^= 0x10
    wire = cobs_encode(bytes(damaged) + crc16(body).to_bytes(2, "little")) + b"\x00"
    replies, t = dut.exchange(wire)
    assert replies == []  # nothing but the probe's answer
    assert (t.tilt_zx, t.command) == (before.tilt_zx, before.command)
    assert error_delta(before, t) == (1, 0)
    assert dut.send_position(msg).position_frame == msg.frame  # and it entered no history


# ----------------------------------------------------------------------------------- framing errors
FRAMING_ERRORS = {
    "empty-packet": cobs_encode(b"") + b"\x00",
    "3-byte-packet": cobs_encode(b"\x06\x01\x02") + b"\x00",
    "code-past-end": b"\x05\x06\x01\x00",
    "oversize": b"\x11" * 60 + b"\x00",
    "oversize-valid-cobs": cobs_encode(bytes([0x7E, 1]) + bytes(range(1, 42)) + b"\x01\x02") + b"\x00",
}


@pytest.mark.parametrize("wire", FRAMING_ERRORS.values(), ids=FRAMING_ERRORS.keys())
def test_malformed_frames_are_frame_errors(dut, wire):
    assert reference_errors(wire) == (0, 1)
    before = dut.probe()
    replies, after = dut.exchange(wire)
    assert nacks_and_acks(replies) == []
    assert error_delta(before, after) == (0, 1)


def test_largest_frame_is_accepted_one_more_byte_is_not(dut):
    """max_packet = 44 bytes (46 on the wire with COBS and delimiter) is answered; 45 is a frame error."""
    seq = dut.next_seq()
    largest = packet_wire(0x7E, seq, bytes(range(1, m.MAX_PACKET - 4 + 1)))
    assert len(largest) == m.MAX_WIRE
    before = dut.probe()
    replies, after = dut.exchange(largest)
    assert nacks_and_acks(replies) == [m.Nack(0x7E, seq, m.ErrorCode.UNKNOWN_MESSAGE, m.NO_FIELD)]
    assert error_delta(before, after) == (0, 0)
    too_big = packet_wire(m.Configure.ID, dut.next_seq(), bytes(range(1, m.MAX_PACKET - 4 + 2)))
    assert len(too_big) == m.MAX_WIRE + 1
    replies, last = dut.exchange(too_big)
    assert nacks_and_acks(replies) == []
    assert error_delta(after, last) == (0, 1)


def test_largest_known_message_at_max_packet_is_bad_length(dut):
    seq = dut.next_seq()
    replies, _ = dut.exchange(packet_wire(m.Configure.ID, seq, bytes(range(1, m.MAX_PACKET - 4 + 1))))
    assert nacks_and_acks(replies) == [m.Nack(m.Configure.ID, seq, m.ErrorCode.BAD_LENGTH, m.NO_FIELD)]


# ------------------------------------------------------------------------------------- resynchronising
rng = random.Random(20240611)
GARBAGE = {
    "nonzero-bytes": bytes(rng.randrange(1, 256) for _ in range(30)),
    "random-bytes": bytes(rng.randrange(0, 256) for _ in range(100)),
    "half-a-frame": encode_frame(m.SetTarget(-0.25, -0.25), 7)[:6],
    "long-run": b"\xff" * 200,
    "idle-delimiters": b"\x00" * 10,
}


@pytest.mark.parametrize("garbage", GARBAGE.values(), ids=GARBAGE.keys())
def test_after_garbage_and_a_delimiter_the_next_frame_is_answered(dut, garbage):
    dut.set_target(0.1, 0.1)
    noise = garbage if garbage.endswith(b"\x00") else garbage + b"\x00"
    assert not any(isinstance(x, Frame) for x in reference_frames(noise))
    expected = reference_errors(noise)
    before = dut.probe()
    msg = m.SetTarget(0.2, -0.1)
    wire, seq = dut.frame_bytes(msg)
    replies, after = dut.exchange(noise + wire)
    assert nacks_and_acks(replies) == [m.Ack(msg.ID, seq)]
    assert error_delta(before, after) == expected
    dut.start()
    t = dut.position(0.0, 0.0)
    assert t.tilt_zx > 0 > t.tilt_zy  # the frame after the garbage was applied


def test_garbage_without_a_delimiter_costs_only_the_next_frame(dut):
    """Garbage glued to a frame makes one bad frame; the decoder is in step again at its delimiter."""
    dut.set_target(0.1, 0.1)
    before = dut.probe()
    lost, lost_seq = dut.frame_bytes(m.SetTarget(-0.1, -0.1))
    kept_msg = m.SetTarget(0.2, -0.1)
    kept, kept_seq = dut.frame_bytes(kept_msg)
    garbage = b"\x42\x13\x37"
    crc, frame = reference_errors(garbage + lost)
    replies, after = dut.exchange(garbage + lost + kept)
    assert nacks_and_acks(replies) == [m.Ack(kept_msg.ID, kept_seq)]
    assert error_delta(before, after) == (crc, frame) and crc + frame == 1


def test_idle_delimiters_are_not_errors(dut):
    before = dut.probe()
    first, first_seq = dut.frame_bytes(m.SetTarget(0.1, 0.0))
    second, second_seq = dut.frame_bytes(m.Stop())
    replies, after = dut.exchange(b"\x00" * 5 + first + b"\x00" * 5 + second + b"\x00" * 5)
    assert error_delta(before, after) == (0, 0)
    assert nacks_and_acks(replies) == [m.Ack(m.SetTarget.ID, first_seq), m.Ack(m.Stop.ID, second_seq)]


@pytest.mark.parametrize("chunk", [1, 3, 7], ids=lambda c: f"{c}-byte-writes")
def test_frames_split_across_writes_are_answered(dut, chunk):
    msgs = [m.SetTarget(0.05, 0.05), m.Stop(), m.Jog(1, 0.02)]
    frames = [dut.frame_bytes(x) for x in msgs]
    mark = len(dut.log)
    dut.send_raw(b"".join(w for w, _ in frames), chunk=chunk)
    t = dut.probe()
    assert nacks_and_acks(dut.log[mark:]) == [m.Ack(x.ID, seq) for x, (_, seq) in zip(msgs, frames, strict=True)]
    assert t.command[1] > 0.0


def test_back_to_back_frames_are_answered_in_order(dut):
    msgs = [m.SetTarget(0.05 * i / 10, 0.0) for i in range(10)] + [DEFAULT_CONFIG, m.Stop()]
    frames = [dut.frame_bytes(x) for x in msgs]
    before, _ = dut.exchange(b"".join(w for w, _ in frames))
    assert nacks_and_acks(before) == [m.Ack(x.ID, seq) for x, (_, seq) in zip(msgs, frames, strict=True)]
