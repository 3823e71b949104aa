"""Several objects on the simulated sheet: each its own body, contact and marker, placed and at rest together, one
object's scene written as it always was, and the tracker finding each on rendered frames."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from mantaray.host.tracker import Presence, Tracker
from mantaray.sim.model import kernel_contact as K
from mantaray.sim.model import mjcf as J
from mantaray.sim.model import model as M
from mantaray.sim.model.plant import Plant
from mantaray.sim.model.rig import Rig
from mantaray.sim.trial.vision import FRAME_PX, camera_option

FLAT = ("cube", "cylinder", "disk")  # objects whose top, and marker, stay up at rest


def _starts(count: int, seed: int) -> list[tuple[float, float]]:
    """count starts over |x|, |y| <= 0.15 m, at least 0.1 m apart (the objects must not start inside each other)."""
    rng = np.random.default_rng(seed)
    while True:
        xy = rng.uniform(-0.15, 0.15, (count, 2))
        if all(np.hypot(*(a - b)) >= 0.1 for k, a in enumerate(xy) for b in xy[k + 1 :]):
            return [tuple(map(float, p)) for p in xy]


def test_a_rig_of_several_objects_names_each_and_refuses_what_it_cannot_carry():
    rig = Rig().with_objects(["cube", "sphere", "cube"])
    assert [o.name for o in rig.objects] == ["cube", "sphere", "cube"] and rig.object.name == "cube"
    with pytest.raises(ValueError, match="no object 'brick'"):
        Rig().with_objects(["cube", "brick"])
    with pytest.raises(ValueError, match="at least one"):
        Rig().with_objects([])
    assert Rig().with_objects(["sphere"]) == Rig()  # one object: the rig as it always was
    assert J.scene_xml(Rig().with_objects(["bunny"])) == J.scene_xml(Rig().with_object("bunny"))


@pytest.mark.parametrize("contact", ["mesh", "kernel"])
def test_several_objects_are_placed_and_come_to_rest_on_the_sheet_together(contact):
    sets = {"fabric.stretch": "threads", "contact.model": "kernel"} if contact == "kernel" else {}
    rig = Plant("paper").set(sets).rig(object_name="cube", resolution=15, timestep_s=0.001).with_objects(FLAT)
    model, data = M.load(rig)
    assert M.object_count(model) == 3
    if contact == "kernel":  # one plugin instance an object, each bearing its own
        assert [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_PLUGIN, K.instance_name(k)) for k in range(3)] == [0, 1, 2]
    starts = _starts(3, seed=11)
    M.place_objects(model, data, starts, rule=rig.fall, settle_max_s=6.0)
    for k, o in enumerate(rig.objects):
        xy = M.object_xy(model, data, k)
        assert not M.fell_off(model, data, rig.fall, k)
        surface = K.surface_height(model, data, k) if contact == "kernel" else M.fabric_height(model, data, *xy)
        centre_z = data.body(J.object_names(k).body).xpos[2]
        assert abs(centre_z - surface - o.half_height_m) < 0.01, (k, centre_z - surface, o.half_height_m)
    rest = [M.object_xy(model, data, k) for k in range(3)]
    assert (
        min(np.hypot(*(a - b)) for k, a in enumerate(rest) for b in rest[k + 1 :]) > 0.04
    )  # apart: none inside another
    with pytest.raises(ValueError, match="holds 3 objects, given 1 starts"):
        M.drop_object(model, data, 0.0, 0.0)


def test_the_tracker_finds_each_object_by_its_marker_on_rendered_frames():
    """Three flat objects with the markers 10, 11, 12 on their tops, at rest where the sheet puts them: each found in
    its own place within 3 mm of its plate's centre, told the plates' height; one taken away is lost, and found again
    when it is back."""
    rig = Plant().rig(resolution=15, timestep_s=0.001).with_objects(FLAT).with_vision("aruco")
    model, data = M.load(rig)
    M.place_objects(model, data, _starts(3, seed=4), rule=rig.fall, settle_max_s=6.0)
    renderer = mujoco.Renderer(model, FRAME_PX[1], FRAME_PX[0])
    renderer.update_scene(data, camera=J.OVERHEAD, scene_option=camera_option())
    image = np.ascontiguousarray(renderer.render()[:, :, ::-1])
    tops = []
    for k in range(3):
        plate = data.geom(J.object_names(k).plate)
        tops.append(plate.xpos + plate.xmat.reshape(3, 3)[:, 2] * J.MARKER_PLATE_M)
    layout = J.marker_layout(rig)
    assert layout.object_ids == (10, 11, 12)
    for k, top in enumerate(tops):
        tracker = Tracker(
            layout, marker_height_m=float(top[2] - rig.module.z0_m), camera_height_m=rig.camera.height_above_z0_m
        )
        seen = tracker.observe(image, 0.0).objects
        assert len(seen) == 3 and all(s.xy_m is not None for s in seen)
        assert np.hypot(*(np.asarray(seen[k].xy_m) - top[:2])) < 0.003, (k, seen[k].xy_m, top[:2])
    # object 1 lifted out of the camera's view and put back: lost, then found again
    presence = Presence(tracker.object_names())
    frames, qadr = [], model.jnt_qposadr[model.joint(J.object_names(1).slides[0]).id]
    back = data.qpos[qadr : qadr + 3].copy()
    for t_s, away in ((0.0, False), (0.5, True), (1.0, False)):
        data.qpos[qadr : qadr + 3] = (5.0, 5.0, 5.0) if away else back  # [m] far beyond the frame
        mujoco.mj_forward(model, data)
        renderer.update_scene(data, camera=J.OVERHEAD, scene_option=camera_option())
        frames.append(presence.update(t_s, tracker.observe(np.ascontiguousarray(renderer.render()[:, :, ::-1]), t_s)))
    assert frames == [
        [],
        ["object 1 (marker 11) lost at 0.50 s (last seen at 0.00 s)"],
        ["object 1 (marker 11) found again at 1.00 s, after 1.00 s unseen"],
    ]


def test_a_trial_steers_object_0_and_reports_where_the_others_were_moved():
    from mantaray.host.link import Link
    from mantaray.host.transport import InProcessTransport
    from mantaray.sim.trial.bridge import Bridge, TrialSpec

    rig = Plant().rig(resolution=11, timestep_s=0.002).with_objects(["sphere", "cube"])
    bridge = Bridge(Link(InProcessTransport(simulated_clock=True)), rig, Plant().tracking())
    with pytest.raises(ValueError, match="1 object beside the steered one, the trial gives 0 starts"):
        bridge.run(TrialSpec((0.1, 0.1), (-0.1, -0.1), duration_s=1.0))
    spec = TrialSpec((0.1, 0.1), (-0.1, -0.1), duration_s=2.0, others_start_m=((-0.12, 0.12),))
    result = bridge.run(spec)
    frames = len(result.t_s)
    assert result.others_xy_m.shape == (frames, 1, 2) and result.others_final_xy_m.shape == (1, 2)
    (other,) = result.summary()["others"]
    assert other["start_m"] == [-0.12, 0.12] and other["fell_off"] is False
    assert other["displacement_m"] == pytest.approx(np.hypot(*(result.others_final_xy_m[0] - (-0.12, 0.12))), abs=1e-5)
    assert other["largest_displacement_m"] >= 0


def test_the_live_view_and_recording_draw_every_object():
    from mantaray.host.loop import CameraFrame
    from mantaray.sim.trial.trial_view import TrialView

    class View:  # what TrialView feeds (host/view.py RunView), its deferred work done at once
        dropped = 0

        def __init__(self):
            self.objects = []

        def frame(self, *args):
            pass

        def defer(self, t_s, work, wait):
            work()

        def mesh(self, *args):
            pass

        def object3d(self, t_s, centres_m, radii_m):
            self.objects.append((np.asarray(centres_m), list(radii_m)))

        def camera(self, *args):
            pass

    rig = Plant().rig(resolution=11, timestep_s=0.002).with_objects(["sphere", "cube"])
    model, data = M.load(rig)
    M.place_objects(model, data, [(0.1, 0.1), (-0.1, -0.1)], rule=rig.fall)
    view = View()
    trial_view = TrialView(view, model, data, rig, link=None)
    trial_view.frame(CameraFrame(0.0, (0.1, 0.1), (0.0, 0.0)), None)
    trial_view._release()
    ((centres, radii),) = view.objects
    expected = [data.body(J.object_names(k).body).xpos for k in range(2)]
    np.testing.assert_array_equal(centres, expected)
    assert radii == [max(o.size_m or (o.half_height_m,)) for o in rig.objects]
