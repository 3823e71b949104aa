"""The paper's hardware experiment (Fig. 3) in simulation: each object from the centre to random targets, Manhattan, 60 s.

Five trials per object of Table I, each from the centre to a target uniform in [-0.2, 0.2]^2 m, with the
alpha the paper used for that object; a trial ends when the object first comes within epsilon (the rig's
loop stops there), falls off, or at 60 s. The targets come from (seed, object, k) alone.
"""
from __future__ import annotations

import numpy as np

from . import findings as F

TOLERANCE_M = 0.02            # [m] epsilon, as in the heatmaps


def fig3_jobs(plant_name: str, values: dict, seed: int, resolution: int, timestep_s: float) -> list[tuple]:
    """One job per (object, k): everything run_fig3_trial needs."""
    jobs = []
    for name in F.FIG3_ALPHA_M:
        for k in range(F.FIG3_TRIALS):
            rng = np.random.default_rng([seed, sum(map(ord, name)), k])
            target = tuple(float(v) for v in rng.uniform(-F.FIG3_TARGET_HALF_M, F.FIG3_TARGET_HALF_M, 2))
            jobs.append((plant_name, dict(values), name, k, target, int(rng.integers(1, 2 ** 31)), resolution,
                         timestep_s))
    return jobs


def run_fig3_trial(job: tuple) -> dict:
    """One Fig. 3 trial with the firmware core in-process: its outcome, path and tilts."""
    from mantaray.host.link import Link
    from mantaray.host.transport import InProcessTransport

    from .bridge import Bridge, TrialSpec
    from .heatmap import controller_gains
    from .plant import Plant

    plant_name, values, name, k, target, seed, resolution, timestep_s = job
    plant = Plant(plant_name).set(values)
    bridge = Bridge(Link(InProcessTransport(simulated_clock=True)),
                    plant.rig(name, resolution=resolution, timestep_s=timestep_s), plant.tracking())
    spec = TrialSpec((0.0, 0.0), target, controller="manhattan", duration_s=F.FIG3_DURATION_S,
                     alpha_m=F.FIG3_ALPHA_M[name], tolerance_m=TOLERANCE_M, seed=seed, stop_when_reached=True,
                     gains=controller_gains("manhattan", None, plant.gain_scale))
    result = bridge.run(spec)
    return {"object": name, "k": k, "target_m": list(target), "alpha_m": F.FIG3_ALPHA_M[name],
            "reached": result.time_to_reach_s is not None, "time_to_reach_s": result.time_to_reach_s,
            "fell_off": bool(result.fell_off), "sim_time_s": round(result.sim_time_s, 3),
            "path_m": np.round(result.true_xy_m, 5).tolist(), "tilt_deg": np.round(result.tilt_deg, 3).tolist()}


def run_fig3(pool, plant_name: str = "polyester", values: dict | None = None, seed: int = 3, resolution: int = 11,
             timestep_s: float = 0.002) -> list[dict]:
    """Every Fig. 3 trial on the pool's workers (heatmap.LocalPool or RayPool), in order."""
    return pool.map_calls(run_fig3_trial, fig3_jobs(plant_name, values or {}, seed, resolution, timestep_s))
