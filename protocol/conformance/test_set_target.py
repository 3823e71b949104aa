"""Conformance: set_target — module bounds, non-finite values, every state but estop, refusals keep the old target."""

from __future__ import annotations

import math

import pytest

from mantaray.host.link import CommandRefused
from mantaray.protocol import messages as m
from mantaray.protocol.conformance.harness import TILT_TOL, f32_above, f32_below

NAN, INF = math.nan, math.inf
OUT, NOT_FINITE = m.ErrorCode.OUT_OF_RANGE, m.ErrorCode.NOT_FINITE

# (name, target for a surface of half sizes hx, hy [m] (0.25 m on one 0.5 m module), code, field)
BAD = [
    ("nan,0", lambda hx, hy: (NAN, 0.0), NOT_FINITE, 0),
    ("inf,0", lambda hx, hy: (INF, 0.0), NOT_FINITE, 0),
    ("-inf,0", lambda hx, hy: (-INF, 0.0), NOT_FINITE, 0),
    ("0,nan", lambda hx, hy: (0.0, NAN), NOT_FINITE, 1),
    ("0,inf", lambda hx, hy: (0.0, INF), NOT_FINITE, 1),
    ("0,-inf", lambda hx, hy: (0.0, -INF), NOT_FINITE, 1),
    ("past the +x edge", lambda hx, hy: (f32_above(hx), 0.0), OUT, 0),
    ("past the -x edge", lambda hx, hy: (f32_below(-hx), 0.0), OUT, 0),
    ("past the +y edge", lambda hx, hy: (0.0, f32_above(hy)), OUT, 1),
    ("past the -y edge", lambda hx, hy: (0.0, f32_below(-hy)), OUT, 1),
    ("1e30,0", lambda hx, hy: (1e30, 0.0), OUT, 0),
    ("0,-3", lambda hx, hy: (0.0, -3.0), OUT, 1),
]


def steering(dut) -> tuple[float, float]:
    """Starts and steps once with the object at the centre: the tilts point at the target."""
    dut.start()
    t = dut.position(0.0, 0.0)
    return t.tilt_zx, t.tilt_zy


@pytest.mark.parametrize("target,code,field", [case[1:] for case in BAD], ids=[case[0] for case in BAD])
def test_bad_target_is_refused_and_keeps_the_old_one(dut, target, code, field):
    dut.set_target(-0.1, 0.1)
    dut.refuse(m.SetTarget(*target(*dut.half())), code, field)
    zx, zy = steering(dut)
    assert zx < 0 < zy  # still towards (-0.1, 0.1)


@pytest.mark.parametrize(
    "target,bad",
    [
        ((NAN, 5.0), {(0, NOT_FINITE), (1, OUT)}),
        ((5.0, NAN), {(0, OUT), (1, NOT_FINITE)}),
        ((NAN, INF), {(0, NOT_FINITE), (1, NOT_FINITE)}),
        ((-1.0, 1.0), {(0, OUT), (1, OUT)}),
    ],
    ids=["nan,5", "5,nan", "nan,inf", "-1,1"],
)
def test_both_fields_bad_names_one_of_them(dut, target, bad):
    dut.set_target(-0.1, 0.1)
    with pytest.raises(CommandRefused) as refused:
        dut.command(m.SetTarget(*target))
    assert (refused.value.nack.field, refused.value.nack.code) in bad
    zx, zy = steering(dut)
    assert zx < 0 < zy


@pytest.mark.parametrize("target", [(0.25, 0.25), (-0.25, -0.25), (0.25, -0.25), (-0.25, 0.25), (0.0, 0.0)])
def test_targets_on_the_module_edge_are_accepted(dut, target):
    dut.set_target(*target)
    zx, zy = steering(dut)  # the first step is kp * error with the boot kp
    kp = m.PID_DEFAULTS[m.Axis.X]["kp"]
    assert zx == pytest.approx(kp * target[0], abs=TILT_TOL)
    assert zy == pytest.approx(kp * target[1], abs=TILT_TOL)


def test_bounds_follow_the_configured_module(dut):
    dut.configure(module_x=1.0, module_y=0.4, tilt_limit=10.0)
    hx, hy = dut.half(1.0, 0.4)
    dut.set_target(hx, hy)
    dut.set_target(-hx, -hy)
    dut.refuse(m.SetTarget(f32_above(hx), 0.0), OUT, 0)
    dut.refuse(m.SetTarget(0.0, hy + 0.01), OUT, 1)


@pytest.mark.parametrize("state", ["idle", "running", "reached", "fault"])
def test_set_target_is_accepted_in_every_state_but_estop(dut, state):
    dut.enter(state)
    ack = dut.set_target(-0.2, -0.1)
    assert ack.ref_id == m.SetTarget.ID
    assert dut.probe().state == m.State[state.upper()]
    dut.stop()
    zx, zy = steering(dut)
    assert zx < 0 and zy < 0


def test_set_target_in_estop_is_bad_state_and_keeps_the_old_target(dut):
    dut.set_target(0.2, 0.1)
    dut.emergency_stop()
    dut.refuse(m.SetTarget(-0.2, -0.1), m.ErrorCode.BAD_STATE)
    dut.stop()
    zx, zy = steering(dut)
    assert zx > 0 and zy > 0


def test_a_new_target_while_running_steers_at_once(dut):
    dut.set_target(0.2, 0.0)
    zx, _ = steering(dut)
    assert zx > 0
    dut.set_target(-0.2, 0.0)
    t = dut.position(0.0, 0.0)
    assert t.tilt_zx < 0
    assert t.state == m.State.RUNNING
