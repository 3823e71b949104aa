"""Conformance: every command in every supervisor state — taken in the states its schema entry names, refused outside
them with the schema's state error before any field is looked at, and the state left as it was."""

from __future__ import annotations

import dataclasses

import pytest

from mantaray.protocol import messages as m
from mantaray.protocol.conformance.harness import DEFAULT_CONFIG, STATES

COMMANDS = [cls for cls in m.MESSAGES.values() if cls.DIRECTION == "host_to_mcu"]


def sample(cls: type[m.Message], dut) -> m.Message:
    """A command of this kind that is valid in idle (its fields pass every check)."""
    if cls is m.Configure:
        return DEFAULT_CONFIG
    if cls is m.ConfigurePid:
        return m.ConfigurePid(m.Axis.X, **m.PID_DEFAULTS[m.Axis.X])
    if cls is m.Jog:
        return m.Jog(0, 0.0)
    if cls is m.Zero:
        return m.Zero(0b0001)
    if cls is m.SimClock:
        return m.SimClock(dut.sim_now_us)  # no step backwards (a wall-clock board answers unsupported)
    if cls is m.ObjectPosition:
        return dut.next_position(0.0, 0.0, dt=1e-6, visible=False)
    return cls()  # identify, set_target (the origin), start, stop, emergency_stop, configure_schedule/cascade


def test_every_command_and_state_is_covered():
    assert {cls.NAME for cls in COMMANDS} == {
        "identify", "configure", "configure_pid", "set_target", "start", "stop", "emergency_stop", "jog",
        "sim_clock", "zero", "configure_schedule", "configure_cascade", "object_position",
    }  # fmt: skip
    assert set(STATES) == {s.name.lower() for s in m.State}
    assert all(cls.STATES for cls in COMMANDS)


@pytest.mark.parametrize("state", STATES)
@pytest.mark.parametrize("cls", COMMANDS, ids=lambda cls: cls.NAME)
def test_a_command_outside_its_states_is_refused_with_the_state_error(dut, cls, state):
    before = dut.enter(state)
    msg = sample(cls, dut)
    if m.State[state.upper()] in cls.STATES:
        if cls is m.Identify:
            assert dut.link.identify().protocol_version == m.PROTOCOL_VERSION
        elif cls is m.ObjectPosition:
            assert dut.send_position(msg).position_frame == msg.frame
        else:
            assert dut.result(msg) != m.STATE_ERROR, f"{cls.NAME} refused in {state}"
        return
    dut.refuse(msg, m.STATE_ERROR, m.NO_FIELD)
    floats = {spec.name: float("nan") for spec in cls.FIELDS if spec.fmt == "f"}
    if floats:  # the state is judged before the fields
        dut.refuse(dataclasses.replace(msg, **floats), m.STATE_ERROR, m.NO_FIELD)
    after = dut.probe()
    assert (after.state, after.faults, after.command) == (before.state, before.faults, before.command)
