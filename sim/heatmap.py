"""The paper's evaluation (Results, Fig. 2): success rate per cell of the workspace, trials in parallel, resumable.

The workspace (the module, m x n) is split into cells x cells squares. Each cell gets N trials; trial k
of cell c has its target uniform inside the cell and its start uniform over the whole workspace,
drawn from a generator seeded with (seed, c, k) alone, so a run is reproducible from its seed
whatever order or machine its trials run on. A trial succeeds if and only if the object ends within
epsilon of the target at the end of T without having fallen off (issue 4); whether it was within
epsilon at any frame before T (where the paper's algorithms stop) is recorded too.

Every finished trial is one line of the results file (JSON lines, after a header line holding the
protocol). Running the same protocol on the same file skips the trials already there, so an
interrupted run continues where it stopped and loses nothing. A run with more trials per cell, or more
cells, on the same file keeps the trials already there and adds the rest (a quick N = 3 map first,
topped up to the paper's N = 10 later).
"""
from __future__ import annotations

import dataclasses
import json
import os
import signal
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable, Iterator

import numpy as np

from mantaray.host.session import controller_axes
from mantaray.protocol import messages as m

from .bridge import Gains, TrialSpec
from .objects import OBJECTS
from .model import SimulationUnstable
from .plant import DEFAULT_PLANT, Plant
from .rig import Fabric, Rig

RESULTS_FORMAT = "mantaray-heatmap/1"
SUCCESS_REGION_AT = 0.9    # [-] cells with at least this success rate form the success region ...
FAILURE_REGION_AT = 0.1    # [-] ... at most this the failure region; those between are uncertain


class ExperimentMismatch(ValueError):
    """The results file was written by a different experiment: continuing it would mix the two."""


@dataclass(frozen=True)
class Experiment:
    """Everything that decides a heatmap's trials and how they run."""
    object_name: str = "sphere"
    controller: str = "manhattan"
    cells: int = 20                         # [-] per side: the paper's 20 x 20 cells of 2.5 cm
    trials_per_cell: int = 10               # [-] N (the paper: 10)
    tolerance_m: float = 0.02               # [m] epsilon
    duration_s: float = 10.0                # [s] T (the paper: 10 s)
    alpha_m: float = 0.0                    # [m] noise amplitude
    seed: int = 2026
    gains: tuple[float, float, float, float] | None = None   # (kp, ki, kd, integral limit); None: the paper's
    resolution: int = 11                    # [vertices per side] of the fabric; 11 at 2 ms is the fast mode that
    timestep_s: float = 0.002               # [s] keeps per-cell success of the 15 x 15, 1 ms reference (docs/results.md)
    only_cells: tuple[int, ...] | None = None   # run just these cell indices (samples, tests); None: all
    plant: str = DEFAULT_PLANT              # the named plant (sim/plant.toml) ...
    plant_set: tuple[tuple[str, float | str], ...] = ()   # ... with these values set over it
    stop_when_reached: bool = False         # end each trial at the first frame within epsilon (the paper's loop)

    def __post_init__(self) -> None:
        checks = [
            (self.object_name in OBJECTS, f"object must be one of {', '.join(OBJECTS)}, got {self.object_name!r}"),
            (1 <= self.cells <= 200, f"cells per side must be 1..200, got {self.cells}"),
            (1 <= self.trials_per_cell <= 1000, f"trials per cell must be 1..1000, got {self.trials_per_cell}"),
            (0 < self.duration_s <= 600, f"runtime T must be in (0, 600] s, got {self.duration_s}"),
            (self.seed >= 0, f"seed must be >= 0, got {self.seed}"),
            (0 < self.timestep_s <= 0.01, f"timestep must be in (0, 0.01] s, got {self.timestep_s}"),
            (self.gains is None or len(self.gains) == 4,
             f"gains must be four numbers (kp, ki, kd, integral limit), got {self.gains}"),
            (self.only_cells is None or all(0 <= c < self.cells ** 2 for c in self.only_cells),
             f"cell indices must be 0..{self.cells ** 2 - 1}"),
            (self.only_cells is None or len(set(self.only_cells)) == len(self.only_cells),
             f"cell indices must not repeat, got {self.only_cells}"),
        ]
        for ok, message in checks:
            if not ok:
                raise ValueError(message)
        Fabric(resolution=self.resolution)      # refuses an even or too small resolution
        self.plant_model()                       # refuses an unknown plant or a value outside its range
        trial_spec(self, Trial(0, 0, (0.0, 0.0), (0.0, 0.0), 1))   # the controller, tolerance, alpha, gains: schema's

    def plant_model(self) -> Plant:
        return Plant(self.plant, self.plant_set)

    def rig(self) -> Rig:
        """The simulated rig this protocol runs on."""
        return self.plant_model().rig(self.object_name, resolution=self.resolution, timestep_s=self.timestep_s)

    def cell_ids(self) -> list[int]:
        return list(self.only_cells) if self.only_cells is not None else list(range(self.cells ** 2))

    def to_json(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in dataclasses.asdict(self).items()}

    @classmethod
    def from_json(cls, data: dict) -> Experiment:
        fields = {k: (tuple(v) if isinstance(v, list) else v) for k, v in data.items()}
        fields["plant_set"] = tuple(tuple(kv) for kv in fields.get("plant_set", ()))
        return cls(**fields)


@dataclass(frozen=True)
class Trial:
    """One trial of the protocol: where it starts and what it aims at."""
    cell: int                     # cell index: ix + iy * cells (ix along x from -m/2, iy along y from -n/2)
    k: int                        # trial number within the cell
    start_m: tuple[float, float]
    target_m: tuple[float, float]
    seed: int                     # the trial's seed for the firmware's noise and the camera model

    @property
    def key(self) -> str:
        return f"{self.cell}:{self.k}"


def cell_bounds(protocol: Experiment, module_m: tuple[float, float], cell: int) -> tuple[float, float, float, float]:
    """(x_lo, x_hi, y_lo, y_hi) [m] of a cell in the fabric frame."""
    ix, iy = cell % protocol.cells, cell // protocol.cells
    wx, wy = module_m[0] / protocol.cells, module_m[1] / protocol.cells
    x0, y0 = -module_m[0] / 2, -module_m[1] / 2
    return x0 + ix * wx, x0 + (ix + 1) * wx, y0 + iy * wy, y0 + (iy + 1) * wy


def make_trial(protocol: Experiment, module_m: tuple[float, float], cell: int, k: int) -> Trial:
    """Trial k of a cell: target uniform in the cell, start uniform over the workspace, from (seed, cell, k) alone."""
    rng = np.random.default_rng([protocol.seed, cell, k])
    x_lo, x_hi, y_lo, y_hi = cell_bounds(protocol, module_m, cell)
    target = (float(rng.uniform(x_lo, x_hi)), float(rng.uniform(y_lo, y_hi)))
    hx, hy = module_m[0] / 2, module_m[1] / 2
    start = (float(rng.uniform(-hx, hx)), float(rng.uniform(-hy, hy)))
    return Trial(cell, k, start, target, int(rng.integers(1, 2 ** 31)))


def trials(protocol: Experiment) -> list[Trial]:
    """Every trial of the protocol, cell by cell."""
    f = protocol.rig().frame
    module = (f.size_x_m, f.size_y_m)
    return [make_trial(protocol, module, c, k) for c in protocol.cell_ids() for k in range(protocol.trials_per_cell)]


def trial_spec(protocol: Experiment, trial: Trial) -> TrialSpec:
    return TrialSpec(trial.start_m, trial.target_m, controller=protocol.controller, duration_s=protocol.duration_s,
                     alpha_m=protocol.alpha_m, tolerance_m=protocol.tolerance_m, seed=trial.seed,
                     gains=controller_gains(protocol.controller, protocol.gains, protocol.plant_model().gain_scale),
                     stop_when_reached=protocol.stop_when_reached)


def controller_gains(controller: str, gains: tuple[float, float, float, float] | None,
                     scale: float = 1.0) -> dict[str, Gains]:
    """The gains to configure per axis: the given ones, else the paper's; kp, ki, kd times scale (the plant's reading of
    the PID's unit: 180/pi when the paper's gains are per radian). Empty: the firmware's own defaults as they are."""
    if gains is None and scale == 1.0:
        return {}
    out = {}
    for axis in controller_axes(controller):
        kp, ki, kd, limit = gains if gains is not None else m.PID_DEFAULTS[axis].values()
        out[axis.name.lower()] = Gains(kp * scale, ki * scale, kd * scale, limit)
    return out


# ------------------------------------------------------------------------------------------- results file
@dataclass
class ResultsFile:
    """The JSON-lines results of one protocol: a header line, then one line per finished trial.

    A line that is not a valid trial record (a disk error, a hand edit) is kept out of the counts and named in
    `rejected`; continuing the run moves it to <file>.rejected, so nothing is lost, and its trial runs again. A last
    line cut off by an interruption is dropped quietly: its trial runs again too."""
    path: Path
    protocol: Experiment
    records: dict[str, dict] = field(default_factory=dict)   # trial key -> record
    rejected: list[tuple[int, str]] = field(default_factory=list)   # (line number from 1, why) of refused lines

    @classmethod
    def open(cls, path: str | Path, protocol: Experiment) -> ResultsFile:
        """Open for this protocol: create the file, or read what an earlier run of the same protocol left."""
        path = Path(path)
        results = cls(path, protocol)
        if not path.exists() or _cut_header(path.read_bytes()):   # new, or its header was cut off as it was written
            path.parent.mkdir(parents=True, exist_ok=True)
            _replace(path, json.dumps(_header(protocol)).encode() + b"\n")
            return results
        stored = _read(path)
        now = protocol.plant_model().values
        if stored.plant_values is not None and stored.plant_values != now:
            changed = sorted(k for k in now if stored.plant_values.get(k) != now[k])
            raise ExperimentMismatch(f"{path} was run on the plant {protocol.plant!r} when its values were others "
                                   f"({', '.join(changed)} differ in sim/plant.toml since); use another --out")
        if stored.protocol != protocol and not _extends(stored.protocol, protocol):
            changed = sorted(k for k, v in protocol.to_json().items() if stored.protocol.to_json().get(k) != v)
            raise ExperimentMismatch(f"{path} holds a run with other options ({', '.join(changed)} differ); "
                                   f"use another --out, the same options to continue it, or more trials or "
                                   f"cells to add to it")
        if stored.bad_lines:                    # kept aside, never lost
            with open(path.with_name(path.name + ".rejected"), "ab") as f:
                f.write(b"".join(line + b"\n" for line in stored.bad_lines))
        if stored.protocol != protocol or stored.bad_lines or stored.cut:
            # the header names the (possibly grown) run; only the good lines stay
            _replace(path, json.dumps(_header(protocol)).encode() + b"\n"
                     + b"".join(line + b"\n" for line in stored.good_lines))
        results.records, results.rejected = stored.records, stored.rejected
        return results

    @classmethod
    def load(cls, path: str | Path) -> ResultsFile:
        """Read a results file whatever its protocol (for figures and comparisons)."""
        stored = _read(Path(path))
        return cls(Path(path), stored.protocol, stored.records, stored.rejected)

    def append(self, record: dict) -> None:
        with open(self.path, "a") as f:
            f.write(json.dumps(record) + "\n")
        self.records[record["key"]] = record

    def missing(self) -> list[Trial]:
        return [t for t in trials(self.protocol) if t.key not in self.records]

    def warnings(self) -> list[str]:
        """One line per refused line of the file, for the user."""
        return [f"{self.path} line {line}: {why}; not counted (its trial runs again when the run continues, and "
                f"the line is kept in {self.path.name}.rejected)" for line, why in self.rejected]


def _cut_header(raw: bytes) -> bool:
    """Whether a file is all or the start of a results header and nothing more (a run interrupted as it began)."""
    prefix = b'{"format": "' + RESULTS_FORMAT.encode()
    return b"\n" not in raw and (raw.startswith(prefix) or prefix.startswith(raw))


def _replace(path: Path, content: bytes) -> None:
    """Write the whole file at once: an interruption leaves the old file or the new, never half of one."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(content)
    os.replace(tmp, path)


def _extends(stored: Experiment, wanted: Experiment) -> bool:
    """Whether wanted only adds trials to stored (more per cell, or more cells), so every stored trial is one of
    wanted's: trials are drawn from (seed, cell, k) alone."""
    same_otherwise = dataclasses.replace(stored, trials_per_cell=wanted.trials_per_cell,
                                         only_cells=wanted.only_cells) == wanted
    more_per_cell = wanted.trials_per_cell >= stored.trials_per_cell
    more_cells = wanted.only_cells is None or (stored.only_cells is not None
                                               and set(stored.only_cells) <= set(wanted.only_cells))
    return same_otherwise and more_per_cell and more_cells


def _header(protocol: Experiment) -> dict:
    """A results file's first line: the protocol, and the values its plant had (a named plant may be refitted)."""
    return {"format": RESULTS_FORMAT, "protocol": protocol.to_json(), "plant_values": protocol.plant_model().values}


RECORD_TYPES = {"key": str, "cell": int, "k": int, "success": bool, "reached": bool, "fell_off": bool,
                "target_m": list}   # what aggregation reads from a trial record, by type
TYPE_NAMES = {str: "a string", int: "a whole number", bool: "true or false", list: "a list"}


def record_problem(record, protocol: Experiment) -> str | None:
    """Why a parsed line is not a trial record of this protocol, or None when it is one."""
    if not isinstance(record, dict):
        return f"not a trial record (a JSON {type(record).__name__})"
    for name, kind in RECORD_TYPES.items():
        if name not in record:
            return f"no {name!r} field"
        value = record[name]
        if type(value) is not kind:   # exact: a bool is not a count, 7 is not a success
            return f"{name} must be {TYPE_NAMES[kind]}, got {value!r}"
    if record["cell"] not in set(protocol.cell_ids()) or not 0 <= record["k"] < protocol.trials_per_cell:
        return f"trial {record['cell']}:{record['k']} is not one of this run's"
    if record["key"] != f"{record['cell']}:{record['k']}":
        return f"key {record['key']!r} does not match cell {record['cell']}, trial {record['k']}"
    return None


@dataclass
class _Contents:
    """What a results file holds, line by line."""
    protocol: Experiment
    plant_values: dict | None
    records: dict[str, dict] = field(default_factory=dict)
    good_lines: list[bytes] = field(default_factory=list)
    bad_lines: list[bytes] = field(default_factory=list)
    rejected: list[tuple[int, str]] = field(default_factory=list)
    cut: bool = False            # the last line was cut off (an interruption mid-write)


def _read(path: Path) -> _Contents:
    raw = path.read_bytes()
    if _cut_header(raw):
        raise ValueError(f"{path} holds no complete header line (a run interrupted as it began); rerun the same "
                         f"heatmap command to start it afresh")
    lines = raw.split(b"\n")
    try:
        header = json.loads(lines[0])
    except json.JSONDecodeError:
        raise ValueError(f"{path} is not a heatmap results file (its first line is not JSON)") from None
    if not isinstance(header, dict) or header.get("format") != RESULTS_FORMAT:
        raise ValueError(f"{path} is not a heatmap results file ({RESULTS_FORMAT})")
    try:
        protocol = Experiment.from_json(header["protocol"])
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"{path}: its header's protocol is not valid ({exc})") from None
    out = _Contents(protocol, header.get("plant_values"), cut=lines[-1] != b"")
    for number, line in enumerate(lines[1:-1], start=2):   # the last element follows the final newline
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            problem = "not JSON"
        else:
            problem = record_problem(record, protocol)
            if problem is None and record["key"] in out.records:
                problem = f"repeats trial {record['key']}"
        if problem is None:
            out.records[record["key"]] = record
            out.good_lines.append(line)
        else:
            out.rejected.append((number, problem))
            out.bad_lines.append(line)
    return out


# ------------------------------------------------------------------------------------------- aggregation
@dataclass(frozen=True)
class Summary:
    """Per-cell rates and the paper's totals for one results file."""
    rates: np.ndarray            # [cells, cells] success rate per cell, [iy, ix]; NaN where no trial ran
    reach_rates: np.ndarray      # the same under the paper's stopping rule (within epsilon at any frame)
    fell_rates: np.ndarray       # share of trials that fell off
    trials_per_cell: np.ndarray  # [cells, cells] trials counted in each cell
    score: float                 # sum of per-cell success rates (the paper: 171.3 Manhattan, 108.2 Euclidean)
    reach_score: float
    region_cells: dict[str, int]  # success / uncertain / failure: cells in each region
    cell_area_m2: float

    @property
    def trials(self) -> int:
        """Trials counted, over all cells."""
        return int(self.trials_per_cell.sum())

    def region_area_m2(self, region: str) -> float:
        return self.region_cells[region] * self.cell_area_m2

    def to_json(self) -> dict:
        return {"trials": self.trials, "score": round(self.score, 2), "reach_score": round(self.reach_score, 2),
                "cells_run": int(np.isfinite(self.rates).sum()),
                "regions": {name: {"cells": n, "area_m2": round(self.region_area_m2(name), 5)}
                            for name, n in self.region_cells.items()},
                "thresholds": {"success_at": SUCCESS_REGION_AT, "failure_at": FAILURE_REGION_AT}}


def summarize(results: ResultsFile) -> Summary:
    p = results.protocol
    n = p.cells
    counts = np.zeros((3, n * n))                  # successes, reaches, falls
    totals = np.zeros(n * n)
    for r in results.records.values():
        totals[r["cell"]] += 1
        counts[:, r["cell"]] += (r["success"], r["reached"], r["fell_off"])
    with np.errstate(invalid="ignore", divide="ignore"):
        rates = np.where(totals > 0, counts / np.maximum(totals, 1), np.nan).reshape(3, n, n)
    done = np.isfinite(rates[0])
    regions = {"success": int((rates[0][done] >= SUCCESS_REGION_AT).sum()),
               "failure": int((rates[0][done] <= FAILURE_REGION_AT).sum())}
    regions["uncertain"] = int(done.sum()) - regions["success"] - regions["failure"]
    f = p.rig().frame
    return Summary(rates=rates[0], reach_rates=rates[1], fell_rates=rates[2],
                   trials_per_cell=totals.reshape(n, n).astype(int),
                   score=float(np.nansum(rates[0])), reach_score=float(np.nansum(rates[1])),
                   region_cells=regions, cell_area_m2=f.size_x_m * f.size_y_m / n ** 2)


# ------------------------------------------------------------------------------------------- running
def trial_record(trial: Trial, result) -> dict:
    """The results-file line of a finished trial (result: a bridge.TrialResult)."""
    return {"key": trial.key, "cell": trial.cell, "k": trial.k, "seed": trial.seed,
            "start_m": [round(v, 5) for v in trial.start_m], "target_m": [round(v, 5) for v in trial.target_m],
            "final_m": [round(float(v), 5) for v in result.final_xy_m], "final_error_m": round(result.final_error_m, 5),
            "success": bool(result.success), "reached": result.time_to_reach_s is not None,
            "time_to_reach_s": result.time_to_reach_s, "fell_off": bool(result.fell_off),
            "sim_time_s": round(result.sim_time_s, 3), "wall_time_s": round(result.wall_time_s, 3)}


def unplaceable_record(trial: Trial, why: str) -> dict:
    """A trial whose start is not over the fabric (only at the very corners): it counts as fallen off."""
    return {"key": trial.key, "cell": trial.cell, "k": trial.k, "seed": trial.seed,
            "start_m": list(trial.start_m), "target_m": list(trial.target_m), "final_m": [None, None],
            "final_error_m": None, "success": False, "reached": False, "time_to_reach_s": None,
            "fell_off": True, "sim_time_s": 0.0, "wall_time_s": 0.0, "unplaceable": why}


class TrialRunner:
    """Runs trials in this process: the firmware core in-process (no pty) and the MuJoCo model of the trial's rig.

    The runner keeps one link (the firmware runs on across trials, as a board does); it loads a model when a
    trial's rig differs from the last one's (the two controllers of one plant share it).
    """

    def __init__(self, protocol: Experiment | None = None) -> None:
        from mantaray.host.link import Link
        from mantaray.host.transport import InProcessTransport

        self.protocol = protocol
        self._link = Link(InProcessTransport(simulated_clock=True))
        self._rig_key: str | None = None
        self._bridge_now = None
        self._unstable: tuple[str, SimulationUnstable] | None = None   # the last rig that would not load

    def _bridge(self, protocol: Experiment):
        from .bridge import Bridge
        key = json.dumps([protocol.object_name, protocol.plant, protocol.plant_set, protocol.resolution,
                          protocol.timestep_s])
        if self._unstable is not None and self._unstable[0] == key:
            raise self._unstable[1]        # the same rig diverges the same way: do not load it again
        if key != self._rig_key:
            try:
                self._bridge_now = Bridge(self._link, protocol.rig(), protocol.plant_model().tracking())
            except SimulationUnstable as exc:
                self._unstable = (key, exc)
                raise
            self._rig_key = key
        return self._bridge_now

    def result(self, trial: Trial, protocol: Experiment | None = None):
        """The bridge.TrialResult of one trial of protocol (default: the runner's own)."""
        protocol = protocol or self.protocol
        bridge = self._bridge(protocol)
        try:
            return bridge.run(trial_spec(protocol, trial))
        except SimulationUnstable as exc:   # this rig diverges: its other trials are refused without running
            self._unstable = (self._rig_key, exc)
            raise

    def run(self, trial: Trial, protocol: Experiment | None = None) -> dict:
        """The record of one trial of protocol (default: the runner's own)."""
        try:
            result = self.result(trial, protocol)
        except ValueError as exc:        # model.fabric_height: the start is not over the fabric
            if "not over the fabric" not in str(exc):
                raise
            return unplaceable_record(trial, str(exc))
        return trial_record(trial, result)

    def call(self, fn: Callable, arg):
        """fn(self, arg): a job that needs this process's runner (a Ray actor's, or a pool worker's)."""
        return fn(self, arg)


_worker: TrialRunner | None = None


def _init_worker() -> None:
    global _worker
    signal.signal(signal.SIGINT, signal.SIG_IGN)   # Ctrl-C is the parent's to handle: no traceback per worker
    _worker = TrialRunner()


def _run_in_worker(job: tuple[dict, Trial]) -> dict:
    protocol_json, trial = job
    return _worker.run(trial, Experiment.from_json(protocol_json))


def _call_in_worker(job: tuple[Callable, object]) -> object:
    fn, arg = job
    return _worker.call(fn, arg)


class LocalPool:
    """Worker processes of this machine that run (protocol, trial) jobs; `jobs` = 1 runs them in this process."""

    def __init__(self, jobs: int) -> None:
        self.jobs = jobs
        self._pool = None
        self._runner = TrialRunner() if jobs == 1 else None

    def __enter__(self) -> LocalPool:
        if self.jobs > 1:
            import multiprocessing
            self._pool = multiprocessing.get_context("forkserver").Pool(self.jobs, initializer=_init_worker)
        return self

    def __exit__(self, *exc) -> None:
        if self._pool is not None:
            self._pool.terminate() if exc[0] is not None else self._pool.close()
            self._pool.join()

    def imap(self, jobs: list[tuple[Experiment, Trial]], ordered: bool = False) -> Iterator[dict]:
        """Records as the jobs finish (in any order), or in the jobs' order."""
        if self._pool is None:
            for protocol, trial in jobs:
                yield self._runner.run(trial, protocol)
            return
        mapper = self._pool.imap if ordered else self._pool.imap_unordered
        yield from mapper(_run_in_worker, [(p.to_json(), t) for p, t in jobs], chunksize=1)

    def map(self, jobs: list[tuple[Experiment, Trial]]) -> list[dict]:
        """The jobs' records, in the jobs' order."""
        return list(self.imap(jobs, ordered=True))

    def map_calls(self, fn: Callable, args: list) -> list:
        """[fn(runner, a) for a in args] on the workers, each with its process's TrialRunner (fn a module-level
        function), in order."""
        if self._pool is None:
            return [self._runner.call(fn, a) for a in args]
        return self._pool.map(_call_in_worker, [(fn, a) for a in args], chunksize=1)


class RayPool:
    """Ray actors (a cluster at address, or a local Ray instance) that run (protocol, trial) jobs."""

    def __init__(self, jobs: int | None, address: str | None) -> None:
        import ray
        from ray.util import ActorPool

        if not ray.is_initialized():
            ray.init(address=address, include_dashboard=False, logging_level="ERROR", log_to_driver=False)
        actors_n = jobs or max(1, int(ray.cluster_resources().get("CPU", 1)))
        actor = ray.remote(num_cpus=1)(TrialRunner)
        self._pool = ActorPool([actor.remote() for _ in range(actors_n)])

    def __enter__(self) -> RayPool:
        return self

    def __exit__(self, *exc) -> None:
        pass

    def imap(self, jobs: list[tuple[Experiment, Trial]], ordered: bool = False) -> Iterator[dict]:
        """Records as the jobs finish (in any order), or in the jobs' order."""
        mapper = self._pool.map if ordered else self._pool.map_unordered
        yield from mapper(lambda actor, job: actor.run.remote(job[1], job[0]), jobs)

    def map(self, jobs: list[tuple[Experiment, Trial]]) -> list[dict]:
        """The jobs' records, in the jobs' order."""
        return list(self.imap(jobs, ordered=True))

    def map_calls(self, fn: Callable, args: list) -> list:
        """[fn(runner, a) for a in args] on the actors (which hold every CPU they asked for), in order."""
        return list(self._pool.map(lambda actor, a: actor.call.remote(fn, a), args))


def run_local(protocol: Experiment, todo: list[Trial], jobs: int) -> Iterator[dict]:
    """Records of the trials as they finish, on `jobs` processes of this machine (1: this process)."""
    with LocalPool(jobs) as pool:
        yield from pool.imap([(protocol, t) for t in todo])


def run_ray(protocol: Experiment, todo: list[Trial], jobs: int | None, address: str | None) -> Iterator[dict]:
    """Records of the trials as they finish, on Ray actors (a cluster at address, or a local Ray instance)."""
    with RayPool(jobs, address) as pool:
        yield from pool.imap([(protocol, t) for t in todo])


def run(results: ResultsFile, records: Iterable[dict], progress: Callable[[dict], None] | None = None) -> None:
    """Append every record to the results file as it arrives (the file is the only state a resumption needs)."""
    for record in records:
        results.append(record)
        if progress is not None:
            progress(record)
