"""The declared parameter space of the simulated rig (sim/model/plant.toml): every value the paper does not give, its range and source."""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass
from functools import cache
from pathlib import Path

TABLE = Path(__file__).resolve().parent / "plant.toml"
SCALES = ("linear", "log", "one_minus_log")
KINDS = ("physical", "structure", "reading")
LOG_FROM_ZERO_DECADES = 4  # a log-scaled range that starts at 0 is searched over [high / 1e4, high]
_KEY = re.compile(r"^(?P<section>[a-z_]+)\.(?P<field>[a-z_0-9]+)(\[(?P<index>\d)\])?$")


class ParameterError(ValueError):
    """A parameter name that is not declared, or a value outside its declared range."""


@dataclass(frozen=True)
class Parameter:
    """One declared quantity: the Rig field (or camera setting, or reading) it sets, with its range and source."""

    key: str  # section.field or section.field[i]
    value: float | str  # the default: the polyester plant
    low: float | None  # inclusive range; None for a parameter with choices
    high: float | None
    choices: tuple[str, ...]  # a string's choices (a reading's, or fabric.stretch's); () for a number
    scale: str
    unit: str
    kind: str
    search: bool
    source: str
    reason: str
    mujoco: float | None  # MuJoCo's own default, where it has one

    @property
    def section(self) -> str:
        return _KEY.match(self.key)["section"]

    @property
    def field(self) -> str:
        return _KEY.match(self.key)["field"]

    @property
    def index(self) -> int | None:
        index = _KEY.match(self.key)["index"]
        return None if index is None else int(index)

    def check(self, value) -> float | str:
        """value, if it lies in the declared range (or is one of the choices); else a ParameterError saying why."""
        if self.choices:
            if value not in self.choices:
                raise ParameterError(f"{self.key} must be one of {', '.join(self.choices)}, got {value!r}")
            return value
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise ParameterError(f"{self.key} must be a number [{self.unit}], got {value!r}") from None
        if not (math.isfinite(number) and self.low <= number <= self.high):
            raise ParameterError(
                f"{self.key} = {value!r} is outside its declared range "
                f"[{self.low:g}, {self.high:g}] {self.unit} (sim/model/plant.toml: {self.reason})"
            )
        return number

    def search_bounds(self) -> tuple[float, float]:
        """The interval the search samples, in the parameter's own unit (a log range from 0 starts higher)."""
        if self.scale == "log" and self.low <= 0:
            return self.high / 10**LOG_FROM_ZERO_DECADES, self.high
        return self.low, self.high


def _parameter(key: str, entry: dict) -> Parameter:
    if not _KEY.match(key):
        raise ValueError(f"{TABLE}: parameter key {key!r} is not section.field or section.field[i]")
    span = entry["range"]
    choices = tuple(span) if isinstance(entry["value"], str) else ()
    p = Parameter(
        key=key,
        value=entry["value"],
        low=None if choices else float(span[0]),
        high=None if choices else float(span[1]),
        choices=choices,
        scale=entry.get("scale", "linear"),
        unit=entry.get("unit", ""),
        kind=entry["kind"],
        search=bool(entry["search"]),
        source=entry["source"],
        reason=entry["reason"],
        mujoco=entry.get("mujoco"),
    )
    if p.scale not in SCALES or p.kind not in KINDS:
        raise ValueError(f"{TABLE}: {key}: scale must be one of {SCALES}, kind one of {KINDS}")
    p.check(p.value)
    if p.mujoco is not None:
        p.check(p.mujoco)
    return p


@cache
def _table() -> tuple[dict[str, Parameter], dict[str, dict[str, float | str]]]:
    data = tomllib.loads(TABLE.read_text())
    parameters = {key: _parameter(key, entry) for key, entry in data["parameter"].items()}
    plants = {}
    for name, values in data.get("plant", {}).items():
        plants[name] = {
            key: lookup(key, parameters).check(value) for key, value in values.items() if not key.startswith("_")
        }
    return parameters, plants


def lookup(key: str, parameters: dict[str, Parameter] | None = None) -> Parameter:
    parameters = parameters if parameters is not None else _table()[0]
    try:
        return parameters[key]
    except KeyError:
        raise ParameterError(
            f"{key!r} is not a declared parameter of the plant; the declared ones are: {', '.join(parameters)}"
        ) from None


def parameters() -> dict[str, Parameter]:
    """Every declared parameter, by key, in the table's order."""
    return dict(_table()[0])


def default(key: str) -> float | str:
    """The declared default of one parameter (what sim/model/rig.py's dataclasses start from)."""
    return lookup(key).value


def recorded_values(values: dict[str, float | str]) -> dict[str, float | str]:
    """A plant's values as a results file recorded them, with every parameter declared since at its value: a new
    parameter's value reproduces the model as it was before it (sim/model/plant.toml)."""
    return {key: p.value for key, p in parameters().items()} | values


def plant_values(name: str) -> dict[str, float | str]:
    """The values a named plant sets (over the defaults)."""
    plants = _table()[1]
    if name not in plants:
        raise ParameterError(f"no plant named {name!r}; the plants are: {', '.join(plants)}")
    return dict(plants[name])


def plant_names() -> list[str]:
    return list(_table()[1])


def markdown_table() -> str:
    """The table for sim/README.md (generated: the README never restates a value by hand). "value" is the default,
    the polyester plant's; each other named plant has a column with its own value where it sets one."""
    others = [name for name in plant_names() if plant_values(name)]
    rows = [
        "| parameter | value | "
        + "".join(f"`{name}` plant | " for name in others)
        + "range | MuJoCo's default | searched | kind | source; why this range |",
        "|---|---|" + "---|" * len(others) + "---|---|---|---|---|",
    ]
    for p in parameters().values():
        unit = "" if p.unit in ("", "-") else f" {p.unit}"

        def shown(value, p: Parameter = p, unit: str = unit) -> str:
            return value if p.choices else f"{value:g}{unit}"

        span = " / ".join(p.choices) if p.choices else f"{p.low:g} – {p.high:g}{unit}"
        mujoco = "" if p.mujoco is None else f"{p.mujoco:g}"
        named = "".join(f"{shown(plant_values(n)[p.key]) if p.key in plant_values(n) else ''} | " for n in others)
        rows.append(
            f"| `{p.key}` | {shown(p.value)} | {named}{span} | {mujoco} | {'yes' if p.search else 'no'} | "
            f"{p.kind} | {p.source}; {p.reason} |"
        )
    return "\n".join(rows)


README = Path(__file__).resolve().parents[1] / "README.md"
README_BEGIN = "<!-- parameters: begin (generated from sim/model/plant.toml by python3 -m mantaray.sim.model.parameters --write-readme) -->"
README_END = "<!-- parameters: end -->"


def write_readme() -> None:
    """Replace the generated table in sim/README.md with the table as declared now."""
    text = README.read_text()
    start, end = text.index(README_BEGIN) + len(README_BEGIN), text.index(README_END)
    README.write_text(text[:start] + "\n" + markdown_table() + "\n" + text[end:])


if __name__ == "__main__":
    import sys

    if sys.argv[1:] != ["--write-readme"]:
        sys.exit("usage: python3 -m mantaray.sim.model.parameters --write-readme")
    write_readme()
