"""A target typed during a rig run (t X,Y Enter, host/rig_run.py): whatever is typed is taken or refused in words."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from mantaray.host.rig_run import Course, RigRun, StopRules

HALF_M = (0.25, 0.25)
FIXED = Course((0.1, 0.1))  # the run's target before anything is typed


class _Log:
    def __init__(self) -> None:
        self.lines: list[tuple[str, dict]] = []

    def write(self, kind: str, fields: dict) -> None:
        self.lines.append((kind, fields))


class _Session:
    def __init__(self) -> None:
        self.targets: list[tuple[float, float]] = []
        self.estopped = False

    def emergency_stop(self) -> None:
        self.estopped = True

    def set_target(self, x: float, y: float) -> None:
        self.targets.append((x, y))


def _run(course: Course = FIXED) -> RigRun:
    run = RigRun("/dev/null", None, None, None, _Log(), course, StopRules(0.02, 1.0, 10.0, HALF_M, HALF_M))
    run.session = _Session()
    return run


def _type(run: RigRun, keys: str) -> None:
    for key in keys:
        run._type_target(key)


@settings(max_examples=300, deadline=None)
@given(st.text(alphabet="0123456789.,+-", max_size=30))
def test_any_typed_text_is_taken_when_it_is_a_point_on_the_fabric_and_refused_in_words_otherwise(text):
    run = _run()
    _type(run, "t" + text + "\r")
    try:
        x, y = (float(v) for v in text.replace(",", " ").split())
        on_fabric = math.isfinite(x) and math.isfinite(y) and abs(x) <= HALF_M[0] and abs(y) <= HALF_M[1]
    except ValueError:
        on_fabric = False
    events = [f["text"] for kind, f in run.log.lines if kind == "event"]
    assert len(events) == 1
    if on_fabric:
        assert run.session.targets == [(x, y)] and run.course.centre_m == (x, y)
        assert events[0].startswith("new target")
    else:
        assert run.session.targets == [] and run.course.centre_m == (0.1, 0.1)
        assert "refused" in events[0] and "the run goes on" in events[0]


def test_backspace_takes_a_typed_character_back():
    run = _run()
    _type(run, "t0.19\x7f\x7f2,0\r")
    assert run.session.targets == [(0.2, 0.0)]


def test_escape_drops_a_target_being_typed_and_the_next_key_counts_again():
    run = _run()
    _type(run, "t0.1,0\x1b")
    assert run._typed is None and run.session.targets == [] and run.log.lines == []


def test_a_run_along_a_path_refuses_a_typed_target():
    run = _run(Course((0.0, 0.0), radius_m=0.1))
    _type(run, "t0.1,0\r")
    assert run.session.targets == []
    assert "follows a path" in run.log.lines[-1][1]["text"]


class _Keys:
    def __init__(self, pressed: str) -> None:
        self.pressed = pressed

    def read(self) -> str:
        pressed, self.pressed = self.pressed, ""
        return pressed


@given(st.text(alphabet="0123456789.,+-", max_size=10), st.sampled_from(["e", " ", "s", "S", "E"]))
def test_a_stop_key_while_a_target_is_typed_still_stops_and_drops_the_target(typed, key):
    from mantaray.host.rig_run import EMERGENCY_STOP, KEYS

    run = _run()
    run._keys = _Keys("t" + typed + key)
    assert run._stopped_by_key()
    assert run.outcome == KEYS[key.lower()] and run._typed is None and run.session.targets == []
    assert run.session.estopped == (KEYS[key.lower()] == EMERGENCY_STOP)
