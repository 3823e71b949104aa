"""Benchmark: how many trials a pruned, or a screened, tuning search spends to find what an unpruned one finds.

Run: python3 benchmarks/speed/search_budget.py [--controller cascade] [--plant paper] [--candidates 60] [--ratio 3]
     [--screen-at fast] [--jobs 2] [--out out/bench/search_budget]
One unpruned `sim tune` search at the reference fidelity (sim/model/rig.py, FIDELITIES) with Optuna's random sampler,
seeded, so that its candidates do not depend on their scores; every candidate keeps its misses per cell. Resumable:
the study is OUT/study.db. From it, with no trial run again:
- the pruned search: the same candidates in the same order put to the pruned search's own pruner (successive
  halving over the same nested rungs, sim/search/tune.py replay_pruned), which is exactly what `sim tune --prune` with this
  sampler runs;
- the same budget: the unpruned search given 1/--ratio of its trials (its first candidates) against the pruned one
  given those trials; each one's best (fewest misses on the search's sample), then both bests scored again on a
  held-out sample (--holdout-cells per stratum x the search's trials per cell, another seed) at the reference;
- trials to the best: how many trials each spends before it has seen the unpruned search's best;
- candidates per CPU-hour: candidates over the trials each runs, at the CPU time per trial the study measured
  (its wall time x --jobs);
- with --screen-at (a cheaper fidelity): every candidate scored there on the same sample (resumable:
  OUT/screen.json), the rank correlation of the two scores (Spearman) and where the reference's best ranks there.
Prints the numbers, writes OUT/report.json and OUT/budget.png (best so far against trials run, both searches).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
from pathlib import Path

import numpy as np
import optuna

from mantaray.sim.evaluation import findings as F
from mantaray.sim.evaluation.executors import LocalPool
from mantaray.sim.evaluation.fidelity import parse_fidelity
from mantaray.sim.evaluation.results_file import write_whole
from mantaray.sim.model.parameters import plant_names
from mantaray.sim.search import study as S
from mantaray.sim.search import tune as T

HOLDOUT_SEED = 77  # [-] the held-out sample's seed: not the search's (31)


def kept_scores(path: Path, evidence: T.TuningEvidence, candidates: list, pool, label: str) -> dict[str, float]:
    """Each candidate's misses on evidence's sample, kept in path (JSON) as they come, so an interrupted run resumes."""
    scores = json.loads(path.read_text()) if path.exists() else {}
    for i, t in enumerate(candidates):
        if str(t.number) not in scores:
            scores[str(t.number)] = evidence.evaluate(t.user_attrs["values"], pool)[0][0]
            write_whole(path, json.dumps(scores, indent=1).encode())
            print(
                f"{label}: candidate #{t.number} ({i + 1} of {len(candidates)}): misses {scores[str(t.number)]:.3f}",
                file=sys.stderr,
                flush=True,
            )
    return scores


def best_within(order: list[dict], budget: int) -> tuple[dict | None, int, int]:
    """The best completed candidate of those a search runs before its trials pass budget; candidates and trials run."""
    spent, seen, best = 0, 0, None
    for row in order:
        if spent + row["trials"] > budget:
            break
        spent, seen = spent + row["trials"], seen + 1
        if row["misses"] is not None and (best is None or row["misses"] < best["misses"]):
            best = row
    return best, seen, spent


def trials_until(order: list[dict], number: int) -> int | None:
    """Trials a search has run when candidate `number` completes (None: it never completes there)."""
    spent = 0
    for row in order:
        spent += row["trials"]
        if row["number"] == number:
            return spent if row["misses"] is not None else None
    return None


def figure(unpruned: list[dict], pruned: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    for order, label in ((unpruned, "unpruned"), (pruned, "pruned (replayed)")):
        spent = np.cumsum([r["trials"] for r in order])
        best = np.minimum.accumulate([np.inf if r["misses"] is None else r["misses"] for r in order])
        ax.step(spent, best, where="post", label=label)
    ax.set_xlabel("trials run")
    ax.set_ylabel("best misses per trial so far (both rules)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--controller", default="cascade", choices=sorted(T.SPACE))
    parser.add_argument("--plant", default="paper", choices=plant_names())
    parser.add_argument("--object", default="sphere")
    parser.add_argument("--candidates", type=int, default=60, help="candidates of the unpruned search (>= 20)")
    parser.add_argument("--cells-per-stratum", type=int, default=4)
    parser.add_argument("--trials-per-cell", type=int, default=3)
    parser.add_argument("--duration", type=float, default=10.0, help="T [s]")
    parser.add_argument("--fidelity", default="reference", help="the search's: a named fidelity or RESOLUTION:STEP")
    parser.add_argument("--ratio", type=float, default=3.0, help="the budget: the unpruned search's trials / ratio")
    parser.add_argument("--holdout-cells", type=int, default=8, help="held-out cells per stratum")
    parser.add_argument("--screen-at", default=None, metavar="FIDELITY", help="a cheaper fidelity to screen at")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--out", default="out/bench/search_budget")
    args = parser.parse_args()
    if args.candidates < 2 or args.ratio <= 1:
        parser.error("--candidates must be at least 2 and --ratio above 1")
    try:
        at = parse_fidelity(args.fidelity)
        screen = parse_fidelity(args.screen_at) if args.screen_at else None
        evidence = T.TuningEvidence(
            controller=args.controller,
            object_name=args.object,
            plant=args.plant,
            cells_per_stratum=args.cells_per_stratum,
            trials_per_cell=args.trials_per_cell,
            duration_s=args.duration,
            resolution=at.resolution,
            timestep_s=at.timestep_s,
        )
        evidence.experiment(T.settings_of(args.controller, T.boot_values(args.controller)))
    except ValueError as exc:
        parser.error(str(exc))
    out = Path(args.out)
    try:
        study = T.open_tuning(out / "study.db", evidence)
    except S.StudyMismatch as exc:
        parser.error(str(exc))
    study.sampler = optuna.samplers.RandomSampler(seed=evidence.seed * 100_003 + len(study.trials))
    with LocalPool(args.jobs) as pool:

        def progress(n: int, total: int, info: dict) -> None:
            print(f"search: candidate {n} of {total}: misses {info['objectives'][0]:.3f}", file=sys.stderr, flush=True)

        S.run_study(study, evidence, T.knobs(args.controller), {}, args.candidates, pool, progress)
        done = sorted(S.completed(study), key=lambda t: t.number)
        unpruned = [
            {"number": t.number, "trials": t.user_attrs["details"]["trials"], "misses": t.values[0]} for t in done
        ]
        pruned = T.replay_pruned(dataclasses.replace(evidence, prune=True), done)
        budget = int(sum(r["trials"] for r in unpruned) / args.ratio)
        winners = {name: best_within(order, budget) for name, order in (("unpruned", unpruned), ("pruned", pruned))}
        by_number = {t.number: t for t in done}
        holdout = dataclasses.replace(evidence, cells_per_stratum=args.holdout_cells, seed=HOLDOUT_SEED)
        held = kept_scores(
            out / "holdout.json",
            holdout,
            [by_number[n] for n in sorted({w[0]["number"] for w in winners.values() if w[0]})],
            pool,
            "held-out",
        )
        screened = (
            kept_scores(
                out / f"screen_{screen.slug}.json",
                dataclasses.replace(evidence, resolution=screen.resolution, timestep_s=screen.timestep_s),
                done,
                pool,
                f"screen {screen.label}",
            )
            if screen
            else None
        )
    cpu_per_trial_s = sum(t.user_attrs["wall_s"] for t in done) * args.jobs / sum(r["trials"] for r in unpruned)
    overall = min(unpruned, key=lambda r: r["misses"])
    report = {
        "search": {
            "controller": args.controller,
            "plant": args.plant,
            "object": args.object,
            "fidelity": at.label,
            "candidates": len(done),
            "cells_per_stratum": args.cells_per_stratum,
            "trials_per_cell": args.trials_per_cell,
            "seed": evidence.seed,
            "sampler": "random",
        },
        "trials": {
            "unpruned": sum(r["trials"] for r in unpruned),
            "pruned": sum(r["trials"] for r in pruned),
            "stopped": sum(r["misses"] is None for r in pruned),
        },
        "candidates_per_cpu_hour": {
            name: round(len(order) / (sum(r["trials"] for r in order) * cpu_per_trial_s) * 3600, 2)
            for name, order in (("unpruned", unpruned), ("pruned", pruned))
        },
        "cpu_per_trial_s": round(cpu_per_trial_s, 2),
        "best": {
            "number": overall["number"],
            "misses": overall["misses"],
            "trials_until": {
                "unpruned": trials_until(unpruned, overall["number"]),
                "pruned": trials_until(pruned, overall["number"]),
            },
        },
        "budget": {
            "trials": budget,
            **{
                name: {
                    "candidates": seen,
                    "trials": spent,
                    "best": None if best is None else best["number"],
                    "misses": None if best is None else best["misses"],
                    "held_out_misses": None if best is None else held[str(best["number"])],
                }
                for name, (best, seen, spent) in winners.items()
            },
            "held_out": {"cells_per_stratum": args.holdout_cells, "seed": HOLDOUT_SEED},
        },
    }
    if screened is not None:
        numbers = [r["number"] for r in unpruned]
        cheap = np.array([screened[str(n)] for n in numbers])
        report["screen"] = {
            "fidelity": screen.label,
            "candidates": len(numbers),
            "rank_correlation": F.rank_correlation(np.array([r["misses"] for r in unpruned]), cheap),
            "rank_of_best_there": int(1 + np.sum(cheap < screened[str(overall["number"])])),
        }
    out.mkdir(parents=True, exist_ok=True)
    write_whole(out / "report.json", json.dumps(report, indent=1).encode())
    figure(unpruned, pruned, out / "budget.png")
    print(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
