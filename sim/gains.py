"""One PID's gains as the configure_pid message carries them, in the paper's units (output in degrees of tilt)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Gains:
    """One PID's gains, as configure_pid carries them (output in degrees of tilt)."""

    kp: float  # [deg/m]
    ki: float  # [deg/(m s)]
    kd: float  # [deg s/m]
    integral_limit: float  # [deg]
