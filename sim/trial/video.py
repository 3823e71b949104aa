"""Video of a trial from the scene's overhead camera, rendered offscreen (EGL without a display: sim/__init__.py)."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from ..model import mjcf as J

FPS_RANGE = (1.0, 240.0)  # [1/s] video frame rates a recorder takes


TARGET_RGBA = (1.0, 0.0, 1.0, 0.5)  # the target's tolerance disk in the video: translucent magenta
DISK_HALF_THICKNESS_M = 0.0005  # [m]
BORDER_RGBA = (1.0, 1.0, 1.0, 0.6)  # an array's module borders: translucent white lines
BORDER_HALF_WIDTH_M = 0.003  # [m]


class Recorder:
    """Renders the overhead camera every 1/fps simulated seconds; attach to Bridge.recorder, then save().

    With mark_target(), every frame also shows the target's tolerance disk and the trial's time; on an array, the
    borders between its modules (grid, a protocol Grid)."""

    def __init__(
        self, model: mujoco.MjModel, fps: float = 30.0, width: int = 480, height: int = 480, grid=None
    ) -> None:
        if not FPS_RANGE[0] <= fps <= FPS_RANGE[1]:
            raise ValueError(f"video fps must be {FPS_RANGE[0]:g}..{FPS_RANGE[1]:g}, got {fps}")
        self.fps = fps
        self.renderer = mujoco.Renderer(model, height, width)
        self.frames: list = []
        self.next_s: float | None = None
        self._target: tuple[np.ndarray, float, float] | None = None  # (centre [m, world], radius [m], t0 [s])
        self._borders = _borders(grid) if grid is not None else []  # ((x, y) centre, (half x, half y)) [m]

    def mark_target(self, target_m, tolerance_m: float, z_m: float, t0_s: float) -> None:
        """Show the target as a disk of radius tolerance_m at height z_m [m, world], and the time since t0_s [s]."""
        self._target = (np.array([target_m[0], target_m[1], z_m], dtype=float), tolerance_m, t0_s)

    def capture(self, data: mujoco.MjData) -> None:
        """Render a frame if data.time has reached the next video frame time (cheap otherwise)."""
        if self.next_s is None:
            self.next_s = data.time
        if data.time + 1e-9 >= self.next_s:
            self.renderer.update_scene(data, camera=J.OVERHEAD)
            frame = self._with_target(data) if self._target is not None else self.renderer.render()
            self.frames.append(frame)
            self.next_s += 1.0 / self.fps

    def _with_target(self, data: mujoco.MjData) -> np.ndarray:
        import cv2

        centre, radius, t0 = self._target
        scene = self.renderer.scene
        for (x, y), (half_x, half_y) in self._borders:
            if scene.ngeom < scene.maxgeom:
                mujoco.mjv_initGeom(
                    scene.geoms[scene.ngeom],
                    mujoco.mjtGeom.mjGEOM_BOX,
                    np.array([half_x, half_y, DISK_HALF_THICKNESS_M]),
                    np.array([x, y, centre[2]]),
                    np.eye(3).ravel(),
                    np.array(BORDER_RGBA, dtype=np.float32),
                )
                scene.ngeom += 1
        if scene.ngeom < scene.maxgeom:
            mujoco.mjv_initGeom(
                scene.geoms[scene.ngeom],
                mujoco.mjtGeom.mjGEOM_CYLINDER,
                np.array([radius, radius, DISK_HALF_THICKNESS_M]),
                centre,
                np.eye(3).ravel(),
                np.array(TARGET_RGBA, dtype=np.float32),
            )
            scene.ngeom += 1
        frame = np.ascontiguousarray(self.renderer.render())
        cv2.putText(frame, f"t = {data.time - t0:5.2f} s", (10, 30), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (255, 255, 255), 2)
        return frame

    def save(self, path: str | Path) -> Path:
        """Write the frames as MP4 (H.264 through imageio-ffmpeg)."""
        import imageio.v2 as imageio

        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        with imageio.get_writer(path, fps=self.fps, codec="libx264", quality=7, macro_block_size=16) as writer:
            for frame in self.frames:
                writer.append_data(frame)
        return path


def _borders(grid) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """The lines between an array's modules as thin boxes: (centre (x, y), half sizes (x, y)) [m]; none on one module."""
    hx, hy = grid.half_extent_m
    lines = [((-hx + i * grid.module_x_m, 0.0), (BORDER_HALF_WIDTH_M, hy)) for i in range(1, grid.modules_x)]
    return lines + [((0.0, -hy + j * grid.module_y_m), (hx, BORDER_HALF_WIDTH_M)) for j in range(1, grid.modules_y)]
