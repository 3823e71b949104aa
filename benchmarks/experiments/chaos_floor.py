"""How many trial outcomes flip when every start moves a little: the fidelity gate's floors at several sizes.

Run: python3 benchmarks/experiments/chaos_floor.py [--fidelity 15:0.00025] [--plant polyester]
     [--set fabric.stretch=threads] [--shifts 0.0001,0.001,0.003] [--pairs 60] [--jobs 2]
The gate (`mantaray sim fidelity`, sim/evaluation/fidelity.py) reports the trials a cheaper configuration flips beside those the
finer one flips with every start moved (2 mm, the rig's repeatability; 0.1 mm, a diagnostic of chaos). A rolling
sphere's path is chaotic, so how many flips a
start moved d brings grows with d; this measures that growth on one configuration, on the gate's own sample (the
paper's Manhattan and Euclidean, 8 cells a stratum x 5 trials, seed 77), its first --pairs trials of each controller
in the gate's run order (a stratified prefix). Each shifted run is kept where the gate keeps its runs
(out/fidelity/trials/, the same file a gate's floor uses for 0.1 mm), so it resumes and shares trials (on a fresh
clone, `python3 benchmarks/experiments/fidelity_study.py --collect` first puts the committed ones there). Prints, per
shift, the flips of reached, fell off and within ε at T against the unmoved run, and the mean |difference| of the time
to reach and of the final error; a mesh or step change that flips about as many trials as a shift of d changes the
outcomes as much as moving every start by d does.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from mantaray.sim.evaluation import executors as X
from mantaray.sim.evaluation import fidelity as G
from mantaray.sim.evaluation.experiment import trials
from mantaray.sim.evaluation.results_file import ResultsFile
from mantaray.sim.model.parameters import ParameterError
from mantaray.sim.model.plant import parse_setting

REPO = Path(__file__).resolve().parents[2]
TRIALS = REPO / "out" / "fidelity" / "trials"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--fidelity", default="15:0.00025", help="RESOLUTION:TIMESTEP, or a named fidelity")
    parser.add_argument("--plant", default="polyester")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a plant value; repeatable")
    parser.add_argument("--shifts", default="0.0001,0.001,0.003", help="start shifts [m], comma-separated")
    parser.add_argument("--pairs", type=int, default=60, help="trials of each controller, in the gate's run order")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    try:
        fidelity = G.parse_fidelity(args.fidelity)
        fixed = tuple(sorted(parse_setting(text) for text in args.set))
        shifts = [float(v) for v in args.shifts.split(",")]
    except (ValueError, ParameterError) as exc:
        parser.error(str(exc))
    if not all(0 < s <= 0.01 for s in shifts) or args.pairs < 1:
        parser.error("each shift must be in (0, 0.01] m, and --pairs at least 1")
    arms = (G.Arm("manhattan", "manhattan"), G.Arm("euclidean", "euclidean"))
    sample = G.GateSample(plant=args.plant, plant_set=fixed, arms=arms)
    position = sample.run_order()
    runs = {
        (arm.label, shift): ResultsFile.open(
            sample.results_path(TRIALS, arm, fidelity, shift), sample.experiment(arm, fidelity, shift)
        )
        for arm in arms
        for shift in (0.0, *shifts)
    }
    first = {}  # each arm's first --pairs trial keys in the gate's order
    for arm in arms:
        ordered = sorted(trials(runs[arm.label, 0.0].experiment), key=position)
        first[arm.label] = [t.key for t in ordered[: args.pairs]]
    todo = [
        (i, t)
        for i, ((label, _), results) in enumerate(runs.items())
        for t in results.missing()
        if t.key in first[label]
    ]
    print(f"{len(todo)} trials to run on {args.jobs} workers", file=sys.stderr, flush=True)
    done = []

    def progress(record: dict) -> None:
        done.append(record)
        if len(done) % 10 == 0 or len(done) == len(todo):
            print(f"  {len(done)}/{len(todo)} trials", file=sys.stderr, flush=True)

    X.run_into(list(runs.values()), todo, args.jobs, progress)
    print(
        f"{sample.plant_label} plant, {fidelity.label}: flips against the unmoved run over {args.pairs} trials of each "
        "of manhattan, euclidean"
    )
    print("shift [mm] | reached | fell off | within ε at T | mean |Δ time to reach| [s] | mean |Δ final error| [cm]")
    for shift in shifts:
        pairs = [
            (runs[arm.label, 0.0].records[key], runs[arm.label, shift].records[key])
            for arm in arms
            for key in first[arm.label]
        ]
        flips = {k: sum(bool(a[k]) != bool(b[k]) for a, b in pairs) for k in ("reached", "fell_off", "success")}
        reach = [
            abs(a["time_to_reach_s"] - b["time_to_reach_s"])
            for a, b in pairs
            if a["time_to_reach_s"] is not None and b["time_to_reach_s"] is not None
        ]
        error = [
            abs(a["final_error_m"] - b["final_error_m"])
            for a, b in pairs
            if a["final_error_m"] is not None and b["final_error_m"] is not None  # None: a start off the sheet
        ]
        print(
            f"{shift * 1000:g} | {flips['reached']} | {flips['fell_off']} | {flips['success']} | "
            f"{np.mean(reach):.2f} ({len(reach)}) | {np.mean(error) * 100:.2f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
