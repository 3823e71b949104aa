"""The closed loop the rig and the simulation share: frames numbered and timed as the protocol says, unseen and
dropped frames recorded without an answer, the tolerance judged with and without a hold, the run ended by its stop rules,
the plant called in one order each frame."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from mantaray.host.link import Link
from mantaray.host.loop import STOPPED_BY_SOURCE, STOPPED_REACHED, CameraFrame, ClosedLoop, Tolerance
from mantaray.host.session import Setup
from mantaray.host.transport import InProcessTransport
from mantaray.protocol import messages as m


def _telemetry(frame: int) -> m.Telemetry:
    return m.Telemetry(
        position_frame=frame, state=m.State.RUNNING, tilt_zx=1.0, tilt_zy=-2.0, command=(0.01, 0.02, 0.03, 0.04)
    )


def test_frames_are_numbered_timed_and_flagged_as_the_protocol_says():
    sent = []
    loop = ClosedLoop(lambda msg: sent.append(msg) or _telemetry(msg.frame), time_base_us=0xFFFF_FF00, frame=0xFFFE)
    loop.step(0.0, (0.01, -0.02), (0.1, 0.1))
    loop.step(0.5, None, (0.1, 0.1))  # not seen
    loop.step(1.0, (math.nan, 0.0), (0.1, 0.1))  # a tracker's NaN is not seen either
    assert [msg.frame for msg in sent] == [0xFFFF, 0, 1]  # u16, wraps
    assert [msg.capture_time for msg in sent] == [
        0xFFFF_FF00,
        (0xFFFF_FF00 + 500_000) & 0xFFFFFFFF,
        (0xFFFF_FF00 + 1_000_000) & 0xFFFFFFFF,
    ]  # u32 on the firmware clock
    assert [bool(msg.flags & m.PositionFlags.NOT_VISIBLE) for msg in sent] == [False, True, True]
    assert (sent[0].x, sent[0].y) == (0.01, -0.02)
    rows = loop.arrays()
    assert np.isnan(rows["measured_xy_m"][1:]).all() and rows["state"].tolist() == [int(m.State.RUNNING)] * 3


def test_a_dropped_frame_uses_up_its_number_and_records_no_answer():
    loop = ClosedLoop(lambda msg: _telemetry(msg.frame) if msg.frame != 3 else None)
    answers = [
        loop.step(0.0, (0.0, 0.0), (0.0, 0.0)),
        loop.dropped(0.1, (0.0, 0.0)),
        loop.step(0.2, (0.0, 0.0), (0.0, 0.0)),  # frame 3: no telemetry came
        loop.step(0.3, (0.0, 0.0), (0.0, 0.0)),
    ]
    rows = loop.arrays()
    assert loop.frame == 4 and [t.position_frame for t in answers if t is not None] == [1, 4]
    assert rows["state"].tolist() == [int(m.State.RUNNING), -1, -1, int(m.State.RUNNING)]
    assert np.isnan(rows["tilt_deg"][1:3]).all() and np.isnan(rows["command_m"][1:3]).all()
    assert rows["t_s"].tolist() == [0.0, 0.1, 0.2, 0.3] and rows["target_m"].shape == (4, 2)


@given(st.lists(st.floats(0.0, 0.05), min_size=1, max_size=40), st.floats(0.001, 0.05))
def test_without_a_hold_the_tolerance_holds_exactly_at_the_frames_within(distances, tolerance):
    judge = Tolerance(tolerance)
    answers = [judge.update(0.1 * k, (d, 0.0), (0.0, 0.0)) for k, d in enumerate(distances)]
    assert answers == [d < tolerance for d in distances]
    within = [k for k, d in enumerate(distances) if d < tolerance]
    assert judge.first_s == (0.1 * within[0] if within else None)


def test_a_hold_counts_from_the_latest_entry_and_leaving_restarts_it():
    judge = Tolerance(0.02, hold_s=1.0)
    path = [(0.0, 0.01), (0.5, 0.01), (0.9, 0.03), (1.0, 0.01), (1.9, 0.01), (2.0, 0.01)]
    answers = [judge.update(t, (d, 0.0), (0.0, 0.0)) for t, d in path]
    assert answers == [False, False, False, False, False, True] and judge.first_s == 0.0


def test_a_setup_is_sent_in_the_order_the_firmware_takes_it():
    setup = Setup(m.Configure(tolerance=0.03), {m.Axis.X: dict(m.PID_DEFAULTS[m.Axis.X], kp=10.0)}, (0.1, -0.1))
    commands = setup.commands()
    assert [type(c) for c in commands] == [m.Configure, m.ConfigurePid, m.SetTarget]
    link = Link(InProcessTransport(simulated_clock=True))
    for command in commands:
        assert isinstance(link.command(command), m.Ack)


class _Plant:
    """A plant whose frames are given: it logs every call the loop makes, and its deliver() says False at `falls`."""

    def __init__(self, frames, falls: int | None = None) -> None:
        self._frames, self.falls, self.calls = frames, falls, []

    def frames(self):
        for k, frame in enumerate(self._frames):
            self.calls.append(("frame", k))
            yield frame

    def deliver(self, frame) -> bool:
        k = self._frames.index(frame)
        self.calls.append(("deliver", k))
        return k != self.falls

    def answered(self, frame, telemetry) -> None:
        self.calls.append(
            ("answered", self._frames.index(frame), None if telemetry is None else telemetry.position_frame)
        )


def _frames(xs, target=(0.0, 0.0)):
    return [CameraFrame(0.1 * k, (x, 0.0), target, judged_xy_m=(x, 0.0)) for k, x in enumerate(xs)]


@given(st.lists(st.floats(-0.3, 0.3), min_size=1, max_size=30), st.booleans())
def test_run_ends_at_the_first_frame_within_only_when_told_to_stop_there(xs, stop):
    sent = []
    loop = ClosedLoop(lambda msg: sent.append(msg.frame) or _telemetry(msg.frame))
    plant = _Plant(_frames(xs))
    why = loop.run(plant, Tolerance(0.02), stop_when_reached=stop)
    first = next((k for k, x in enumerate(xs) if abs(x) < 0.02), None)
    if stop and first is not None:
        assert why == STOPPED_REACHED and len(sent) == first  # the frame judged within is not sent
    else:
        assert why == STOPPED_BY_SOURCE and len(sent) == len(xs)
    assert [c[2] for c in plant.calls if c[0] == "answered"] == sent  # the plant takes each sent frame's answer


@given(st.lists(st.booleans(), min_size=1, max_size=20), st.integers(0, 25))
def test_the_loop_calls_its_plant_in_one_order_each_frame(dropped, falls):
    frames = _frames([0.2] * len(dropped))
    for frame, drop in zip(frames, dropped, strict=True):
        frame.dropped = drop
    plant = _Plant(frames, falls)
    ClosedLoop(lambda msg: _telemetry(msg.frame)).run(plant, Tolerance(0.02), stop_when_reached=True)
    expected = []
    for k in range(min(falls, len(frames) - 1) + 1):
        expected += [("frame", k), ("deliver", k)] + ([("answered", k)] if k != falls else [])
    assert [c[:2] for c in plant.calls] == expected  # a frame not delivered is neither sent nor answered
    answered = [c for c in plant.calls if c[0] == "answered"]
    assert [c[2] is None for c in answered] == dropped[: len(answered)]  # a dropped frame has no answer


def test_run_records_dropped_frames_and_ends_when_a_delivery_says_so():
    frames = _frames([0.2, 0.2, 0.2, 0.2])
    frames[1].dropped = True
    plant = _Plant(frames, falls=2)  # the object fell on the way to the firmware with frame 2
    loop = ClosedLoop(lambda msg: _telemetry(msg.frame))
    assert loop.run(plant, Tolerance(0.02), stop_when_reached=True) == STOPPED_BY_SOURCE
    rows = loop.arrays()
    assert ("deliver", 2) in plant.calls and ("frame", 3) not in plant.calls
    assert len(rows["t_s"]) == 2 and rows["state"].tolist() == [int(m.State.RUNNING), -1]
