"""The simulation's part of a run's view (host/view.py): the overhead camera rendered, the fabric's mesh, the objects."""

from __future__ import annotations

import math
import queue
from pathlib import Path

import mujoco
import numpy as np

from mantaray.host.link import Link
from mantaray.host.loop import CameraFrame
from mantaray.host.view import QUEUE_FRAMES, RunView
from mantaray.protocol import messages as m

from ..model import mjcf as J
from ..model import model as M
from ..model.rig import Rig

# [px] Side of the rendered camera image the view shows (square, as the overhead camera's field). It and what the
# camera leaves out (on a machine without a GPU, llvmpipe, shadows and reflections are three quarters of a frame's
# rendering) keep the view within 10 % of a run's wall time: docs/viewer.md, benchmarks/speed/view_overhead.py.
CAMERA_PX = 240
PLAIN = (mujoco.mjtRndFlag.mjRND_SHADOW, mujoco.mjtRndFlag.mjRND_REFLECTION, mujoco.mjtRndFlag.mjRND_SKYBOX)


class TrialView:
    """Feeds a RunView from the simulated rig after every camera frame: the loop's values, the rendered camera with
    the target drawn in pixels, the fabric's mesh and the object (its height above the fabric's plane: MuJoCo's
    world z is the fabric frame's z + z0)."""

    def __init__(
        self, view: RunView, model: mujoco.MjModel, data: mujoco.MjData, rig: Rig, link: Link, lockstep: bool = True
    ) -> None:
        self.view, self.model, self.data, self.rig, self.link = view, model, data, rig, link
        self.lockstep = lockstep  # the run waits for a view that falls behind; in real time it drops frames instead
        self.camera = model.camera(J.OVERHEAD).id
        self.triangles = M.fabric_triangles(model)
        self.radii_m = [max(o.size_m or (o.half_height_m,)) for o in rig.objects]  # [m] each object's ball
        self.tolerance_m = 0.0  # [m] the present trial's epsilon
        self.renderer: mujoco.Renderer | None = None  # made on the view's thread, which alone renders
        # copies of the physics state for the view's thread: one per frame it may lag behind, and one being drawn
        self._free: queue.Queue = queue.Queue()
        for _ in range(QUEUE_FRAMES + 2):
            self._free.put(mujoco.MjData(model))

    def start(self, tolerance_m: float) -> None:
        """A trial begins, with its epsilon [m]."""
        self.tolerance_m = tolerance_m

    def frame(self, frame: CameraFrame, telemetry: m.Telemetry | None) -> None:
        """The loop's values now; the camera, the mesh and the object drawn on the view's thread from a copy of the
        physics state."""
        seen = None if frame.dropped else frame.measured_xy_m
        self.view.frame(frame.capture_s, seen, frame.target_m, self.tolerance_m, telemetry, self.link)
        try:
            snapshot = self._free.get(block=self.lockstep)
        except queue.Empty:  # in real time, every copy is still queued: this frame goes without its picture
            self.view.dropped += 1
            return
        mujoco.mj_copyData(snapshot, self.model, self.data)
        t, target, tolerance = frame.capture_s, frame.target_m, self.tolerance_m
        self.view.defer(t, lambda: self._draw(t, snapshot, seen, target, tolerance), wait=self.lockstep)

    def _draw(self, t_s: float, data: mujoco.MjData, seen, target_m, tolerance_m: float) -> None:
        """On the view's thread: the fabric and the object, then the camera with the target, epsilon and the
        detection drawn at the object centre's height (on target, they coincide in the image)."""
        try:
            centres = [data.body(J.object_names(k).body).xpos.copy() for k in range(len(self.radii_m))]
            centre = centres[0]  # the steered object's: the detection and the target are drawn at its height
            camera_at = (data.cam_xpos[self.camera].copy(), data.cam_xmat[self.camera].copy())
            self.view.mesh(t_s, M.fabric_vertices(self.model, data), self.triangles)
            self.view.object3d(t_s, centres, self.radii_m)
            if self.renderer is None:
                self.renderer = mujoco.Renderer(self.model, CAMERA_PX, CAMERA_PX)
                for flag in PLAIN:
                    self.renderer.scene.flags[flag] = False
            self.renderer.update_scene(data, camera=self.camera)
            image_bgr = self.renderer.render()[:, :, ::-1]
        finally:
            self._free.put(data)
        z_m = float(centre[2])
        detection = None
        if seen is not None and np.all(np.isfinite(seen)):
            detection = self._project(camera_at, np.asarray([seen], dtype=float), z_m)[0]
        self.view.camera(t_s, image_bgr, lambda p: self._project(camera_at, p, z_m), target_m, tolerance_m, detection)

    def close(self) -> Path | None:
        """End the view: its renderer released on the thread that made it (an EGL context is bound to its thread),
        then the RunView closed; the recording's path, or None (RunView.close)."""
        self.view.defer(0.0, self._release)
        return self.view.close()

    def _release(self) -> None:
        if self.renderer is not None:
            self.renderer.close()
            self.renderer = None

    def _project(self, camera_at: tuple[np.ndarray, np.ndarray], points_m: np.ndarray, z_m: float) -> np.ndarray:
        """Through MuJoCo's pinhole (fovy over the image height) of the camera at (position [m, world], 3 x 3
        orientation): (k, 2) points [m] in the fabric frame at world height z_m to pixels (x right, y down)."""
        position, orientation = camera_at
        world = np.column_stack([points_m, np.full(len(points_m), z_m)])
        rotation = orientation.reshape(3, 3)  # camera axes in world: x right, y up, looks along -z
        local = (world - position) @ rotation
        focal_px = (CAMERA_PX / 2) / math.tan(math.radians(self.model.cam_fovy[self.camera]) / 2)
        depth = -local[:, 2]
        return np.column_stack(
            [CAMERA_PX / 2 + focal_px * local[:, 0] / depth, CAMERA_PX / 2 - focal_px * local[:, 1] / depth]
        )
