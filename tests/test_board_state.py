"""A board's state in words (host/board_state.py): the faulted actuator and, on an array, every module it is a corner of."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from mantaray.host.board_state import NO_ACTUATOR, state_text
from mantaray.protocol import messages as m
from mantaray.protocol.rig import Grid


def _telemetry(actuator: int, faults: int = 0) -> m.Telemetry:
    return m.Telemetry(state=m.State.FAULT, faults=m.Faults(faults), fault_actuator=actuator)


def _identity(nx: int, ny: int) -> m.IdentifyReply:
    return m.IdentifyReply(modules_x=nx, modules_y=ny)


def test_no_faulted_actuator_names_the_state_and_its_faults_alone():
    text = state_text(_telemetry(NO_ACTUATOR, m.Faults.POSITION_TIMEOUT), _identity(2, 2))
    assert text == "FAULT (position_timeout)"


def test_one_module_names_the_actuator():
    assert state_text(_telemetry(3), _identity(1, 1)) == "FAULT, actuator 3"


@given(st.integers(1, 3), st.integers(1, 3), st.data())
def test_an_array_names_the_actuator_and_every_module_it_stopped(nx, ny, data):
    grid = Grid(nx, ny)
    actuator = data.draw(st.integers(0, grid.actuator_count - 1))
    text = state_text(_telemetry(actuator), _identity(nx, ny))
    assert text.startswith(f"FAULT, actuator {actuator}")
    if grid.module_count > 1:
        listed = text.split("module")[1].split(":")[0].lstrip("s ").split(", ")
        assert tuple(int(k) for k in listed) == grid.modules_of(actuator)
        assert "every module of the array stopped" in text


def test_an_actuator_the_rig_lacks_is_said_to_be_so():
    assert "not on this rig" in state_text(_telemetry(12), _identity(2, 2))
