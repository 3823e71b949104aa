"""Benchmark: the calibration's best candidates on a larger sample drawn from another seed (a hold-out check).

Run: python3 benchmarks/experiments/check_candidates.py [--study out/calibration/paper/study.db] [--top 3]
     [--plants polyester,paper] [--cells-per-stratum 8] [--trials-per-cell 4] [--seed 77] [--jobs 2]
A search scores candidates on a small sample (12-15 trials a stratum), so the best of many is partly the luckiest.
This takes the --top candidates of a findings study (most findings holding, then the smallest sum of objectives)
and scores each again, with the same code, on --cells-per-stratum cells of each stratum and --trials-per-cell
trials each, drawn from --seed (not the search's). --plants scores named plants (sim/model/plant.toml) on the same
hold-out sample, beside them. Prints each one's F1-F5 (for a candidate, on both samples) and writes them as
JSON to --out.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import optuna

from mantaray.sim.evaluation.executors import LocalPool
from mantaray.sim.model.parameters import plant_names
from mantaray.sim.search import calibrate as C
from mantaray.sim.search import study as S


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--study", default="out/calibration/paper/study.db")
    parser.add_argument("--top", type=int, default=3, help="how many of the study's best candidates (0: none)")
    parser.add_argument("--plants", default="", help="named plants to score on the same sample, comma-separated")
    parser.add_argument("--cells-per-stratum", type=int, default=8)
    parser.add_argument("--trials-per-cell", type=int, default=4)
    parser.add_argument("--seed", type=int, default=77)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", default="out/calibration/check.json")
    args = parser.parse_args()
    if not Path(args.study).exists():
        parser.error(f"no study at {args.study}: run mantaray sim calibrate first")
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.load_study(study_name=S.STUDY_NAME, storage=f"sqlite:///{args.study}")
    config = study.user_attrs["config"]["evidence"]
    if config.get("kind") != "findings":
        parser.error(f"{args.study} is not a findings study")
    searched = C.FindingsEvidence(**{k: tuple(v) if isinstance(v, list) else v for k, v in config.items()})
    check = dataclasses.replace(
        searched, cells_per_stratum=args.cells_per_stratum, trials_per_cell=args.trials_per_cell, seed=args.seed
    )
    ranked = sorted(
        (t for t in S.completed(study) if t.user_attrs["details"]["passed"] >= 0),
        key=lambda t: (-t.user_attrs["details"]["passed"], sum(t.values)),
    )[: args.top]
    rows = []
    with LocalPool(args.jobs) as pool:
        for name in filter(None, args.plants.split(",")):
            if name not in plant_names():
                parser.error(f"unknown plant {name!r}; the plants are: {', '.join(plant_names())}")
            objectives, details = dataclasses.replace(check, plant=name).evaluate({}, pool)
            rows.append(
                {
                    "plant": name,
                    "check": {
                        "objectives": list(objectives),
                        "findings": details["findings"],
                        "stats": details["stats"],
                    },
                }
            )
            print(f"plant {name} ({details['rule']} rule), hold-out sample:")
            for finding, f in details["findings"].items():
                print(f"  {finding}: {'holds' if f['holds'] else 'fails'}   {f['measured']}")
            print(f"  objectives {[round(v, 3) for v in objectives]}", flush=True)
        for t in ranked:
            t0 = time.perf_counter()
            objectives, details = check.evaluate(t.user_attrs["values"], pool)
            rows.append(
                {
                    "number": t.number,
                    "values": t.user_attrs["values"],
                    "search": {"objectives": t.values, "findings": t.user_attrs["details"]["findings"]},
                    "check": {
                        "objectives": list(objectives),
                        "findings": details["findings"],
                        "stats": details["stats"],
                    },
                    "wall_s": round(time.perf_counter() - t0, 1),
                }
            )
            print(
                f"candidate #{t.number} ({details['rule']} rule), search sample -> hold-out sample "
                f"({check.cells_per_stratum} cells x {check.trials_per_cell} trials a stratum, seed {check.seed}):"
            )
            for name, f in details["findings"].items():
                before = t.user_attrs["details"]["findings"][name]
                print(
                    f"  {name}: {'holds' if before['holds'] else 'fails'} -> {'holds' if f['holds'] else 'fails'}"
                    f"   {f['measured']}"
                )
            print(
                f"  objectives {[round(v, 3) for v in t.values]} -> {[round(v, 3) for v in objectives]}, "
                f"{rows[-1]['wall_s']} s",
                flush=True,
            )
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
