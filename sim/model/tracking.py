"""The camera as the simulated controller sees it: frame rate, latency, noise and lost frames."""

from __future__ import annotations

import math
from dataclasses import dataclass

from .parameters import default
from .rig import VISION_MODES


@dataclass(frozen=True)
class Tracking:
    """The camera as the controller sees it: rate, latency, noise and lost frames (the paper: 12 Hz)."""

    rate_hz: float = default("tracking.rate_hz")  # [Hz] frames per second
    latency_s: float = default("tracking.latency_s")  # [s] capture -> delivery to the firmware; below one frame period
    noise_m: float = 0.0  # [m] standard deviation of Gaussian noise on x and on y
    drop_rate: float = 0.0  # [-] probability that a frame never reaches the firmware
    vision: str | None = None  # None: the true position; "aruco" or "blob": the tracker on rendered frames

    def __post_init__(self) -> None:
        if not (math.isfinite(self.rate_hz) and 0.5 <= self.rate_hz <= 1000):
            raise ValueError(f"camera rate must be 0.5..1000 Hz, got {self.rate_hz}")
        if not (0 <= self.latency_s < 1 / self.rate_hz):
            raise ValueError(
                f"camera latency must be at least 0 and below one frame period "
                f"({1 / self.rate_hz:.3f} s), got {self.latency_s}"
            )
        if not (0 <= self.noise_m <= 0.1):
            raise ValueError(f"camera noise must be 0..0.1 m, got {self.noise_m}")
        if not (0 <= self.drop_rate < 1):
            raise ValueError(f"drop rate must be in [0, 1), got {self.drop_rate}")
        if self.vision not in (None, *VISION_MODES):
            raise ValueError(f"vision must be one of {', '.join(VISION_MODES)}, got {self.vision!r}")


DEFAULT_TRACKING = Tracking()  # the default plant's camera: the paper's 12 Hz, no noise, no lost frames
