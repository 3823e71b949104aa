"""Conformance: configure — accepted bounds, each refusal's code and field, refusals change nothing, idle only."""

from __future__ import annotations

import dataclasses
import math

import pytest

from mantaray.host.link import CommandRefused
from mantaray.protocol import messages as m
from mantaray.protocol.conformance.harness import (
    ALT_CONFIG,
    BASE_CONFIG,
    CONFIGURE_FIELD,
    DEFAULT_CONFIG,
    TILT_TOL,
    base_config_fingerprint,
    config_fingerprint,
    f32,
    f32_above,
    f32_below,
)

NAN, INF = math.nan, math.inf
OUT, NOT_FINITE = m.ErrorCode.OUT_OF_RANGE, m.ErrorCode.NOT_FINITE


def max_tilt(module_x: float, module_y: float) -> float:
    """The schema's bound on tilt_limit [deg]: atan(range / ((m + n) / 2)), range 0.25 m."""
    return math.degrees(math.atan(0.25 / ((module_x + module_y) / 2)))


# Each case: fields changed from ALT_CONFIG (valid, and different from BASE_CONFIG in every field, so a
# partly applied refusal would show), the error and the field it must name.
BAD = [
    ({"controller": len(m.Controller)}, OUT, "controller"),
    ({"controller": 255}, OUT, "controller"),
    ({"module_x": NAN}, NOT_FINITE, "module_x"),
    ({"module_x": INF}, NOT_FINITE, "module_x"),
    ({"module_x": -INF}, NOT_FINITE, "module_x"),
    ({"module_x": f32_below(0.1)}, OUT, "module_x"),
    ({"module_x": f32_above(10.0)}, OUT, "module_x"),
    ({"module_x": -0.4}, OUT, "module_x"),
    ({"module_y": NAN}, NOT_FINITE, "module_y"),
    ({"module_y": -INF}, NOT_FINITE, "module_y"),
    ({"module_y": f32_below(0.1)}, OUT, "module_y"),
    ({"module_y": f32_above(10.0)}, OUT, "module_y"),
    ({"tilt_limit": NAN}, NOT_FINITE, "tilt_limit"),
    ({"tilt_limit": INF}, NOT_FINITE, "tilt_limit"),
    ({"tilt_limit": f32_below(0.1)}, OUT, "tilt_limit"),
    ({"tilt_limit": f32_above(89.0)}, OUT, "tilt_limit"),
    ({"tilt_limit": 0.0}, OUT, "tilt_limit"),
    # within [0.1, 89] but above atan(0.25 / ((m + n) / 2)) for the module in the same message
    ({"module_x": 0.5, "module_y": 0.5, "tilt_limit": 27.0}, OUT, "tilt_limit"),
    ({"module_x": 1.0, "module_y": 1.0, "tilt_limit": max_tilt(1.0, 1.0) + 0.01}, OUT, "tilt_limit"),
    ({"module_x": 10.0, "module_y": 10.0, "tilt_limit": 1.5}, OUT, "tilt_limit"),
    ({"module_x": 0.1, "module_y": 0.1, "tilt_limit": 89.0}, OUT, "tilt_limit"),
    ({"tolerance": NAN}, NOT_FINITE, "tolerance"),
    ({"tolerance": INF}, NOT_FINITE, "tolerance"),
    ({"tolerance": f32_below(0.001)}, OUT, "tolerance"),
    ({"tolerance": f32_above(0.5)}, OUT, "tolerance"),
    ({"noise_amplitude": NAN}, NOT_FINITE, "noise_amplitude"),
    ({"noise_amplitude": -INF}, NOT_FINITE, "noise_amplitude"),
    ({"noise_amplitude": f32_below(0.0)}, OUT, "noise_amplitude"),
    ({"noise_amplitude": f32_above(0.25)}, OUT, "noise_amplitude"),
    ({"deadman": 0}, OUT, "deadman"),
    ({"deadman": 19}, OUT, "deadman"),
    ({"deadman": 60001}, OUT, "deadman"),
    ({"deadman": 65535}, OUT, "deadman"),
    ({"telemetry_period": 1}, OUT, "telemetry_period"),
    ({"telemetry_period": 2}, OUT, "telemetry_period"),
    ({"telemetry_period": 3}, OUT, "telemetry_period"),
    ({"telemetry_period": 4}, OUT, "telemetry_period"),
    ({"telemetry_period": 60001}, OUT, "telemetry_period"),
    ({"telemetry_period": 65535}, OUT, "telemetry_period"),
    ({"velocity_filter": NAN}, NOT_FINITE, "velocity_filter"),
    ({"velocity_filter": f32_below(0.0)}, OUT, "velocity_filter"),
    ({"velocity_filter": f32_above(10.0)}, OUT, "velocity_filter"),
]


def _id(case) -> str:
    changes, code, _ = case
    return "-".join(f"{k}={v:.9g}" if isinstance(v, float) else f"{k}={v}" for k, v in changes.items())


@pytest.mark.parametrize("changes,code,field", BAD, ids=[_id(c) for c in BAD])
def test_bad_configure_is_refused_and_changes_nothing(dut, changes, code, field):
    reference = base_config_fingerprint(dut)
    dut.command(BASE_CONFIG)
    dut.refuse(dataclasses.replace(ALT_CONFIG, **changes), code, CONFIGURE_FIELD[field])
    assert config_fingerprint(dut) == reference


@pytest.mark.parametrize(
    "changes,bad",
    [
        ({"controller": 9, "deadman": 3}, {("controller", OUT), ("deadman", OUT)}),
        ({"tolerance": NAN, "telemetry_period": 2}, {("tolerance", NOT_FINITE), ("telemetry_period", OUT)}),
        (
            {"module_x": 20.0, "module_y": NAN, "noise_amplitude": 1.0},
            {("module_x", OUT), ("module_y", NOT_FINITE), ("noise_amplitude", OUT)},
        ),
    ],
)
def test_several_bad_fields_name_one_of_them(dut, changes, bad):
    reference = base_config_fingerprint(dut)
    dut.command(BASE_CONFIG)
    with pytest.raises(CommandRefused) as refused:
        dut.command(dataclasses.replace(ALT_CONFIG, **changes))
    nack = refused.value.nack
    assert (nack.field, nack.code) in {(CONFIGURE_FIELD[name], code) for name, code in bad}
    assert config_fingerprint(dut) == reference


ACCEPTED = [
    *({"controller": controller} for controller in m.Controller),
    {"module_x": f32(0.1)},
    {"module_x": 10.0, "tilt_limit": 1.0},
    {"module_y": f32(0.1)},
    {"module_y": 10.0, "tilt_limit": 1.0},
    {"module_x": 10.0, "module_y": 10.0, "tilt_limit": 1.4},
    {"tilt_limit": f32(0.1)},
    {"tilt_limit": 26.565051},
    {"module_x": 1.0, "module_y": 1.0, "tilt_limit": max_tilt(1.0, 1.0) - 0.001},
    {"module_x": 0.1, "module_y": 0.1, "tilt_limit": 68.0},
    {"tolerance": f32(0.001)},
    {"tolerance": 0.5},
    {"noise_amplitude": 0.0},
    {"noise_amplitude": 0.25},
    {"noise_seed": 0},
    {"noise_seed": 0xFFFFFFFF},
    {"deadman": 20},
    {"deadman": 60000},
    {"telemetry_period": 0},
    {"telemetry_period": 5},
    {"telemetry_period": 60000},
    {"velocity_filter": 0.0},
    {"velocity_filter": 10.0},
]


@pytest.mark.parametrize("changes", ACCEPTED, ids=[_id((c, None, None)) for c in ACCEPTED])
def test_boundary_values_are_accepted(dut, changes):
    ack = dut.configure(**changes)
    assert isinstance(ack, m.Ack) and ack.ref_id == m.Configure.ID


def test_each_field_of_an_accepted_configure_takes_effect(dut):
    """The reference run tells BASE_CONFIG from ALT_CONFIG field by field (so the refusal tests above
    would see any field of a refused configure that got applied)."""
    reference = base_config_fingerprint(dut)
    for field in m.Configure.FIELDS:
        changed = dataclasses.replace(BASE_CONFIG, **{field.name: getattr(ALT_CONFIG, field.name)})
        dut.command(changed)
        assert config_fingerprint(dut) != reference, f"configure.{field.name} made no difference"
    dut.command(BASE_CONFIG)
    assert config_fingerprint(dut) == reference


@pytest.mark.parametrize("state", ["running", "reached", "fault", "estop"])
def test_configure_outside_idle_is_bad_state_and_changes_nothing(dut, state):
    reference = base_config_fingerprint(dut)
    dut.command(BASE_CONFIG)
    if state == "fault":
        dut.command(dataclasses.replace(BASE_CONFIG, deadman=20))
    dut.enter(state)
    dut.refuse(ALT_CONFIG, m.ErrorCode.BAD_STATE)
    t = dut.probe()
    assert t.state == m.State[state.upper()]
    dut.stop()
    if state == "fault":
        dut.command(BASE_CONFIG)
    assert config_fingerprint(dut) == reference


def test_tilt_limit_saturates_the_tilts(dut):
    for axis in (m.Axis.X, m.Axis.Y):
        dut.configure_pid(axis, kp=1000.0)
    dut.configure(tilt_limit=12.5)
    dut.set_target(0.2, -0.2)
    dut.start()
    t = dut.position(0.0, 0.0)
    assert t.tilt_zx == pytest.approx(12.5, abs=TILT_TOL)
    assert t.tilt_zy == pytest.approx(-12.5, abs=TILT_TOL)


def test_refused_tilt_limit_keeps_the_old_saturation(dut):
    for axis in (m.Axis.X, m.Axis.Y):
        dut.configure_pid(axis, kp=1000.0)
    dut.configure(tilt_limit=12.5)
    dut.refuse(dataclasses.replace(DEFAULT_CONFIG, tilt_limit=20.0, deadman=5), OUT, CONFIGURE_FIELD["deadman"])
    dut.refuse(dataclasses.replace(DEFAULT_CONFIG, tilt_limit=27.0), OUT, CONFIGURE_FIELD["tilt_limit"])
    dut.set_target(0.2, 0.2)
    dut.start()
    t = dut.position(0.0, 0.0)
    assert (t.tilt_zx, t.tilt_zy) == (pytest.approx(12.5, abs=TILT_TOL), pytest.approx(12.5, abs=TILT_TOL))


@pytest.mark.parametrize("tolerance,state", [(0.02, m.State.RUNNING), (0.2, m.State.REACHED)])
def test_tolerance_decides_reached(dut, tolerance, state):
    dut.configure(tolerance=tolerance)
    dut.set_target(0.0, 0.0)
    dut.start()
    assert dut.position(0.1, 0.0).state == state


def test_refused_tolerance_keeps_the_old_one(dut):
    dut.refuse(
        dataclasses.replace(DEFAULT_CONFIG, tolerance=0.2, telemetry_period=3), OUT, CONFIGURE_FIELD["telemetry_period"]
    )
    dut.set_target(0.0, 0.0)
    dut.start()
    assert dut.position(0.1, 0.0).state == m.State.RUNNING
    assert dut.position(0.01, 0.0).state == m.State.REACHED


def test_refused_controller_keeps_manhattan(dut):
    """Manhattan saturates each tilt on its own: a diagonal error gives (L, L); Euclidean would give
    (L/sqrt 2, L/sqrt 2)."""
    limit = DEFAULT_CONFIG.tilt_limit
    for axis in m.Axis:
        dut.configure_pid(axis, kp=1000.0)
    dut.refuse(
        dataclasses.replace(DEFAULT_CONFIG, controller=m.Controller.EUCLIDEAN, module_x=NAN),
        NOT_FINITE,
        CONFIGURE_FIELD["module_x"],
    )
    cx, cy = dut.grid().module_centre(0)  # object and target in one module: no route between modules
    dut.set_target(cx + 0.2, cy + 0.2)
    dut.start()
    t = dut.position(cx - 0.2, cy - 0.2)
    assert t.tilt_zx == pytest.approx(limit, abs=TILT_TOL)
    assert t.tilt_zy == pytest.approx(limit, abs=TILT_TOL)
    dut.stop()
    dut.configure(controller=m.Controller.EUCLIDEAN)
    dut.start()
    t = dut.position(cx - 0.2, cy - 0.2)
    assert t.tilt_zx == pytest.approx(limit / math.sqrt(2), abs=TILT_TOL)
    assert t.tilt_zy == pytest.approx(limit / math.sqrt(2), abs=TILT_TOL)


def test_refused_module_size_keeps_the_target_bounds(dut):
    dut.refuse(
        dataclasses.replace(DEFAULT_CONFIG, module_x=0.4, module_y=0.4, tolerance=0.0),
        OUT,
        CONFIGURE_FIELD["tolerance"],
    )
    hx, hy = dut.half(0.5, 0.5)
    dut.set_target(hx, -hy)  # inside 0.5 m modules, outside 0.4 m ones
    dut.configure(module_x=0.4, module_y=0.4)
    dut.refuse(m.SetTarget(hx, 0.0), OUT, 0)
    dut.refuse(m.SetTarget(0.0, -hy), OUT, 1)


def test_configure_shrinking_the_module_drops_a_target_outside_it(dut):
    """Firmware behaviour beyond the schema's no_target doc ("start was sent before any set_target"):
    a target left outside a smaller module is forgotten, so start then answers no_target."""
    dut.set_target(*dut.half(0.5, 0.5))
    dut.configure(module_x=0.3, module_y=0.3)
    dut.refuse(m.Start(), m.ErrorCode.NO_TARGET)
    dut.set_target(*dut.half(0.3, 0.3))
    dut.start()
    assert dut.probe().state == m.State.RUNNING


def test_configure_keeps_a_target_still_inside_the_module(dut):
    dut.set_target(0.1, -0.1)
    dut.configure(module_x=0.3, module_y=0.3)
    dut.start()
    t = dut.position(0.0, 0.0)
    assert t.state == m.State.RUNNING
    assert t.tilt_zx > 0 > t.tilt_zy
