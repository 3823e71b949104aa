"""Independent float64 model of the controllers beyond the paper (PROTOCOL.md, Controllers) to check the C++ against."""

# Written from PROTOCOL.md's equations, not from the firmware source:
#   velocity     v <- v + dt / (tau + dt) ((p - p_prev) / dt - v), 0 at start and after a restart
#   scheduled    w = clamp(1 - (h - |p|) / edge_zone, 0, 1); kP, kI x (1 - w (1 - edge_gain)); kD x (1 + w edge_brake);
#                the tilt toward the nearest edge within tilt_limit (1 - w (1 - edge_tilt)), toward the other the same
#                with w' = clamp(1 - (h + |p|) / edge_zone, 0, 1); with brake_speed > 0 the tilt along the motion
#                within x clamp(1 - |v| / brake_speed, 0, 1)
#   cascade      v* = clamp(position_gain e, +-speed_limit); tilt = PID(v* - v), its derivative -(v - v_prev) / dt
# and Manhattan's plane, noise and clamp (paper_reference.py) for both.
from __future__ import annotations

import math
from dataclasses import dataclass, field

import paper_reference as ref


@dataclass
class Schedule:
    edge_zone: float = 0.05  # [m]
    edge_gain: float = 1.0  # [-]
    edge_tilt: float = 1.0  # [-]
    edge_brake: float = 0.0  # [-]
    brake_speed: float = 0.0  # [m/s] 0: off


@dataclass
class Cascade:
    position_gain: float = 3.0  # [1/s]
    speed_limit: float = 0.15  # [m/s]


def bounded(x: float, low: float, high: float) -> float:
    """Within [low, high]; NaN becomes 0."""
    return 0.0 if math.isnan(x) else min(max(x, low), high)


@dataclass
class BoundedPid:
    """The paper's PID (paper_reference.Pid) with an output range [low, high] instead of ±limit."""

    integral: float = 0.0

    def update(self, g: ref.Gains, error: float, error_rate: float, dt: float, low: float, high: float) -> float:
        p, d = g.kp * error, g.kd * error_rate
        candidate = bounded(self.integral + g.ki * error * dt, -g.integral_limit, g.integral_limit)
        total = p + candidate + d
        if not ((total > high and candidate > self.integral) or (total < low and candidate < self.integral)):
            self.integral = candidate
        return bounded(p + self.integral + d, low, high)


@dataclass
class BeyondController:
    """'scheduled' (gains x, y) or 'cascade' (gains vx, vy); step() as paper_reference.Controller's."""

    kind: str
    m: float
    n: float
    tilt_limit: float  # [deg]
    alpha: float  # [m]
    gains: dict[str, ref.Gains]
    velocity_filter: float  # [s]
    schedule: Schedule = field(default_factory=Schedule)
    cascade: Cascade = field(default_factory=Cascade)
    seed: int = 1

    def __post_init__(self) -> None:
        self.reset(self.seed)

    def reset(self, seed: int) -> None:
        self.pids = {axis: BoundedPid() for axis in ("x", "y", "vx", "vy")}
        self.noise = ref.Xorshift32(seed)
        self.prev: tuple[float, float] | None = None
        self.v = [0.0, 0.0]

    def _scheduled(self, axis: str, p: float, half: float, error: float, rate: float, v: float, dt: float) -> float:
        s, g = self.schedule, self.gains[axis]
        w_edge = {side: min(max(1.0 - (half - side * p) / s.edge_zone, 0.0), 1.0) for side in (1, -1)}
        w = max(w_edge.values())  # the nearer edge's
        ease = 1.0 - w * (1.0 - s.edge_gain)
        gains = ref.Gains(g.kp * ease, g.ki * ease, g.kd * (1.0 + w * s.edge_brake), g.integral_limit)
        high, low = (side * self.tilt_limit * (1.0 - w_edge[side] * (1.0 - s.edge_tilt)) for side in (1, -1))
        if s.brake_speed > 0:
            fade = min(max(1.0 - abs(v) / s.brake_speed, 0.0), 1.0)
            high, low = (high * fade, low) if v > 0 else (high, low * fade) if v < 0 else (high, low)
        return self.pids[axis].update(gains, error, rate, dt, low, high)

    def _cascade(self, axis: str, error: float, v: float, acceleration: float, dt: float) -> float:
        c = self.cascade
        wanted = bounded(c.position_gain * error, -c.speed_limit, c.speed_limit)
        return self.pids[axis].update(
            self.gains[axis], wanted - v, -acceleration, dt, -self.tilt_limit, self.tilt_limit
        )

    def step(self, target: tuple[float, float], position: tuple[float, float], dt: float) -> ref.Step:
        rate_known = self.prev is not None and dt > 0
        dt = dt if rate_known else 0.0
        e = (target[0] - position[0], target[1] - position[1])
        last_v = list(self.v)
        if rate_known:
            for i in range(2):
                self.v[i] += dt / (self.velocity_filter + dt) * ((position[i] - self.prev[i]) / dt - self.v[i])
        else:
            self.v = [0.0, 0.0]
        tilts = []
        for i, (axis, half) in enumerate((("x", self.m / 2), ("y", self.n / 2))):
            if self.kind == "scheduled":
                rate = -(position[i] - self.prev[i]) / dt if rate_known else 0.0
                tilts.append(self._scheduled(axis, position[i], half, e[i], rate, self.v[i], dt))
            elif self.kind == "cascade":
                acceleration = (self.v[i] - last_v[i]) / dt if rate_known else 0.0
                tilts.append(self._cascade("v" + axis, e[i], self.v[i], acceleration, dt))
            else:
                raise ValueError(f"unknown controller {self.kind!r}")
        delta = [self.noise.uniform_pm1() for _ in range(4)]
        command = ref.commands(ref.manhattan_normal(*tilts), self.m, self.n, self.alpha, delta)
        self.prev = (position[0], position[1])
        return ref.Step(tilts[0], tilts[1], command, math.hypot(*e))
