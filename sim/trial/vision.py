"""Vision in the loop: the host's tracker (host/tracker.py) on frames the scene's overhead camera renders."""

from __future__ import annotations

import colorsys

import mujoco
import numpy as np

from mantaray.host.tracker import BlobColour, Tracker

from ..model import mjcf as J
from ..model import model as M
from ..model.rig import VISION_MODES, Rig

FRAME_PX = (1280, 720)  # [px] width, height: the resolution the tracker's accuracy is specified at
BLOB_HUE_WIDTH = 10  # [OpenCV hue units, 0..179] either side of the object's hue
BLOB_MIN_SATURATION = 80  # [0..255]
BLOB_MIN_VALUE = 60  # [0..255]


def blob_colour(rgba: tuple[float, float, float, float]) -> BlobColour:
    """An HSV window around an object's colour, for the colour-blob tracker; a colour too pale or too dark for a
    hue window (white, grey, black: the fabric's and the markers' greys would match it) is refused."""
    h, s, v = colorsys.rgb_to_hsv(*rgba[:3])
    if s * 255 < BLOB_MIN_SATURATION or v * 255 < BLOB_MIN_VALUE:
        raise ValueError(
            f"the colour {rgba[:3]} is too pale or dark to track as a blob (saturation {s * 255:.0f}, "
            f"value {v * 255:.0f}; at least {BLOB_MIN_SATURATION} and {BLOB_MIN_VALUE} of 255)"
        )
    hue = int(round(h * 179))
    low, high = max(0, hue - BLOB_HUE_WIDTH), min(179, hue + BLOB_HUE_WIDTH)
    return BlobColour((low, BLOB_MIN_SATURATION, BLOB_MIN_VALUE), (high, 255, 255))


def camera_option() -> mujoco.MjvOption:
    """What the rig's camera sees of the scene: everything but MuJoCo's sites (the tracking site's dot would lie on
    the object's marker, over a white cell of some ids)."""
    option = mujoco.MjvOption()
    option.sitegroup[:] = 0
    return option


def check_scene(rig: Rig, mode: str) -> None:
    """ValueError unless the rig's scene carries what the tracker mode needs: before any model is loaded."""
    if mode not in VISION_MODES:
        raise ValueError(f"vision mode must be one of {', '.join(VISION_MODES)}, got {mode!r}")
    if not rig.camera.corner_markers:
        raise ValueError("vision in the loop needs the scene's corner markers (Rig.camera.corner_markers)")
    if mode == "aruco" and not rig.camera.object_marker:
        raise ValueError("aruco vision needs the object's marker in the scene (Rig.camera.object_marker)")


class CameraVision:
    """Renders the overhead camera and measures the object with the tracker, as the rig's camera would.

    The tracker's one rig-specific number, the height of what it tracks above the corner markers' plane,
    is measured once with the object at rest at the centre, as a user would with a ruler.
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, rig: Rig, mode: str) -> None:
        check_scene(rig, mode)
        self.mode = mode
        self.renderer = mujoco.Renderer(model, FRAME_PX[1], FRAME_PX[0])
        self.option = camera_option()
        M.place_object(model, data, 0.0, 0.0, rule=rig.fall)
        if mode == "aruco":
            height = data.site(J.MARKER).xpos[2] + 2 * J.MARKER_PLATE_M - rig.module.z0_m  # the plate's top
        else:
            height = data.body(J.OBJECT).xpos[2] - rig.module.z0_m  # the silhouette's centre
        self.tracker = Tracker(
            marker_height_m=float(height),
            camera_height_m=rig.camera.height_above_z0_m,
            blobs=(blob_colour(rig.object.rgba),) if mode == "blob" else (),
        )

    def measure(self, data: mujoco.MjData, capture_time_s: float) -> np.ndarray | None:
        """The tracker's (x, y) [m] of the object in the frame rendered now, or None if it saw none."""
        self.renderer.update_scene(data, camera=J.OVERHEAD, scene_option=self.option)
        image = self.renderer.render()[:, :, ::-1]  # RGB -> OpenCV's BGR
        observation = self.tracker.observe(np.ascontiguousarray(image), capture_time_s)
        return np.asarray(observation.xy_m) if observation.visible else None
