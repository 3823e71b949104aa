"""A controller's settings as one file: which controller, and the schema fields it changes from the firmware's boot values.

The tuner (mantaray sim tune) writes one; `mantaray rig --settings`, `mantaray sim run --settings` and
`mantaray sim heatmap --settings` read it, and a firmware takes it as the commands it becomes (Setup.commands). Every
key is a field of protocol/schema.toml, so the file says nothing the firmware does not check itself:

    controller = "scheduled"
    plant = "paper"         # optional: the simulated plant the values are for (sim commands refuse another)
    [configure]             # only the controller's own fields: tilt_limit, velocity_filter
    tilt_limit = 22.0
    [configure_schedule]    # any field of the controller's own settings messages
    edge_zone = 0.08
    [pid.x]                 # the PIDs the controller runs
    kp = 40.0

What each controller reads (its configure fields, its settings messages, its PIDs) is schema.toml's [controllers].
"""

from __future__ import annotations

import dataclasses
import math
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

from mantaray.protocol import messages as m
from mantaray.protocol import rig
from mantaray.protocol.codec import FieldRefused

from .session import controller_axes

# what any controller's settings may change of configure, and the messages of every controller's own settings
CONFIGURE_KEYS = tuple(dict.fromkeys(key for keys in m.CONTROLLER_CONFIGURE.values() for key in keys))
SETTINGS_MESSAGES = {cls.NAME: cls for cls in m.SETTINGS_MESSAGES}
PID_KEYS = tuple(spec.name for spec in m.ConfigurePid.FIELDS if spec.name != "axis")


PLANT_NAME = re.compile(r"[A-Za-z0-9_.-]+")  # a plant's name as sim/model/plant.toml's [plant.NAME] tables give it
TILT_SLACK_DEG = 1e-4  # [deg] the firmware's slack on the derived limit (float rounding)


def max_tilt_deg(module_x_m: float, module_y_m: float) -> float:
    """[deg] The steepest tilt configure takes for the module: atan(range / ((m + n) / 2))."""
    return math.degrees(math.atan(rig.default().actuator_range_m / ((module_x_m + module_y_m) / 2)))


class SettingsError(ValueError):
    """A settings file or value the schema (or the controller) does not allow; the message names the key."""


@dataclass(frozen=True)
class ControllerSettings:
    """controller and flat (key, value) pairs, kept sorted: "configure.tilt_limit", "configure_schedule.edge_zone",
    "pid.x.kp"; plant, when given, names the simulated plant (sim/model/plant.toml) the values were tuned for: the gains
    are the firmware's numbers, which a plant reading the paper's gains per radian needs 180/pi times larger."""

    controller: str = "manhattan"
    values: tuple[tuple[str, float], ...] = ()
    plant: str | None = None

    def __post_init__(self) -> None:
        if self.controller.upper() not in m.Controller.__members__:
            raise SettingsError(
                f"controller must be one of {', '.join(c.name.lower() for c in m.Controller)}, got {self.controller!r}"
            )
        object.__setattr__(self, "controller", self.controller.lower())
        if self.plant is not None and not PLANT_NAME.fullmatch(self.plant):
            raise SettingsError(f"plant must be a plant's name (letters, digits, _ . -), got {self.plant!r}")
        keys = [str(k) for k, _ in self.values]
        object.__setattr__(self, "values", tuple(sorted((str(k), float(v)) for k, v in self.values)))  # canonical
        if len(set(keys)) != len(keys):
            raise SettingsError(f"a key is given twice: {sorted(k for k in keys if keys.count(k) > 1)[0]}")
        axes = {a.name.lower() for a in controller_axes(self.controller)}
        configure_keys = m.CONTROLLER_CONFIGURE[m.Controller[self.controller.upper()]]
        sections = [cls.NAME for cls in m.CONTROLLER_SETTINGS[m.Controller[self.controller.upper()]]]
        for key in keys:
            section, _, name = key.rpartition(".")
            allowed = (
                (section == "configure" and name in configure_keys)
                or (section in sections and name in {s.name for s in SETTINGS_MESSAGES[section].FIELDS})
                or (section.startswith("pid.") and section[4:] in axes and name in PID_KEYS)
            )
            if not allowed:  # a key the controller would not read is a mistake, not a setting
                raise SettingsError(
                    f"{key!r} is no setting of the {self.controller} controller; its settings are "
                    f"configure.{{{','.join(configure_keys)}}}, "
                    + "".join(f"{name} fields, " for name in sections)
                    + f"pid.{{{','.join(sorted(axes))}}}.{{{','.join(PID_KEYS)}}}"
                )
        pids = [m.ConfigurePid(axis=axis, **fields) for axis, fields in self.gains({}).items()]
        for command in [*self.commands(), *pids]:  # every value within the schema's bounds, before a firmware sees it
            try:
                command.check()
            except FieldRefused as refused:
                raise SettingsError(
                    f"{self._key_of(command, refused.field)}: {refused.reason} (protocol/schema.toml)"
                ) from None
        try:
            configure = self.configure(m.Configure()).check()
        except FieldRefused as refused:
            raise SettingsError(f"configure.{refused.field}: {refused.reason} (protocol/schema.toml)") from None
        steepest = max_tilt_deg(configure.module_x, configure.module_y)
        if configure.tilt_limit > steepest + TILT_SLACK_DEG:
            raise SettingsError(
                f"configure.tilt_limit: {configure.tilt_limit:g} deg is steeper than the module allows "
                f"({steepest:.6f} deg = atan(range / ((m + n) / 2)), PROTOCOL.md section 5)"
            )

    def _key_of(self, command: m.Message, field: str) -> str:
        if isinstance(command, m.ConfigurePid):
            return f"pid.{command.axis.name.lower()}.{field}"
        return f"{command.NAME}.{field}"

    def get(self, key: str) -> float | None:
        return dict(self.values).get(key)

    def with_gains(self, gains: tuple[float, float, float, float]) -> ControllerSettings:
        """These settings with (kp, ki, kd, integral_limit), the firmware's numbers (configure_pid's), on every PID
        the controller runs: what --gains sets. SettingsError for a gain outside the schema's bounds, or one these
        settings give already (a key given twice)."""
        pids = [
            (f"pid.{axis.name.lower()}.{name}", value)
            for axis in controller_axes(self.controller)
            for name, value in zip(PID_KEYS, gains, strict=True)
        ]
        return dataclasses.replace(self, values=(*self.values, *pids))

    # ------------------------------------------------------------------------------- as commands
    def configure(self, base: m.Configure) -> m.Configure:
        """base with this controller and its configure fields."""
        fields = {name: self.get(f"configure.{name}") for name in CONFIGURE_KEYS}
        return dataclasses.replace(
            base, controller=m.Controller[self.controller.upper()], **{k: v for k, v in fields.items() if v is not None}
        )

    def gains(self, base: dict[m.Axis, dict]) -> dict[m.Axis, dict]:
        """base (axis -> configure_pid fields) with this controller's PID keys set over it."""
        out = {axis: dict(fields) for axis, fields in base.items()}
        for axis in controller_axes(self.controller):
            for name in PID_KEYS:
                value = self.get(f"pid.{axis.name.lower()}.{name}")
                if value is not None:
                    out.setdefault(axis, dict(m.PID_DEFAULTS[axis]))[name] = value
        return out

    def commands(self) -> list[m.Message]:
        """configure_schedule and configure_cascade with these values over their boot values (the PIDs: gains())."""
        return [
            cls(**{s.name: v for s in cls.FIELDS if (v := self.get(f"{name}.{s.name}")) is not None})
            for name, cls in SETTINGS_MESSAGES.items()
        ]

    # ------------------------------------------------------------------------------------- a file
    def dumps(self, comment: str = "") -> str:
        """The TOML the file holds (comment, if given, as its first lines)."""
        lines = [f"# {line}" for line in comment.splitlines()]
        lines.append(f'controller = "{self.controller}"')
        if self.plant is not None:
            lines.append(f'plant = "{self.plant}"')
        sections: dict[str, list[tuple[str, float]]] = {}
        for key, value in self.values:
            section, _, name = key.rpartition(".")
            sections.setdefault(section, []).append((name, value))
        for section, items in sections.items():
            lines += ["", f"[{section}]", *(f"{name} = {value!r}" for name, value in items)]
        return "\n".join(lines) + "\n"

    @classmethod
    def loads(cls, text: str, source: str = "settings") -> ControllerSettings:
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise SettingsError(f"{source}: not TOML ({exc})") from None
        controller = data.pop("controller", None)
        if not isinstance(controller, str):
            raise SettingsError(f'{source}: needs controller = "NAME"')
        plant = data.pop("plant", None)
        if plant is not None and not isinstance(plant, str):
            raise SettingsError(f"{source}: plant must be a plant's name (letters, digits, _ . -), got {plant!r}")
        values = []

        def walk(prefix: str, table: dict) -> None:
            for key, value in table.items():
                if isinstance(value, dict):
                    walk(f"{prefix}{key}.", value)
                elif isinstance(value, (int, float)) and not isinstance(value, bool):
                    values.append((f"{prefix}{key}", float(value)))
                else:
                    raise SettingsError(f"{source}: {prefix}{key} must be a number, got {value!r}")

        walk("", data)
        try:
            return cls(controller, tuple(values), plant)
        except SettingsError as exc:
            raise SettingsError(f"{source}: {exc}") from None

    @classmethod
    def load(cls, path: str | Path) -> ControllerSettings:
        try:
            text = Path(path).read_text()
        except OSError as exc:
            raise SettingsError(f"cannot read the settings {path}: {exc.strerror or exc}") from None
        except UnicodeDecodeError:
            raise SettingsError(f"{path}: not a settings file (not text)") from None
        return cls.loads(text, str(path))
