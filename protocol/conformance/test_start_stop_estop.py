"""Conformance: the state table — start (idle only, needs a target), stop (always, clears faults), emergency_stop."""

from __future__ import annotations

import pytest

from mantaray.protocol import messages as m
from mantaray.protocol.conformance.harness import ALT_GAINS, STATES, TILT_TOL

LEVEL = (0.0, 0.0, 0.0, 0.0)


def assert_level(t: m.Telemetry) -> None:
    assert (t.tilt_zx, t.tilt_zy, tuple(t.command)) == (0.0, 0.0, LEVEL)


# ------------------------------------------------------------------------------------------------- start
def test_start_before_any_set_target_is_no_target(dut):
    """Checked once, when the session connected, before any test had set a target."""
    if dut.first_start == m.ErrorCode.OK:
        pytest.skip("the firmware already had a target when the suite connected (reset it to check this)")
    assert dut.first_start == m.ErrorCode.NO_TARGET


def test_start_goes_from_idle_to_running(dut):
    dut.set_target(0.1, 0.1)
    ack = dut.start()
    assert ack.ref_id == m.Start.ID
    t = dut.probe()
    assert t.state == m.State.RUNNING
    assert t.faults == 0
    assert_level(t)  # nothing to steer by before the first position


@pytest.mark.parametrize("state", ["running", "reached", "fault", "estop"])
def test_start_outside_idle_is_bad_state_and_changes_nothing(dut, state):
    before = dut.enter(state)
    dut.refuse(m.Start(), m.ErrorCode.BAD_STATE)
    after = dut.probe()
    assert (after.state, after.faults, after.tilt_zx, after.tilt_zy, after.command) == (
        before.state,
        before.faults,
        before.tilt_zx,
        before.tilt_zy,
        before.command,
    )


def test_start_resets_the_pids(dut):
    dut.configure_pid(m.Axis.X, kp=10.0, ki=100.0, kd=0.0, integral_limit=20.0)
    dut.set_target(0.1, 0.0)
    dut.start()
    first = dut.position(0.0, 0.0).tilt_zx
    wound = [dut.position(0.0, 0.0, dt=0.1).tilt_zx for _ in range(3)]
    assert first == pytest.approx(1.0, abs=TILT_TOL)
    assert wound == [pytest.approx(v, abs=TILT_TOL) for v in (2.0, 3.0, 4.0)]  # the integral grows 1 deg a step
    dut.stop()
    dut.start()
    assert dut.position(0.0, 0.0).tilt_zx == pytest.approx(1.0, abs=TILT_TOL)  # integral forgotten


def noisy_run(dut, seed: int) -> list[tuple]:
    dut.configure(noise_amplitude=0.01, noise_seed=seed)
    dut.set_target(0.1, 0.05)
    dut.start()
    out = [tuple(dut.position(x, 0.0).command) for x in (0.0, 0.01, 0.02, 0.03)]
    dut.stop()
    return out


def test_start_reseeds_the_noise(dut):
    first = noisy_run(dut, seed=12345)
    assert noisy_run(dut, seed=12345) == first
    assert noisy_run(dut, seed=54321) != first
    dut.configure(noise_amplitude=0.0)
    dut.set_target(0.1, 0.05)
    dut.start()
    assert tuple(dut.position(0.0, 0.0).command) != first[0]


def test_noise_seed_zero_is_seed_one(dut):
    assert noisy_run(dut, seed=0) == noisy_run(dut, seed=1)


def test_start_forgets_the_camera_history(dut):
    dut.set_target(0.1, 0.0)
    dut.position(0.0, 0.0)
    repeat = m.ObjectPosition(dut.frame, dut.capture_us, 0.0, 0.0, m.PositionFlags(0))
    dut.refuse_position(repeat, m.ErrorCode.STALE_POSITION, 0)
    dut.start()
    assert dut.send_position(repeat).state == m.State.RUNNING


def test_start_ends_a_jog(dut):
    dut.command(m.Jog(dut.corners(0)[2], 0.1))
    assert dut.probe().command[2] == pytest.approx(0.1, abs=1e-5)
    dut.set_target(0.1, 0.0)
    dut.start()
    assert_level(dut.probe())


# -------------------------------------------------------------------------------------------------- stop
@pytest.mark.parametrize("state", STATES)
def test_stop_is_accepted_in_every_state_and_levels_to_idle(dut, state):
    dut.enter(state)
    ack = dut.stop()
    assert ack.ref_id == m.Stop.ID
    t = dut.probe()
    assert t.state == m.State.IDLE
    assert t.faults == 0
    assert_level(t)


def test_stop_clears_both_faults(dut):
    dut.enter("fault")
    dut.emergency_stop()
    t = dut.probe()
    assert t.faults == m.Faults.POSITION_TIMEOUT | m.Faults.ESTOP
    dut.stop()
    assert dut.probe().faults == 0


def test_stop_twice_is_fine(dut):
    dut.stop()
    dut.stop()
    assert dut.probe().state == m.State.IDLE


# ---------------------------------------------------------------------------------------- emergency stop
@pytest.mark.parametrize("state", STATES)
def test_emergency_stop_is_accepted_in_every_state(dut, state):
    before = dut.enter(state)
    ack = dut.emergency_stop()
    assert ack.ref_id == m.EmergencyStop.ID
    t = dut.probe()
    assert t.state == m.State.ESTOP
    assert t.faults == before.faults | m.Faults.ESTOP
    assert_level(t)


def test_emergency_stop_cuts_a_running_controller(dut):
    dut.set_target(0.2, 0.2)
    dut.start()
    assert dut.position(0.0, 0.0).tilt_zx > 0
    dut.emergency_stop()
    t = dut.position(-0.1, -0.1)  # positions are still answered, but steer nothing
    assert t.state == m.State.ESTOP
    assert_level(t)


def test_emergency_stop_is_latched_until_stop(dut, advance):
    dut.configure(deadman=50)
    dut.set_target(0.1, 0.0)
    dut.emergency_stop()
    dut.refuse(m.Start(), m.ErrorCode.BAD_STATE)
    dut.refuse(m.SetTarget(0.0, 0.0), m.ErrorCode.BAD_STATE)
    dut.refuse(m.Configure(), m.ErrorCode.BAD_STATE)
    dut.refuse(m.ConfigurePid(m.Axis.X, **ALT_GAINS), m.ErrorCode.BAD_STATE)
    dut.refuse(m.Jog(0, 0.1), m.ErrorCode.BAD_STATE)
    dut.emergency_stop()
    dut.position(0.0, 0.0)
    advance(0.1)  # longer than the deadman: an estop is no position timeout
    t = dut.probe()
    assert (t.state, t.faults) == (m.State.ESTOP, m.Faults.ESTOP)
    assert_level(t)
    dut.stop()
    t = dut.probe()
    assert (t.state, t.faults) == (m.State.IDLE, 0)
    dut.start()  # the target set before the estop is still there
    assert dut.probe().state == m.State.RUNNING
