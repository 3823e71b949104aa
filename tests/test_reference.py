"""The C++ transform and controllers against the independent float64 model of the paper (tests/paper_reference.py)."""

from __future__ import annotations

import ctypes
import math
import struct
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import beyond_reference as beyond  # noqa: E402
import paper_reference as ref  # noqa: E402

from mantaray.host.link import CommandRefused, Link  # noqa: E402
from mantaray.host.transport import InProcessTransport  # noqa: E402
from mantaray.protocol import messages as m  # noqa: E402

TILT_QUANTUM = 0.01  # [deg] telemetry tilt resolution
COMMAND_QUANTUM = 1e-5  # [m] telemetry command resolution
TILT_EPS = 2e-4  # [deg] float32 arithmetic of the firmware, on top of half a quantum
COMMAND_EPS = 1e-6  # [m]


def f32(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


# ------------------------------------------------------------------------ (a) the transform, via ctypes
def manhattan_cpp(lib, zx, zy, mx, my) -> np.ndarray:
    out = (ctypes.c_float * 4)()
    lib.mr_manhattan_commands(zx, zy, mx, my, out)
    return np.array(out[:], dtype=np.float64)


def euclidean_cpp(lib, theta, ex, ey, mx, my) -> np.ndarray:
    out = (ctypes.c_float * 4)()
    lib.mr_euclidean_commands(theta, ex, ey, mx, my, out)
    return np.array(out[:], dtype=np.float64)


def module_sizes(rng, n) -> tuple[np.ndarray, np.ndarray]:
    """Module sides across configure's whole range [0.1, 10] m, log-uniform, with the paper's 0.5 m often."""
    sides = np.exp(rng.uniform(math.log(0.1), math.log(10.0), size=(2, n)))
    sides[:, : n // 5] = 0.5
    return sides.astype(np.float32).astype(np.float64)


def term_scale(normal: np.ndarray, mx: float, my: float) -> float:
    """Size of the terms of a_i, (|n_x| m/2 + |n_y| n/2) / |n_z|: what float32 rounding is relative to."""
    return (abs(normal[0]) * mx / 2 + abs(normal[1]) * my / 2) / abs(normal[2])


N_TRANSFORM = 6000


def test_manhattan_transform_matches_the_paper(capi):
    rng = np.random.default_rng(20240601)
    limit = np.where(rng.random(N_TRANSFORM) < 0.7, 30.0, 89.0)
    zx = rng.uniform(-1, 1, N_TRANSFORM) * limit
    zy = rng.uniform(-1, 1, N_TRANSFORM) * limit
    zx[:50], zy[50:100] = 0.0, 0.0
    zx, zy = zx.astype(np.float32).astype(np.float64), zy.astype(np.float32).astype(np.float64)
    mx, my = module_sizes(rng, N_TRANSFORM)
    worst = 0.0
    for i in range(N_TRANSFORM):
        got = manhattan_cpp(capi, zx[i], zy[i], mx[i], my[i])
        normal = ref.manhattan_normal(zx[i], zy[i])
        want = ref.raw_commands(normal, mx[i], my[i])
        tol = 1e-5 * term_scale(normal, mx[i], my[i]) + 1e-12
        err = np.max(np.abs(got - want))
        assert err <= tol, (zx[i], zy[i], mx[i], my[i], got, want)
        worst = max(worst, err / tol)
    assert worst > 0  # the comparison did compare something


def test_euclidean_transform_matches_the_paper(capi):
    rng = np.random.default_rng(7)
    n = N_TRANSFORM
    theta = (rng.uniform(-1, 1, n) * np.where(rng.random(n) < 0.7, 30.0, 89.0)).astype(np.float32)
    magnitude = np.exp(rng.uniform(math.log(1e-6), math.log(1e3), n))
    angle = rng.uniform(-math.pi, math.pi, n)
    ex = (magnitude * np.cos(angle)).astype(np.float32)
    ey = (magnitude * np.sin(angle)).astype(np.float32)
    ex[:40] = 0.0  # along y only
    ey[40:80] = 0.0  # along x only
    ex[80:120] = ey[80:120] = 0.0  # d = 0: n = (0, 0, 1), a level plane
    mx, my = module_sizes(rng, n)
    for i in range(n):
        t, x, y = float(theta[i]), float(ex[i]), float(ey[i])
        got = euclidean_cpp(capi, t, x, y, mx[i], my[i])
        normal = ref.euclidean_normal(t, x, y)
        want = ref.raw_commands(normal, mx[i], my[i])
        if x == 0.0 and y == 0.0:
            assert np.all(got == 0.0) and np.all(want == 0.0)
            continue
        tol = 1e-5 * term_scale(normal, mx[i], my[i]) + 1e-12
        assert np.max(np.abs(got - want)) <= tol, (t, x, y, mx[i], my[i], got, want)


def test_max_tilt_matches_the_paper(capi):
    rng = np.random.default_rng(3)
    mx, my = module_sizes(rng, N_TRANSFORM)
    ranges = rng.uniform(0.01, 1.0, N_TRANSFORM).astype(np.float32)
    for i in range(N_TRANSFORM):
        got = capi.mr_max_tilt_deg(mx[i], my[i], float(ranges[i]))
        want = ref.max_tilt_deg(mx[i], my[i], float(ranges[i]))
        assert abs(got - want) <= 1e-6 * want + 1e-6, (mx[i], my[i], ranges[i], got, want)
    assert capi.mr_max_tilt_deg(0.5, 0.5, 0.25) == pytest.approx(26.565051, abs=1e-5)  # the paper's +-26 deg


def test_reference_self_consistency():
    """The model itself: corners lie on the plane, z0 cancels, and the tilt limit puts a corner at the range."""
    rng = np.random.default_rng(11)
    for _ in range(200):
        mx, my = rng.uniform(0.1, 10, 2)
        normal = ref.manhattan_normal(*rng.uniform(-60, 60, 2))
        x_i, y_i = ref.actuator_positions(mx, my)
        z_i = ref.heights(normal, mx, my)
        residual = normal[0] * x_i + normal[1] * y_i + normal[2] * (z_i - ref.Z0)
        assert np.allclose(residual, 0, atol=1e-12)
        assert np.allclose(ref.raw_commands(normal, mx, my), ref.raw_commands(normal, mx, my, z0=7.0), atol=1e-12)
        limit = ref.max_tilt_deg(mx, my)
        at_limit = ref.raw_commands(ref.manhattan_normal(limit, limit), mx, my)
        assert np.max(np.abs(at_limit)) == pytest.approx(ref.ACTUATOR_RANGE, rel=1e-12)
    # positive theta_zx lowers the +x corners (1, 3); positive theta_zy lowers the +y corners (2, 3)
    a = ref.raw_commands(ref.manhattan_normal(10.0, 0.0), 0.5, 0.5)
    assert a[1] > 0 and a[3] > 0 and a[0] < 0 and a[2] < 0
    a = ref.raw_commands(ref.manhattan_normal(0.0, 10.0), 0.5, 0.5)
    assert a[2] > 0 and a[3] > 0 and a[0] < 0 and a[1] < 0


def test_xorshift_reference_known_values():
    """xorshift32 (13, 17, 5) from seed 1: Marsaglia's sequence; seed 0 behaves as seed 1."""
    rng = ref.Xorshift32(1)
    assert [rng.next() for _ in range(3)] == [270369, 67634689, 2647435461]
    zero = ref.Xorshift32(0)
    assert zero.next() == 270369
    draws = [ref.Xorshift32(s).uniform_pm1() for s in range(1, 2000)]
    assert all(-1.0 <= d < 1.0 for d in draws)


# --------------------------------------------------------------- (b) the controllers, in the firmware
@dataclass
class RunConfig:
    kind: str  # 'manhattan', 'euclidean', 'scheduled' or 'cascade'
    tilt_limit: float
    alpha: float
    seed: int
    deadman: int  # [ms]
    telemetry_period: int  # [ms]
    gains: dict[str, ref.Gains]  # by axis name: x, y, radial, vx, vy (absent: the firmware's defaults)
    velocity_filter: float = f32(0.05)  # [s]
    schedule: beyond.Schedule = field(default_factory=beyond.Schedule)
    cascade: beyond.Cascade = field(default_factory=beyond.Cascade)


def random_config(rng, kind: str, deadman: int = 60000) -> RunConfig:
    def gains() -> ref.Gains:
        return ref.Gains(
            *(f32(v) for v in (rng.uniform(0, 120), rng.uniform(0, 60), rng.uniform(0, 25), rng.uniform(0.5, 30)))
        )

    return RunConfig(
        kind=kind,
        tilt_limit=f32(rng.uniform(3.0, 26.5)),
        alpha=f32(rng.uniform(0.0, 0.1)),
        seed=int(rng.integers(0, 2**32)),
        deadman=deadman,
        telemetry_period=int(rng.choice([0, 0, 5, 40])),
        gains={"x": gains(), "y": gains(), "radial": gains(), "vx": gains(), "vy": gains()},
        velocity_filter=f32(rng.choice([0.0, rng.uniform(0.0, 0.5)])),
        schedule=beyond.Schedule(
            *(
                f32(v)
                for v in (
                    rng.uniform(0.005, 0.6),
                    rng.uniform(0, 1),
                    rng.uniform(0, 1),
                    rng.uniform(0, 20),
                    rng.choice([0.0, rng.uniform(0.01, 2.0)]),
                )
            )
        ),
        cascade=beyond.Cascade(f32(rng.uniform(0, 20)), f32(rng.uniform(0.001, 1.0))),
    )


class Harness:
    """The in-process firmware and the reference fed the same frames; compares every telemetry."""

    def __init__(self, cfg: RunConfig) -> None:
        self.cfg = cfg
        self.link = Link(InProcessTransport(simulated_clock=True))  # a fresh boot: the core's state is global
        self.link.identify()
        self.link.command(
            m.Configure(
                controller=m.Controller[cfg.kind.upper()],
                module_x=0.5,
                module_y=0.5,
                tilt_limit=cfg.tilt_limit,
                tolerance=0.02,
                noise_amplitude=cfg.alpha,
                noise_seed=cfg.seed,
                deadman=cfg.deadman,
                telemetry_period=cfg.telemetry_period,
                velocity_filter=cfg.velocity_filter,
            )
        )
        for axis in m.Axis:
            g = cfg.gains.get(axis.name.lower())
            if g is not None:
                self.link.command(m.ConfigurePid(axis=axis, kp=g.kp, ki=g.ki, kd=g.kd, integral_limit=g.integral_limit))
        self.link.command(m.ConfigureSchedule(**vars(cfg.schedule)))
        self.link.command(m.ConfigureCascade(**vars(cfg.cascade)))
        if cfg.kind in ("manhattan", "euclidean"):
            self.model = ref.Controller(cfg.kind, 0.5, 0.5, cfg.tilt_limit, cfg.alpha, cfg.gains, cfg.seed)
        else:
            self.model = beyond.BeyondController(
                cfg.kind,
                0.5,
                0.5,
                cfg.tilt_limit,
                cfg.alpha,
                cfg.gains,
                cfg.velocity_filter,
                cfg.schedule,
                cfg.cascade,
                cfg.seed,
            )
        self.frame = 0
        self.capture_us = 1_000_000
        self.clock_us = 0
        self.clock_since_valid_us = 0  # firmware time since the last visible position (or start)
        self.last_step_capture: int | None = None
        self.target = (0.0, 0.0)
        self.last_telemetry: m.Telemetry | None = None
        self.steps = 0

    def set_target(self, x: float, y: float) -> None:
        self.target = (f32(x), f32(y))
        self.link.command(m.SetTarget(*self.target))

    def start(self) -> None:
        self.link.command(m.Start())
        self.model.reset(self.cfg.seed)
        self.last_step_capture = None
        self.last_telemetry = None  # start levels the surface
        self.clock_since_valid_us = 0

    def stop(self) -> None:
        self.link.command(m.Stop())
        self.last_telemetry = None

    def advance(self, gap_us: int) -> None:
        """Host capture clock moves by gap_us; the firmware clock follows, but never far enough to trip the
        deadman (a real gap longer than the deadman is what the capture times alone must reveal)."""
        self.capture_us += gap_us
        step = max(0, min(gap_us, self.cfg.deadman * 1000 // 2 - self.clock_since_valid_us))
        self.clock_us += step
        self.clock_since_valid_us += step
        self.link.command(m.SimClock(now=self.clock_us))

    def position(self, x: float, y: float, visible: bool = True) -> m.Telemetry:
        self.frame = (self.frame + 1) & 0xFFFF
        x, y = f32(x), f32(y)
        flags = m.PositionFlags(0) if visible else m.PositionFlags.NOT_VISIBLE
        tel = self.link.position(
            m.ObjectPosition(frame=self.frame, capture_time=self.capture_us & 0xFFFFFFFF, x=x, y=y, flags=flags)
        )
        assert tel.faults == 0, tel
        assert tel.position_frame == self.frame
        assert tel.measured == tel.command  # the native HAL's actuators are ideal
        if not visible:
            held = self.last_telemetry or m.Telemetry()  # level after start
            assert (tel.tilt_zx, tel.tilt_zy, tel.command) == (held.tilt_zx, held.tilt_zy, held.command), (
                "commands hold while the object is not visible"
            )
            self.last_telemetry = tel
            return tel
        self.clock_since_valid_us = 0
        # the supervisor's dt: capture-time difference since the last step; 0 (a restart) past the deadman
        dt = 0.0
        if self.last_step_capture is not None:
            gap = self.capture_us - self.last_step_capture
            dt = gap * 1e-6 if gap <= self.cfg.deadman * 1000 else 0.0
        self.last_step_capture = self.capture_us
        want = self.model.step(self.target, (x, y), dt)
        self.compare(tel, want)
        self.last_telemetry = tel
        self.steps += 1
        return tel

    def refused_position(self, x: float, y: float) -> None:
        """A visible measurement no controller may see (NaN, inf, off the module): refused, naming the field, and
        nothing of it is kept (the next frame's dt, velocity and commands are as if it never came)."""
        with pytest.raises(CommandRefused) as refused:
            self.link.position(
                m.ObjectPosition(
                    frame=(self.frame + 1) & 0xFFFF, capture_time=self.capture_us & 0xFFFFFFFF, x=f32(x), y=f32(y)
                )
            )
        x_bad = not (math.isfinite(x) and abs(x) <= 0.5)  # the module's half side is 0.5 m here
        bad = x if x_bad else y
        assert refused.value.code == (m.ErrorCode.OUT_OF_RANGE if math.isfinite(bad) else m.ErrorCode.NOT_FINITE)
        names = [spec.name for spec in m.ObjectPosition.FIELDS]
        assert refused.value.nack.field == names.index("x" if x_bad else "y")

    def compare(self, tel: m.Telemetry, want: ref.Step) -> None:
        context = (self.cfg, self.steps, tel, want)
        assert abs(tel.tilt_zx - want.tilt_zx) <= TILT_QUANTUM / 2 + TILT_EPS, context
        assert abs(tel.tilt_zy - want.tilt_zy) <= TILT_QUANTUM / 2 + TILT_EPS, context
        assert max(abs(tel.tilt_zx), abs(tel.tilt_zy)) <= self.cfg.tilt_limit + TILT_QUANTUM / 2
        for got, expected in zip(tel.command, want.command, strict=True):
            assert abs(got - expected) <= COMMAND_QUANTUM / 2 + COMMAND_EPS, context
            assert abs(got) <= ref.ACTUATOR_RANGE
        if abs(want.distance - 0.02) > 1e-6:
            expected_state = m.State.REACHED if want.distance < 0.02 else m.State.RUNNING
            assert tel.state == expected_state, context


def drive(h: Harness, rng, steps: int, allow_long_gaps: bool = False) -> None:
    """A random-walk object with occasional jumps, target changes, lost frames, and a restart midway."""
    h.set_target(*rng.uniform(-0.25, 0.25, 2))
    h.start()
    p = rng.uniform(-0.25, 0.25, 2)
    restart_at = steps // 2
    for i in range(steps):
        if i == restart_at:
            h.stop()
            h.start()
        if rng.random() < 0.04:
            h.set_target(*rng.uniform(-0.25, 0.25, 2))  # mid-run: no derivative kick, in both
        if rng.random() < 0.05:
            p = rng.uniform(-0.3, 0.3, 2)
        else:
            p = p + rng.normal(0, 0.01, 2)
        gap = int(rng.integers(2_000, 150_000))
        if allow_long_gaps and rng.random() < 0.1:
            gap = h.cfg.deadman * 1000 + int(rng.integers(1, 300_000))
        h.advance(gap)
        if rng.random() < 0.03:
            h.position(math.nan if rng.random() < 0.5 else float(p[0]), float(p[1]), visible=False)
        elif rng.random() < 0.03:
            bad = [math.nan, math.inf, -math.inf, 1e30, 0.51][int(rng.integers(5))]
            h.refused_position(*((bad, float(p[1])) if rng.random() < 0.5 else (float(p[0]), bad)))
        else:
            h.position(float(p[0]), float(p[1]))


@pytest.mark.parametrize("run", range(8))
def test_controllers_match_the_paper_step_by_step(run):
    rng = np.random.default_rng(1000 + run)
    kind = "manhattan" if run % 2 == 0 else "euclidean"
    h = Harness(random_config(rng, kind, deadman=60000 if run < 6 else 150))
    drive(h, rng, steps=320, allow_long_gaps=run >= 6)
    assert h.steps >= 280


@pytest.mark.parametrize("run", range(8))
def test_controllers_beyond_the_paper_match_their_reference_step_by_step(run):
    """The scheduled and cascade controllers, their settings and gains drawn at random, against beyond_reference."""
    rng = np.random.default_rng(3000 + run)
    kind = "scheduled" if run % 2 == 0 else "cascade"
    h = Harness(random_config(rng, kind, deadman=60000 if run < 6 else 150))
    drive(h, rng, steps=320, allow_long_gaps=run >= 6)
    assert h.steps >= 280


def test_the_scheduled_controller_with_its_default_schedule_steps_as_the_papers_manhattan():
    """configure_schedule's defaults schedule nothing: the firmware's scheduled against the paper's Algorithm 1."""
    rng = np.random.default_rng(77)
    cfg = random_config(rng, "scheduled")
    cfg.schedule = beyond.Schedule()
    h = Harness(cfg)
    h.model = ref.Controller("manhattan", 0.5, 0.5, cfg.tilt_limit, cfg.alpha, cfg.gains, cfg.seed)
    drive(h, rng, steps=200)


def test_a_schedule_wider_than_half_the_module_limits_each_side_by_its_own_edge():
    """edge_zone > h: the tilt toward each edge is limited by that edge's own distance, so the limits are the same
    just either side of the centre (no jump where the nearest edge changes), and off the centre they differ as each
    edge's weight says; the firmware agrees with its reference at every step."""
    rng = np.random.default_rng(91)
    cfg = random_config(rng, "scheduled")
    cfg.gains = {axis: ref.Gains(f32(2000.0), 0.0, 0.0, f32(1.0)) for axis in ("x", "y")}  # saturates at the limit
    zone, edge_tilt = rng.uniform(0.4, 0.6), rng.uniform(0.1, 0.9)
    cfg.schedule = beyond.Schedule(edge_zone=f32(zone), edge_tilt=f32(edge_tilt))
    h = Harness(cfg)
    tilt = {}
    for p in (1e-4, -1e-4, 0.1, -0.1):
        for target in (0.25, -0.25):
            if tilt:
                h.stop()
            h.set_target(target, 0.0)
            h.start()
            h.advance(100_000)
            tilt[p, target] = h.position(p, 0.0).tilt_zx

    def limit(distance_to_edge: float) -> float:  # [deg] the schedule's limit toward an edge that far away
        w = min(max(1.0 - distance_to_edge / zone, 0.0), 1.0)
        return cfg.tilt_limit * (1.0 - w * (1.0 - edge_tilt))

    for p in (1e-4, -1e-4, 0.1, -0.1):
        assert tilt[p, 0.25] == pytest.approx(limit(0.25 - p), abs=0.01), (p, tilt)  # toward +x
        assert tilt[p, -0.25] == pytest.approx(-limit(0.25 + p), abs=0.01), (p, tilt)  # toward -x
    assert abs(tilt[1e-4, 0.25] - tilt[-1e-4, 0.25]) < 0.01 and abs(tilt[1e-4, -0.25] - tilt[-1e-4, -0.25]) < 0.01
    assert abs(tilt[0.1, 0.25]) < abs(tilt[0.1, -0.25]) - 0.05  # off the centre the nearer edge limits more


def test_paper_gains_and_defaults_match():
    """The boot configuration: the paper's gains, the 0.5 m module and the 26.57 deg limit, no noise."""
    for kind in ("manhattan", "euclidean"):
        rng = np.random.default_rng(5 if kind == "manhattan" else 6)
        defaults = m.PID_DEFAULTS
        gains = {
            name: ref.Gains(*(f32(defaults[axis][k]) for k in ("kp", "ki", "kd", "integral_limit")))
            for axis, name in ((m.Axis.X, "x"), (m.Axis.Y, "y"), (m.Axis.RADIAL, "radial"))
        }
        cfg = RunConfig(kind, f32(26.565051), 0.0, 1, 500, 0, gains)
        h = Harness(cfg)
        drive(h, rng, steps=100)


@pytest.mark.parametrize("kind", ["manhattan", "euclidean"])
def test_target_change_gives_no_derivative_kick(kind):
    """With the object still, a new target changes only P (and I): a large kD adds nothing, in both."""
    gains = {name: ref.Gains(f32(20.0), 0.0, f32(1000.0), f32(10.0)) for name in ("x", "y", "radial")}
    cfg = RunConfig(kind, f32(26.5), 0.0, 1, 60000, 0, gains)
    h = Harness(cfg)
    h.set_target(0.1, -0.05)
    h.start()
    for _ in range(3):
        h.advance(100_000)
        h.position(0.02, 0.03)
    h.set_target(-0.2, 0.2)
    h.advance(100_000)
    tel = h.position(0.02, 0.03)
    e = (f32(-0.2) - f32(0.02), f32(0.2) - f32(0.03))
    if kind == "manhattan":
        assert tel.tilt_zx == pytest.approx(20.0 * e[0], abs=0.006)
        assert tel.tilt_zy == pytest.approx(20.0 * e[1], abs=0.006)
    else:
        d = math.hypot(*e)
        assert math.hypot(tel.tilt_zx, tel.tilt_zy) == pytest.approx(20.0 * d, abs=0.01)


def test_euclidean_direction_is_a_unit_vector_for_tiny_errors():
    gains = {name: ref.Gains(0.0, f32(100.0), 0.0, f32(26.0)) for name in ("x", "y", "radial")}
    h = Harness(RunConfig("euclidean", f32(26.5), 0.0, 1, 60000, 0, gains))
    h.set_target(0.0, 0.0)
    h.start()
    for i in range(12):  # wind the integral up to its 26 deg bound: theta = 26 deg once the error vanishes
        h.capture_us += 100_000
        h.link.position(m.ObjectPosition(frame=100 + i, capture_time=h.capture_us, x=-0.25, y=0.0))
    h.capture_us += 100_000
    tel = h.link.position(m.ObjectPosition(frame=200, capture_time=h.capture_us, x=-4.5e-23, y=0.0))
    # the full wound-up angle, along the (tiny) error's direction: neither lost to underflow nor grown past it
    assert math.hypot(tel.tilt_zx, tel.tilt_zy) == pytest.approx(26.0, abs=0.005), tel
    assert tel.tilt_zx > 0 and abs(tel.tilt_zy) < 1e-6, tel
