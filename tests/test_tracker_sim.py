"""The tracker on frames the MuJoCo scene's overhead camera renders (ArUco textures), and vision in the loop."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from mantaray.host import tracker as T
from mantaray.host.link import Link
from mantaray.host.transport import InProcessTransport
from mantaray.sim.model import mjcf as J
from mantaray.sim.model import model as M
from mantaray.sim.model.objects import OBJECTS
from mantaray.sim.model.rig import Rig
from mantaray.sim.model.tracking import Tracking
from mantaray.sim.trial.bridge import Bridge, TrialSpec
from mantaray.sim.trial.vision import FRAME_PX, CameraVision, blob_colour


@pytest.fixture(scope="module")
def cube_scene():
    rig = Rig().with_object("cube").with_vision("aruco")
    model, data = M.load(rig)
    return rig, model, data


def marker_truth(model, data, rig) -> tuple[np.ndarray, float]:
    """Where the object's marker really is: its plate's top centre, (x, y) [m] and height above z0 [m]."""
    plate = data.geom("object_marker")
    top = plate.xpos + plate.xmat.reshape(3, 3)[:, 2] * J.MARKER_PLATE_M
    return top[:2].copy(), float(top[2] - rig.module.z0_m)


def test_rendered_frames_are_tracked_within_2_mm_rms_at_1280x720(cube_scene):
    """The tracker's own accuracy: against the marker's true position, told the marker's true height."""
    rig, model, data = cube_scene
    vision = CameraVision(model, data, rig, "aruco")
    rng = np.random.default_rng(3)
    errors = []
    for _ in range(12):
        M.drop_object(model, data, *rng.uniform(-0.2, 0.2, 2))
        while data.time < 1.0:  # let it come to rest where the fabric puts it (tilted a bit)
            mujoco.mj_step(model, data)
        truth, height = marker_truth(model, data, rig)
        vision.tracker.marker_height_m = height
        measured = vision.measure(data, data.time)
        assert measured is not None
        errors.append(np.hypot(*(measured - truth)))
    assert (vision.renderer.width, vision.renderer.height) == FRAME_PX
    rms = float(np.sqrt(np.mean(np.square(errors))))
    assert rms < 0.002, (rms, errors)


def test_an_object_out_of_sight_is_reported_not_guessed(cube_scene):
    rig, model, data = cube_scene
    vision = CameraVision(model, data, rig, "aruco")
    mujoco.mj_resetDataKeyframe(model, data, model.key(M.REST_KEY).id)  # the object parked beside the frame
    mujoco.mj_forward(model, data)
    assert vision.measure(data, 0.0) is None
    vision.renderer.update_scene(data, camera=J.OVERHEAD)
    observation = vision.tracker.observe(np.ascontiguousarray(vision.renderer.render()[:, :, ::-1]), 0.0)
    assert observation.status == T.NO_OBJECT and observation.corners_seen == (0, 1, 2, 3)


def test_vision_in_the_loop_steers_the_sphere_by_its_colour():
    """Positions from the tracker on rendered frames (the sphere rolls: a marker on it would roll away)."""
    bridge = Bridge(Link(InProcessTransport(simulated_clock=True)), Rig().with_vision("blob"), Tracking(vision="blob"))
    spec = TrialSpec((0.05, -0.05), (-0.05, 0.05), duration_s=3.0)  # it reaches epsilon at 1.4 s
    result = bridge.run(spec)
    seen = np.all(np.isfinite(result.measured_xy_m), axis=1)
    assert seen.mean() > 0.95 and result.watch.unseen_frames == (~seen).sum()
    error = np.hypot(*(result.measured_xy_m[seen] - result.true_xy_m[seen]).T)
    assert float(np.sqrt(np.mean(error**2))) < 0.003  # what the firmware was told, against the truth
    assert not result.fell_off and result.time_to_reach_s is not None


def test_vision_needs_the_scenes_markers():
    with pytest.raises(ValueError, match="corner_markers"):
        Bridge(Link(InProcessTransport(simulated_clock=True)), Rig(), Tracking(vision="blob"))
    with pytest.raises(ValueError, match="object_marker"):
        Bridge(Link(InProcessTransport(simulated_clock=True)), Rig().with_vision("blob"), Tracking(vision="aruco"))


@pytest.mark.parametrize("name", sorted(OBJECTS))
def test_every_object_is_found_by_its_colour_at_rest(name):
    """--vision blob works for each of Table I's objects: the tracker sees it where it lies."""
    rig = Rig().with_object(name).with_vision("blob")
    model, data = M.load(rig)
    vision = CameraVision(model, data, rig, "blob")  # places the object at the centre
    measured = vision.measure(data, data.time)
    assert measured is not None, name
    # within half of epsilon: the silhouette's centre is the body's centre of mass only for symmetric shapes
    # (the bunny's are 7 mm apart)
    assert np.hypot(*(measured - data.body(J.OBJECT).xpos[:2])) < 0.01


def test_a_colour_too_pale_to_track_as_a_blob_is_refused():
    with pytest.raises(ValueError, match="too pale or dark"):
        blob_colour((0.95, 0.9, 0.8, 1.0))  # a white egg on grey markers: nothing to tell apart
