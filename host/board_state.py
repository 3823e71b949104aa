"""A board's state in words: its latched faults and, where an actuator faulted, which one and which modules it stopped."""

from __future__ import annotations

from mantaray.protocol import messages as m
from mantaray.protocol.rig import Grid

NO_ACTUATOR = 255  # telemetry.fault_actuator when no actuator faulted (schema.toml)


def state_text(telemetry: m.Telemetry, identity: m.IdentifyReply | None = None) -> str:
    """IDLE, FAULT (position_timeout), ESTOP; with the faulted actuator, and on an array (identity's shape) the
    modules it is a corner of, all of which the supervisor's shutdown stopped with every other."""
    faults = [f.name.lower() for f in m.Faults if telemetry.faults & f and f != m.Faults.ESTOP]  # its own state
    text = m.State(telemetry.state).name + (f" ({', '.join(faults)})" if faults else "")
    actuator = telemetry.fault_actuator
    if actuator == NO_ACTUATOR:
        return text
    text += f", actuator {actuator}"
    grid = Grid(identity.modules_x, identity.modules_y) if identity is not None else Grid()
    if grid.module_count == 1:
        return text
    modules = grid.modules_of(actuator) if actuator < grid.actuator_count else ()
    shared = (
        f"a corner of module{'s' if len(modules) > 1 else ''} {', '.join(map(str, modules))}"
        if modules
        else "not on this rig"
    )
    return f"{text} ({shared}: every module of the array stopped)"
