"""The paper's hardware experiment (Fig. 3) in simulation: each object from the centre to random targets, 60 s, with
Manhattan (the paper's) or another controller's settings.

Five trials per object of Table I, each from the centre to a target uniform in [-0.2, 0.2]^2 m, with the
alpha the paper used for that object; a trial ends when the object first comes within epsilon (the rig's
loop stops there), falls off, or at 60 s. The targets come from (seed, object, k) alone. The trials run
through the heatmap's trial runners (heatmap.LocalPool or RayPool), one protocol per object.
"""

from __future__ import annotations

import numpy as np

from mantaray.host.controller_settings import ControllerSettings

from ..model.model import SimulationUnstable
from ..model.plant import DEFAULT_PLANT
from ..model.rig import DEFAULT_FIDELITY
from . import findings as F
from .experiment import Experiment, Trial


def fig3_jobs(
    plant_name: str,
    values: dict,
    seed: int,
    resolution: int,
    timestep_s: float,
    settings: ControllerSettings | None = None,
) -> list[tuple]:
    """One (protocol, trial) per object and k; the targets depend on the seed alone, whatever the controller."""
    settings = settings or ControllerSettings("manhattan")
    jobs = []
    for name, alpha_m in F.FIG3_ALPHA_M.items():
        experiment = Experiment(
            object_name=name,
            controller=settings.controller,
            cells=1,
            trials_per_cell=F.FIG3_TRIALS,
            duration_s=F.FIG3_DURATION_S,
            alpha_m=alpha_m,
            seed=seed,
            resolution=resolution,
            timestep_s=timestep_s,
            plant=plant_name,
            plant_set=tuple(values.items()),
            stop_when_reached=True,
            settings=settings.values,
        )
        for k in range(F.FIG3_TRIALS):
            rng = np.random.default_rng([seed, sum(map(ord, name)), k])
            target = tuple(float(v) for v in rng.uniform(-F.FIG3_TARGET_HALF_M, F.FIG3_TARGET_HALF_M, 2))
            jobs.append((experiment, Trial(0, k, (0.0, 0.0), target, int(rng.integers(1, 2**31)))))
    return jobs


def run_fig3_trial(runner, job: tuple) -> dict:
    """One Fig. 3 trial on the process's runner: its outcome, path and tilts (a diverging plant: fell off, said so)."""
    experiment, trial = job
    row = {
        "object": experiment.object_name,
        "k": trial.k,
        "target_m": list(trial.target_m),
        "alpha_m": experiment.alpha_m,
    }
    try:
        result = runner.result(trial, experiment)
    except SimulationUnstable as exc:
        return {
            **row,
            "reached": False,
            "time_to_reach_s": None,
            "fell_off": True,
            "unstable": str(exc),
            "path_m": [],
            "tilt_deg": [],
        }
    return {
        **row,
        "reached": result.time_to_reach_s is not None,
        "time_to_reach_s": result.time_to_reach_s,
        "fell_off": bool(result.fell_off),
        "sim_time_s": round(result.sim_time_s, 3),
        "path_m": np.round(result.true_xy_m, 5).tolist(),
        "tilt_deg": np.round(result.tilt_deg, 3).tolist(),
    }


def run_fig3(
    pool,
    plant_name: str = DEFAULT_PLANT,
    values: dict | None = None,
    seed: int = 3,
    resolution: int = DEFAULT_FIDELITY.resolution,
    timestep_s: float = DEFAULT_FIDELITY.timestep_s,
    settings: ControllerSettings | None = None,
) -> list[dict]:
    """Every Fig. 3 trial on the pool's workers, in order."""
    return pool.map_calls(run_fig3_trial, fig3_jobs(plant_name, values or {}, seed, resolution, timestep_s, settings))
