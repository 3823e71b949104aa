"""Benchmark: does the log fit recover a plant's hidden parameters from logs the simulation wrote with them?

Run: python3 benchmarks/experiments/log_fit_recovery.py [--runs 1,3,5] [--candidates 60] [--horizon 3] [--jobs 2]
A hidden plant (the polyester plant with other rolling damping and actuator speed) drives the sphere with the
Manhattan controller in closed loop (firmware in-process) through --max-runs random central runs; each is
written as `mantaray rig` writes a run. Then, for each count of logs in --runs, `mantaray sim calibrate --log`'s
search (the same code) fits the two parameters from the first that many logs, comparing each run's first --horizon
seconds, with the others at the polyester values, and the recovered values are printed beside the hidden ones. Everything stays in --out: logs, one study
per count (resumable: a rerun only adds candidates).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from mantaray.sim.evaluation.executors import LocalPool
from mantaray.sim.model.parameters import default
from mantaray.sim.search import calibrate as C
from mantaray.sim.search import study as S
from mantaray.sim.search.logfit import LogEvidence, write_log

HIDDEN = {"contact.rolling_damping_per_s": 2.0, "actuators.pulley_circumference_m": 0.06}
RUN_S = 8.0  # [s] each logged run
RADIUS_M = 0.12  # [m] starts and targets within this of the centre


def make_logs(out: Path, n: int, seed: int) -> list[Path]:
    """n closed-loop runs on the hidden plant, as rig logs (written once; reused on a rerun)."""
    from mantaray.host.link import Link
    from mantaray.host.transport import InProcessTransport
    from mantaray.sim.model.plant import Plant
    from mantaray.sim.trial.bridge import Bridge, TrialSpec

    paths = [out / f"run{k}.jsonl" for k in range(n)]
    if all(p.exists() for p in paths):
        return paths
    plant = Plant().set(HIDDEN)
    bridge = Bridge(
        Link(InProcessTransport(simulated_clock=True)),
        plant.rig(resolution=LogEvidence.resolution, timestep_s=LogEvidence.timestep_s),
        plant.tracking(),
    )
    rng = np.random.default_rng(seed)
    for k, path in enumerate(paths):
        start, target = (tuple(float(v) for v in rng.uniform(-RADIUS_M, RADIUS_M, 2)) for _ in range(2))
        result = bridge.run(TrialSpec(start, target, duration_s=RUN_S, seed=k + 1))
        write_log(path, result, "sphere", "hidden: " + json.dumps(HIDDEN))
    return paths


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", default="1,3,5", help="how many logs each fit sees")
    parser.add_argument("--candidates", type=int, default=60, help="candidates per fit")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--seed", type=int, default=4)
    parser.add_argument(
        "--horizon",
        type=float,
        default=3.0,
        help="[s] compare each run's first HORIZON seconds "
        "(0: the whole run; later frames of a rolling ball are chaotic and make the error rugged)",
    )
    parser.add_argument("--out", default="out/logfit")
    args = parser.parse_args()
    counts = [int(v) for v in args.runs.split(",")]
    out = Path(args.out)
    logs = make_logs(out / "logs", max(counts), args.seed)
    keys = C.searched(list(HIDDEN), {})
    print(
        f"hidden: {HIDDEN}; the polyester plant's: { ({k: default(k) for k in HIDDEN}) }; "
        f"{args.candidates} candidates per fit, {RUN_S:g} s runs"
    )
    rows = []
    with LocalPool(args.jobs) as pool:
        for n in counts:
            evidence = LogEvidence(
                logs=tuple(str(p.resolve()) for p in logs[:n]), seed=args.seed, horizon_s=args.horizon or None
            )
            study = S.open_study(out / f"fit_{n}_runs_horizon{args.horizon:g}" / "study.db", evidence, keys, {})
            S.run_study(study, evidence, keys, {}, args.candidates, pool)
            best = S.best_trial(study)
            found = best.user_attrs["values"]
            errors = {k: found[k] / v - 1 for k, v in HIDDEN.items()}
            rows.append(
                {
                    "runs": n,
                    "horizon_s": args.horizon,
                    "candidates": len(S.completed(study)),
                    "found": found,
                    "relative_error": errors,
                    "trajectory_error_m": best.values[0],
                }
            )
            print(
                f"{n} run(s): "
                + ", ".join(f"{k} {found[k]:.4g} (hidden {v:g}, {errors[k]:+.1%})" for k, v in HIDDEN.items())
                + f"; mean trajectory error {best.values[0] * 1000:.2f} mm",
                flush=True,
            )
    (out / f"recovery_horizon{args.horizon:g}.json").write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
