"""The log of a rig run (what `mantaray rig` writes): one JSON-lines file, written as it runs and read back for fitting."""

from __future__ import annotations

import itertools
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np


class RunLog:
    """One JSON-lines file per run: the configuration first, then every position frame and telemetry frame.

    RunLog(path, header) writes that file over; RunLog.new(folder, prefix, header) names a file of its own."""

    def __init__(self, path: Path, header: dict, *, exclusive: bool = False) -> None:
        """exclusive: the file must not exist yet (FileExistsError), and this process is the one that created it."""
        path.parent.mkdir(parents=True, exist_ok=True)
        self.path = path
        self._file = open(path, "x" if exclusive else "w")
        self.write("config", header)

    @classmethod
    def new(cls, folder: Path, prefix: str, header: dict) -> RunLog:
        """A log in a file no other run has: folder/PREFIX-YYYYmmdd-HHMMSS.jsonl, or -2, -3 ... after the stamp when
        runs started in the same second (created exclusively, so two at once never share one)."""
        stamp = time.strftime("%Y%m%d-%H%M%S")
        for n in itertools.count(1):
            try:
                return cls(folder / f"{prefix}-{stamp}{f'-{n}' if n > 1 else ''}.jsonl", header, exclusive=True)
            except FileExistsError:
                continue
        raise AssertionError("itertools.count() never ends")

    def write(self, kind: str, record: dict) -> None:
        self._file.write(json.dumps({"kind": kind, "t": round(time.monotonic(), 6), **record}) + "\n")
        self._file.flush()

    def close(self) -> None:
        self._file.close()


class RunLogError(ValueError):
    """A file that is not a usable rig log (not JSON lines, no config, no frames)."""


@dataclass(frozen=True)
class LoggedRun:
    """A rig log as arrays, one row per position frame (in the order they were sent)."""

    path: Path
    args: dict  # the run's options as logged (controller, target, alpha, object, ...)
    t_s: np.ndarray  # [s] capture time of each frame from the run's start
    xy_m: np.ndarray  # [m] tracked position; NaN where the object was not seen
    command_m: np.ndarray  # [m] a_0..a_3 of the telemetry that answered the frame; NaN where none came

    @property
    def start_m(self) -> tuple[float, float]:
        """The first position seen."""
        seen = np.flatnonzero(np.isfinite(self.xy_m[:, 0]))
        return float(self.xy_m[seen[0], 0]), float(self.xy_m[seen[0], 1])


def read_run_log(path: str | Path) -> LoggedRun:
    """Read a rig log; RunLogError says what is wrong with a file that is not one."""
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise RunLogError(f"cannot read the rig log {path}: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise RunLogError(f"{path} is not text: not a rig log") from None
    records = []
    for n, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            if n == len(lines):  # a last line cut off by an interruption
                break
            raise RunLogError(f"{path}:{n} is not JSON: not a rig log") from None
        if not isinstance(record, dict):
            raise RunLogError(f"{path}:{n} is not a JSON object: not a rig log")
        records.append((n, record))
    if not records or records[0][1].get("kind") != "config":
        raise RunLogError(f"{path} does not start with a config line: not a rig log (mantaray rig writes them)")
    rows: dict[int, int] = {}
    t: list[float] = []
    xy: list = []
    cmd: list = []
    for n, r in records[1:]:
        try:
            if r.get("kind") == "position":
                rows[r["frame"]] = len(t)
                t.append(float(r["capture_s"]))
                xy.append(tuple(map(float, r["xy_m"])) if r.get("xy_m") is not None else (math.nan, math.nan))
                cmd.append((math.nan,) * 4)
            elif r.get("kind") == "telemetry" and r.get("position_frame") in rows:
                command = tuple(map(float, r["command"]))
                if len(command) != 4:
                    raise ValueError
                cmd[rows[r["position_frame"]]] = command
        except (KeyError, TypeError, ValueError):
            raise RunLogError(f"{path}:{n}: a {r.get('kind')} line without the fields mantaray rig writes") from None
    xy_m = np.asarray(xy, dtype=float).reshape(-1, 2)
    if not np.isfinite(xy_m[:, 0]).any():
        raise RunLogError(f"{path} holds no frame in which the object was seen")
    args = records[0][1].get("args")
    return LoggedRun(
        path, args if isinstance(args, dict) else {}, np.asarray(t, float), xy_m, np.asarray(cmd, float).reshape(-1, 4)
    )
