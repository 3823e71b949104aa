"""Conformance: array_commands — an array's every actuator command just before each telemetry; one module sends none."""

from __future__ import annotations

import pytest

from mantaray.protocol import messages as m
from mantaray.protocol.conformance.harness import ACTUATOR_RANGE

WIRE_M = 1e-5  # [m] one unit of a command on the wire (schema.toml's scale)


def answered(dut, x: float, y: float) -> tuple[m.Telemetry, list[m.ArrayCommands]]:
    """A position's telemetry, and the array_commands that came just before it."""
    mark, sent = len(dut.log), len(dut.array_commands)
    t = dut.position(x, y)
    at = mark + dut.log[mark:].index(t)
    return t, [msg for index, msg in dut.array_commands[sent:] if index == at]


@pytest.mark.parametrize("fx, fy", [(-0.6, -0.6), (0.6, -0.4), (-0.2, 0.7), (0.4, 0.4)])
def test_array_commands_come_before_an_arrays_every_telemetry_and_never_from_one_module(dut, fx, fy):
    """An object at (fx, fy) of the surface's half sides, the target opposite. On an array: one array_commands before
    the telemetry, saying at the driven module's corners what telemetry says, every command within the travel, some
    actuator outside the driven module moved with its plane, and 0 past the rig's actuators. On one module: none."""
    grid = dut.grid()
    hx, hy = grid.half_extent_m
    x, y = fx * hx, fy * hy
    dut.set_target(-x, -y)
    dut.start()
    t, before = answered(dut, x, y)
    if grid.module_count == 1:
        assert before == []
        return
    assert len(before) == 1
    commands = before[0].command
    assert t.module == grid.module_at(x, y)
    for corner, actuator in enumerate(grid.module_corners(t.module)):
        assert commands[actuator] == pytest.approx(t.command[corner], abs=WIRE_M / 2)
    assert all(abs(a) <= ACTUATOR_RANGE + WIRE_M for a in commands)
    assert all(a == 0.0 for a in commands[grid.actuator_count :])
    assert any(commands[a] != 0.0 for a in range(grid.actuator_count) if a not in grid.module_corners(t.module))
