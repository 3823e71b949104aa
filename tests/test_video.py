"""The trial video: overhead frames at the requested rate, with the target's tolerance disk and the trial's time on them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mantaray.sim.model import model as M
from mantaray.sim.model.rig import Rig
from mantaray.sim.trial.video import FPS_RANGE, Recorder

RIG = Rig()


@pytest.fixture(scope="module")
def scene():
    return M.load(RIG)


def _pixel(rig: Rig, x_m: float, y_m: float, size_px: int) -> tuple[int, int]:
    """(column, row) of a point at height z0 in the overhead camera's image (straight down, fovy, square image)."""
    half_width_m = rig.camera.height_above_z0_m * math.tan(math.radians(rig.camera.fovy_deg) / 2)
    return (
        round(size_px / 2 + x_m / half_width_m * size_px / 2),
        round(size_px / 2 - y_m / half_width_m * size_px / 2),
    )


def test_frames_show_the_target_disk_where_the_target_is_and_the_time(scene):
    model, data = scene
    plain, marked = Recorder(model, fps=10), Recorder(model, fps=10)
    target, tolerance = (0.1, -0.05), 0.02
    marked.mark_target(target, tolerance, RIG.module.z0_m, data.time)
    plain.capture(data)
    marked.capture(data)
    changed = np.abs(plain.frames[0].astype(int) - marked.frames[0].astype(int)).sum(axis=2) > 30
    column, row = _pixel(RIG, *target, 480)
    radius_px = tolerance / (RIG.camera.height_above_z0_m * math.tan(math.radians(RIG.camera.fovy_deg) / 2)) * 240
    assert changed[row, column]  # the disk is on the target ...
    ys, xs = np.nonzero(changed)
    away = np.hypot(xs - column, ys - row) > 2 * radius_px  # the disk, and its shadow on the sagging sheet
    assert np.all((ys[away] < 40) & (xs[away] < 160))  # ... and nothing else changed but the time
    assert away.any()  # which is written top left


def test_frames_come_at_the_requested_rate(scene):
    model, data = scene
    recorder = Recorder(model, fps=10)
    for _ in range(round(0.5 / model.opt.timestep)):  # 0.5 s of physics
        M.step_until(model, data, data.time + model.opt.timestep, recorder.capture)
    assert len(recorder.frames) == 5


@pytest.mark.parametrize("fps", [0.0, FPS_RANGE[1] + 1])
def test_a_frame_rate_outside_its_range_is_refused(scene, fps):
    with pytest.raises(ValueError, match="video fps"):
        Recorder(scene[0], fps=fps)
