"""The declared parameter space (sim/model/plant.toml) and plants: ranges honoured, defaults in one place, the README in step."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mantaray.paths import REPO
from mantaray.protocol import messages as m
from mantaray.sim.evaluation.experiment import Experiment, trial_spec, trials
from mantaray.sim.model import parameters as P
from mantaray.sim.model.plant import Plant, boot_gains, parse_setting
from mantaray.sim.model.rig import Rig

PHYSICAL = [p for p in P.parameters().values() if p.section not in ("tracking", "reading")]


def _rig_value(rig: Rig, p: P.Parameter):
    value = getattr(getattr(rig, p.section), p.field)
    return value if p.index is None else value[p.index]


def test_every_default_and_mujoco_default_lies_in_its_declared_range():
    for p in P.parameters().values():
        assert p.check(p.value) == p.value
        if p.mujoco is not None:
            p.check(p.mujoco)
        assert p.source and p.reason and p.kind in P.KINDS


def test_the_rig_takes_its_defaults_from_the_table():
    rig = Rig()
    for p in PHYSICAL:
        assert _rig_value(rig, p) == p.value, p.key


@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_a_plant_sets_any_value_within_range_on_the_field_it_names(data):
    p = data.draw(st.sampled_from(PHYSICAL))
    value = data.draw(st.sampled_from(p.choices) if p.choices else st.floats(p.low, p.high, allow_nan=False))
    rig = Plant().set({p.key: value}).rig()
    assert _rig_value(rig, p) == (value if p.choices else pytest.approx(value))


@pytest.mark.parametrize(
    "key, value, needle",
    [
        ("fabric.size_m", 0.7, r"outside its declared range \[0.5, 0.6\] m"),
        ("contact.rolling_damping_per_s", -1, "outside its declared range"),
        ("fabric.mass_kg", math.nan, "outside its declared range"),
        ("fabric.mass_kg", "heavy", "must be a number"),
        ("reading.pid_unit", "grad", "must be one of deg, rad"),
        ("fabric.size", 0.5, "is not a declared parameter"),
    ],
)
def test_a_value_outside_its_range_or_an_undeclared_key_is_refused(key, value, needle):
    with pytest.raises(P.ParameterError, match=needle):
        Plant().set({key: value})


def test_a_command_line_setting_is_parsed_and_checked():
    assert parse_setting("fabric.size_m=0.55") == ("fabric.size_m", 0.55)
    assert parse_setting("reading.success_rule=reached") == ("reading.success_rule", "reached")
    with pytest.raises(P.ParameterError, match="KEY=VALUE"):
        parse_setting("fabric.size_m")
    with pytest.raises(P.ParameterError, match="outside"):
        parse_setting("fabric.size_m=2")


def test_an_unknown_plant_is_refused_and_every_named_plant_is_valid():
    with pytest.raises(P.ParameterError, match="no plant named"):
        Plant("teflon")
    for name in P.plant_names():
        Plant(name).rig()


def test_a_protocol_refuses_an_out_of_range_plant_value():
    with pytest.raises(P.ParameterError, match="outside"):
        Experiment(plant_set=(("fabric.size_m", 0.3),))


def test_the_readme_table_is_generated_from_the_declared_table():
    readme = (REPO / "sim" / "README.md").read_text()
    block = re.search(r"<!-- parameters: begin.*?-->\n(.*?)\n<!-- parameters: end -->", readme, re.S)
    assert block, "sim/README.md has no generated parameter table"
    assert block.group(1).strip() == P.markdown_table().strip(), (
        "sim/README.md's parameter table is stale: python3 -m mantaray.sim.model.parameters --write-readme"
    )


def test_the_radian_reading_scales_the_papers_boot_gains_and_nothing_else():
    scale = Plant().set({"reading.pid_unit": "rad"}).gain_scale
    boot, paper = boot_gains(scale), m.PID_DEFAULTS
    assert boot[m.Axis.X]["kp"] == pytest.approx(paper[m.Axis.X]["kp"] * 180 / math.pi)
    assert boot[m.Axis.Y]["kd"] == pytest.approx(paper[m.Axis.Y]["kd"] * 180 / math.pi)
    assert boot[m.Axis.X]["integral_limit"] == paper[m.Axis.X]["integral_limit"]
    assert boot[m.Axis.VX] == paper[m.Axis.VX]  # the cascade's velocity PIDs are no gains of the paper
    assert boot_gains(1.0) == paper  # degrees: the firmware's own boot gains
    experiment = Experiment(
        cells=2, trials_per_cell=1, plant_set=(("reading.pid_unit", "rad"),), controller="euclidean"
    )
    gains = trial_spec(experiment, trials(experiment)[0]).setup().gains
    assert gains[m.Axis.RADIAL]["ki"] == pytest.approx(paper[m.Axis.RADIAL]["ki"] * 180 / math.pi)


def test_a_users_gains_are_the_firmwares_numbers_on_every_plant():
    """--gains (pid.AXIS.NAME settings) reach the firmware as given, whatever the plant's reading; the PIDs they
    leave out keep the plant's reading of the paper's."""
    given = (("pid.radial.kp", 50.0),)
    for reading in ("deg", "rad"):
        experiment = Experiment(
            cells=2,
            trials_per_cell=1,
            controller="euclidean",
            plant_set=(("reading.pid_unit", reading),),
            settings=given,
        )
        gains = trial_spec(experiment, trials(experiment)[0]).setup().gains
        scale = 180 / math.pi if reading == "rad" else 1.0
        assert gains[m.Axis.RADIAL]["kp"] == 50.0
        assert gains[m.Axis.RADIAL]["kd"] == pytest.approx(m.PID_DEFAULTS[m.Axis.RADIAL]["kd"] * scale)


def test_the_corner_clamp_holds_its_edge_vertices_at_the_carriage():
    from mantaray.sim.model import mjcf as J
    from mantaray.sim.model import model as M

    plant = Plant().set({"fabric.corner_clamp_m": 0.08})
    rig = plant.rig(resolution=11, timestep_s=0.002)
    model, data = M.load(rig)
    for i in range(4):
        held = J.clamped_vertices(rig, i)
        assert len(held) == 2 * int(0.08 // rig.fabric.spacing_m)
        for vertex, dx, dy in held:
            offset = data.body(f"{J.FABRIC}_{vertex}").xpos - data.body(f"carriage{i}").xpos
            assert np.allclose(offset[:2], (dx, dy), atol=2e-3) and abs(offset[2]) < 2e-3
