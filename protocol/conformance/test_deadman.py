"""Conformance: the deadman — running without a valid position for `deadman` ms levels the surface and latches a fault."""

from __future__ import annotations

import pytest

from mantaray.protocol import messages as m

LEVEL = (0.0, 0.0, (0.0, 0.0, 0.0, 0.0))


def assert_timed_out(t: m.Telemetry) -> None:
    assert (t.state, t.faults) == (m.State.FAULT, m.Faults.POSITION_TIMEOUT)
    assert (t.tilt_zx, t.tilt_zy, t.command) == LEVEL


def start_steering(dut, deadman: int) -> m.Telemetry:
    dut.configure(deadman=deadman)
    dut.set_target(0.2, 0.2)
    dut.start()
    t = dut.position(0.0, 0.0)
    assert t.state == m.State.RUNNING and t.tilt_zx > 0
    return t


def test_no_position_for_the_deadman_faults_and_levels(dut, advance):
    start_steering(dut, deadman=50)
    advance(0.1)
    assert_timed_out(dut.probe())


def test_the_deadman_starts_at_start(dut, advance):
    dut.configure(deadman=50)
    dut.set_target(0.1, 0.0)
    dut.start()
    advance(0.1)  # the first position never came
    assert_timed_out(dut.probe())


def test_valid_positions_keep_it_running(dut, advance):
    start_steering(dut, deadman=100)
    for _ in range(5):  # 200 ms in all, a position every 40 ms
        advance(0.04)
        assert dut.position(0.0, 0.0).state == m.State.RUNNING
    assert dut.probe().faults == 0


def test_not_visible_positions_do_not_feed_it(dut, advance):
    start_steering(dut, deadman=100)
    for _ in range(5):
        advance(0.04)
        dut.position(0.0, 0.0, visible=False)
    assert_timed_out(dut.probe())


def test_reached_times_out_too(dut, advance):
    dut.configure(deadman=50)
    dut.set_target(0.0, 0.0)
    dut.start()
    assert dut.position(0.0, 0.0).state == m.State.REACHED
    advance(0.1)
    assert_timed_out(dut.probe())


def test_the_fault_is_latched_until_stop(dut, advance):
    start_steering(dut, deadman=50)
    advance(0.1)
    for x in (0.0, 0.05, 0.1):  # positions come back: still a fault, still level
        assert_timed_out(dut.position(x, 0.0))
    dut.refuse(m.Start(), m.ErrorCode.BAD_STATE)
    dut.stop()
    t = dut.probe()
    assert (t.state, t.faults) == (m.State.IDLE, 0)
    dut.start()
    assert dut.position(0.0, 0.0).state == m.State.RUNNING


@pytest.mark.parametrize("state", ["idle", "estop"])
def test_no_deadman_outside_running(dut, advance, state):
    dut.configure(deadman=50)
    dut.set_target(0.1, 0.0)
    dut.enter(state)
    advance(0.15)
    t = dut.probe()
    assert t.state == m.State[state.upper()]
    assert not t.faults & m.Faults.POSITION_TIMEOUT


@pytest.mark.clock("simulated")
def test_deadman_boundary_is_exact(dut):
    """Faults once more than `deadman` ms passed; exactly `deadman` ms is still in time."""
    start_steering(dut, deadman=50)
    dut.set_sim_clock(dut.sim_now_us + 50_000)
    assert dut.probe().state == m.State.RUNNING
    dut.set_sim_clock(dut.sim_now_us + 1)
    assert_timed_out(dut.probe())


@pytest.mark.clock("simulated")
def test_each_valid_position_restarts_the_deadman(dut):
    start_steering(dut, deadman=50)
    dut.set_sim_clock(dut.sim_now_us + 49_000)
    dut.position(0.0, 0.0)
    dut.set_sim_clock(dut.sim_now_us + 50_000)
    assert dut.probe().state == m.State.RUNNING
    dut.set_sim_clock(dut.sim_now_us + 1)
    assert dut.probe().state == m.State.FAULT


@pytest.mark.clock("wall")
@pytest.mark.wall_timing
def test_deadman_fires_on_time(dut, advance):
    start_steering(dut, deadman=100)
    advance(0.03)
    assert dut.probe().state == m.State.RUNNING
    advance(0.12)
    assert_timed_out(dut.probe())
