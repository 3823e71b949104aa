"""The options several `mantaray sim` commands take alike (argparse parent parsers), each defined once, and the
argument types they parse with."""

from __future__ import annotations

import argparse
import math

from mantaray.arguments import number
from mantaray.host.cli_controller import add_controller_arguments, add_gains_argument
from mantaray.protocol import messages as m
from mantaray.protocol.codec import bounds_text

from ..model.objects import OBJECTS
from ..model.parameters import ParameterError, plant_names
from ..model.plant import DEFAULT_PLANT, parse_setting
from ..model.rig import DEFAULT_FIDELITY, FIDELITIES


def point(text: str) -> tuple[float, float]:
    """X,Y [m]: two finite numbers, comma or space between."""
    parts = text.replace(",", " ").split()
    try:
        x, y = (float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected two numbers X,Y in metres, got {text!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise argparse.ArgumentTypeError(f"coordinates must be finite, got {text!r}")
    return x, y


def cells(text: str) -> tuple[int, ...]:
    """Cell indices, comma or space between."""
    try:
        return tuple(int(v) for v in text.replace(",", " ").split())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected cell indices like 0,21,210, got {text!r}") from None


# ------------------------------------------------------------------------------------------- shared options
def options(*parents: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """A parent parser: options that several commands take alike."""
    return argparse.ArgumentParser(add_help=False, parents=list(parents))


def shared() -> dict[str, argparse.ArgumentParser]:
    """The options several commands share, each defined here once, by name."""
    jobs = options()
    jobs.add_argument("--jobs", type=number(1, integer=True), help="parallel workers (default: every core)")
    pool = options(jobs)
    pool.add_argument(
        "--executor",
        choices=["local", "ray"],
        default="local",
        help="local processes, or Ray actors (a local Ray instance, or --ray-address; without --jobs, a worker for "
        "every CPU of the cluster)",
    )
    pool.add_argument("--ray-address", help="address of a running Ray cluster (e.g. ray://head:10001)")
    fidelity = options()
    named = ", ".join(f"{name} {f.label}" for name, f in FIDELITIES.items())
    fidelity.add_argument(
        "--resolution",
        type=int,
        default=DEFAULT_FIDELITY.resolution,
        help=f"fabric vertices per side (odd); the named fidelities: {named}",
    )
    fidelity.add_argument("--timestep", type=float, default=DEFAULT_FIDELITY.timestep_s, help="physics step [s]")
    trial = options()
    trial.add_argument("--object", choices=sorted(OBJECTS), default="sphere", help="the paper's object (Table I)")
    trial.add_argument("--duration", type=float, default=10.0, help="runtime T [s] (paper: 10)")
    alpha = options()
    alpha.add_argument(
        "--alpha",
        type=float,
        default=0.0,
        help=f"noise amplitude α [m], {bounds_text(m.Configure, 'noise_amplitude')} (paper: 0.1 cube, 0.05 bunny)",
    )
    controller = options()
    add_controller_arguments(controller)
    add_gains_argument(controller)
    controller.add_argument(
        "--tolerance", type=float, default=0.02, help=f"ε [m], {bounds_text(m.Configure, 'tolerance')}"
    )
    controller.add_argument(
        "--plant",
        choices=plant_names(),
        help=f"the simulated plant (sim/model/plant.toml) (default: the one --settings was tuned for, else {DEFAULT_PLANT})",
    )
    report = options()
    report.add_argument(
        "--json", action="store_true", help="print the result as JSON on stdout (progress stays on stderr)"
    )
    return {
        "jobs": jobs,
        "pool": pool,
        "fidelity": fidelity,
        "trial": trial,
        "alpha": alpha,
        "closed_loop": controller,
        "json": report,
    }


def plant(default: str) -> argparse.ArgumentParser:
    """--plant with a default of its own: for a command that runs no --settings."""
    plant = options()
    plant.add_argument(
        "--plant", choices=plant_names(), default=default, help="the simulated plant (sim/model/plant.toml)"
    )
    return plant


def _setting(text: str) -> tuple[str, float | str]:
    try:
        return parse_setting(text)
    except ParameterError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def plant_set() -> argparse.ArgumentParser:
    """--set KEY=VALUE: a value of the plant fixed for this command, checked against its declared range."""
    fixed = options()
    fixed.add_argument(
        "--set",
        action="append",
        default=[],
        type=_setting,
        metavar="KEY=VALUE",
        help="fix a value of the plant (a key of sim/model/plant.toml, within its declared range); repeatable",
    )
    return fixed


def out(what: str, default: str | None = None) -> argparse.ArgumentParser:
    """--out: the folder a command writes into (its default named in `what` where it depends on other options)."""
    out = options()
    out.add_argument("--out", default=default, metavar="DIR", help=f"directory for {what}")
    return out


def sample(parser: argparse.ArgumentParser, cells_per_stratum: int, trials_per_cell: int) -> None:
    """--cells-per-stratum and --trials-per-cell: the stratified sample a search or a gate draws."""
    parser.add_argument(
        "--cells-per-stratum",
        type=number(1, integer=True),
        default=cells_per_stratum,
        help="cells drawn from each of centre, axes, diagonals, edges and corners",
    )
    parser.add_argument("--trials-per-cell", type=number(1, integer=True), default=trials_per_cell)
