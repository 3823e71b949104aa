"""Rig logs as calibration evidence: replay a log's commands on the simulated rig and compare its trajectory with the log's.

A rig log (host/runlog.py, what `mantaray rig` writes) holds every camera frame's tracked position and the
telemetry that answered it, whose a_0..a_3 are the commands the actuators then followed. Replaying those
commands open loop, from the logged start, on a candidate plant gives the trajectory that plant would have
had; the evidence is the mean distance between it and the logged one. `write_log` writes a simulated trial
in the same format, so a fit can be checked on logs whose plant is known.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mantaray.host.runlog import LoggedRun, RunLog, RunLogError, read_run_log

from ..model.plant import DEFAULT_PLANT
from ..model.rig import DEFAULT_FIDELITY

FELL_ERROR_M = 0.25  # [m] the error a frame counts for once the replayed object has fallen off


def replay(run: LoggedRun, rig, latency_s: float = 0.0, horizon_s: float | None = None) -> np.ndarray:
    """The simulated object's (x, y) [m] at each logged frame's capture time, driven by the logged commands.

    Each frame's command is applied latency_s after its capture, at the step it falls due, as the bridge applies
    the firmware's answer. Rows after the object fell off are NaN; horizon_s ends the replay early. Raises
    SimulationUnstable if the physics diverges, and RunLogError if the log starts where there is no fabric.
    """
    from ..model import model as M

    model, data = M.load(rig)
    try:
        M.drop_object(model, data, *run.start_m)
    except ValueError as exc:  # model.fabric_height: not over the fabric
        raise RunLogError(f"{run.path}: the run starts at {run.start_m}, {exc}") from None
    t0 = data.time
    half_step_s = 0.5 * model.opt.timestep
    out = np.full((len(run.t_s), 2), np.nan)
    pending: list[tuple[float, np.ndarray]] = []  # (run time [s], command [m]) not yet applied

    def apply_due(_=None) -> None:
        while pending and pending[0][0] <= data.time - t0 + half_step_s:
            M.set_commands(model, data, pending.pop(0)[1])

    for k, t_s in enumerate(run.t_s):
        if horizon_s is not None and t_s > horizon_s:
            break
        apply_due()
        M.step_until(model, data, t0 + t_s, apply_due)
        if M.fell_off(model, data, rig.fall):
            break
        out[k] = M.object_xy(model, data)
        if np.all(np.isfinite(run.command_m[k])):
            pending.append((t_s + latency_s, run.command_m[k]))
    return out


def trajectory_error_m(simulated_xy: np.ndarray, logged_xy: np.ndarray) -> float:
    """Mean distance [m] over the frames the log saw the object in; a frame after the replay fell counts FELL_ERROR_M."""
    seen = np.isfinite(logged_xy[:, 0])
    n = min(len(simulated_xy), len(logged_xy))
    seen[n:] = False
    distance = np.linalg.norm(simulated_xy[:n] - logged_xy[:n], axis=1)
    distance = np.where(np.isfinite(distance), distance, FELL_ERROR_M)
    return float(distance[seen[:n]].mean())


def _replay_error(_runner, job: tuple) -> float:
    """The trajectory error of one log on one candidate plant (a pool job; it needs no trial runner)."""
    path, plant_name, values, object_name, resolution, timestep_s, horizon_s = job
    from ..model.plant import Plant

    plant = Plant(plant_name).set(values)
    run = read_run_log(path)
    rig = plant.rig(object_name, resolution=resolution, timestep_s=timestep_s)
    simulated = replay(run, rig, plant.values["tracking.latency_s"], horizon_s)
    logged = run.xy_m if horizon_s is None else np.where((run.t_s <= horizon_s)[:, None], run.xy_m, np.nan)
    return trajectory_error_m(simulated, logged)


@dataclass(frozen=True)
class LogEvidence:
    """Rig logs: the candidate plant, driven by each log's commands, should retrace each log's trajectory."""

    logs: tuple[str, ...]
    object_name: str = "sphere"
    plant: str = DEFAULT_PLANT
    horizon_s: float | None = None  # [s] compare only the first part of each run (None: all of it)
    resolution: int = DEFAULT_FIDELITY.resolution  # [vertices per side] (sim/model/rig.py, FIDELITIES)
    timestep_s: float = DEFAULT_FIDELITY.timestep_s  # [s]
    seed: int = 12
    kind: str = "log"
    objective_names: tuple[str, ...] = ("mean trajectory error [m]",)
    penalty: tuple[float, ...] = (FELL_ERROR_M,)  # a plant that cannot be simulated: as if it fell at once

    def evaluate(self, values: dict[str, float | str], pool) -> tuple[tuple[float, ...], dict]:
        jobs = [
            (log, self.plant, values, self.object_name, self.resolution, self.timestep_s, self.horizon_s)
            for log in self.logs
        ]
        errors = pool.map_calls(_replay_error, jobs)
        return (float(np.mean(errors)),), {
            "errors_m": {Path(p).name: round(e, 5) for p, e in zip(self.logs, errors, strict=True)},
            "passed": 0,
        }


def check_logs(paths: list[str], object_name: str, horizon_s: float | None) -> None:
    """Refuse, before a search starts, a file that is not a usable rig log (RunLogError): unreadable, fewer than two
    frames, logged with another object than the fit's, or with no frame seen before the horizon."""
    if horizon_s is not None and not (math.isfinite(horizon_s) and horizon_s > 0):
        raise RunLogError(f"--horizon must be a positive number of seconds, got {horizon_s}")
    for path in paths:
        run = read_run_log(path)
        if len(run.t_s) < 2:
            raise RunLogError(f"{run.path} has fewer than two frames: nothing to fit")
        logged = run.args.get("object")
        if logged is not None and logged != object_name:
            raise RunLogError(f"{run.path} was logged with the {logged}, not the {object_name}: pass --object {logged}")
        seen = np.isfinite(run.xy_m[:, 0]) & (run.t_s <= (horizon_s if horizon_s is not None else math.inf))
        if seen.sum() < 2:
            raise RunLogError(
                f"{run.path} has fewer than two frames with the object seen before the horizon ({horizon_s} s)"
            )


def write_log(path: str | Path, result, object_name: str, plant_name: str) -> Path:
    """Write a simulated trial (bridge.TrialResult) as `mantaray rig` writes a run: config, then per camera frame
    its position and the telemetry that answered it."""
    spec = result.spec
    log = RunLog(
        Path(path),
        {
            "args": {
                "controller": spec.controller,
                "target": list(spec.target_m),
                "alpha": spec.alpha_m,
                "tolerance": spec.tolerance_m,
                "object": object_name,
                "simulated_plant": plant_name,
            }
        },
    )
    try:
        for k, t_s in enumerate(result.t_s):
            frame = k + 1
            xy = result.measured_xy_m[k]
            seen = bool(np.all(np.isfinite(xy)))
            log.write(
                "position",
                {
                    "frame": frame,
                    "capture_s": round(float(t_s), 6),
                    "status": "OK" if seen else "NO_OBJECT",
                    "xy_m": [float(xy[0]), float(xy[1])] if seen else None,
                    "corners_seen": [0, 1, 2, 3],
                },
            )
            if np.all(np.isfinite(result.command_m[k])):
                log.write(
                    "telemetry",
                    {
                        "position_frame": frame,
                        "state": int(result.state[k]),
                        "tilt_zx": float(result.tilt_deg[k, 0]),
                        "tilt_zy": float(result.tilt_deg[k, 1]),
                        "command": [float(v) for v in result.command_m[k]],
                    },
                )
        log.write("end", {"outcome": "fell off" if result.fell_off else "timeout"})
    finally:
        log.close()
    return Path(path)
