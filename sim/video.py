"""Video of a trial from the scene's overhead camera, rendered offscreen (EGL without a display: sim/__init__.py)."""
from __future__ import annotations

from pathlib import Path

import mujoco

from . import model as M

FPS_RANGE = (1.0, 240.0)   # [1/s] video frame rates a recorder takes


class Recorder:
    """Renders the overhead camera every 1/fps simulated seconds; attach to Bridge.recorder, then save()."""

    def __init__(self, model: mujoco.MjModel, fps: float = 30.0, width: int = 480, height: int = 480) -> None:
        if not FPS_RANGE[0] <= fps <= FPS_RANGE[1]:
            raise ValueError(f"video fps must be {FPS_RANGE[0]:g}..{FPS_RANGE[1]:g}, got {fps}")
        self.fps = fps
        self.renderer = mujoco.Renderer(model, height, width)
        self.frames: list = []
        self.next_s: float | None = None

    def capture(self, data: mujoco.MjData) -> None:
        """Render a frame if data.time has reached the next video frame time (cheap otherwise)."""
        if self.next_s is None:
            self.next_s = data.time
        if data.time + 1e-9 >= self.next_s:
            self.renderer.update_scene(data, camera=M.OVERHEAD)
            self.frames.append(self.renderer.render())
            self.next_s += 1.0 / self.fps

    def save(self, path: str | Path) -> Path:
        """Write the frames as MP4 (H.264 through imageio-ffmpeg)."""
        import imageio.v2 as imageio

        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        with imageio.get_writer(path, fps=self.fps, codec="libx264", quality=7, macro_block_size=16) as writer:
            for frame in self.frames:
                writer.append_data(frame)
        return path
