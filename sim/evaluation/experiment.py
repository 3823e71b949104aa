"""The paper's evaluation (Results, Fig. 2) as an experiment: its design, its cells and every trial's start and target.

The workspace (the module, m x n) is split into cells x cells squares. Each cell gets N trials; trial k
of cell c has its target uniform inside the cell and its start uniform over the whole workspace,
drawn from a generator seeded with (seed, c, k) alone, so a run is reproducible from its seed
whatever order or machine its trials run on. A trial succeeds if and only if the object ends within
epsilon of the target at the end of T without having fallen off (issue 4); whether it was within
epsilon at any frame before T (where the paper's algorithms stop) is recorded too. The trials run on
sim/evaluation/executors.py, their records go to sim/evaluation/results_file.py, and sim/evaluation/summary.py makes the map.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..model.objects import OBJECTS
from ..model.plant import DEFAULT_PLANT, Plant
from ..model.rig import DEFAULT_FIDELITY, Fabric, Rig, Solver
from ..trial.bridge import TrialSpec


class ExperimentMismatch(ValueError):
    """The results file was written by a different experiment: continuing it would mix the two."""


@dataclass(frozen=True)
class Experiment:
    """Everything that decides a heatmap's trials and how they run."""

    object_name: str = "sphere"
    controller: str = "manhattan"
    cells: int = 20  # [-] per side: the paper's 20 x 20 cells of 2.5 cm
    trials_per_cell: int = 10  # [-] N (the paper: 10)
    tolerance_m: float = 0.02  # [m] epsilon
    duration_s: float = 10.0  # [s] T (the paper: 10 s)
    alpha_m: float = 0.0  # [m] noise amplitude
    seed: int = 2026
    resolution: int = DEFAULT_FIDELITY.resolution  # [vertices per side] of the fabric (sim/model/rig.py, FIDELITIES)
    timestep_s: float = DEFAULT_FIDELITY.timestep_s  # [s] physics step
    only_cells: tuple[int, ...] | None = None  # run just these cell indices (samples, tests); None: all
    plant: str = DEFAULT_PLANT  # the named plant (sim/model/plant.toml) ...
    plant_set: tuple[tuple[str, float | str], ...] = ()  # ... with these values set over it
    stop_when_reached: bool = False  # end each trial at the first frame within epsilon (the paper's loop)
    settings: tuple[tuple[str, float], ...] = ()  # the controller's own settings (host/controller_settings.py)
    start_shift_m: float = 0.0  # [m] every start moved this far, each in its own direction drawn from
    # (seed, cell, k): the same trials, perturbed (the fidelity gate's floor)
    adaptive: bool = False  # each cell's trials stop once its region is decided (sim/evaluation/adaptive.py): at most N

    def __post_init__(self) -> None:
        checks = [
            (self.object_name in OBJECTS, f"object must be one of {', '.join(OBJECTS)}, got {self.object_name!r}"),
            (1 <= self.cells <= 200, f"cells per side must be 1..200, got {self.cells}"),
            (1 <= self.trials_per_cell <= 1000, f"trials per cell must be 1..1000, got {self.trials_per_cell}"),
            (0 < self.duration_s <= 600, f"runtime T must be in (0, 600] s, got {self.duration_s}"),
            (self.seed >= 0, f"seed must be >= 0, got {self.seed}"),
            (0 <= self.start_shift_m <= 0.01, f"start shift must be 0..0.01 m, got {self.start_shift_m}"),
            (
                self.only_cells is None or all(0 <= c < self.cells**2 for c in self.only_cells),
                f"cell indices must be 0..{self.cells**2 - 1}",
            ),
            (
                self.only_cells is None or len(set(self.only_cells)) == len(self.only_cells),
                f"cell indices must not repeat, got {self.only_cells}",
            ),
        ]
        if self.adaptive:
            from .adaptive import MIN_TRIALS

            checks.append(
                (
                    self.trials_per_cell > MIN_TRIALS,
                    f"an adaptive run needs more than {MIN_TRIALS} trials per cell (every cell runs "
                    f"{MIN_TRIALS}), got {self.trials_per_cell}",
                )
            )
        for ok, message in checks:
            if not ok:
                raise ValueError(message)
        Fabric(resolution=self.resolution)  # refuses an even or too small resolution
        Solver(timestep_s=self.timestep_s)  # ... and a step no fidelity takes
        self.plant_model()  # refuses an unknown plant or a value outside its range
        trial_spec(self, Trial(0, 0, (0.0, 0.0), (0.0, 0.0), 1))  # the controller, tolerance, alpha, settings: schema's

    def plant_model(self) -> Plant:
        return Plant(self.plant, self.plant_set)

    def rig(self) -> Rig:
        """The simulated rig this protocol runs on."""
        return self.plant_model().rig(self.object_name, resolution=self.resolution, timestep_s=self.timestep_s)

    def cell_ids(self) -> list[int]:
        return list(self.only_cells) if self.only_cells is not None else list(range(self.cells**2))

    def to_json(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in dataclasses.asdict(self).items()}

    @classmethod
    def from_json(cls, data: dict) -> Experiment:
        fields = {k: (tuple(v) if isinstance(v, list) else v) for k, v in data.items()}
        fields["plant_set"] = tuple(tuple(kv) for kv in fields.get("plant_set", ()))
        fields["settings"] = tuple(tuple(kv) for kv in fields.get("settings", ()))
        if fields.pop("gains", None) is not None:  # files written before --gains became settings keys
            raise ValueError(
                "its gains were given apart from the settings, in the paper's units (before 2026-12-07); its trials "
                "cannot be continued or compared with a run that gives them as settings: rerun it"
            )
        return cls(**fields)


@dataclass(frozen=True)
class Trial:
    """One trial of the protocol: where it starts and what it aims at."""

    cell: int  # cell index: ix + iy * cells (ix along x from -m/2, iy along y from -n/2)
    k: int  # trial number within the cell
    start_m: tuple[float, float]
    target_m: tuple[float, float]
    seed: int  # the trial's seed for the firmware's noise and the camera model

    @property
    def key(self) -> str:
        return f"{self.cell}:{self.k}"


def cell_bounds(experiment: Experiment, module_m: tuple[float, float], cell: int) -> tuple[float, float, float, float]:
    """(x_lo, x_hi, y_lo, y_hi) [m] of a cell in the fabric frame."""
    ix, iy = cell % experiment.cells, cell // experiment.cells
    wx, wy = module_m[0] / experiment.cells, module_m[1] / experiment.cells
    x0, y0 = -module_m[0] / 2, -module_m[1] / 2
    return x0 + ix * wx, x0 + (ix + 1) * wx, y0 + iy * wy, y0 + (iy + 1) * wy


def make_trial(experiment: Experiment, module_m: tuple[float, float], cell: int, k: int) -> Trial:
    """Trial k of a cell: target uniform in the cell, start uniform over the workspace, from (seed, cell, k) alone;
    the start moved by protocol.start_shift_m (kept on the workspace) in a direction drawn from them too."""
    rng = np.random.default_rng([experiment.seed, cell, k])
    x_lo, x_hi, y_lo, y_hi = cell_bounds(experiment, module_m, cell)
    target = (float(rng.uniform(x_lo, x_hi)), float(rng.uniform(y_lo, y_hi)))
    hx, hy = module_m[0] / 2, module_m[1] / 2
    start = (float(rng.uniform(-hx, hx)), float(rng.uniform(-hy, hy)))
    seed = int(rng.integers(1, 2**31))
    if experiment.start_shift_m:  # its own draw, so that every other number of the trial stays as it was
        angle = np.random.default_rng([experiment.seed, cell, k, 1]).uniform(0.0, 2 * np.pi)
        start = (
            float(np.clip(start[0] + experiment.start_shift_m * np.cos(angle), -hx, hx)),
            float(np.clip(start[1] + experiment.start_shift_m * np.sin(angle), -hy, hy)),
        )
    return Trial(cell, k, start, target, seed)


def trials(experiment: Experiment) -> list[Trial]:
    """Every trial of the protocol, cell by cell."""
    f = experiment.rig().module
    module = (f.size_x_m, f.size_y_m)
    return [
        make_trial(experiment, module, c, k) for c in experiment.cell_ids() for k in range(experiment.trials_per_cell)
    ]


def trial_spec(experiment: Experiment, trial: Trial) -> TrialSpec:
    return TrialSpec(
        trial.start_m,
        trial.target_m,
        controller=experiment.controller,
        duration_s=experiment.duration_s,
        alpha_m=experiment.alpha_m,
        tolerance_m=experiment.tolerance_m,
        seed=trial.seed,
        gain_scale=experiment.plant_model().gain_scale,
        stop_when_reached=experiment.stop_when_reached,
        settings=experiment.settings,
    )
