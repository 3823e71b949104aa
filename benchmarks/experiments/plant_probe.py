"""Benchmark: which of a plant's values hold an object back, by setting them one group at a time on a small sample.

Run: python3 benchmarks/experiments/plant_probe.py [--plant paper] [--object cube] [--alpha 0.1] [--cells 4] [--trials 4]
     [--seed 77] [--jobs 2] --probe "KEY=VALUE[,KEY=VALUE...]" [--probe ...]
Runs the Manhattan controller on --cells x --cells cells, --trials trials each (trials end at the first frame within
eps), once on the plant as it is and once per --probe with those values set over it (checked against their
declared ranges), all on the same starts and targets (--seed). Prints, per run, the share of trials that reached
the target, the share that fell off, and the median distance the object moved in the trials that did not fall
[m], so a probe that frees a stuck object shows as a larger move.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from mantaray.sim.evaluation import executors as X
from mantaray.sim.evaluation import experiment as E
from mantaray.sim.model.objects import OBJECTS
from mantaray.sim.model.parameters import ParameterError, plant_names
from mantaray.sim.model.plant import parse_setting


def sample_stats(records: list[dict]) -> dict:
    """Reached and fell-off shares, and the median move [m] of the trials that stayed on the fabric."""
    moved_m = [float(np.hypot(*np.subtract(r["final_m"], r["start_m"]))) for r in records if not r["fell_off"]]
    return {
        "reached": float(np.mean([r["reached"] for r in records])),
        "fell": float(np.mean([r["fell_off"] for r in records])),
        "median_moved_m": float(np.nanmedian(moved_m)) if moved_m else float("nan"),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--plant", choices=plant_names(), default="paper")
    parser.add_argument("--object", choices=sorted(OBJECTS), default="cube")
    parser.add_argument("--alpha", type=float, default=0.1, help="noise amplitude alpha [m]")
    parser.add_argument("--cells", type=int, default=4, help="cells per side of the sample")
    parser.add_argument("--trials", type=int, default=4, help="trials per cell")
    parser.add_argument("--seed", type=int, default=77, help="seed of starts and targets (not the protocol's 2026)")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument(
        "--probe",
        action="append",
        default=[],
        metavar="KEY=VALUE,...",
        help="values to set together over the plant; repeatable, one run each",
    )
    args = parser.parse_args()
    try:
        probes = [()] + [tuple(parse_setting(text) for text in group.split(",")) for group in args.probe]
    except ParameterError as exc:
        parser.error(str(exc))
    for probe in probes:
        experiment = E.Experiment(
            object_name=args.object,
            controller="manhattan",
            alpha_m=args.alpha,
            cells=args.cells,
            trials_per_cell=args.trials,
            seed=args.seed,
            plant=args.plant,
            plant_set=probe,
            stop_when_reached=True,
        )
        t0 = time.perf_counter()
        stats = sample_stats(list(X.run_local(experiment, E.trials(experiment), jobs=args.jobs)))
        label = ", ".join(f"{k}={v}" for k, v in probe) or f"{args.plant} as it is"
        print(
            f"{label}: reached {stats['reached']:.2f}, fell {stats['fell']:.2f}, "
            f"median move {stats['median_moved_m'] * 100:.1f} cm ({time.perf_counter() - t0:.0f} s)",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
