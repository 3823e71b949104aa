"""Independent float64 NumPy model of the paper's controllers (Methods, Algorithms 1 and 2) to check the C++ against."""

# Written from the paper's equations, not from the firmware source:
#   Manhattan normal   n = (sin θzx, sin θzy, cos θzx)                               (Algorithm 1, line 7)
#   Euclidean normal   n = (e_x/d sin θ, e_y/d sin θ, cos θ) for d > 0, (0, 0, 1) for d = 0  (eq. normal_eu)
#   plane              n_x x + n_y y + n_z (z - z0) = 0 through P0 = (0, 0, z0)
#   heights            z_i = (z0 n_z - n_x x_i - n_y y_i) / n_z
#   commands           a_i = (z0 - z_i) + α δ_i,  δ_i ~ U(-1, 1), each actuator within [-0.25, 0.25] m
# with the stack's conventions: angles in degrees (the PID output unit), actuators numbered
# 0 (-m/2, -n/2), 1 (+m/2, -n/2), 2 (-m/2, +n/2), 3 (+m/2, +n/2), a_i > 0 lowers corner i, and δ_i drawn
# from a seeded xorshift32 so a run can be reproduced bit for bit.
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

Z0 = 1.5  # [m] reference height of the paper; it cancels out of a_i
ACTUATOR_RANGE = 0.25  # [m] each actuator's travel about z0 (the paper; test_rig_description checks rig.toml's)
ACTUATOR_SIGNS = np.array([(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)])  # (sign x_i, sign y_i)


def actuator_positions(m: float, n: float) -> tuple[np.ndarray, np.ndarray]:
    """Base positions (x_i, y_i) [m] of the four actuators of an m x n module."""
    return ACTUATOR_SIGNS[:, 0] * (m / 2.0), ACTUATOR_SIGNS[:, 1] * (n / 2.0)


def manhattan_normal(tilt_zx_deg, tilt_zy_deg) -> np.ndarray:
    """Algorithm 1: n = (sin θzx, sin θzy, cos θzx); the last axis holds (n_x, n_y, n_z)."""
    zx = np.radians(np.asarray(tilt_zx_deg, dtype=np.float64))
    zy = np.radians(np.asarray(tilt_zy_deg, dtype=np.float64))
    return np.stack(np.broadcast_arrays(np.sin(zx), np.sin(zy), np.cos(zx)), axis=-1)


def euclidean_normal(theta_deg, e_x, e_y) -> np.ndarray:
    """Algorithm 2: n = (e_x/d sin θ, e_y/d sin θ, cos θ) with d = |e|, and (0, 0, 1) where d = 0."""
    theta = np.radians(np.asarray(theta_deg, dtype=np.float64))
    e_x = np.asarray(e_x, dtype=np.float64)
    e_y = np.asarray(e_y, dtype=np.float64)
    theta, e_x, e_y = np.broadcast_arrays(theta, e_x, e_y)
    d = np.hypot(e_x, e_y)
    moving = d > 0
    safe_d = np.where(moving, d, 1.0)
    n_x = np.where(moving, e_x / safe_d * np.sin(theta), 0.0)
    n_y = np.where(moving, e_y / safe_d * np.sin(theta), 0.0)
    n_z = np.where(moving, np.cos(theta), 1.0)
    return np.stack([n_x, n_y, n_z], axis=-1)


def heights(normal: np.ndarray, m: float, n: float, z0: float = Z0) -> np.ndarray:
    """z_i = (z0 n_z - n_x x_i - n_y y_i) / n_z: where the plane meets each actuator's vertical; last axis = i."""
    normal = np.asarray(normal, dtype=np.float64)
    x_i, y_i = actuator_positions(m, n)
    n_x, n_y, n_z = normal[..., 0:1], normal[..., 1:2], normal[..., 2:3]
    return (z0 * n_z - n_x * x_i - n_y * y_i) / n_z


def raw_commands(normal: np.ndarray, m: float, n: float, z0: float = Z0) -> np.ndarray:
    """a_i = z0 - z_i before noise and clamping [m], + lowers corner i."""
    return z0 - heights(normal, m, n, z0)


def clamp(x, limit):
    """Clamp to [-limit, limit]; NaN becomes 0 (a non-number must never reach an actuator)."""
    x = np.asarray(x, dtype=np.float64)
    return np.where(np.isnan(x), 0.0, np.clip(x, -limit, limit))


def commands(normal: np.ndarray, m: float, n: float, alpha: float = 0.0, delta=None) -> np.ndarray:
    """a_i = (z0 - z_i) + α δ_i, each then held within the actuator range ±0.25 m."""
    a = raw_commands(normal, m, n)
    if delta is not None:
        a = a + alpha * np.asarray(delta, dtype=np.float64)
    return clamp(a, ACTUATOR_RANGE)


def max_tilt_deg(m: float, n: float, actuator_range: float = ACTUATOR_RANGE) -> float:
    """Largest tilt on both axes at once that keeps every corner in range: atan(range / ((m + n) / 2)) [deg]."""
    return math.degrees(math.atan(actuator_range / ((m + n) / 2.0)))


class Xorshift32:
    """Marsaglia's xorshift32 (13, 17, 5); a zero seed is replaced by 1."""

    def __init__(self, seed: int) -> None:
        self.state = (seed & 0xFFFFFFFF) or 1

    def next(self) -> int:
        s = self.state
        s ^= (s << 13) & 0xFFFFFFFF
        s ^= s >> 17
        s ^= (s << 5) & 0xFFFFFFFF
        self.state = s
        return s

    def uniform_pm1(self) -> float:
        """δ ~ U(-1, 1): the top 24 bits of the next state mapped onto [-1, 1)."""
        return (self.next() >> 8) * (2.0 / 2**24) - 1.0


@dataclass
class Gains:
    kp: float  # [deg/m]
    ki: float  # [deg/(m s)]
    kd: float  # [deg s/m]
    integral_limit: float  # [deg]


@dataclass
class Pid:
    """PID on an error [m] giving a tilt [deg]: clamped integral, no integration while the output saturates
    in the integral's direction, derivative on the measured motion, output clamped to ±output_limit."""

    gains: Gains
    integral: float = 0.0

    def update(self, error: float, error_rate: float, dt: float, output_limit: float) -> float:
        g = self.gains
        p = g.kp * error
        d = g.kd * error_rate
        candidate = float(clamp(self.integral + g.ki * error * dt, g.integral_limit))
        total = p + candidate + d
        winding_up = (total > output_limit and candidate > self.integral) or (
            total < -output_limit and candidate < self.integral
        )
        if not winding_up:
            self.integral = candidate
        return float(clamp(p + self.integral + d, output_limit))


@dataclass
class Step:
    """What one control step produces."""

    tilt_zx: float  # [deg] (Euclidean: θ resolved along x)
    tilt_zy: float  # [deg]
    command: np.ndarray  # [m] a_i after noise and clamping
    distance: float  # [m] |p_d - p|


@dataclass
class Controller:
    """Algorithm 1 (kind 'manhattan', PIDs x and y) or Algorithm 2 (kind 'euclidean', one radial PID).

    step() takes the measured position, the current target and dt [s]; dt <= 0, or the first step after
    reset, integrates nothing and has no derivative. The derivative acts on the measured motion only
    (the previous position's error is taken against the current target), so a target change gives no kick.
    """

    kind: str
    m: float
    n: float
    tilt_limit: float  # [deg]
    alpha: float  # [m] noise amplitude
    gains: dict[str, Gains]  # 'x', 'y', 'radial'
    seed: int = 1
    pids: dict[str, Pid] = field(init=False)
    noise: Xorshift32 = field(init=False)
    prev: tuple[float, float] | None = field(init=False, default=None)

    def __post_init__(self) -> None:
        self.reset(self.seed)

    def reset(self, seed: int) -> None:
        self.pids = {axis: Pid(g) for axis, g in self.gains.items()}
        self.noise = Xorshift32(seed)
        self.prev = None

    def step(self, target: tuple[float, float], position: tuple[float, float], dt: float) -> Step:
        x_d, y_d = target
        x, y = position
        rate_known = self.prev is not None and dt > 0
        if not rate_known:
            dt = 0.0
        e_x, e_y = x_d - x, y_d - y
        distance = math.hypot(e_x, e_y)
        if self.kind == "manhattan":
            rate_x = rate_y = 0.0
            if rate_known:
                rate_x = (e_x - (x_d - self.prev[0])) / dt  # = -(x - x_prev) / dt
                rate_y = (e_y - (y_d - self.prev[1])) / dt
            tilt_zx = self.pids["x"].update(e_x, rate_x, dt, self.tilt_limit)
            tilt_zy = self.pids["y"].update(e_y, rate_y, dt, self.tilt_limit)
            normal = manhattan_normal(tilt_zx, tilt_zy)
        elif self.kind == "euclidean":
            rate = 0.0
            if rate_known:
                rate = (distance - math.hypot(x_d - self.prev[0], y_d - self.prev[1])) / dt
            theta = self.pids["radial"].update(distance, rate, dt, self.tilt_limit)
            tilt_zx = theta * e_x / distance if distance > 0 else 0.0
            tilt_zy = theta * e_y / distance if distance > 0 else 0.0
            normal = euclidean_normal(theta, e_x, e_y)
        else:
            raise ValueError(f"unknown controller {self.kind!r}")
        delta = [self.noise.uniform_pm1() for _ in range(4)]  # one draw per actuator, in actuator order
        command = commands(normal, self.m, self.n, self.alpha, delta)
        self.prev = (x, y)
        return Step(tilt_zx, tilt_zy, command, distance)
