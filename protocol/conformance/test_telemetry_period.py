"""Conformance: unsolicited telemetry every telemetry_period ms (0 = none), in every state."""

from __future__ import annotations

import itertools

import pytest

from mantaray.protocol import messages as m


@pytest.mark.parametrize("state", ["idle", "running", "estop"])
def test_period_zero_sends_nothing_unasked(dut, advance, state):
    dut.enter(state)
    assert advance(0.2) == []


@pytest.mark.clock("simulated")
def test_periodic_telemetry_on_a_simulated_clock(dut, advance):
    dut.configure(telemetry_period=50)
    advance(0.05)  # the period may have run out already at configure: start counting afresh
    got = advance(0.05)
    assert [t.time for t in got] == [dut.sim_now_ms]
    assert advance(0.03) == []
    got = advance(0.02)
    assert [t.time for t in got] == [dut.sim_now_ms]
    assert got[0].state == m.State.IDLE


@pytest.mark.clock("wall")
@pytest.mark.wall_timing
def test_periodic_telemetry_on_a_wall_clock(dut, advance):
    dut.configure(telemetry_period=20)
    got = advance(0.3)
    times = [t.time for t in got]
    # never early, and on average close to the period; "close" leaves a scheduler slice (~10 ms) per frame for a
    # busy 2-core machine, where the firmware and this host share the cores (the simulated-clock test above
    # checks the period to the millisecond)
    assert 8 <= len(times) <= 16
    gaps = [(b - a) & 0xFFFFFFFF for a, b in itertools.pairwise(times)]
    assert min(gaps) >= 20
    assert sum(gaps) / len(gaps) <= 30


@pytest.mark.parametrize("state", ["running", "fault", "estop"])
def test_periodic_telemetry_reports_the_state(dut, advance, state):
    dut.configure(telemetry_period=20, deadman=20 if state == "fault" else 500)
    dut.set_target(0.1, 0.0)
    if state == "estop":
        dut.emergency_stop()
    else:
        dut.start()
        dut.position(0.0, 0.0)
    got = advance(0.06)
    assert got
    assert got[-1].state == m.State[state.upper()]


def test_setting_the_period_back_to_zero_stops_it(dut, advance):
    dut.configure(telemetry_period=20)
    assert advance(0.05)
    dut.configure(telemetry_period=0)
    assert advance(0.1) == []
