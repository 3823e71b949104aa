"""The results file of an experiment: a header line holding the experiment, then one JSON line per finished trial.

Running the same experiment on the same file skips the trials already there, so an interrupted run continues
where it stopped and loses nothing. A run with more trials per cell, or more cells, on the same file keeps the
trials already there and adds the rest (a quick N = 3 map first, topped up to the paper's N = 10 later). One
process at a time continues a file: a second run on it would do the same trials again and write each line twice.
"""

from __future__ import annotations

import atexit
import dataclasses
import fcntl
import gzip
import json
import os
import shlex
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

from ..model import parameters as P
from ..model.mjcf import model_identity
from .experiment import Experiment, ExperimentMismatch, Trial, trials

RESULTS_FORMAT = "mantaray-heatmap/1"


class ResultsFileBusy(Exception):
    """Another process is continuing the same results file; the message names it."""


_HELD: dict[Path, tuple[Path, IO[str]]] = {}  # results file (resolved) -> its lock file, path and open, held here


def _lock(path: Path) -> None:
    """Hold the lock of path (the file <name>.lock beside it) for the rest of this process, or raise ResultsFileBusy
    naming the process that holds it. The lock is flock's: the kernel drops it when its holder exits, however it
    ends, so a killed run blocks no later one. A process that opens the same file again holds it already. The lock
    is a file of its own because continuing a run may replace the results file (write_whole); the process removes it
    as it exits (_release), and a lock taken on a file removed meanwhile is taken again on the one there now."""
    key = path.resolve()
    if key in _HELD:
        return
    lock_path = path.absolute().with_name(path.name + ".lock")  # absolute: removed at exit, from any folder
    while True:
        lock = os.fdopen(os.open(lock_path, os.O_RDWR | os.O_CREAT, 0o644), "r+")
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = lock.read().strip() or "a process that has not written its PID yet"
            lock.close()
            raise ResultsFileBusy(
                f"{path} is being continued by another run ({holder}); wait for it to end or stop "
                f"it: two runs on one file would do the same trials twice"
            ) from None
        if _same_file(lock, lock_path):
            break
        lock.close()
    lock.truncate()
    lock.write(f"PID {os.getpid()}: {shlex.join(sys.argv)}\n")
    lock.flush()
    if not _HELD:
        atexit.register(_release, os.getpid())
    _HELD[key] = (lock_path, lock)


def _same_file(lock: IO[str], lock_path: Path) -> bool:
    """Whether the open lock file is still the one at lock_path (its holder did not remove it before we locked it)."""
    try:
        return os.path.samestat(os.fstat(lock.fileno()), os.stat(lock_path))
    except FileNotFoundError:
        return False


def _release(owner_pid: int) -> None:
    """At exit: remove each lock file while still holding it, then let it go (in the process that took the locks,
    not in a child forked from it). A run killed outright leaves its file behind, unlocked: the next run takes it."""
    if os.getpid() != owner_pid:
        return
    for lock_path, lock in _HELD.values():
        lock_path.unlink(missing_ok=True)
        lock.close()


@dataclass
class ResultsFile:
    """The JSON-lines results of one protocol: a header line, then one line per finished trial.

    A line that is not a valid trial record (a disk error, a hand edit) is kept out of the counts and named in
    `rejected`; continuing the run moves it to <file>.rejected, so nothing is lost, and its trial runs again. A last
    line cut off by an interruption is dropped quietly: its trial runs again too."""

    path: Path
    experiment: Experiment
    records: dict[str, dict] = field(default_factory=dict)  # trial key -> record
    rejected: list[tuple[int, str]] = field(default_factory=list)  # (line number from 1, why) of refused lines
    model: dict | None = None  # the model_identity() it ran on (None: written before files recorded it)
    plant_values: dict | None = None  # the plant's values it ran with (None: written before files recorded them)

    @classmethod
    def open(cls, path: str | Path, experiment: Experiment) -> ResultsFile:
        """Open for this protocol: create the file, or read what an earlier run of the same protocol left. The
        process holds the file from here on (ResultsFileBusy when another one does)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        _lock(path)
        results = cls(
            path, experiment, model=model_identity(experiment.rig()), plant_values=experiment.plant_model().values
        )
        if not path.exists() or _cut_header(path.read_bytes()):  # new, or its header was cut off as it was written
            write_whole(path, json.dumps(_header(results)).encode() + b"\n")
            return results
        with open(path, "rb") as f:
            gzipped = f.read(len(GZIP_MAGIC)) == GZIP_MAGIC
        if gzipped:
            raise ValueError(
                f"{path} is gzipped: it opens for figures and comparisons as it is; to continue its run, "
                f"gunzip it first (or start from its uncompressed copy)"
            )
        stored = _read(path)
        _refuse_another_run(path, stored, results)
        if stored.bad_lines:  # kept aside, never lost
            with open(path.with_name(path.name + ".rejected"), "ab") as f:
                f.write(b"".join(line + b"\n" for line in stored.bad_lines))
        if stored.experiment != experiment or stored.bad_lines or stored.cut:
            # the header names the (possibly grown) run; only the good lines stay
            write_whole(
                path,
                json.dumps(_header(results)).encode() + b"\n" + b"".join(line + b"\n" for line in stored.good_lines),
            )
        results.records, results.rejected = stored.records, stored.rejected
        return results

    @classmethod
    def read(cls, path: str | Path, experiment: Experiment) -> ResultsFile:
        """Read a run of this protocol as it stands, without holding or changing it (another process may be adding
        to it: a last line cut off as it is written is left out); refused as open() refuses a run of other options,
        plant values or model."""
        path = Path(path)
        results = cls(
            path, experiment, model=model_identity(experiment.rig()), plant_values=experiment.plant_model().values
        )
        stored = _read(path)
        _refuse_another_run(path, stored, results)
        results.records, results.rejected = stored.records, stored.rejected
        return results

    @classmethod
    def load(cls, path: str | Path) -> ResultsFile:
        """Read a results file whatever its protocol (for figures and comparisons)."""
        stored = _read(Path(path))
        return cls(Path(path), stored.experiment, stored.records, stored.rejected, stored.model, stored.plant_values)

    def append(self, record: dict) -> None:
        with open(self.path, "a") as f:
            f.write(json.dumps(record) + "\n")
        self.records[record["key"]] = record

    def missing(self) -> list[Trial]:
        return [t for t in trials(self.experiment) if t.key not in self.records]

    def warnings(self) -> list[str]:
        """One line per refused line of the file, for the user."""
        return [
            f"{self.path} line {line}: {why}; not counted (its trial runs again when the run continues, and "
            f"the line is kept in {self.path.name}.rejected)"
            for line, why in self.rejected
        ]


def _refuse_another_run(path: Path, stored: _Contents, wanted: ResultsFile) -> None:
    """ExperimentMismatch where the stored run is not one of wanted's: its plant's values, its options (but for
    more trials or cells) or its model differ."""
    experiment = wanted.experiment
    now = wanted.plant_values
    if stored.plant_values is not None and stored.plant_values != now:
        changed = sorted(k for k in now if stored.plant_values.get(k) != now[k])
        raise ExperimentMismatch(
            f"{path} was run on the plant {experiment.plant!r} when its values were others "
            f"({', '.join(changed)} differ in sim/model/plant.toml since); use another --out"
        )
    if stored.experiment != experiment and not _extends(stored.experiment, experiment):
        changed = sorted(k for k, v in experiment.to_json().items() if stored.experiment.to_json().get(k) != v)
        raise ExperimentMismatch(
            f"{path} holds a run with other options ({', '.join(changed)} differ); "
            f"use another --out, the same options to continue it, or more trials or "
            f"cells to add to it"
        )
    if stored.model != wanted.model:
        raise ExperimentMismatch(_other_model(path, stored.model, wanted.model))


def _other_model(path: Path, stored: dict | None, now: dict) -> str:
    """Why a results file written on another model is not continued, and how to start it again."""
    was = (
        "a model from before results files recorded theirs"
        if stored is None
        else f"model {stored.get('mjcf_sha1')} on MuJoCo {stored.get('mujoco')}"
    )
    return (
        f"{path} was written on {was}; this run's is model {now['mjcf_sha1']} on MuJoCo {now['mujoco']} (the MJCF "
        f"the rig generates, or MuJoCo, changed since): its trials would mix two models. Start it again with "
        f"another --out, or move {path.name} away; it still opens for figures and comparisons"
    )


def _cut_header(raw: bytes) -> bool:
    """Whether a file is all or the start of a results header and nothing more (a run interrupted as it began)."""
    prefix = b'{"format": "' + RESULTS_FORMAT.encode()
    return b"\n" not in raw and (raw.startswith(prefix) or prefix.startswith(raw))


def write_whole(path: Path, content: bytes) -> None:
    """Write the whole file at once: an interruption leaves the old file or the new, never half of one."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(content)
    os.replace(tmp, path)


def _extends(stored: Experiment, wanted: Experiment) -> bool:
    """Whether wanted only adds trials to stored (more per cell, or more cells), so every stored trial is one of
    wanted's: trials are drawn from (seed, cell, k) alone."""
    same_otherwise = (
        dataclasses.replace(stored, trials_per_cell=wanted.trials_per_cell, only_cells=wanted.only_cells) == wanted
    )
    more_per_cell = wanted.trials_per_cell >= stored.trials_per_cell
    more_cells = wanted.only_cells is None or (
        stored.only_cells is not None and set(stored.only_cells) <= set(wanted.only_cells)
    )
    return same_otherwise and more_per_cell and more_cells


def _header(results: ResultsFile) -> dict:
    """A results file's first line: the protocol, the values its plant had (a named plant may be refitted) and the
    model that stepped it (the generated MJCF's digest and MuJoCo's version)."""
    return {
        "format": RESULTS_FORMAT,
        "protocol": results.experiment.to_json(),
        "plant_values": results.plant_values,
        "model": results.model,
    }


RECORD_TYPES = {
    "key": str,
    "cell": int,
    "k": int,
    "success": bool,
    "reached": bool,
    "fell_off": bool,
    "target_m": list,
}  # what aggregation reads from a trial record, by type
TYPE_NAMES = {str: "a string", int: "a whole number", bool: "true or false", list: "a list"}


def record_problem(record, experiment: Experiment) -> str | None:
    """Why a parsed line is not a trial record of this protocol, or None when it is one."""
    if not isinstance(record, dict):
        return f"not a trial record (a JSON {type(record).__name__})"
    for name, kind in RECORD_TYPES.items():
        if name not in record:
            return f"no {name!r} field"
        value = record[name]
        if type(value) is not kind:  # exact: a bool is not a count, 7 is not a success
            return f"{name} must be {TYPE_NAMES[kind]}, got {value!r}"
    if record["cell"] not in set(experiment.cell_ids()) or not 0 <= record["k"] < experiment.trials_per_cell:
        return f"trial {record['cell']}:{record['k']} is not one of this run's"
    if record["key"] != f"{record['cell']}:{record['k']}":
        return f"key {record['key']!r} does not match cell {record['cell']}, trial {record['k']}"
    return None


@dataclass
class _Contents:
    """What a results file holds, line by line."""

    experiment: Experiment
    plant_values: dict | None
    model: dict | None  # model_identity() of the run; None in files written before it was recorded
    records: dict[str, dict] = field(default_factory=dict)
    good_lines: list[bytes] = field(default_factory=list)
    bad_lines: list[bytes] = field(default_factory=list)
    rejected: list[tuple[int, str]] = field(default_factory=list)
    cut: bool = False  # the last line was cut off (an interruption mid-write)


GZIP_MAGIC = b"\x1f\x8b"  # how a gzipped file begins (the committed runs in docs/results/ are)


def _read(path: Path) -> _Contents:
    raw = path.read_bytes()
    if raw.startswith(GZIP_MAGIC):
        try:
            raw = gzip.decompress(raw)
        except (OSError, EOFError) as exc:
            raise ValueError(f"{path} is a damaged gzip file ({exc})") from None
    if _cut_header(raw):
        raise ValueError(
            f"{path} holds no complete header line (a run interrupted as it began); rerun the same "
            f"heatmap command to start it afresh"
        )
    lines = raw.split(b"\n")
    try:
        header = json.loads(lines[0])
    except json.JSONDecodeError:
        raise ValueError(f"{path} is not a heatmap results file (its first line is not JSON)") from None
    if not isinstance(header, dict) or header.get("format") != RESULTS_FORMAT:
        raise ValueError(f"{path} is not a heatmap results file ({RESULTS_FORMAT})")
    if "protocol" not in header:
        raise ValueError(
            f"{path}: its header line names no protocol (the experiment its trials belong to), so its "
            f"trials cannot be placed; was it edited by hand?"
        )
    try:
        experiment = Experiment.from_json(header["protocol"])
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"{path}: its header's protocol is not valid ({exc})") from None
    recorded = header.get("plant_values")
    plant_values = None if recorded is None else P.recorded_values(recorded)
    out = _Contents(experiment, plant_values, header.get("model"), cut=lines[-1] != b"")
    for number, line in enumerate(lines[1:-1], start=2):  # the last element follows the final newline
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            problem = "not JSON"
        else:
            problem = record_problem(record, experiment)
            if problem is None and record["key"] in out.records:
                problem = f"repeats trial {record['key']}"
        if problem is None:
            out.records[record["key"]] = record
            out.good_lines.append(line)
        else:
            out.rejected.append((number, problem))
            out.bad_lines.append(line)
    return out


WALL_CLOCK_FIELDS = ("wall_time_s", "physics_wall_s")  # a record's fields that depend on the machine, not the trial


def trial_record(trial: Trial, result) -> dict:
    """The results-file line of a finished trial (result: a bridge.TrialResult)."""
    return {
        "key": trial.key,
        "cell": trial.cell,
        "k": trial.k,
        "seed": trial.seed,
        "start_m": [round(v, 5) for v in trial.start_m],
        "target_m": [round(v, 5) for v in trial.target_m],
        "final_m": [round(float(v), 5) for v in result.final_xy_m],
        "final_error_m": round(result.final_error_m, 5),
        "success": bool(result.success),
        "reached": result.time_to_reach_s is not None,
        "time_to_reach_s": result.time_to_reach_s,
        "fell_off": bool(result.fell_off),
        "sim_time_s": round(result.sim_time_s, 3),
        "wall_time_s": round(result.wall_time_s, 3),
        "physics_wall_s": round(result.physics_wall_s, 3),
    }


def unplaceable_record(trial: Trial, why: str) -> dict:
    """A trial whose start is not over the fabric (only at the very corners): it counts as fallen off."""
    return {
        "key": trial.key,
        "cell": trial.cell,
        "k": trial.k,
        "seed": trial.seed,
        "start_m": list(trial.start_m),
        "target_m": list(trial.target_m),
        "final_m": [None, None],
        "final_error_m": None,
        "success": False,
        "reached": False,
        "time_to_reach_s": None,
        "fell_off": True,
        "sim_time_s": 0.0,
        "wall_time_s": 0.0,
        "physics_wall_s": 0.0,
        "unplaceable": why,
    }
