"""A plant: one point of the declared parameter space (sim/model/plant.toml), named or not, as the Rig, camera and readings it gives."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from mantaray.protocol import messages as m

from . import parameters as P
from .rig import Rig
from .tracking import Tracking

DEFAULT_PLANT = "polyester"  # the physically calibrated rig of sim/README.md
PAPER_GAINS = ("kp", "ki", "kd")  # the gains the paper gives of its PIDs (PAPER_AXES); the integral bound is in degrees
PID_MAX = {spec.name: spec.max for spec in m.ConfigurePid.FIELDS if spec.name != "axis"}  # the schema's bounds


def firmware_gain(axis: m.Axis, name: str, paper_value: float, gain_scale: float) -> float:
    """The unit rule, applied here alone: a gain of the paper's (kp, ki, kd of the x, y and radial PIDs) in the
    paper's units is gain_scale (Plant.gain_scale) times that for the firmware, clipped to the schema's bound;
    every other setting, and every gain a user gives (--gains, a settings file), is the firmware's number already."""
    if axis in m.PAPER_AXES and name in PAPER_GAINS:
        return min(paper_value * gain_scale, PID_MAX[name])
    return paper_value


def paper_gain(axis: m.Axis, name: str, firmware_value: float, gain_scale: float) -> float:
    """firmware_gain's inverse: a firmware's setting in the paper's units (a gain the bound clipped reads as its
    bound's)."""
    return firmware_value / gain_scale if axis in m.PAPER_AXES and name in PAPER_GAINS else firmware_value


def boot_gains(gain_scale: float) -> dict[m.Axis, dict]:
    """axis -> configure_pid fields: the firmware's boot gains (the paper's) read with gain_scale (firmware_gain)."""
    return {
        axis: {name: firmware_gain(axis, name, value, gain_scale) for name, value in fields.items()}
        for axis, fields in m.PID_DEFAULTS.items()
    }


def plant_for(settings, given: str | None) -> str:
    """The plant a command runs settings on: --plant (given), else the one the settings file was tuned for, else the
    default. A --plant other than the file's is refused (ValueError): the file's gains are that plant's reading."""
    if given is not None and settings.plant is not None and given != settings.plant:
        raise ValueError(
            f"the settings were tuned for the {settings.plant} plant, not {given}: their gains are the "
            f"firmware's numbers for that plant (drop --plant, or give --plant {settings.plant})"
        )
    if settings.plant is not None and settings.plant not in P.plant_names():
        raise ValueError(
            f"the settings were tuned for a plant {settings.plant!r} that sim/model/plant.toml does not "
            f"declare; the plants are: {', '.join(P.plant_names())}"
        )
    return given or settings.plant or DEFAULT_PLANT


@dataclass(frozen=True)
class Plant:
    """A named plant with values set over it; every value is checked against its declared range."""

    name: str = DEFAULT_PLANT
    overrides: tuple[tuple[str, float | str], ...] = ()  # (key, value) set over the named plant, in order
    values: dict[str, float | str] = field(init=False, compare=False, repr=False)

    def __post_init__(self) -> None:
        values = {key: p.value for key, p in P.parameters().items()}
        values.update(P.plant_values(self.name))
        for key, value in self.overrides:
            values[key] = P.lookup(key).check(value)
        object.__setattr__(self, "values", values)

    def set(self, mapping: dict[str, float | str]) -> Plant:
        """This plant with more values set (keys as in sim/model/plant.toml); refuses an undeclared key or a value out of range."""
        return Plant(self.name, self.overrides + tuple((k, P.lookup(k).check(v)) for k, v in mapping.items()))

    def rig(
        self, object_name: str = "sphere", *, resolution: int | None = None, timestep_s: float | None = None
    ) -> Rig:
        """The Rig of this plant carrying an object; resolution and timestep choose the physics' fidelity (not the plant)."""
        rig = Rig().with_object(object_name)
        for key, value in self.values.items():
            p = P.lookup(key)
            if p.section in ("tracking", "reading"):
                continue
            rig = _set_field(rig, p, value)
        if resolution is not None:
            rig = dataclasses.replace(rig, fabric=dataclasses.replace(rig.fabric, resolution=resolution))
        if timestep_s is not None:
            rig = dataclasses.replace(rig, solver=dataclasses.replace(rig.solver, timestep_s=timestep_s))
        return rig

    def tracking(self, **kwargs) -> Tracking:
        """The camera model (sim/model/tracking.py) of this plant; kwargs set the rest (noise, drops, vision) or override
        its rate and latency (a None keeps the plant's)."""
        given = {k: v for k, v in kwargs.items() if v is not None}
        return Tracking(
            **{"rate_hz": self.values["tracking.rate_hz"], "latency_s": self.values["tracking.latency_s"], **given}
        )

    @property
    def gain_scale(self) -> float:
        """Factor on the paper's kp, ki, kd for the firmware, which takes degrees: 1, or 180/pi if they are per radian."""
        return 180.0 / math.pi if self.values["reading.pid_unit"] == "rad" else 1.0

    @property
    def success_rule(self) -> str:
        """end (within eps at T) or reached (within eps at any frame, where the paper's loop stops)."""
        return self.values["reading.success_rule"]


def _set_field(rig: Rig, p: P.Parameter, value: float | str) -> Rig:
    """rig with the field a parameter names set to value (a tuple member through its index)."""
    part = getattr(rig, p.section)
    if p.index is None:
        new = value
    else:
        members = list(getattr(part, p.field))
        members[p.index] = value
        new = tuple(members)
    return dataclasses.replace(rig, **{p.section: dataclasses.replace(part, **{p.field: new})})


def parse_setting(text: str) -> tuple[str, float | str]:
    """KEY=VALUE as given on a command line (--set fabric.size_m=0.55), checked against the declared range."""
    key, sep, value = text.partition("=")
    if not sep:
        raise P.ParameterError(f"expected KEY=VALUE (e.g. fabric.size_m=0.55), got {text!r}")
    p = P.lookup(key.strip())
    return p.key, p.check(value.strip() if p.choices else value)
