"""The Fig. 3 experiment's design (objects, alphas, targets from the seed) and its figure, on synthetic runs."""

from __future__ import annotations

import numpy as np

from mantaray.host.controller_settings import ControllerSettings
from mantaray.plots import fig3_figure
from mantaray.sim.evaluation import findings as F
from mantaray.sim.evaluation.fig3 import fig3_jobs


def test_every_object_gets_five_targets_in_the_square_with_its_papers_alpha():
    jobs = fig3_jobs("polyester", {}, seed=3, resolution=11, timestep_s=0.002)
    assert len(jobs) == 7 * F.FIG3_TRIALS
    for experiment, trial in jobs:
        assert experiment.alpha_m == F.FIG3_ALPHA_M[experiment.object_name] and experiment.controller == "manhattan"
        assert experiment.duration_s == 60.0 and experiment.stop_when_reached
        assert trial.start_m == (0.0, 0.0) and all(abs(v) <= 0.2 for v in trial.target_m)
    again = fig3_jobs("polyester", {}, seed=3, resolution=11, timestep_s=0.002)
    other = fig3_jobs("polyester", {}, seed=4, resolution=11, timestep_s=0.002)
    assert [t for _, t in jobs] == [t for _, t in again] and [t for _, t in jobs] != [t for _, t in other]


def test_another_controller_runs_the_same_targets_with_its_settings():
    tuned = ControllerSettings("scheduled", (("configure_schedule.edge_tilt", 0.4),))
    paper = fig3_jobs("polyester", {}, seed=3, resolution=11, timestep_s=0.002)
    jobs = fig3_jobs("polyester", {}, seed=3, resolution=11, timestep_s=0.002, settings=tuned)
    assert [t for _, t in jobs] == [t for _, t in paper]  # paired: the same targets and seeds
    assert all(p.controller == "scheduled" and p.settings == tuned.values for p, _ in jobs)


def test_the_figure_draws_a_column_per_object(tmp_path):
    rng = np.random.default_rng(0)
    runs = {
        name: [
            {
                "path_m": np.cumsum(rng.normal(0, 0.01, (20, 2)), axis=0).tolist(),
                "tilt_deg": rng.normal(0, 10, (20, 2)).tolist(),
                "target_m": [0.1, -0.1],
                "reached": True,
                "fell_off": False,
                "alpha_m": alpha,
            }
            for _ in range(2)
        ]
        for name, alpha in F.FIG3_ALPHA_M.items()
    }
    path = fig3_figure(runs, 0.02, (0.5, 0.5), 26.57, "synthetic", tmp_path / "fig3.png")
    assert path.exists() and path.stat().st_size > 20_000
