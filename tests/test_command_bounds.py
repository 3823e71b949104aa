"""Property: whatever the host sends (NaN, inf, huge, invalid settings), no actuator command leaves ±0.25 m."""

from __future__ import annotations

import ctypes
import dataclasses
import math
import struct

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from mantaray.host.link import CommandRefused, Link
from mantaray.host.transport import InProcessTransport
from mantaray.protocol import messages as m
from mantaray.protocol import rig
from mantaray.protocol.codec import FieldRefused

RANGE = rig.default().actuator_range_m  # [m] actuator travel (protocol/rig.toml)
SLACK = 1e-9  # [m] decoding raw * 1e-5 in float64
E = m.ErrorCode


def f32(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


def finite(x: float) -> bool:
    return math.isfinite(x)


# ------------------------------------------------------------------------------------- strategies
EXTREMES = [
    math.nan,
    math.inf,
    -math.inf,
    3.4028234663852886e38,
    -3.4028234663852886e38,
    1e30,
    -1e30,
    1e10,
    -1e10,
    1.401298464324817e-45,
    -1.401298464324817e-45,
    1e-30,
    0.0,
    -0.0,
    0.25,
    -0.25,
    f32(0.25000003),
    -f32(0.25000003),
    0.5,
    -0.5,
    4.5e-23,
    -4.5e-23,
]


def f32s(lo: float, hi: float) -> st.SearchStrategy[float]:
    """float32 values in [f32(lo), f32(hi)]: the bounds as the firmware's float literals see them."""
    return st.floats(f32(lo), f32(hi), width=32)


def wild_floats() -> st.SearchStrategy[float]:
    """Anything a float32 can hold, weighted towards the nasty values."""
    return st.one_of(st.sampled_from(EXTREMES), st.floats(width=32))


def positions() -> st.SearchStrategy[float]:
    return st.one_of(f32s(-0.6, 0.6), f32s(-0.6, 0.6), wild_floats())


def field_value(spec, valid: st.SearchStrategy) -> st.SearchStrategy:
    return st.one_of(valid, valid, valid, valid, wild_floats() if spec.fmt == "f" else st.integers(0, 0xFFFF))


@st.composite
def wild_configures(draw) -> m.Configure:
    """Each field valid most of the time, anything a float32 / integer can hold otherwise."""
    specs = {s.name: s for s in m.Configure.FIELDS}

    def f(name, lo, hi):
        return draw(field_value(specs[name], f32s(lo, hi)))

    return m.Configure(
        controller=draw(st.one_of(st.sampled_from(list(m.Controller)), st.integers(0, 255))),
        module_x=f("module_x", 0.1, 10.0),
        module_y=f("module_y", 0.1, 10.0),
        tilt_limit=f("tilt_limit", 0.1, 89.0),
        tolerance=f("tolerance", 0.001, 0.5),
        noise_amplitude=f("noise_amplitude", 0.0, 0.25),
        noise_seed=draw(st.integers(0, 2**32 - 1)),
        deadman=draw(st.one_of(st.integers(20, 60000), st.integers(0, 0xFFFF))),
        telemetry_period=draw(st.one_of(st.just(0), st.integers(5, 200), st.integers(0, 0xFFFF))),
        velocity_filter=f("velocity_filter", 0.0, 10.0),
    )


@st.composite
def valid_configures(draw) -> m.Configure:
    """Every field valid, the tilt limit anywhere up to (and a hair past) the module's geometric limit."""
    module_x, module_y = draw(f32s(0.1, 10.0)), draw(f32s(0.1, 10.0))
    steepest = math.degrees(math.atan(RANGE / ((module_x + module_y) / 2)))
    tilt = f32(max(0.1, steepest * draw(st.sampled_from([1.0, 1.0 + 1e-7, 0.999]) | st.floats(0.01, 1.0))))
    return m.Configure(
        controller=draw(st.sampled_from(list(m.Controller))),
        module_x=module_x,
        module_y=module_y,
        tilt_limit=tilt,
        tolerance=draw(f32s(0.001, 0.5)),
        noise_amplitude=draw(f32s(0.0, 0.25)),
        noise_seed=draw(st.integers(0, 2**32 - 1)),
        deadman=draw(st.integers(20, 60000)),
        telemetry_period=draw(st.sampled_from([0, 5, 100, 60000])),
        velocity_filter=draw(f32s(0.0, 10.0)),
    )


def configures() -> st.SearchStrategy[m.Configure]:
    return st.one_of(valid_configures(), wild_configures())


@st.composite
def configure_pids(draw) -> m.ConfigurePid:
    if draw(st.booleans()):  # all valid, the extremes included

        def gain(hi):
            return draw(st.one_of(f32s(0.0, hi), st.sampled_from([0.0, hi])))

        axis = draw(st.sampled_from(list(m.Axis)))
    else:

        def gain(hi):
            return draw(st.one_of(f32s(0.0, hi), f32s(0.0, hi), wild_floats()))

        axis = draw(st.one_of(st.sampled_from(list(m.Axis)), st.integers(0, 255)))
    return m.ConfigurePid(axis=axis, kp=gain(10000.0), ki=gain(10000.0), kd=gain(10000.0), integral_limit=gain(90.0))


@st.composite
def controller_settings(draw) -> m.Message:
    """configure_schedule or configure_cascade: each field within its bounds, its extremes included, or anything."""
    cls = draw(st.sampled_from([m.ConfigureSchedule, m.ConfigureCascade]))
    return cls(
        **{
            spec.name: draw(
                field_value(spec, st.one_of(f32s(spec.min, spec.max), st.sampled_from([spec.min, spec.max])))
            )
            for spec in cls.FIELDS
        }
    )


OPS = st.one_of(
    st.tuples(st.just("configure"), configures()),
    st.tuples(st.just("controller_settings"), controller_settings()),
    st.tuples(st.just("configure_pid"), configure_pids()),
    st.tuples(st.just("set_target"), st.tuples(positions(), positions())),
    st.tuples(st.just("start"), st.none()),
    st.tuples(st.just("stop"), st.none()),
    st.tuples(st.just("emergency_stop"), st.none()),
    st.tuples(
        st.just("jog"),
        st.tuples(st.one_of(st.integers(0, 3), st.integers(0, 255)), st.one_of(f32s(-0.25, 0.25), wild_floats())),
    ),
    st.tuples(st.just("clock"), st.integers(0, 120_000)),
    st.tuples(
        st.just("positions"),
        st.lists(st.tuples(positions(), positions(), st.booleans(), st.integers(1, 200_000)), min_size=1, max_size=12),
    ),
)


# ------------------------------------------------------------------------- the host's expectations
class Model:
    """Just enough of the supervisor to know which commands must be accepted and what each refusal says."""

    def __init__(self, capi) -> None:
        self.capi = capi
        self.config = m.Configure()  # boot defaults
        self.idle = True
        self.estop = False
        self.target: tuple[float, float] | None = None

    def inside(self, x: float, y: float, c: m.Configure) -> bool:
        return -0.5 * f32(c.module_x) <= x <= 0.5 * f32(c.module_x) and -0.5 * f32(c.module_y) <= y <= 0.5 * f32(
            c.module_y
        )

    def bounds(self, cls, msg) -> tuple[E, int] | None:
        """The schema's field-local checks as the host runs them before sending (Message.check): the firmware's
        generated validate() must refuse exactly these, with the same code and field."""
        try:
            msg.check()
        except FieldRefused as refused:
            return E[refused.code.upper()], [s.name for s in cls.FIELDS].index(refused.field)
        return None

    def configure(self, c: m.Configure) -> tuple[E, int] | None:
        if not self.idle:
            return E.BAD_STATE, m.NO_FIELD
        refusal = self.bounds(m.Configure, c)
        if refusal:
            return refusal
        limit = np.float32(self.capi.mr_max_tilt_deg(f32(c.module_x), f32(c.module_y), RANGE)) + np.float32(1e-4)
        if np.float32(c.tilt_limit) > limit:
            return E.OUT_OF_RANGE, 3
        if c.telemetry_period != 0 and c.telemetry_period < 5:
            return E.OUT_OF_RANGE, 8
        self.config = c
        if self.target is not None and not self.inside(*self.target, c):
            self.target = None
        return None

    def configure_pid(self, p: m.ConfigurePid) -> tuple[E, int] | None:
        if not self.idle:
            return E.BAD_STATE, m.NO_FIELD
        return self.bounds(m.ConfigurePid, p)

    def controller_settings(self, msg: m.Message) -> tuple[E, int] | None:
        if not self.idle:
            return E.BAD_STATE, m.NO_FIELD
        return self.bounds(type(msg), msg)

    def set_target(self, x: float, y: float) -> tuple[E, int] | None:
        x, y = f32(x), f32(y)
        if self.estop:
            return E.BAD_STATE, m.NO_FIELD
        if not finite(x):
            return E.NOT_FINITE, 0
        if not finite(y):
            return E.NOT_FINITE, 1
        if not self.inside(x, 0.0, self.config):
            return E.OUT_OF_RANGE, 0
        if not self.inside(0.0, y, self.config):
            return E.OUT_OF_RANGE, 1
        self.target = (x, y)
        return None

    def start(self) -> tuple[E, int] | None:
        if not self.idle:
            return E.BAD_STATE, m.NO_FIELD
        if self.target is None:
            return E.NO_TARGET, m.NO_FIELD
        self.idle = False
        return None

    def jog(self, actuator: int, position: float) -> tuple[E, int] | None:
        if not self.idle:
            return E.BAD_STATE, m.NO_FIELD
        if actuator > 3:
            return E.OUT_OF_RANGE, 0
        position = f32(position)
        if not finite(position):
            return E.NOT_FINITE, 1
        if abs(position) > RANGE:
            return E.OUT_OF_RANGE, 1
        return None


class Rig:
    """A freshly booted in-process firmware, its expected behaviour, and the bound checks."""

    def __init__(self, capi) -> None:
        self.telemetry: list[m.Telemetry] = []
        self.checked = 0
        self.link = Link(InProcessTransport(simulated_clock=True), on_message=self._collect)
        self.link.identify()
        self.model = Model(capi)
        self.frame = 0
        self.capture_us = 0
        self.clock_us = 0

    def _collect(self, msg) -> None:
        if isinstance(msg, m.Telemetry):
            self.telemetry.append(msg)

    def check_bounds(self) -> None:
        """Every telemetry received so far: commands and measured positions within the actuator range."""
        while self.link.receive() is not None:  # unsolicited telemetry still queued
            pass
        for msg in self.telemetry[self.checked :]:
            for value in msg.command + msg.measured:
                assert math.isfinite(value) and abs(value) <= RANGE + SLACK, msg
        self.checked = len(self.telemetry)

    def expect(self, msg, refusal: tuple[E, int] | None) -> None:
        try:
            self.link.command(msg, checked=False)  # the firmware's refusals are under test
        except CommandRefused as refused:
            assert refusal is not None, f"{msg} refused: {refused}"
            assert (refused.nack.code, refused.nack.field) == (refusal[0], refusal[1]), (msg, refused.nack)
        else:
            assert refusal is None, f"{msg} accepted; expected {refusal}"
        self.check_bounds()

    def position(self, x: float, y: float, visible: bool, gap_us: int) -> m.Telemetry | None:
        self.frame = (self.frame + 1) & 0xFFFF
        self.capture_us = (self.capture_us + gap_us) & 0xFFFFFFFF
        msg = m.ObjectPosition(
            frame=self.frame,
            capture_time=self.capture_us,
            x=x,
            y=y,
            flags=m.PositionFlags(0) if visible else m.PositionFlags.NOT_VISIBLE,
        )
        config, refusal = self.model.config, None
        if visible and not finite(f32(x)):
            refusal = (E.NOT_FINITE, 2)
        elif visible and not finite(f32(y)):
            refusal = (E.NOT_FINITE, 3)
        elif visible and abs(f32(x)) > f32(config.module_x):  # beyond the module by more than half of it
            refusal = (E.OUT_OF_RANGE, 2)
        elif visible and abs(f32(y)) > f32(config.module_y):
            refusal = (E.OUT_OF_RANGE, 3)
        try:
            tel = self.link.position(msg)
        except CommandRefused as refused:
            assert refusal is not None, (msg, refused.nack)
            assert (refused.nack.code, refused.nack.field) == refusal
            self.check_bounds()
            # refused whole: its frame counter and capture time were not taken, so they are still fresh
            self.capture_us = (self.capture_us - gap_us) & 0xFFFFFFFF
            self.frame = (self.frame - 1) & 0xFFFF
            return None
        assert refusal is None, f"{msg} accepted"
        self.check_bounds()
        return tel

    def run(self, op: str, arg) -> None:
        model = self.model
        if op == "configure":
            self.expect(arg, model.configure(arg))
        elif op == "configure_pid":
            self.expect(arg, model.configure_pid(arg))
        elif op == "controller_settings":
            self.expect(arg, model.controller_settings(arg))
        elif op == "set_target":
            self.expect(m.SetTarget(*arg), model.set_target(*arg))
        elif op == "start":
            self.expect(m.Start(), model.start())
        elif op == "stop":
            self.expect(m.Stop(), None)
            model.idle, model.estop = True, False
        elif op == "emergency_stop":
            self.expect(m.EmergencyStop(), None)
            model.idle, model.estop = False, True
        elif op == "jog":
            self.expect(m.Jog(*arg), model.jog(*arg))
        elif op == "clock":
            self.clock_us += arg
            self.expect(m.SimClock(now=self.clock_us), None)
        elif op == "positions":
            for x, y, visible, gap in arg:
                self.clock_us += min(gap, 5_000)
                self.expect(m.SimClock(now=self.clock_us), None)
                self.position(x, y, visible, gap)
        else:
            raise AssertionError(op)


# ------------------------------------------------------------------------------------------ tests
@settings(
    max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(ops=st.lists(OPS, min_size=1, max_size=25))
def test_random_command_sequences_keep_every_command_in_range(capi, ops):
    rig = Rig(capi)
    for op, arg in ops:
        rig.run(op, arg)
    rig.check_bounds()


@settings(
    max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(
    config=configures(),
    pids=st.lists(st.one_of(configure_pids(), controller_settings()), max_size=3),
    target=st.tuples(f32s(-0.05, 0.05), f32s(-0.05, 0.05)),
    frames=st.lists(
        st.tuples(positions(), positions(), st.booleans(), st.integers(1, 200_000)), min_size=1, max_size=40
    ),
)
def test_running_controller_keeps_every_command_in_range(capi, config, pids, target, frames):
    """Configured (or refused), started, then fed extreme positions: the control path itself is bounded."""
    rig = Rig(capi)
    rig.run("configure", config)
    for pid in pids:
        rig.run("configure_pid" if isinstance(pid, m.ConfigurePid) else "controller_settings", pid)
    rig.run("set_target", target)
    rig.run("start", None)
    rig.run("positions", frames)


EXTREME_PIDS = [m.ConfigurePid(axis=axis, kp=10000.0, ki=10000.0, kd=10000.0, integral_limit=90.0) for axis in m.Axis]


@pytest.mark.parametrize("controller", list(m.Controller), ids=lambda c: c.name.lower())
@pytest.mark.parametrize("module", [(0.1, 0.1), (0.5, 0.5), (10.0, 0.1), (10.0, 10.0)])
def test_extreme_gains_modules_and_noise(capi, controller, module):
    """Maximal gains and noise, the steepest tilt each module allows, and positions all over the float range."""
    rig = Rig(capi)
    tilt = float(np.float32(capi.mr_max_tilt_deg(*module, RANGE)))
    rig.run(
        "configure",
        m.Configure(
            controller=controller,
            module_x=module[0],
            module_y=module[1],
            tilt_limit=tilt,
            noise_amplitude=0.25,
            noise_seed=12345,
            deadman=60000,
            telemetry_period=5,
        ),
    )
    for pid in EXTREME_PIDS:
        rig.run("configure_pid", pid)
    rig.run("set_target", (module[0] / 2, -module[1] / 2))
    rig.run("start", None)
    rng = np.random.default_rng(42)
    values = EXTREMES + list(rng.uniform(-1, 1, 30))
    frames = [
        (float(x), float(y), True, int(g))
        for x, y, g in zip(
            rng.permutation(values * 2),
            rng.permutation(values * 2),
            rng.integers(1, 100_000, 2 * len(values)),
            strict=True,
        )
    ]
    rig.run("positions", frames)
    extremes = [t for t in rig.telemetry if t.state in (m.State.RUNNING, m.State.REACHED)]
    assert extremes and max(abs(c) for t in extremes for c in t.command) >= 0.2  # the limits were reached


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    sides=st.tuples(f32s(0.1, 10.0), f32s(0.1, 10.0)),
    fractions=st.tuples(st.floats(-1, 1), st.floats(-1, 1)),
    error=st.tuples(f32s(-10, 10), f32s(-10, 10)),
)
def test_raw_transform_stays_in_range_within_the_tilt_limit(capi, sides, fractions, error):
    """Within |theta| <= atan(range / ((m + n) / 2)) the unclamped plane keeps every corner in range, for
    both normals (Manhattan: tan(theta) (m + n) / 2 at worst; Euclidean: tan(theta) sqrt(m^2 + n^2) / 2)."""
    limit = capi.mr_max_tilt_deg(sides[0], sides[1], RANGE)
    zx, zy = (f32(f * limit) for f in fractions)
    out = (ctypes.c_float * 4)()
    capi.mr_manhattan_commands(zx, zy, sides[0], sides[1], out)
    assert max(abs(a) for a in out) <= RANGE * (1 + 1e-5), (zx, zy, sides, list(out))
    capi.mr_euclidean_commands(zx, error[0], error[1], sides[0], sides[1], out)
    assert max(abs(a) for a in out) <= RANGE * (1 + 1e-5), (zx, error, sides, list(out))


def test_raw_transform_leaves_the_range_beyond_the_tilt_limit(capi):
    """...and beyond it, it does not (and a 90 deg Manhattan tilt divides by ~0): the firmware's clamp is needed."""
    out = (ctypes.c_float * 4)()
    capi.mr_manhattan_commands(40.0, 40.0, 0.5, 0.5, out)
    assert max(abs(a) for a in out) > RANGE
    capi.mr_manhattan_commands(90.0, 0.0, 0.5, 0.5, out)
    assert max(abs(a) for a in out) > 1e5


@pytest.mark.parametrize("seed", range(6))
def test_non_finite_positions_are_refused_and_change_nothing(capi, seed):
    """A run with NaN/inf positions interleaved equals the run without them, telemetry for telemetry."""
    rng = np.random.default_rng(seed)
    bad_values = [math.nan, math.inf, -math.inf]
    valid = [
        (float(x), float(y), int(g))
        for x, y, g in zip(
            rng.uniform(-0.3, 0.3, 60), rng.uniform(-0.3, 0.3, 60), rng.integers(20_000, 120_000, 60), strict=True
        )
    ]

    def run(with_bad: bool) -> list[tuple]:
        rig = Rig(capi)
        rig.run(
            "configure",
            m.Configure(
                controller=m.Controller(seed % 2),
                noise_amplitude=0.05,
                noise_seed=seed,
                deadman=60000,
                telemetry_period=0,
            ),
        )
        rig.run("set_target", (0.1, -0.1))
        rig.run("start", None)
        seen = []
        for x, y, gap in valid:
            if with_bad and rng.random() < 0.4:
                bx = bad_values[rng.integers(3)] if rng.random() < 0.7 else x
                by = bad_values[rng.integers(3)] if bx == x else y
                assert rig.position(bx, by, True, gap) is None  # refused: not_finite
            tel = rig.position(x, y, True, gap)
            seen.append((tel.state, tel.position_frame, tel.tilt_zx, tel.tilt_zy, tel.command, tel.measured))
        return seen

    assert run(with_bad=True) == run(with_bad=False)


def _unchecked_spec(**fields):
    """A TrialSpec built without its own checks, to see what its commands would do to a firmware."""
    from dataclasses import fields as dc_fields

    from mantaray.sim.trial.bridge import TrialSpec

    spec = object.__new__(TrialSpec)
    for f in dc_fields(TrialSpec):
        object.__setattr__(
            spec,
            f.name,
            fields.get(f.name, f.default if f.default_factory is dataclasses.MISSING else f.default_factory()),
        )
    return spec


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    tolerance=st.one_of(f32s(0.001, 0.5), f32s(0.001, 0.5), f32s(0.0, 0.6), wild_floats()),
    alpha=st.one_of(f32s(0.0, 0.25), f32s(0.0, 0.25), f32s(-0.05, 0.3), wild_floats()),
    gains=st.one_of(
        st.none(),
        st.tuples(
            st.one_of(f32s(0.0, 10000.0), f32s(0.0, 12000.0), wild_floats()),
            f32s(0.0, 100.0),
            f32s(0.0, 100.0),
            st.one_of(f32s(0.0, 90.0), f32s(0.0, 95.0), wild_floats()),
        ),
    ),
    controller=st.sampled_from(list(m.Controller)),
)
def test_a_trial_spec_is_refused_exactly_when_the_firmware_would_refuse_its_commands(
    tolerance, alpha, gains, controller
):
    """The host checks a trial's settings against the schema before any firmware sees them (TrialSpec), and
    that check agrees with the firmware: what it lets through is accepted, what it refuses the firmware refuses."""
    from mantaray.host.controller_settings import PID_KEYS
    from mantaray.host.session import controller_axes
    from mantaray.sim.trial.bridge import TrialSpec

    name = controller.name.lower()
    axes = controller_axes(name) if gains is not None else ()
    fields = dict(start_m=(0.0, 0.0), target_m=(0.1, -0.1), controller=name, tolerance_m=tolerance, alpha_m=alpha)
    pids = tuple((f"pid.{a.name.lower()}.{k}", v) for a in axes for k, v in zip(PID_KEYS, gains or (), strict=True))
    try:
        TrialSpec(**fields, settings=pids)  # --gains, as every command carries them: settings keys
        refused_by_host = None
    except ValueError as exc:
        refused_by_host = exc
    link = Link(InProcessTransport(simulated_clock=True))
    link.identify()
    refused_by_firmware = []
    given = [m.ConfigurePid(a, *gains) for a in axes]  # what those keys become, unchecked
    for command in [*_unchecked_spec(**fields).setup().commands(), *given]:
        try:
            link.command(command, checked=False)
        except CommandRefused as refused:
            refused_by_firmware.append(refused)
    link.close()
    event("refused" if refused_by_host else "accepted")
    assert (refused_by_host is None) == (not refused_by_firmware), (refused_by_host, refused_by_firmware)
