"""Conformance: sim_clock — sets a simulated clock (never backwards), what is due runs first; wall clocks refuse it."""

from __future__ import annotations

import time

import pytest

from mantaray.protocol import messages as m

simulated = pytest.mark.clock("simulated")
wall = pytest.mark.clock("wall")


@simulated
def test_sim_clock_sets_the_firmware_time(dut):
    ack = dut.set_sim_clock(dut.sim_now_us + 1_234_567)
    assert ack.ref_id == m.SimClock.ID
    assert dut.probe().time == dut.sim_now_ms


@simulated
def test_simulated_time_stands_still_between_sim_clocks(dut):
    first = dut.probe().time
    time.sleep(0.05)
    assert dut.probe().time == first == dut.sim_now_ms


@simulated
def test_sim_clock_to_the_same_time_is_accepted(dut):
    dut.set_sim_clock(dut.sim_now_us + 5000)
    dut.set_sim_clock(dut.sim_now_us)
    assert dut.probe().time == dut.sim_now_ms


@simulated
@pytest.mark.parametrize("back_us", [1, 1000, 1_000_000])
def test_sim_clock_backwards_is_out_of_range_and_changes_nothing(dut, back_us):
    dut.set_sim_clock(dut.sim_now_us + 2_000_000)
    dut.refuse(m.SimClock(dut.sim_now_us - back_us), m.ErrorCode.OUT_OF_RANGE, field=None)
    assert dut.probe().time == dut.sim_now_ms
    dut.set_sim_clock(dut.sim_now_us + 1)  # and time still goes on from where it was


@simulated
def test_sim_clock_backwards_names_the_now_field(dut):
    dut.set_sim_clock(dut.sim_now_us + 1000)
    dut.refuse(m.SimClock(dut.sim_now_us - 1), m.ErrorCode.OUT_OF_RANGE, field=0)


@simulated
def test_what_is_due_at_the_new_time_happens_before_the_ack(dut):
    dut.configure(deadman=100, telemetry_period=50)
    dut.set_target(0.1, 0.0)
    dut.start()
    mark = len(dut.log)
    dut.set_sim_clock(dut.sim_now_us + 150_000)
    ack_at = next(i for i, msg in enumerate(dut.log) if i >= mark and isinstance(msg, m.Ack))
    periodic = [msg for msg in dut.log[mark:ack_at] if isinstance(msg, m.Telemetry)]
    assert len(periodic) == 1
    assert periodic[0].time == dut.sim_now_ms
    assert periodic[0].state == m.State.FAULT  # the deadman ran at the new time, before the telemetry
    assert periodic[0].faults == m.Faults.POSITION_TIMEOUT


@wall
@pytest.mark.parametrize("now", [0, 10_000_000, 0xFFFFFFFF])
def test_sim_clock_on_a_wall_clock_is_unsupported(dut, now):
    before = dut.probe().time
    dut.refuse(m.SimClock(now), m.ErrorCode.UNSUPPORTED)
    time.sleep(0.05)
    after = dut.probe().time
    assert 40 <= (after - before) & 0xFFFFFFFF <= 1000  # wall time went on, untouched


@wall
def test_wall_clock_runs_in_milliseconds(dut):
    t0, h0 = dut.probe().time, time.monotonic()
    time.sleep(0.2)
    t1, h1 = dut.probe().time, time.monotonic()
    host_ms = (h1 - h0) * 1000
    assert abs(((t1 - t0) & 0xFFFFFFFF) - host_ms) <= 20 + 0.05 * host_ms


@simulated
def test_telemetry_time_counts_on_across_the_microsecond_wrap(dut):
    """telemetry.time [ms] wraps at 2^32 ms (49.7 days), not when the u32 microsecond clock does (71.6 min)."""
    before = dut.probe().time
    for _ in range(3):  # 3 x (2^31 - 1) us: past the microsecond clock's wrap
        dut.set_sim_clock(dut.sim_now_us + 0x7FFFFFFF)
    after = dut.probe().time
    assert after == dut.sim_now_ms
    assert after - before in (6_442_450, 6_442_451)  # 6,442,450.941 ms, whatever the sub-millisecond rest was
