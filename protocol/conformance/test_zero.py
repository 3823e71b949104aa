"""Conformance: zero (homing) — the masked actuators stand at 0 m and hold there; idle only; the mask is checked."""

from __future__ import annotations

import pytest

from mantaray.protocol import messages as m
from mantaray.protocol.conformance.harness import COMMAND_TOL

OUT = m.ErrorCode.OUT_OF_RANGE


def _jog_all(dut) -> None:
    for i, p in enumerate((0.05, -0.1, 0.15, -0.2)):
        dut.command(m.Jog(i, p))


@pytest.mark.parametrize("mask", [0b0001, 0b0110, 0b1000, 0b1111])
def test_zero_makes_the_masked_actuators_hold_at_zero(dut, mask):
    _jog_all(dut)
    ack = dut.command(m.Zero(mask))
    assert ack.ref_id == m.Zero.ID
    t = dut.probe()
    expected = [0.0 if mask & (1 << i) else p for i, p in enumerate((0.05, -0.1, 0.15, -0.2))]
    assert tuple(t.command) == pytest.approx(expected, abs=COMMAND_TOL)
    for i in range(4):
        if mask & (1 << i):
            assert t.measured[i] == pytest.approx(0.0, abs=2e-3)  # where they stand is now z0


@pytest.mark.parametrize("mask", [0, 16, 255, 1 << 15, 0xFFFF])
def test_a_mask_naming_no_actuator_or_too_many_is_refused(dut, mask):
    _jog_all(dut)
    before = tuple(dut.probe().command)
    dut.refuse(m.Zero(mask), OUT, 0)
    assert tuple(dut.probe().command) == before


@pytest.mark.parametrize("state", ["running", "reached", "fault", "estop"])
def test_zero_outside_idle_is_bad_state(dut, state):
    before = dut.enter(state)
    dut.refuse(m.Zero(0b1111), m.ErrorCode.BAD_STATE)
    after = dut.probe()
    assert (after.state, after.command) == (before.state, before.command)
