"""The ArUco tracker on synthetic perspective images with known ground truth: accuracy, parallax, lost markers,
several objects by marker id or colour, and when one is lost and found again."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from synthetic_camera import LAYOUT, H, W, camera, intrinsics, render

from mantaray.host import tracker as T
from mantaray.host.markers import MarkerLayout


def test_homography_mode_is_within_2_mm_rms_at_1280x720():
    rng = np.random.default_rng(1)
    tracker = T.Tracker(LAYOUT, marker_height_m=0.0)
    errors = []
    for _ in range(40):
        truth = rng.uniform(-0.25, 0.25, 2)
        obs = tracker.observe(render(truth, rng=rng), capture_time_s=1.0)
        assert obs.status == T.OK and obs.corners_seen == (0, 1, 2, 3)
        errors.append(np.hypot(*(np.asarray(obs.xy_m) - truth)))
    rms = float(np.sqrt(np.mean(np.square(errors))))
    assert rms < 0.002, rms


def test_the_markers_height_is_corrected_for_parallax():
    """The object's marker 5 cm above the corner markers' plane, near the fabric's edge."""
    truth, height = np.array([0.22, -0.18]), 0.05
    image = render(truth, marker_height_m=height)
    naive = T.Tracker(LAYOUT, marker_height_m=0.0).observe(image, 0.0)
    corrected = T.Tracker(LAYOUT, marker_height_m=height, camera_height_m=1.0).observe(image, 0.0)
    assert np.hypot(*(np.asarray(naive.xy_m) - truth)) > 0.01  # 1.5 cm off without the correction
    assert np.hypot(*(np.asarray(corrected.xy_m) - truth)) < 0.002


def test_with_a_calibration_a_tilted_off_centre_camera_is_handled_exactly():
    rng = np.random.default_rng(2)
    cam = camera(1.2, xy_m=(0.04, -0.05), tilt_deg=3.0)
    calibration = T.Calibration(intrinsics(), np.zeros(5))
    tracker = T.Tracker(LAYOUT, marker_height_m=0.04, calibration=calibration)
    errors = []
    for _ in range(25):
        truth = rng.uniform(-0.22, 0.22, 2)
        obs = tracker.observe(render(truth, marker_height_m=0.04, cam=cam, rng=rng), 0.0)
        assert obs.status == T.OK
        errors.append(np.hypot(*(np.asarray(obs.xy_m) - truth)))
    assert float(np.sqrt(np.mean(np.square(errors)))) < 0.002


def test_a_missing_object_or_fabric_frame_is_reported_never_guessed():
    tracker = T.Tracker(LAYOUT)
    first = tracker.observe(render(None, hide_corner=2), capture_time_s=0.0)
    assert first.status == T.NO_FRAME and first.xy_m is None and first.corners_seen == (0, 1, 3)
    assert tracker.observe(render(None), 0.1).status == T.NO_OBJECT
    hidden = tracker.observe(render((0.1, 0.1), hide_corner=0), 0.2)  # a hand over corner 0
    assert hidden.status == T.OK and hidden.reused_frame_fit and hidden.corners_seen == (1, 2, 3)
    stale = tracker.observe(render((0.1, 0.1), hide_corner=0), 0.2 + tracker.max_frame_age_s + 1)
    assert stale.status == T.NO_FRAME


def test_colour_blob_tracking_for_a_marker_less_object():
    image = cv2.cvtColor(render(None), cv2.COLOR_GRAY2BGR)
    k, (rvec, tvec) = intrinsics(), camera(1.0)
    centre, _ = cv2.projectPoints(np.array([[0.12, 0.07, 0.0]]), rvec, tvec, k, None)
    cv2.circle(image, tuple(int(round(v)) for v in centre.ravel()), 20, (40, 200, 240), -1)  # a yellow egg
    tracker = T.Tracker(LAYOUT, blobs=(T.BlobColour((20, 120, 120), (35, 255, 255)),))
    obs = tracker.observe(image, 0.0)
    assert obs.status == T.OK and np.hypot(obs.xy_m[0] - 0.12, obs.xy_m[1] - 0.07) < 0.002
    assert tracker.observe(cv2.cvtColor(render(None), cv2.COLOR_GRAY2BGR), 0.1).status == T.NO_OBJECT


def test_frames_from_a_video_file_carry_the_videos_time(tmp_path):
    path = str(tmp_path / "clip.avi")
    writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*"MJPG"), 12.0, (W, H))
    for x in (-0.1, 0.0, 0.1):
        writer.write(cv2.cvtColor(render((x, 0.05)), cv2.COLOR_GRAY2BGR))
    writer.release()
    source, tracker = T.FrameSource(path), T.Tracker(LAYOUT)
    seen = []
    while (frame := source.read()) is not None:
        seen.append(tracker.observe(*frame))
    source.close()
    assert [round(o.capture_time_s * 12) for o in seen] == [0, 1, 2]
    assert [round(o.xy_m[0], 2) for o in seen] == [-0.1, 0.0, 0.1]
    with pytest.raises(OSError, match="cannot open"):
        T.FrameSource(str(tmp_path / "missing.avi"))


@pytest.mark.parametrize("calibrated", [False, True])
def test_the_projection_draws_fabric_points_where_the_camera_sees_them_and_the_detection_is_the_markers_pixel(
    calibrated,
):
    """What the view draws the target and epsilon with: points at the marker's height back to pixels, within a
    pixel of the camera's own projection, for points drawn from a seed; and the detection's pixel at the marker."""
    rng = np.random.default_rng(5)
    height = 0.04
    cam = camera(1.0) if not calibrated else camera(1.0, tilt_deg=8.0)  # homography mode: a camera straight above
    calibration = T.Calibration(intrinsics(), np.zeros(5)) if calibrated else None
    tracker = T.Tracker(LAYOUT, marker_height_m=height, calibration=calibration)
    assert tracker.projection(height) is None
    truth = rng.uniform(-0.2, 0.2, 2)
    obs = tracker.observe(render(truth, marker_height_m=height, cam=cam, rng=rng), capture_time_s=1.0)
    project = tracker.projection(height)
    assert obs.visible and project is not None
    points = rng.uniform(-0.25, 0.25, (50, 2))
    expected, _ = cv2.projectPoints(np.hstack([points, np.full((50, 1), height)]), *cam, intrinsics(), None)
    error_px = np.hypot(*(project(points) - expected.reshape(-1, 2)).T)
    assert error_px.max() < 1.0, error_px.max()
    marker_px, _ = cv2.projectPoints(np.array([[*truth, height]]), *cam, intrinsics(), None)
    assert np.hypot(*(np.asarray(obs.pixel) - marker_px.reshape(2))) < 1.0
    assert np.hypot(*(project(np.array([obs.xy_m]))[0] - obs.pixel)) < 1.0  # on target, drawn on the detection


def test_several_objects_keep_their_places_by_marker_id_and_one_hidden_leaves_the_others_measured():
    rng = np.random.default_rng(7)
    layout = MarkerLayout(object_ids=(10, 11, 12, 13))
    tracker = T.Tracker(layout)
    for _ in range(6):
        truth = rng.uniform(-0.2, 0.2, (4, 2))
        while min(np.hypot(*(a - b)) for k, a in enumerate(truth) for b in truth[k + 1 :]) < 0.06:
            truth = rng.uniform(-0.2, 0.2, (4, 2))  # markers apart, as objects on a sheet are
        hidden = int(rng.integers(4))
        shown = [(i, truth[k]) for k, i in enumerate(layout.object_ids) if k != hidden]
        first, more = (shown[0][1], shown[1:]) if hidden != 0 else (None, shown)
        obs = tracker.observe(render(first, rng=rng, more=more), 0.0)
        assert obs.status == (T.NO_OBJECT if hidden == 0 else T.OK) and len(obs.objects) == 4
        for k, seen in enumerate(obs.objects):
            if k == hidden:
                assert seen.xy_m is None
            else:
                assert np.hypot(*(np.asarray(seen.xy_m) - truth[k])) < 0.003
    assert tracker.object_names() == [f"object {k} (marker {10 + k})" for k in range(4)]


def test_two_colours_are_two_objects():
    image = cv2.cvtColor(render(None), cv2.COLOR_GRAY2BGR)
    k, (rvec, tvec) = intrinsics(), camera(1.0)
    places = {(40, 200, 240): (0.12, 0.07), (240, 80, 40): (-0.1, -0.05)}  # yellow, blue (BGR)
    for bgr, xy in places.items():
        centre, _ = cv2.projectPoints(np.array([[*xy, 0.0]]), rvec, tvec, k, None)
        cv2.circle(image, tuple(int(round(v)) for v in centre.ravel()), 20, bgr, -1)
    yellow, blue = T.BlobColour((20, 120, 120), (35, 255, 255)), T.BlobColour((100, 120, 120), (130, 255, 255))
    obs = T.Tracker(LAYOUT, blobs=(blue, yellow)).observe(image, 0.0)
    assert np.hypot(obs.objects[0].xy_m[0] + 0.1, obs.objects[0].xy_m[1] + 0.05) < 0.002
    assert np.hypot(obs.objects[1].xy_m[0] - 0.12, obs.objects[1].xy_m[1] - 0.07) < 0.002


@given(st.lists(st.booleans(), min_size=1, max_size=60), st.integers(1, 8))
def test_presence_reports_a_loss_once_it_lasts_and_a_return_once_each(seen, lost_after_frames):
    """At 10 frames a second: a loss is reported at the frame lost_after_s after the object was last seen (or after
    the first frame), a return at the first frame that sees it after a reported loss; reports alternate, and a gap
    shorter than lost_after_s is never reported."""
    presence = T.Presence(["the object"], lost_after_s=(lost_after_frames - 0.5) / 10)  # between two frames
    lines = []
    for k, s in enumerate(seen):
        obs = T.Observation(k / 10, T.OK if s else T.NO_OBJECT, (T.ObjectSeen((0.0, 0.0) if s else None),))
        lines += [(k, line.split()[2]) for line in presence.update(k / 10, obs)]
    expected, since, lost = [], 0, False
    for k, s in enumerate(seen):
        if s:
            if lost:
                expected.append((k, "found"))
            since, lost = k, False
        elif not lost and k - since >= lost_after_frames:
            expected.append((k, "lost"))
            lost = True
    assert lines == expected
    assert presence.lost() == ([0] if lost else [])
    assert T.Presence(["x"]).update(0.0, T.Observation(0.0, T.NO_FRAME)) == []  # no fabric frame: nothing said


@pytest.mark.parametrize(
    "ids, why",
    [((), "at least one"), ((10, 10), "10 given to two objects"), ((10, 2), "2 is a corner"), ((50,), "50 is not in")],
)
def test_a_layout_whose_markers_would_be_confused_is_refused(ids, why):
    with pytest.raises(ValueError, match=why):
        MarkerLayout(object_ids=ids)
