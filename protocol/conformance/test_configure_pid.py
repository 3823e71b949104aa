"""Conformance: configure_pid — gains take effect per axis, each refusal's code and field, refusals change nothing."""

from __future__ import annotations

import math

import pytest

from mantaray.protocol import messages as m
from mantaray.protocol.conformance.harness import (
    ALT_GAINS,
    CONFIGURE_PID_FIELD,
    TILT_TOL,
    base_pid_fingerprint,
    f32_above,
    f32_below,
    pid_fingerprint,
)

NAN, INF = math.nan, math.inf
OUT, NOT_FINITE = m.ErrorCode.OUT_OF_RANGE, m.ErrorCode.NOT_FINITE

BAD = [({"axis": len(m.Axis)}, OUT, "axis"), ({"axis": 255}, OUT, "axis")]
for _gain, _max in (("kp", 10000.0), ("ki", 10000.0), ("kd", 10000.0), ("integral_limit", 90.0)):
    BAD += [
        ({_gain: NAN}, NOT_FINITE, _gain),
        ({_gain: INF}, NOT_FINITE, _gain),
        ({_gain: -INF}, NOT_FINITE, _gain),
        ({_gain: f32_below(0.0)}, OUT, _gain),
        ({_gain: -1.0}, OUT, _gain),
        ({_gain: f32_above(_max)}, OUT, _gain),
    ]


def _id(case) -> str:
    changes = case[0]
    return "-".join(f"{k}={v:.9g}" if isinstance(v, float) else f"{k}={v}" for k, v in changes.items())


@pytest.mark.parametrize("axis", list(m.Axis), ids=lambda a: a.name.lower())
@pytest.mark.parametrize("changes,code,field", BAD, ids=[_id(c) for c in BAD])
def test_bad_configure_pid_is_refused_and_changes_nothing(dut, axis, changes, code, field):
    reference = base_pid_fingerprint(dut)
    msg = m.ConfigurePid(**{"axis": axis, **ALT_GAINS, **changes})
    dut.refuse(msg, code, CONFIGURE_PID_FIELD[field])
    assert pid_fingerprint(dut) == reference


@pytest.mark.parametrize("axis", list(m.Axis), ids=lambda a: a.name.lower())
def test_gains_take_effect_on_their_axis_only(dut, axis):
    reference = base_pid_fingerprint(dut)
    for gain, value in ALT_GAINS.items():
        dut.configure_pid(axis, **{gain: value})
        changed = pid_fingerprint(dut)
        assert changed[axis.name] != reference[axis.name], f"{axis.name}.{gain} made no difference"
        others = {k: v for k, v in changed.items() if k != axis.name}
        assert others == {k: v for k, v in reference.items() if k != axis.name}
        dut.configure_pid(axis)  # back to the boot gains
    assert pid_fingerprint(dut) == reference


@pytest.mark.parametrize(
    "gains",
    [
        {"kp": 0.0, "ki": 0.0, "kd": 0.0, "integral_limit": 0.0},
        {"kp": 10000.0, "ki": 10000.0, "kd": 10000.0, "integral_limit": 90.0},
    ],
    ids=["zero", "max"],
)
@pytest.mark.parametrize("axis", list(m.Axis), ids=lambda a: a.name.lower())
def test_boundary_gains_are_accepted(dut, axis, gains):
    ack = dut.configure_pid(axis, **gains)
    assert isinstance(ack, m.Ack) and ack.ref_id == m.ConfigurePid.ID


def test_first_step_is_proportional(dut):
    """Right after start the controller has no rate: the tilt is kp * error (degrees per metre)."""
    dut.configure_pid(m.Axis.X, kp=10.0, ki=500.0, kd=500.0)
    dut.configure_pid(m.Axis.Y, kp=20.0, ki=500.0, kd=500.0)
    dut.set_target(0.1, -0.15)
    dut.start()
    t = dut.position(0.0, 0.0)
    assert t.tilt_zx == pytest.approx(1.0, abs=TILT_TOL)
    assert t.tilt_zy == pytest.approx(-3.0, abs=TILT_TOL)


def test_integral_term_is_bounded_by_integral_limit(dut):
    dut.configure_pid(m.Axis.X, kp=10.0, ki=100.0, kd=0.0, integral_limit=0.5)
    dut.set_target(0.1, 0.0)
    dut.start()
    dut.position(0.0, 0.0)
    tilts = [dut.position(0.0, 0.0, dt=0.1).tilt_zx for _ in range(3)]
    # kp * 0.1 = 1 deg, plus the integral: 1 deg per step at ki * 0.1 m * 0.1 s, but at most 0.5 deg
    assert tilts == [pytest.approx(1.5, abs=TILT_TOL)] * 3


@pytest.mark.parametrize("state", ["running", "reached", "fault", "estop"])
def test_configure_pid_outside_idle_is_bad_state_and_changes_nothing(dut, state):
    reference = base_pid_fingerprint(dut)
    dut.enter(state)
    for axis in m.Axis:
        dut.refuse(m.ConfigurePid(axis, **ALT_GAINS), m.ErrorCode.BAD_STATE)
    assert dut.probe().state == m.State[state.upper()]
    dut.stop()
    dut.configure()
    assert pid_fingerprint(dut) == reference
