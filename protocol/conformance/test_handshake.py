"""Conformance: identify and its reply (versions, schema hash, frame size, clock), in every state."""

from __future__ import annotations

import pytest

from mantaray.protocol import messages as m
from mantaray.protocol.conformance.harness import STATES, packet_wire


def test_identify_reply_matches_this_host(dut):
    reply = dut.command(m.Identify())
    assert isinstance(reply, m.IdentifyReply)
    assert reply.protocol_version == m.PROTOCOL_VERSION
    assert reply.schema_hash == m.SCHEMA_HASH
    assert reply.max_wire == m.MAX_WIRE
    assert reply.clock in (m.Clock.WALL, m.Clock.SIMULATED)


def test_identify_reports_an_array_shape_that_matches_its_actuators(dut):
    reply = dut.command(m.Identify())
    assert reply.modules_x >= 1 and reply.modules_y >= 1
    assert reply.actuator_count == (reply.modules_x + 1) * (reply.modules_y + 1)  # PROTOCOL.md §5


def test_identify_reply_is_the_same_every_time(dut):
    replies = {dut.command(m.Identify()) for _ in range(3)}
    assert len(replies) == 1


def test_identify_reply_clock_is_how_sim_clock_behaves(dut):
    """clock = simulated <=> sim_clock is accepted; clock = wall <=> it is unsupported."""
    if dut.simulated:
        dut.set_sim_clock(dut.sim_now_us)
    else:
        dut.refuse(m.SimClock(0), m.ErrorCode.UNSUPPORTED)


@pytest.mark.parametrize("state", STATES)
def test_identify_is_answered_in_every_state_and_changes_it_not(dut, state):
    before = dut.enter(state)
    reply = dut.command(m.Identify())
    assert reply.schema_hash == m.SCHEMA_HASH
    dut.reset_camera()  # identify forgot the camera history
    after = dut.probe()
    assert after.state == before.state
    assert after.faults == before.faults
    assert after.command == before.command


def test_identify_forgets_the_camera_history(dut):
    dut.position(0.0, 0.0)
    repeat = m.ObjectPosition(dut.frame, dut.capture_us, 0.0, 0.0, m.PositionFlags(0))
    dut.refuse_position(repeat, m.ErrorCode.STALE_POSITION, 0)
    dut.command(m.Identify())
    t = dut.send_position(repeat)  # the same frame counter and capture time are new to it now
    assert t.position_frame == repeat.frame


@pytest.mark.parametrize("extra", [b"\x00", b"\x01\x02\x03\x04"])
def test_identify_with_a_payload_is_bad_length(dut, extra):
    seq = dut.next_seq()
    before, _ = dut.exchange(packet_wire(m.Identify.ID, seq, extra))
    assert [msg for msg in before if isinstance(msg, m.IdentifyReply)] == []
    nacks = [msg for msg in before if isinstance(msg, m.Nack)]
    assert nacks == [m.Nack(m.Identify.ID, seq, m.ErrorCode.BAD_LENGTH, m.NO_FIELD)]
