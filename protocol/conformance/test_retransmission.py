"""Conformance: sequence numbers and retransmission — replies name id and seq; a resent command is answered, not reapplied."""
from __future__ import annotations

import struct

import pytest

from mantaray.protocol import messages as m
from mantaray.protocol.framing import crc16, encode_frame


def replies(msgs) -> list:
    return [x for x in msgs if isinstance(x, (m.Ack, m.Nack))]


def send(dut, wire: bytes) -> list:
    """Raw bytes in, the acks and nacks they drew (synchronised by a probe) out."""
    return replies(dut.exchange(wire)[0])


# ------------------------------------------------------------------------------------- sequence numbers
@pytest.mark.parametrize("seq", [0, 1, 127, 128, 254, 255])
def test_ack_and_nack_name_the_command_id_and_seq(dut, seq):
    assert send(dut, encode_frame(m.SetTarget(0.1, 0.1), seq)) == [m.Ack(m.SetTarget.ID, seq)]
    assert send(dut, encode_frame(m.SetTarget(1.0, 0.1), seq)) == \
        [m.Nack(m.SetTarget.ID, seq, m.ErrorCode.OUT_OF_RANGE, 0)]


def test_sequence_numbers_need_not_be_consecutive(dut):
    for seq in (9, 200, 3, 3 + 128, 77):
        assert send(dut, encode_frame(m.Jog(0, seq / 10000), seq)) == [m.Ack(m.Jog.ID, seq)]
    assert dut.probe().command[0] == pytest.approx(0.0077, abs=1e-5)


def test_firmware_frames_count_up_by_one(dut):
    """Each frame the firmware sends carries the previous one's seq + 1 (mod 256), so a host can count
    lost frames."""
    lost, first = dut.link.lost_frames, dut.link.last_rx_seq
    n = 0
    for i in range(300):  # past a wrap of the 8-bit counter
        if i % 3 == 0:
            dut.probe()
        else:
            dut.set_target(0.001 * (i % 50), 0.0)
        n += 1
    assert dut.link.lost_frames == lost
    assert dut.link.last_rx_seq == (first + n) & 0xFF


# ------------------------------------------------------------------------------------------ retransmission
def test_resent_start_is_acked_again_and_not_applied_twice(dut):
    dut.set_target(0.1, 0.0)
    wire, seq = dut.frame_bytes(m.Start())
    assert send(dut, wire) == [m.Ack(m.Start.ID, seq)]
    dut.position(0.0, 0.0)
    dut.position(0.01, 0.0)  # camera frames in between do not end the retransmission window
    assert send(dut, wire) == [m.Ack(m.Start.ID, seq)]  # a second start would have been bad_state
    assert send(dut, wire) == [m.Ack(m.Start.ID, seq)]
    assert dut.probe().state == m.State.RUNNING


def test_resent_refused_command_gets_the_same_nack(dut):
    wire, seq = dut.frame_bytes(m.Configure(deadman=3))
    expected = [m.Nack(m.Configure.ID, seq, m.ErrorCode.OUT_OF_RANGE, 7)]
    assert send(dut, wire) == expected
    assert send(dut, wire) == expected


def test_a_new_command_in_between_ends_the_retransmission(dut):
    dut.set_target(0.1, 0.0)
    wire, seq = dut.frame_bytes(m.Start())
    assert send(dut, wire) == [m.Ack(m.Start.ID, seq)]
    dut.set_target(0.2, 0.0)  # another command: the start above is no longer the last one
    assert send(dut, wire) == [m.Nack(m.Start.ID, seq, m.ErrorCode.BAD_STATE, m.NO_FIELD)]


def test_same_seq_different_content_is_a_new_command(dut):
    seq = dut.next_seq()
    assert send(dut, encode_frame(m.SetTarget(0.1, 0.0), seq)) == [m.Ack(m.SetTarget.ID, seq)]
    assert send(dut, encode_frame(m.SetTarget(-0.1, 0.0), seq)) == [m.Ack(m.SetTarget.ID, seq)]
    dut.start()
    assert dut.position(0.0, 0.0).tilt_zx < 0  # the second target was applied


def test_same_seq_different_id_is_a_new_command(dut):
    dut.set_target(0.1, 0.0)
    seq = dut.next_seq()
    assert send(dut, encode_frame(m.Start(), seq)) == [m.Ack(m.Start.ID, seq)]
    assert send(dut, encode_frame(m.Stop(), seq)) == [m.Ack(m.Stop.ID, seq)]
    assert dut.probe().state == m.State.IDLE


def test_same_content_new_seq_is_a_new_command(dut):
    dut.set_target(0.1, 0.0)
    first, second = dut.next_seq(), dut.next_seq()
    assert send(dut, encode_frame(m.Start(), first)) == [m.Ack(m.Start.ID, first)]
    assert send(dut, encode_frame(m.Start(), second)) == [m.Nack(m.Start.ID, second, m.ErrorCode.BAD_STATE,
                                                                 m.NO_FIELD)]


def test_identify_ends_the_retransmission_window(dut):
    """A host that (re)connects identifies first; its sequence numbers start afresh."""
    dut.set_target(0.1, 0.0)
    wire, seq = dut.frame_bytes(m.Start())
    assert send(dut, wire) == [m.Ack(m.Start.ID, seq)]
    dut.command(m.Identify())
    dut.reset_camera()
    assert send(dut, wire) == [m.Nack(m.Start.ID, seq, m.ErrorCode.BAD_STATE, m.NO_FIELD)]


def test_a_resent_position_is_stale_not_a_retransmission(dut):
    msg = dut.next_position(0.0, 0.0)
    wire, seq = dut.frame_bytes(msg)
    mark = len(dut.log)
    dut.send_raw(wire)
    dut.send_raw(wire)
    nack = dut.reply_to(m.ObjectPosition.ID, seq)
    assert nack == m.Nack(m.ObjectPosition.ID, seq, m.ErrorCode.STALE_POSITION, 0)
    assert [x.position_frame for x in dut.log[mark:] if isinstance(x, m.Telemetry)] == [msg.frame]


def _crc_twin(first: m.SetTarget, x: float, seq: int) -> bytes:
    """Payload of a set_target(x, y') whose frame has the same id, seq and CRC as `first`'s: y' differs
    from first.y only in its two low mantissa bytes (a tiny, finite, in-range value). The CRC is affine
    in those 16 bits over GF(2), so they are solved for rather than searched."""
    head = bytes([m.SetTarget.ID, seq])
    target = crc16(head + first.encode_payload())
    y_bits = struct.unpack("<I", struct.pack("<f", first.y))[0] & 0xFFFF0000

    def crc_of(low: int) -> int:
        return crc16(head + struct.pack("<fI", x, y_bits | low))

    base = crc_of(0)
    columns = [crc_of(1 << i) ^ base for i in range(16)]
    # Gaussian elimination: rows (column value, the low bits that produce it)
    rows: list[tuple[int, int]] = []
    for i, col in enumerate(columns):
        combo = 1 << i
        for value, bits in rows:
            if col ^ value < col:
                col, combo = col ^ value, combo ^ bits
        if col:
            rows.append((col, combo))
            rows.sort(reverse=True)
    want, low = target ^ base, 0
    for value, bits in rows:
        if want ^ value < want:
            want, low = want ^ value, low ^ bits
    assert want == 0, "no CRC twin"
    payload = struct.pack("<fI", x, y_bits | low)
    assert crc16(head + payload) == target and payload != first.encode_payload()
    return payload


def test_same_id_seq_and_crc_is_a_retransmission_even_with_other_content(dut):
    """PROTOCOL.md, section 3: a retransmission is a frame whose id, seq and CRC equal the last
    command's; one whose content differs but collides in the CRC-16 is answered again, not applied.
    (The ack then reads 'applied' for a command that was not: a documented limit, 1 in 65536 for two
    consecutive commands with the same id and seq.)"""
    seq = dut.next_seq()
    first = m.SetTarget(0.1, 0.0)
    twin = _crc_twin(first, -0.1, seq)
    assert send(dut, encode_frame(first, seq)) == [m.Ack(m.SetTarget.ID, seq)]
    wire = encode_frame(m.SetTarget.decode_payload(twin), seq)
    assert send(dut, wire) == [m.Ack(m.SetTarget.ID, seq)]
    dut.start()
    assert dut.position(0.0, 0.0).tilt_zx > 0  # still steering to the first target, x = +0.1
