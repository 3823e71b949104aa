"""The paper's hardware experiment (Fig. 3) on named plants: seven objects, five random targets each, 60 s.

Run: python3 benchmarks/experiments/fig3_experiment.py [--plants polyester,paper] [--jobs 2] [--seed 3] [--settings FILE]
With --settings (a controller's settings, as mantaray sim tune writes them) the same targets run with that
controller instead of the paper's Manhattan, on the plant the file was tuned for, and the outputs' names end in
_<controller>.
For each plant: every object of Table I from the centre to five targets uniform in [-0.2, 0.2]^2 m with the
paper's alpha for it (sim/evaluation/fig3.py), ending at the first frame within eps; prints reached/fell per object and
finding F6, draws the figure in the style of Fig. 3 (each object's paths with the targets' tolerance circles
above the phase plot of the tilts within the square of the controller's tilt limit, the paper's +-26.6 deg) to docs/figures/fig3_<plant>.png and writes
the trials (paths and tilts included) to docs/results/fig3_<plant>.json.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from mantaray.host.cli_controller import controller_settings
from mantaray.plots import fig3_figure
from mantaray.protocol import messages as m
from mantaray.sim.evaluation.executors import LocalPool
from mantaray.sim.evaluation.experiment import Experiment
from mantaray.sim.evaluation.fig3 import run_fig3
from mantaray.sim.evaluation.findings import MODULE_M, fig3_finding
from mantaray.sim.model.parameters import plant_names
from mantaray.sim.model.plant import plant_for

REPO = Path(__file__).resolve().parents[2]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--plants",
        help="named plants of sim/model/plant.toml (default: every one, or the one --settings was tuned for)",
    )
    parser.add_argument("--seed", type=int, default=3, help="seed of the targets and the noise")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--figures", default="docs/figures")
    parser.add_argument("--results", default="docs/results")
    parser.add_argument("--settings", metavar="FILE", help="a controller's settings (default: the paper's Manhattan)")
    args = parser.parse_args()
    args.controller = None
    settings = controller_settings(parser, args)
    suffix = "" if settings.controller == "manhattan" and not settings.values else f"_{settings.controller}"
    tilt_limit_deg = settings.configure(m.Configure()).tilt_limit  # [deg] the limit the controller runs with
    plants = args.plants.split(",") if args.plants else [settings.plant] if settings.plant else plant_names()
    unknown = [p for p in plants if p not in plant_names()]
    if unknown:
        parser.error(f"unknown plant(s) {', '.join(unknown)}; the plants are: {', '.join(plant_names())}")
    try:
        for plant in plants:
            plant_for(settings, plant)
    except ValueError as exc:
        parser.error(str(exc))
    with LocalPool(args.jobs) as pool:
        for plant in plants:
            t0 = time.perf_counter()
            records = run_fig3(pool, plant, seed=args.seed, settings=settings)
            finding = fig3_finding(records)
            runs: dict[str, list[dict]] = {}
            for r in records:
                runs.setdefault(r["object"], []).append(r)
            figure = fig3_figure(
                runs,
                Experiment.tolerance_m,
                MODULE_M,
                tilt_limit_deg,
                f"Fig. 3 in simulation, {plant} plant: {settings.controller}, 60 s, from the centre",
                REPO / args.figures / f"fig3_{plant}{suffix}.png",
            )
            out = REPO / args.results / f"fig3_{plant}{suffix}.json"
            out.parent.mkdir(parents=True, exist_ok=True)
            out.write_text(
                json.dumps(
                    {
                        "plant": plant,
                        "seed": args.seed,
                        "controller": settings.controller,
                        "settings": dict(settings.values),
                        "finding": vars(finding),
                        "trials": records,
                    }
                )
                + "\n"
            )
            print(
                f"{plant}: F6 {'holds' if finding.holds else 'fails'}: {finding.measured}; "
                + "; ".join(
                    f"{name} fell {sum(t['fell_off'] for t in trials)}, median time to reach "
                    f"{_median([t['time_to_reach_s'] for t in trials if t['reached']])}"
                    for name, trials in runs.items()
                )
                + f"; {time.perf_counter() - t0:.0f} s; {figure.relative_to(REPO)}",
                flush=True,
            )
    return 0


def _median(values: list) -> str:
    return "-" if not values else f"{sorted(values)[len(values) // 2]:.1f} s"


if __name__ == "__main__":
    sys.exit(main())
