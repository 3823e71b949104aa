"""The closed loop, one for the rig and the simulation: camera frames in, position frames out, telemetry and the
trajectory recorded, the target's tolerance judged, the run ended by its stop rules.

What differs between the two is outside it, behind two interfaces: the plant (`LoopPlant`: the rig's camera and
tracker, or the simulated physics and camera), which gives the frames and takes the answers, and how a position frame
reaches the firmware (`send`: a RigSession on the rig, a Link in lock-step in the simulation). Times are trial time
[s] from the start; positions [m] in the fabric frame.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from mantaray.protocol import messages as m

U16 = 0xFFFF
U32 = 0xFFFFFFFF
US_PER_S = 1_000_000


@dataclass
class Tolerance:
    """Within epsilon of the target: since when, and whether for long enough (hold_s; 0: the first frame within)."""

    tolerance_m: float  # [m] epsilon
    hold_s: float = 0.0  # [s] how long the object must stay within before it counts as reached
    first_s: float | None = None  # [s] the first frame within (the paper's reach), None until then
    _since_s: float | None = None  # [s] start of the present stay within

    def update(self, t_s: float, xy_m, target_m) -> bool:
        """One frame's position: True once the object has stayed within for hold_s."""
        near = math.hypot(xy_m[0] - target_m[0], xy_m[1] - target_m[1]) < self.tolerance_m
        if near and self.first_s is None:
            self.first_s = t_s
        self._since_s = (self._since_s if self._since_s is not None else t_s) if near else None
        return self._since_s is not None and t_s - self._since_s >= self.hold_s


@dataclass
class CameraFrame:
    """One camera frame, as a source gives it to ClosedLoop.run."""

    capture_s: float  # [s] trial time it was taken
    measured_xy_m: object  # (x, y) [m] what the firmware is sent; None: not seen (sent as not visible)
    target_m: tuple[float, float]  # [m] the target at this frame
    judged_xy_m: object = None  # (x, y) [m] where the tolerance is judged (None: not judged at this frame)
    dropped: bool = False  # taken, but never reaches the firmware


STOPPED_REACHED, STOPPED_BY_SOURCE = "reached", "source"  # why ClosedLoop.run ended


class LoopPlant(Protocol):
    """What ClosedLoop.run drives. Each frame, in this order: frames() yields it as captured; the loop judges it;
    deliver(frame) makes it what reaches the firmware (the simulation's drop, noise and latency; a rig's moving
    target); the loop sends it (or records it dropped); answered(frame, telemetry) takes the answer (the simulation
    applies its commands) and records or shows the frame."""

    def frames(self) -> Iterator[CameraFrame]:
        """The camera's frames until the source ends (camera stopped, timeout, object fell)."""
        ...

    def deliver(self, frame: CameraFrame) -> bool:
        """Before the frame is sent: False ends the run there (the object fell on the way)."""
        ...

    def answered(self, frame: CameraFrame, telemetry: m.Telemetry | None) -> None:
        """After the frame was sent (or dropped): its answer, None when none came."""
        ...


@dataclass
class ClosedLoop:
    """Sends camera frames to the firmware and records one row per frame (a dropped frame records no answer).

    send(msg) delivers one position frame and returns its telemetry, or None when none answered it.
    capture_time goes out as time_base_us + the frame's trial time, on the firmware's clock.
    """

    send: Callable[[m.ObjectPosition], m.Telemetry | None]
    time_base_us: int = 0  # [us] the firmware's clock at trial time 0
    frame: int = 0  # the last frame number sent (u16, runs on across trials)
    t_s: list = field(default_factory=list)  # [s] capture times
    measured_xy_m: list = field(default_factory=list)  # [m] what the firmware was sent (NaN: not seen, dropped)
    target_m: list = field(default_factory=list)  # [m] the target at each frame
    tilt_deg: list = field(default_factory=list)  # [deg] theta_zx, theta_zy from telemetry (NaN: no answer)
    command_m: list = field(default_factory=list)  # [m] a_0..a_3 from telemetry
    measured_m: list = field(default_factory=list)  # [m] the actuators' measured positions from telemetry
    state: list = field(default_factory=list)  # supervisor state (-1: no answer)
    module: list = field(default_factory=list)  # the driven module, telemetry.module (-1: no answer)

    def step(self, capture_s: float, measured_xy_m, target_m) -> m.Telemetry | None:
        """One camera frame captured at trial time capture_s: measured_xy_m None (or NaN) is sent as not visible."""
        visible = measured_xy_m is not None and bool(np.all(np.isfinite(measured_xy_m)))
        self.frame = (self.frame + 1) & U16
        msg = m.ObjectPosition(
            frame=self.frame,
            capture_time=(self.time_base_us + round(capture_s * US_PER_S)) & U32,
            x=float(measured_xy_m[0]) if visible else 0.0,
            y=float(measured_xy_m[1]) if visible else 0.0,
            flags=0 if visible else m.PositionFlags.NOT_VISIBLE,
        )
        telemetry = self.send(msg)
        self._record(capture_s, measured_xy_m if visible else None, target_m, telemetry)
        return telemetry

    def run(self, plant: LoopPlant, judge: Tolerance, *, stop_when_reached: bool) -> str:
        """Drive the loop with a plant's frames until a stop rule ends it; returns why (STOPPED_*).

        Each frame, in order (LoopPlant): the tolerance is judged, and once it holds a run with stop_when_reached ends
        there (reached: that frame is neither delivered, sent nor recorded, as the paper's loop stops at it); the
        plant delivers it; it is sent (or recorded as dropped); the plant takes the answer. A plant whose frames end
        (camera stopped, timeout, object fell) ends the run by its own reason."""
        for frame in plant.frames():
            if (
                frame.judged_xy_m is not None
                and judge.update(frame.capture_s, frame.judged_xy_m, frame.target_m)
                and stop_when_reached
            ):
                return STOPPED_REACHED
            if not plant.deliver(frame):
                return STOPPED_BY_SOURCE
            telemetry = None
            if frame.dropped:
                self.dropped(frame.capture_s, frame.target_m)
            else:
                telemetry = self.step(frame.capture_s, frame.measured_xy_m, frame.target_m)
            plant.answered(frame, telemetry)
        return STOPPED_BY_SOURCE

    def dropped(self, capture_s: float, target_m) -> None:
        """A frame the camera took (its number is used up) that never reached the firmware: a row with no answer."""
        self.frame = (self.frame + 1) & U16
        self._record(capture_s, None, target_m, None)

    def _record(self, capture_s: float, xy_m, target_m, telemetry: m.Telemetry | None) -> None:
        self.t_s.append(capture_s)
        self.measured_xy_m.append(tuple(xy_m) if xy_m is not None else (math.nan, math.nan))
        self.target_m.append(tuple(target_m))
        if telemetry is None:
            self.tilt_deg.append((math.nan, math.nan))
            self.command_m.append((math.nan,) * 4)
            self.measured_m.append((math.nan,) * 4)
            self.state.append(-1)
            self.module.append(-1)
        else:
            self.tilt_deg.append((telemetry.tilt_zx, telemetry.tilt_zy))
            self.command_m.append(tuple(telemetry.command))
            self.measured_m.append(tuple(telemetry.measured))
            self.state.append(int(telemetry.state))
            self.module.append(int(telemetry.module))

    def arrays(self) -> dict[str, np.ndarray]:
        """The rows as arrays: t_s (n,), measured_xy_m (n, 2), target_m (n, 2), tilt_deg (n, 2), command_m (n, 4),
        measured_m (n, 4), state (n,), module (n,): the driven module (-1: no answer)."""
        return {
            "t_s": np.asarray(self.t_s, dtype=float),
            "measured_xy_m": np.asarray(self.measured_xy_m, dtype=float).reshape(-1, 2),
            "target_m": np.asarray(self.target_m, dtype=float).reshape(-1, 2),
            "tilt_deg": np.asarray(self.tilt_deg, dtype=float).reshape(-1, 2),
            "command_m": np.asarray(self.command_m, dtype=float).reshape(-1, 4),
            "measured_m": np.asarray(self.measured_m, dtype=float).reshape(-1, 4),
            "state": np.asarray(self.state, dtype=int),
            "module": np.asarray(self.module, dtype=int),
        }
