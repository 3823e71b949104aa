"""Conformance: sequence numbers, order and retransmission — replies name id and seq; a copy of the newest frame is
answered again, not reapplied; a late copy of an older one is refused as stale."""

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
    dut.forget_sequence()
    assert send(dut, encode_frame(m.SetTarget(0.1, 0.1), seq)) == [m.Ack(m.SetTarget.ID, seq)]
    after = dut.next_seq()  # after the probe that synchronised the first answer
    assert send(dut, encode_frame(m.SetTarget(1.0, 0.1), after)) == [
        m.Nack(m.SetTarget.ID, after, m.ErrorCode.OUT_OF_RANGE, 0)
    ]


def test_sequence_numbers_may_jump_ahead_by_up_to_191(dut):
    """Frames lost on the way leave gaps: anything 1 to 191 ahead of the newest frame is new."""
    dut.forget_sequence()
    for seq in (9, 200, 3, 3 + 128, 10):  # ahead by 191, 59, 128, 135
        assert send(dut, encode_frame(m.Jog(0, seq / 10000), seq)) == [m.Ack(m.Jog.ID, seq)]
    assert dut.probe().command[0] == pytest.approx(0.0010, abs=1e-5)


@pytest.mark.parametrize("behind", [1, 2, 63, 64])
def test_a_late_copy_of_an_older_command_is_refused_as_stale_and_changes_nothing(dut, behind):
    """A delayed copy of an older set_target (or stop) never undoes a newer command (PROTOCOL.md section 3)."""
    dut.set_target(0.1, 0.0)
    for msg in (m.SetTarget(-0.1, 0.0), m.Stop()):
        old_seq = (dut.link.seq - behind) & 0xFF  # behind the newest frame taken (each send ends with a probe)
        assert send(dut, encode_frame(msg, old_seq)) == [
            m.Nack(msg.ID, old_seq, m.ErrorCode.STALE_SEQUENCE, m.NO_FIELD)
        ]
    dut.start()
    assert dut.position(0.0, 0.0).tilt_zx > 0  # still steering to the newest target, x = +0.1


def test_65_behind_is_a_new_frame(dut):
    """The stale window is 64 frames: one 65 behind is 191 ahead, a jump over frames lost on the way."""
    dut.set_target(0.1, 0.0)
    far = (dut.link.seq - 65) & 0xFF
    assert send(dut, encode_frame(m.SetTarget(-0.1, 0.0), far)) == [m.Ack(m.SetTarget.ID, far)]


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


def test_a_new_command_in_between_makes_the_old_one_stale(dut):
    dut.set_target(0.1, 0.0)
    wire, seq = dut.frame_bytes(m.Start())
    assert send(dut, wire) == [m.Ack(m.Start.ID, seq)]
    dut.set_target(0.2, 0.0)  # another command: the start above is no longer the newest frame
    assert send(dut, wire) == [m.Nack(m.Start.ID, seq, m.ErrorCode.STALE_SEQUENCE, m.NO_FIELD)]


def test_same_seq_different_content_is_refused_as_stale(dut):
    seq = dut.next_seq()
    assert send(dut, encode_frame(m.SetTarget(0.1, 0.0), seq)) == [m.Ack(m.SetTarget.ID, seq)]
    assert send(dut, encode_frame(m.SetTarget(-0.1, 0.0), seq)) == [
        m.Nack(m.SetTarget.ID, seq, m.ErrorCode.STALE_SEQUENCE, m.NO_FIELD)
    ]
    dut.start()
    assert dut.position(0.0, 0.0).tilt_zx > 0  # the first target stands


def test_same_seq_different_id_is_refused_as_stale(dut):
    dut.set_target(0.1, 0.0)
    seq = dut.next_seq()
    assert send(dut, encode_frame(m.Start(), seq)) == [m.Ack(m.Start.ID, seq)]
    assert send(dut, encode_frame(m.Stop(), seq)) == [m.Nack(m.Stop.ID, seq, m.ErrorCode.STALE_SEQUENCE, m.NO_FIELD)]
    assert dut.probe().state == m.State.RUNNING


def test_same_content_new_seq_is_a_new_command(dut):
    dut.set_target(0.1, 0.0)
    first = dut.next_seq()
    assert send(dut, encode_frame(m.Start(), first)) == [m.Ack(m.Start.ID, first)]
    second = dut.next_seq()
    assert send(dut, encode_frame(m.Start(), second)) == [m.Nack(m.Start.ID, second, m.ErrorCode.BAD_STATE, m.NO_FIELD)]


def test_identify_ends_the_retransmission_window(dut):
    """A host that (re)connects identifies first; its sequence numbers start afresh."""
    dut.set_target(0.1, 0.0)
    wire, seq = dut.frame_bytes(m.Start())
    assert send(dut, wire) == [m.Ack(m.Start.ID, seq)]
    dut.command(m.Identify())
    dut.reset_camera()
    assert send(dut, wire) == [m.Nack(m.Start.ID, seq, m.ErrorCode.BAD_STATE, m.NO_FIELD)]


def test_a_duplicated_position_is_answered_again_and_steps_the_controller_once(dut):
    """A duplicate whose first telemetry was lost must not read as refused: it was applied (once)."""
    dut.set_target(0.1, 0.0)
    dut.start()
    dut.position(0.0, 0.0)
    msg = dut.next_position(0.02, 0.0)
    wire, seq = dut.frame_bytes(msg)
    mark = len(dut.log)
    dut.send_raw(wire)
    dut.send_raw(wire)
    dut.probe()
    answers = [x for x in dut.log[mark:] if isinstance(x, (m.Telemetry, m.Nack))]
    assert not any(isinstance(x, m.Nack) for x in answers)
    first, again = [x for x in answers if isinstance(x, m.Telemetry) and x.position_frame == msg.frame][:2]
    assert (again.tilt_zx, again.tilt_zy, again.command) == (first.tilt_zx, first.tilt_zy, first.command)
    assert dut.position(0.03, 0.0).position_frame == dut.frame  # the camera's count runs on


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
