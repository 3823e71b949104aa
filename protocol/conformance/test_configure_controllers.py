"""Conformance: configure_schedule and configure_cascade — each field takes effect, each refusal's code and field,
refusals change nothing, idle only; the default schedule steps as Manhattan."""

from __future__ import annotations

import dataclasses
import math

import pytest

from mantaray.protocol import messages as m
from mantaray.protocol.conformance.harness import DEFAULT_CONFIG, f32_above, f32_below

NAN, INF = math.nan, math.inf
OUT, NOT_FINITE = m.ErrorCode.OUT_OF_RANGE, m.ErrorCode.NOT_FINITE

# Settings that differ in every field, neither of them neutral, so that each field's change shows in the run below.
BASE = {
    m.ConfigureSchedule: m.ConfigureSchedule(
        edge_zone=0.1, edge_gain=0.5, edge_tilt=0.5, edge_brake=2.0, brake_speed=1.0
    ),
    m.ConfigureCascade: m.ConfigureCascade(position_gain=3.0, speed_limit=0.15),
}
ALT = {
    m.ConfigureSchedule: m.ConfigureSchedule(
        edge_zone=0.2, edge_gain=0.2, edge_tilt=0.1, edge_brake=6.0, brake_speed=0.2
    ),
    m.ConfigureCascade: m.ConfigureCascade(position_gain=8.0, speed_limit=0.05),
}
CONTROLLER = {m.ConfigureSchedule: m.Controller.SCHEDULED, m.ConfigureCascade: m.Controller.CASCADE}
KINDS = list(BASE)


STIFF_KP = 1000.0  # [deg/m] x and y for the run: near an edge a small error then asks for more than its tilt limit


def motion_fingerprint(dut, controller: m.Controller) -> tuple:
    """The tilts of a fixed run from idle with x and y at STIFF_KP: the object moves out toward the +x edge, past a
    target near it, and back, at 20 Hz, with a target that changes twice. Ends in idle with the boot gains."""
    dut.command(dataclasses.replace(DEFAULT_CONFIG, controller=controller))
    for axis in (m.Axis.X, m.Axis.Y):
        dut.configure_pid(axis, kp=STIFF_KP)
    dut.set_target(0.24, 0.0)
    dut.start()
    tilts = []
    for k in range(24):
        if k in (8, 16):
            dut.set_target(*((-0.1, 0.05) if k == 8 else (0.2, -0.2)))
        x = 0.25 * math.sin(k / 6.0)  # out to the edge and back, faster in the middle
        t = dut.position(x, 0.1 * math.cos(k / 4.0), dt=0.05)
        tilts.append((t.tilt_zx, t.tilt_zy))
    dut.stop()
    for axis in (m.Axis.X, m.Axis.Y):
        dut.configure_pid(axis)
    return tuple(tilts)


def _fingerprint(dut, kind) -> tuple:
    dut.command(BASE[kind])
    return motion_fingerprint(dut, CONTROLLER[kind])


def _bad_cases():
    out = []
    for kind in KINDS:
        for spec in kind.FIELDS:
            out += [
                (kind, spec.name, NAN, NOT_FINITE),
                (kind, spec.name, INF, NOT_FINITE),
                (kind, spec.name, f32_below(spec.min), OUT),
                (kind, spec.name, f32_above(spec.max), OUT),
            ]
    return out


BAD = _bad_cases()


@pytest.mark.parametrize("kind,name,value,code", BAD, ids=[f"{k.NAME}.{n}={v:.9g}" for k, n, v, _ in BAD])
def test_a_bad_field_is_refused_with_its_index_and_changes_nothing(dut, kind, name, value, code):
    reference = _fingerprint(dut, kind)
    dut.command(BASE[kind])
    dut.refuse(dataclasses.replace(ALT[kind], **{name: value}), code, [s.name for s in kind.FIELDS].index(name))
    assert motion_fingerprint(dut, CONTROLLER[kind]) == reference


@pytest.mark.parametrize("kind", KINDS, ids=lambda k: k.NAME)
def test_each_field_takes_effect(dut, kind):
    """The run above tells BASE from ALT field by field (so the refusal test would see a field that got applied)."""
    reference = _fingerprint(dut, kind)
    for spec in kind.FIELDS:
        dut.command(dataclasses.replace(BASE[kind], **{spec.name: getattr(ALT[kind], spec.name)}))
        assert motion_fingerprint(dut, CONTROLLER[kind]) != reference, f"{kind.NAME}.{spec.name} made no difference"
    assert _fingerprint(dut, kind) == reference


@pytest.mark.parametrize("kind", KINDS, ids=lambda k: k.NAME)
def test_the_bounds_are_accepted(dut, kind):
    for spec in kind.FIELDS:
        for value in (spec.min, spec.max):
            ack = dut.command(dataclasses.replace(BASE[kind], **{spec.name: value}))
            assert isinstance(ack, m.Ack) and ack.ref_id == kind.ID
    dut.command(kind())


@pytest.mark.parametrize("state", ["running", "reached", "fault", "estop"])
@pytest.mark.parametrize("kind", KINDS, ids=lambda k: k.NAME)
def test_outside_idle_it_is_bad_state_and_changes_nothing(dut, kind, state):
    reference = _fingerprint(dut, kind)
    dut.command(BASE[kind])
    if state == "fault":
        dut.configure(deadman=20)
    dut.enter(state)
    dut.refuse(ALT[kind], m.ErrorCode.BAD_STATE)
    dut.stop()
    assert motion_fingerprint(dut, CONTROLLER[kind]) == reference


def test_the_default_schedule_steps_as_manhattan(dut):
    dut.command(m.ConfigureSchedule())
    assert motion_fingerprint(dut, m.Controller.SCHEDULED) == motion_fingerprint(dut, m.Controller.MANHATTAN)


def test_the_cascade_and_the_schedule_leave_the_papers_controllers_alone(dut):
    paper = {c: motion_fingerprint(dut, c) for c in (m.Controller.MANHATTAN, m.Controller.EUCLIDEAN)}
    for kind in KINDS:
        dut.command(ALT[kind])
    assert {c: motion_fingerprint(dut, c) for c in paper} == paper
    for kind in KINDS:
        dut.command(kind())
