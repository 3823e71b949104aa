"""Conformance: jog — one actuator's command in idle only, index and range checks, refusals change nothing."""

from __future__ import annotations

import math

import pytest

from mantaray.protocol import messages as m
from mantaray.protocol.conformance.harness import ACTUATOR_RANGE, COMMAND_TOL, f32_above, f32_below

OUT, NOT_FINITE = m.ErrorCode.OUT_OF_RANGE, m.ErrorCode.NOT_FINITE
JOGGED = (0.05, -0.1, 0.15, -0.2)  # [m] a position for each of module 0's corners


def commands(dut) -> tuple[float, ...]:
    return tuple(dut.probe().command)


def jog_module_0(dut) -> None:
    """Each of module 0's corners to its JOGGED position: telemetry then shows all four (module 0)."""
    for actuator, position in zip(dut.corners(0), JOGGED, strict=True):
        dut.command(m.Jog(actuator, position))


@pytest.mark.parametrize("corner", range(4))
@pytest.mark.parametrize("position", [0.1, -0.2, ACTUATOR_RANGE, -ACTUATOR_RANGE, 0.0])
def test_jog_moves_one_actuator(dut, corner, position):
    actuator = dut.corners(0)[corner]
    ack = dut.command(m.Jog(actuator, position))
    assert ack.ref_id == m.Jog.ID
    expected = [0.0] * 4
    expected[corner] = position
    t = dut.probe()
    assert t.module == 0
    assert tuple(t.command) == pytest.approx(expected, abs=COMMAND_TOL)


def test_every_actuator_of_the_rig_jogs_and_telemetry_shows_it(dut):
    """On an array, telemetry shows the four actuators of the lowest-numbered module the jogged one is a corner of."""
    for actuator in range(dut.actuator_count):
        dut.command(m.Jog(actuator, 0.01 * (actuator + 1)))
        module, corner = dut.grid().shown(actuator)
        t = dut.probe()
        assert t.module == module
        assert t.command[corner] == pytest.approx(0.01 * (actuator + 1), abs=COMMAND_TOL)


def test_jogs_add_up_across_actuators(dut):
    jog_module_0(dut)
    dut.command(m.Jog(dut.corners(0)[1], 0.01))
    assert commands(dut) == pytest.approx((0.05, 0.01, 0.15, -0.2), abs=COMMAND_TOL)


def _bad(count: int) -> list:
    return [
        ((count, 0.1), OUT, 0),  # the first index past the rig's actuators (16 on a rig of 16)
        ((16, 0.1), OUT, 0),  # past the protocol's 16
        ((255, 0.1), OUT, 0),
        ((0, math.nan), NOT_FINITE, 1),
        ((1, math.inf), NOT_FINITE, 1),
        ((0, -math.inf), NOT_FINITE, 1),
        ((1, f32_above(ACTUATOR_RANGE)), OUT, 1),
        ((1, f32_below(-ACTUATOR_RANGE)), OUT, 1),
        ((0, 1.0), OUT, 1),
    ]


@pytest.mark.parametrize("case", range(len(_bad(4))))
def test_bad_jog_is_refused_and_changes_nothing(dut, case):
    args, code, field = _bad(dut.actuator_count)[case]
    jog_module_0(dut)
    before = commands(dut)
    dut.refuse(m.Jog(*args), code, field)
    assert commands(dut) == before


@pytest.mark.parametrize("state", ["running", "reached", "fault", "estop"])
def test_jog_outside_idle_is_bad_state(dut, state):
    before = dut.enter(state)
    dut.refuse(m.Jog(0, 0.1), m.ErrorCode.BAD_STATE)
    after = dut.probe()
    assert (after.state, after.command) == (before.state, before.command)


def test_stop_ends_a_jog(dut):
    dut.command(m.Jog(dut.corners(0)[3], -0.15))
    assert commands(dut)[3] == pytest.approx(-0.15, abs=COMMAND_TOL)
    dut.stop()
    assert commands(dut) == (0.0, 0.0, 0.0, 0.0)


def test_a_jog_holds_through_configure(dut):
    dut.command(m.Jog(0, 0.12))
    dut.configure(tolerance=0.05)
    dut.configure_pid(m.Axis.X, kp=5.0)
    assert commands(dut)[0] == pytest.approx(0.12, abs=COMMAND_TOL)
