"""Conformance: zero (homing) — the masked actuators stand at 0 m and hold there; idle only; the mask is checked."""

from __future__ import annotations

import pytest

from mantaray.protocol import messages as m
from mantaray.protocol.conformance.harness import COMMAND_TOL
from mantaray.protocol.conformance.test_jog import JOGGED, jog_module_0

OUT = m.ErrorCode.OUT_OF_RANGE


@pytest.mark.parametrize("corners", [0b0001, 0b0110, 0b1000, 0b1111])
def test_zero_makes_the_masked_actuators_hold_at_zero(dut, corners):
    """corners: which of module 0's four actuators the mask names (telemetry shows module 0 after the jogs)."""
    jog_module_0(dut)
    mask = sum(1 << a for c, a in enumerate(dut.corners(0)) if corners & (1 << c))
    ack = dut.command(m.Zero(mask))
    assert ack.ref_id == m.Zero.ID
    t = dut.probe()
    expected = [0.0 if corners & (1 << c) else p for c, p in enumerate(JOGGED)]
    assert tuple(t.command) == pytest.approx(expected, abs=COMMAND_TOL)
    for c in range(4):
        if corners & (1 << c):
            assert t.measured[c] == pytest.approx(0.0, abs=2e-3)  # where they stand is now z0


@pytest.mark.parametrize(
    "mask",
    [
        lambda n: 0,  # no actuator
        lambda n: (1 << n) & 0xFFFF,  # the first the rig lacks (none on a rig of 16: then no actuator either)
        lambda n: 0xFFFF & ~((1 << n) - 1),  # every one it lacks
        lambda n: (1 << n | 1) if n < 16 else 0,  # one it has and the first it lacks
    ],
    ids=["none", "first past", "all past", "one with the first past"],
)
def test_a_mask_naming_no_actuator_or_one_the_rig_lacks_is_refused(dut, mask):
    jog_module_0(dut)
    before = tuple(dut.probe().command)
    dut.refuse(m.Zero(mask(dut.actuator_count)), OUT, 0)
    assert tuple(dut.probe().command) == before


@pytest.mark.parametrize("state", ["running", "reached", "fault", "estop"])
def test_zero_outside_idle_is_bad_state(dut, state):
    before = dut.enter(state)
    dut.refuse(m.Zero(0b1111), m.ErrorCode.BAD_STATE)
    after = dut.probe()
    assert (after.state, after.command) == (before.state, before.command)
