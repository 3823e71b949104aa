"""Conformance: object_position and telemetry — answers, non-finite and stale frames, not_visible, steering, reached."""

from __future__ import annotations

import math

import pytest

from mantaray.protocol import messages as m
from mantaray.protocol.conformance.harness import COMMAND_TOL, POSITION_FIELD, STATES, TILT_TOL

NAN, INF = math.nan, math.inf
VISIBLE, NOT_VISIBLE = m.PositionFlags(0), m.PositionFlags.NOT_VISIBLE
STALE, NOT_FINITE = m.ErrorCode.STALE_POSITION, m.ErrorCode.NOT_FINITE


def same_frame(dut, x=0.0, y=0.0, flags=VISIBLE, capture_delta=0) -> m.ObjectPosition:
    """A frame that repeats the last one's counter (capture time moved by capture_delta us)."""
    return m.ObjectPosition(dut.frame, (dut.capture_us + capture_delta) & 0xFFFFFFFF, x, y, flags)


# ---------------------------------------------------------------------------------------------- answers
@pytest.mark.parametrize("state", STATES)
def test_every_state_answers_a_position_with_telemetry(dut, state):
    dut.enter(state)
    for visible in (True, False):
        msg = dut.next_position(0.01, -0.01, visible=visible)
        t = dut.send_position(msg)
        assert t.position_frame == msg.frame
        assert t.state == m.State[state.upper()]


def test_a_position_is_answered_by_exactly_one_telemetry(dut):
    msg = dut.next_position(0.0, 0.0)
    before, _ = dut.exchange(dut.frame_bytes(msg)[0])
    assert before == [x for x in before if isinstance(x, m.Telemetry)]  # no ack or nack
    assert [x.position_frame for x in before] == [msg.frame]


# ------------------------------------------------------------------------------------------ non-finite
BAD_XY = [
    ((NAN, 0.0), "x"),
    ((INF, 0.0), "x"),
    ((-INF, 0.0), "x"),
    ((0.0, NAN), "y"),
    ((0.0, INF), "y"),
    ((0.0, -INF), "y"),
]


@pytest.mark.parametrize("state", ["idle", "running"])
@pytest.mark.parametrize("xy,field", BAD_XY, ids=[f"{x},{y}" for (x, y), _ in BAD_XY])
def test_non_finite_position_is_not_finite_and_changes_nothing(dut, state, xy, field):
    dut.set_target(0.1, 0.1)
    if state == "running":
        dut.start()
    before = dut.position(0.0, 0.0)
    bad = dut.next_position(*xy)
    dut.refuse_position(bad, NOT_FINITE, POSITION_FIELD[field])
    # the refused frame did not enter the history: its counter and capture time are still new
    again = m.ObjectPosition(bad.frame, bad.capture_time, 0.0, 0.0, VISIBLE)
    after = dut.send_position(again)
    assert after.state == before.state
    if state == "running":  # one integral step of 20 ms since `before`, as if the bad frame never came
        grown = m.PID_DEFAULTS[m.Axis.X]["ki"] * 0.1 * 0.02
        assert after.tilt_zx == pytest.approx(before.tilt_zx + grown, abs=TILT_TOL)
        assert after.tilt_zy == pytest.approx(before.tilt_zy + grown, abs=TILT_TOL)
    else:
        assert (after.tilt_zx, after.tilt_zy, after.command) == (0.0, 0.0, (0.0, 0.0, 0.0, 0.0))


def test_non_finite_position_does_not_feed_the_deadman(dut, advance):
    dut.configure(deadman=100)
    dut.set_target(0.1, 0.0)
    dut.start()
    dut.position(0.0, 0.0)
    for _ in range(4):
        advance(0.04)
        dut.refuse_position(dut.next_position(NAN, 0.0), NOT_FINITE, POSITION_FIELD["x"])
    t = dut.probe()
    assert (t.state, t.faults) == (m.State.FAULT, m.Faults.POSITION_TIMEOUT)


@pytest.mark.parametrize("xy", [(NAN, NAN), (INF, -INF), (1e30, -1e30)])
def test_not_visible_frames_ignore_x_and_y(dut, xy):
    t = dut.position(*xy, visible=False)
    assert t.position_frame == dut.frame


# -------------------------------------------------------------------------------------------------- stale
@pytest.mark.parametrize("state", ["idle", "running"])
def test_repeated_frame_counter_is_stale_field_0(dut, state):
    dut.set_target(0.1, 0.0)
    if state == "running":
        dut.start()
    before = dut.position(0.0, 0.0)
    dut.refuse_position(same_frame(dut, capture_delta=20_000), STALE, POSITION_FIELD["frame"])
    assert dut.probe().position_frame == before.position_frame + 1


@pytest.mark.parametrize("capture_delta", [0, -1, -1_000_000], ids=["equal", "1us-back", "1s-back"])
def test_capture_time_that_does_not_advance_is_stale_field_1(dut, capture_delta):
    dut.position(0.0, 0.0)
    msg = m.ObjectPosition((dut.frame + 1) & 0xFFFF, (dut.capture_us + capture_delta) & 0xFFFFFFFF, 0.0, 0.0, VISIBLE)
    dut.refuse_position(msg, STALE, POSITION_FIELD["capture_time"])


def test_repeated_counter_and_time_name_the_counter(dut):
    dut.position(0.0, 0.0)
    dut.refuse_position(same_frame(dut), STALE, POSITION_FIELD["frame"])


def test_stale_frame_changes_nothing(dut):
    dut.set_target(0.2, 0.0)
    dut.start()
    before = dut.position(0.0, 0.0)
    last_frame, last_capture = dut.frame, dut.capture_us
    # a stale frame that would move the object to the far side of the target
    dut.refuse_position(same_frame(dut, x=0.25, capture_delta=20_000), STALE, POSITION_FIELD["frame"])
    dut.refuse_position(
        m.ObjectPosition(last_frame + 1, last_capture, 0.25, 0.0, VISIBLE), STALE, POSITION_FIELD["capture_time"]
    )
    # history unchanged: the frame right after the last accepted one is still accepted
    after = dut.send_position(m.ObjectPosition(last_frame + 1, last_capture + 1, 0.0, 0.0, VISIBLE))
    assert after.position_frame == last_frame + 1
    assert before.tilt_zx > 0
    assert after.tilt_zx == pytest.approx(before.tilt_zx, abs=TILT_TOL)  # 1 us later, the object unmoved


def test_not_visible_frames_count_in_the_history(dut):
    dut.position(0.0, 0.0, visible=False)
    dut.refuse_position(same_frame(dut, capture_delta=1000), STALE, POSITION_FIELD["frame"])
    dut.refuse_position(same_frame(dut, flags=NOT_VISIBLE, capture_delta=1000), STALE, POSITION_FIELD["frame"])


def test_skipped_frames_are_accepted(dut):
    dut.position(0.0, 0.0)
    dut.frame += 5  # the camera dropped five frames
    t = dut.position(0.0, 0.0)
    assert t.position_frame == dut.frame


def test_frame_counter_wraps(dut):
    dut.frame = 0xFFFE
    assert dut.position(0.0, 0.0).position_frame == 0xFFFF
    assert dut.position(0.0, 0.0).position_frame == 0
    assert dut.position(0.0, 0.0).position_frame == 1


def test_capture_time_wraps(dut):
    """capture_time is a u32 of microseconds (71.6 min): it advances across the wrap."""
    dut.capture_us = 0xFFFFFFFF - 15_000
    dut.position(0.0, 0.0)  # capture 0xFFFFFFFF - 15000 + 20000, wrapped
    assert dut.capture_us == 4_999
    t = dut.position(0.0, 0.0)
    assert t.position_frame == dut.frame


# --------------------------------------------------------------------------------------------- telemetry
def test_telemetry_in_idle_is_level_and_fault_free(dut):
    t = dut.position(0.1, 0.1)
    assert (t.state, t.faults) == (m.State.IDLE, 0)
    assert (t.tilt_zx, t.tilt_zy, t.command) == (0.0, 0.0, (0.0, 0.0, 0.0, 0.0))


def test_a_position_in_idle_steers_nothing(dut):
    dut.set_target(0.2, 0.2)
    for x in (0.0, -0.1, 0.1):
        t = dut.position(x, x)
        assert (t.tilt_zx, t.tilt_zy, t.command) == (0.0, 0.0, (0.0, 0.0, 0.0, 0.0))


@pytest.mark.clock("simulated")
def test_position_age_counts_from_the_last_valid_position(dut, advance):
    assert dut.position(0.0, 0.0).position_age == 0
    advance(0.2)
    assert dut.probe().position_age == 200  # not_visible frames do not count as valid
    assert dut.position(0.0, 0.0, visible=False).position_age == 200
    assert dut.position(0.0, 0.0).position_age == 0


@pytest.mark.clock("wall")
@pytest.mark.wall_timing
def test_position_age_counts_from_the_last_valid_position_wall(dut, advance):
    assert dut.position(0.0, 0.0).position_age <= 5
    advance(0.1)
    age = dut.probe().position_age
    assert 95 <= age <= 300
    assert dut.position(0.0, 0.0).position_age <= 5


QUADRANTS = [(0.1, 0.0), (-0.1, 0.0), (0.0, 0.1), (0.0, -0.1), (0.1, 0.1), (-0.1, 0.05)]


@pytest.mark.parametrize("target", QUADRANTS)
@pytest.mark.parametrize("controller", list(m.Controller), ids=lambda c: c.name.lower())
def test_tilts_point_at_the_target(dut, controller, target):
    dut.configure(controller=controller)
    dut.set_target(*target)
    dut.start()
    t = dut.position(0.0, 0.0)
    for tilt, error in ((t.tilt_zx, target[0]), (t.tilt_zy, target[1])):
        if error == 0:
            assert tilt == 0.0
        else:
            assert math.copysign(1.0, tilt) == math.copysign(1.0, error) and abs(tilt) > 0.1
    if controller == m.Controller.EUCLIDEAN:  # one tilt, resolved along the error
        assert math.atan2(t.tilt_zy, t.tilt_zx) == pytest.approx(math.atan2(target[1], target[0]), abs=0.01)


def manhattan_commands(zx_deg: float, zy_deg: float, mx: float = 0.5, my: float = 0.5) -> tuple:
    """Algorithm 1's plane: n = (sin zx, sin zy, cos zx); a_i = (n_x x_i + n_y y_i) / n_z, actuator i at
    x = -+m/2 (i = 0, 2 / 1, 3) and y = -+n/2 (i = 0, 1 / 2, 3)."""
    nx, ny, nz = math.sin(math.radians(zx_deg)), math.sin(math.radians(zy_deg)), math.cos(math.radians(zx_deg))
    return tuple((nx * (mx / 2 if i & 1 else -mx / 2) + ny * (my / 2 if i & 2 else -my / 2)) / nz for i in range(4))


def test_commands_follow_the_plane(dut):
    """+tilt_zx lowers the +x corners (1, 3) and raises the -x corners (0, 2); +tilt_zy lowers the +y
    corners (2, 3); the commands are the plane's heights at the corners."""
    for axis in (m.Axis.X, m.Axis.Y):
        dut.configure_pid(axis, kp=50.0, ki=0.0, kd=0.0)
    dut.set_target(0.1, 0.0)
    dut.start()
    t = dut.position(0.0, 0.0)
    assert (t.tilt_zx, t.tilt_zy) == (pytest.approx(5.0, abs=TILT_TOL), 0.0)
    assert t.command == pytest.approx(manhattan_commands(5.0, 0.0), abs=2 * COMMAND_TOL)
    assert t.command[1] > 0 and t.command[3] > 0 and t.command[0] < 0 and t.command[2] < 0
    dut.set_target(0.0, -0.1)
    t = dut.position(0.0, 0.0)
    assert (t.tilt_zx, t.tilt_zy) == (0.0, pytest.approx(-5.0, abs=TILT_TOL))
    assert t.command == pytest.approx(manhattan_commands(0.0, -5.0), abs=2 * COMMAND_TOL)
    assert t.command[0] > 0 and t.command[1] > 0 and t.command[2] < 0 and t.command[3] < 0
    dut.set_target(0.1, 0.1)
    t = dut.position(0.0, 0.0)
    assert t.command == pytest.approx(manhattan_commands(5.0, 5.0), abs=2 * COMMAND_TOL)


def test_not_visible_frames_step_nothing(dut):
    dut.set_target(0.1, 0.1)
    dut.start()
    steered = dut.position(0.0, 0.0)
    for _ in range(3):
        t = dut.position(0.3, -0.3, visible=False)
        assert (t.tilt_zx, t.tilt_zy, t.command) == (steered.tilt_zx, steered.tilt_zy, steered.command)
        assert t.state == m.State.RUNNING


def test_reached_within_tolerance_and_back_to_running(dut):
    dut.configure(tolerance=0.05)
    for axis in (m.Axis.X, m.Axis.Y):
        dut.configure_pid(axis, kd=0.0)  # no derivative kick from the jumps below
    dut.set_target(0.1, 0.1)
    dut.start()
    assert dut.position(0.0, 0.0).state == m.State.RUNNING  # 0.141 m away
    t = dut.position(0.07, 0.07)  # 0.042 m
    assert t.state == m.State.REACHED
    assert t.tilt_zx > 0 and t.tilt_zy > 0  # control goes on while reached
    assert dut.position(0.1, 0.1).state == m.State.REACHED
    assert dut.position(0.2, 0.1).state == m.State.RUNNING  # pushed away: 0.1 m
    assert dut.position(0.1, 0.14).state == m.State.REACHED


@pytest.mark.parametrize("dt", [0.05, 0.1, 0.2])
def test_dt_is_the_difference_of_capture_times(dut, dt):
    """The integral grows by ki * error * dt, dt from the capture times (not from when frames arrive)."""
    dut.configure_pid(m.Axis.X, kp=10.0, ki=100.0, kd=0.0, integral_limit=20.0)
    dut.set_target(0.1, 0.0)
    dut.start()
    assert dut.position(0.0, 0.0).tilt_zx == pytest.approx(1.0, abs=TILT_TOL)
    grown = dut.position(0.0, 0.0, dt=dt).tilt_zx - 1.0
    assert grown == pytest.approx(100.0 * 0.1 * dt, abs=2 * TILT_TOL)


def test_a_capture_gap_longer_than_the_deadman_restarts_the_time_base(dut):
    dut.configure(deadman=200)
    dut.configure_pid(m.Axis.X, kp=10.0, ki=100.0, kd=1000.0, integral_limit=20.0)
    dut.set_target(0.1, 0.0)
    dut.start()
    assert dut.position(0.0, 0.0).tilt_zx == pytest.approx(1.0, abs=TILT_TOL)
    # 0.5 s of capture time later (firmware time has not moved): no integral, no derivative step
    t = dut.position(0.01, 0.0, dt=0.5)
    assert t.state == m.State.RUNNING
    assert t.tilt_zx == pytest.approx(10.0 * 0.09, abs=TILT_TOL)


def test_commands_stay_within_the_actuator_range(dut):
    for axis in (m.Axis.X, m.Axis.Y):
        dut.configure_pid(axis, kp=1000.0)
    dut.configure(noise_amplitude=0.25, noise_seed=99)
    dut.set_target(0.25, 0.25)
    dut.start()
    worst = 0.0
    for i in range(20):
        t = dut.position(-0.25 + 0.01 * (i % 3), -0.25)
        worst = max(worst, *(abs(a) for a in t.command))
    assert 0.2 < worst <= 0.25 + COMMAND_TOL / 2


# ---------------------------------------------------------------------------------------- bounds and pauses
@pytest.mark.parametrize(
    "beyond, field",
    [((0.01, 0.0), 2), ((-0.01, 0.0), 2), ((0.0, 0.01), 3), ((0.0, -0.01), 3), ((1e38, 0.0), 2), ((0.0, -3e38), 3)],
)
def test_a_position_beyond_the_module_by_more_than_half_of_it_is_out_of_range(dut, beyond, field):
    """On the 0.5 m module a measurement is within +-0.5 m (the fabric and half a module beside it; on an array, the
    surface and half a module beside it); farther (beyond [m] past that) is no measurement of the object (and near
    1e38 m would overflow the Euclidean distance)."""
    dut.configure(module_x=0.5, module_y=0.5)
    reach_x, reach_y = (h + 0.25 for h in dut.half(0.5, 0.5))
    dut.set_target(0.1, 0.0)
    dut.start()
    before = dut.position(0.0, 0.0)
    bad = dut.next_position(
        *(b + math.copysign(r, b) if b else 0.0 for b, r in zip(beyond, (reach_x, reach_y), strict=True))
    )
    dut.refuse_position(bad, m.ErrorCode.OUT_OF_RANGE, field)
    after = dut.send_position(m.ObjectPosition(bad.frame, bad.capture_time, 0.0, 0.0, VISIBLE))  # still new
    assert after.state == before.state  # refused whole: it entered no history
    assert dut.position(reach_x, -reach_y).state == m.State.RUNNING  # the bound itself is a measurement


@pytest.mark.clock("simulated")
def test_frames_after_a_pause_longer_than_the_deadman_start_afresh_however_far_the_capture_time_jumped(dut):
    """A camera paused for 36 min or more (a capture-time jump of 2^31 us or more) would read as going backwards."""
    dut.configure(deadman=500)
    dut.position(0.0, 0.0)
    dut.set_sim_clock(dut.sim_now_us + 600_000)  # more than the deadman without a frame
    dut.capture_us = (dut.capture_us + 0x80000000 - 20_000) & 0xFFFFFFFF  # position() adds its 20 ms
    assert dut.position(0.0, 0.0).position_frame == dut.frame
    dut.refuse_position(same_frame(dut, capture_delta=1000), STALE, 0)  # within a stream, still stale
