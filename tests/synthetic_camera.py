"""A synthetic overhead camera for the tests: pinhole projection of the rig's ArUco markers, known ground truth."""

from __future__ import annotations

import math

import cv2
import numpy as np

from mantaray.host.markers import MarkerLayout, marker_image, quiet_scale

LAYOUT = MarkerLayout()
W, H = 1280, 720
FOVY_DEG = 45.0
TEXTURE_PX = 256


def intrinsics() -> np.ndarray:
    f = (H / 2) / math.tan(math.radians(FOVY_DEG) / 2)
    return np.array([[f, 0, W / 2], [0, f, H / 2], [0, 0, 1]])


def camera(height_m: float, xy_m=(0.0, 0.0), tilt_deg: float = 0.0):
    """(rvec, tvec) of a camera looking down at the fabric from height_m above xy_m, tilted about x."""
    a = math.radians(tilt_deg)
    down = np.array([[1, 0, 0], [0, -1, 0], [0, 0, -1]], dtype=float)  # image right +x, image down -y
    tilt = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    rotation = tilt @ down  # world -> camera
    centre = np.array([xy_m[0], xy_m[1], height_m])
    return cv2.Rodrigues(rotation)[0], -rotation @ centre


def render(object_xy=None, marker_height_m=0.0, cam=None, hide_corner=None, noise=2.0, rng=None, more=()) -> np.ndarray:
    """A grey image of the corner markers (plane z = 0) and the object's marker (the layout's first id) at its
    height, in perspective; more: further (marker id, (x, y)) objects at the same height."""
    rvec, tvec = cam if cam is not None else camera(1.0)
    k = intrinsics()
    image = np.full((H, W), 140, np.float64)
    patches = [
        (LAYOUT.corner_ids[i], c, LAYOUT.corner_size_m, 0.0)
        for i, c in enumerate(LAYOUT.corner_centres_m())
        if i != hide_corner
    ]
    if object_xy is not None:
        patches.append((LAYOUT.object_ids[0], np.asarray(object_xy), LAYOUT.object_size_m, marker_height_m))
    patches += [(i, np.asarray(xy), LAYOUT.object_size_m, marker_height_m) for i, xy in more]
    for marker_id, centre, size, z in patches:
        half = size * quiet_scale(LAYOUT) / 2
        world = np.array(
            [
                [centre[0] - half, centre[1] + half, z],
                [centre[0] + half, centre[1] + half, z],
                [centre[0] + half, centre[1] - half, z],
                [centre[0] - half, centre[1] - half, z],
            ]
        )
        pixels, _ = cv2.projectPoints(world, rvec, tvec, k, None)
        src = np.array([[0, 0], [TEXTURE_PX, 0], [TEXTURE_PX, TEXTURE_PX], [0, TEXTURE_PX]], np.float32)
        warp = cv2.getPerspectiveTransform(src, pixels.reshape(4, 2).astype(np.float32))
        texture = marker_image(LAYOUT, marker_id, TEXTURE_PX).astype(np.float64)
        ink = cv2.warpPerspective(texture, warp, (W, H), flags=cv2.INTER_AREA)
        cover = cv2.warpPerspective(np.ones_like(texture), warp, (W, H), flags=cv2.INTER_AREA)
        image = image * (1 - cover) + ink
    image = cv2.GaussianBlur(image, (0, 0), 0.6)
    if noise:
        image += (rng or np.random.default_rng(0)).normal(0, noise, image.shape)
    return np.clip(image, 0, 255).astype(np.uint8)


def write_video(path, xy_of_frame, frames: int, fps: float) -> str:
    """A video file of the rendered object at xy_of_frame(k) in frame k: a camera for `mantaray rig --camera`."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, (W, H))
    for k in range(frames):
        writer.write(cv2.cvtColor(render(xy_of_frame(k)), cv2.COLOR_GRAY2BGR))
    writer.release()
    return str(path)
