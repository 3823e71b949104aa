"""The paper's full simulation protocol (Fig. 2) with our stack: five heatmap runs, their difference map, the figures.

Run: python3 benchmarks/experiments/paper_heatmaps.py [--runs sphere_manhattan,sphere_euclidean] [--jobs 2] [--plant paper]
     [--fidelity reference]
Each run is `mantaray sim heatmap` with the paper's protocol (20 x 20 cells, 10 trials, T = 10 s,
eps = 0.02 m) on the named plant (sim/model/plant.toml) at the named fidelity (sim/model/rig.py, FIDELITIES; default the
reference) into out/heatmap/<run>/ (a plant other than polyester suffixes the run's name with _<plant>, a fidelity
other than the fast mode, which the committed runs of docs/results.md were made in, with its mesh and step, such as
_15x15_0.5ms); runs are resumable, so an interrupted script continues where it
stopped, and --trials 3 gives a quick map that a later run with the paper's 10 tops up. A run starts
from the committed trials (docs/results/<run>.jsonl.gz) when out/ has none, and writes every trial back
there (also when interrupted; --collect writes back a run still going), so a fresh clone continues the committed
runs instead of repeating them. The wall time of every session of a run is kept in docs/figures/heatmaps.json, so
the total a run took is known even when it was split. The figures are copied to docs/figures/ beside the scores,
regions and zone rates, and the paper's findings F1-F5 (sim/evaluation/findings.py) on the two sphere maps, under both success
rules. A plant that reads the paper's success rule as "reached" ends each trial at its first frame within eps
(--stop-when-reached), unless --to-end runs every trial to T (both success rules measured; the run's name gets
_to_end).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from mantaray.sim.evaluation.committed import keep, restore, trials_in
from mantaray.sim.evaluation.fidelity import parse_fidelity
from mantaray.sim.evaluation.findings import CENTRAL_HALF_M, CORNER_FROM_M
from mantaray.sim.model.plant import DEFAULT_PLANT, Plant
from mantaray.sim.model.rig import FIDELITIES

REPO = Path(__file__).resolve().parents[2]
COMMITTED = REPO / "docs" / "results"  # every trial of each run, <run>.jsonl.gz
RUNS = {  # name: (object, controller, alpha [m]) as in the paper's Fig. 2
    "sphere_manhattan": ("sphere", "manhattan", 0.0),
    "sphere_euclidean": ("sphere", "euclidean", 0.0),
    "cube_manhattan_alpha0.1": ("cube", "manhattan", 0.1),
    "bunny_manhattan_alpha0.1": ("bunny", "manhattan", 0.1),
    "bunny_manhattan_alpha0.05": ("bunny", "manhattan", 0.05),
}


ZONES = {  # name: which cells, from the cell centres' |x|, |y| [m] on the paper's 0.5 m module
    "centre (|x|, |y| < 0.05 m)": lambda ax, ay: (ax < 0.05) & (ay < 0.05),
    "central (|x|, |y| < 0.10 m)": lambda ax, ay: (ax < CENTRAL_HALF_M) & (ay < CENTRAL_HALF_M),
    "outer 5 cm band": lambda ax, ay: np.maximum(ax, ay) > 0.20,
    "corners (7.5 cm squares)": lambda ax, ay: (ax > CORNER_FROM_M) & (ay > CORNER_FROM_M),
}


def zone_rates(results_path: Path) -> dict:
    """Mean success, reach and fall rates over the zones of the workspace, and the regions under the reach rule."""
    from mantaray.sim.evaluation import results_file as R
    from mantaray.sim.evaluation import summary as S

    results = R.ResultsFile.load(results_path)
    s, p = S.summarize(results), results.experiment
    centres = -0.25 + (np.arange(p.cells) + 0.5) * 0.5 / p.cells
    ax, ay = np.meshgrid(np.abs(centres), np.abs(centres))
    zones = {
        name: {
            kind: round(float(np.nanmean(rates[pick(ax, ay)])), 3)
            for kind, rates in (("success", s.rates), ("reach", s.reach_rates), ("fell", s.fell_rates))
        }
        for name, pick in ZONES.items()
    }
    reach = s.reach_rates[np.isfinite(s.reach_rates)]
    regions = {
        "success": int((reach >= S.SUCCESS_REGION_AT).sum()),
        "failure": int((reach <= S.FAILURE_REGION_AT).sum()),
    }
    regions["uncertain"] = len(reach) - regions["success"] - regions["failure"]
    return {"zones": zones, "reach_regions_cells": regions}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", default=",".join(RUNS), help="comma-separated names of: " + ", ".join(RUNS))
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--trials", type=int, default=10, help="trials per cell (the paper: 10)")
    parser.add_argument("--out", default="out/heatmap")
    parser.add_argument("--figures", default="docs/figures")
    parser.add_argument(
        "--plant", default=DEFAULT_PLANT, help="the simulated plant (a [plant.NAME] of sim/model/plant.toml)"
    )
    parser.add_argument(
        "--to-end",
        action="store_true",
        help="run every trial to T, also on a plant read with the paper's stopping rule, so that both "
        "success rules are measured (the baseline of docs/results.md, Beyond the paper)",
    )
    parser.add_argument(
        "--collect",
        action="store_true",
        help="only write back the trials out/ holds (say, of a run still going) to docs/results/",
    )
    parser.add_argument(
        "--fidelity",
        default="reference",
        help="fast, reference or RESOLUTION:TIMESTEP: the physics the runs are made at",
    )
    args = parser.parse_args()
    try:
        fidelity = parse_fidelity(args.fidelity)
    except ValueError as exc:
        parser.error(str(exc))
    from mantaray.sim.model.parameters import plant_names

    if args.plant not in plant_names():
        parser.error(f"unknown plant {args.plant!r}; the plants are: {', '.join(plant_names())}")
    suffix = "" if args.plant == DEFAULT_PLANT else f"_{args.plant}"
    # A plant read with the paper's stopping rule ends its trials there (exact for that rule, 2-4x faster);
    # its maps then carry no "ends within eps at T".
    stop = ["--stop-when-reached"] if Plant(args.plant).success_rule == "reached" and not args.to_end else []
    if stop == [] and Plant(args.plant).success_rule == "reached":
        suffix += "_to_end"
    if fidelity != FIDELITIES["fast"]:
        suffix += f"_{fidelity.slug}"
    names = args.runs.split(",")
    unknown = [n for n in names if n not in RUNS]
    if unknown:
        parser.error(f"unknown run(s) {', '.join(unknown)}; known: {', '.join(RUNS)}")

    figures = REPO / args.figures
    figures.mkdir(parents=True, exist_ok=True)
    table_path = figures / "heatmaps.json"
    table = json.loads(table_path.read_text()) if table_path.exists() else {}
    for run in names:
        obj, controller, alpha = RUNS[run]
        name = run + suffix
        out = REPO / args.out / name
        results_path = out / "results.jsonl"
        committed = COMMITTED / f"{name}.jsonl.gz"
        if not args.collect and restore(results_path, committed):
            print(f"{name}: continuing from the committed trials in {committed.relative_to(REPO)}", flush=True)
        if args.collect:
            held = keep(results_path, committed)
            print(
                f"{name}: {held} trials kept in {committed.relative_to(REPO)}"
                if held
                else f"{name}: no trials in {results_path.relative_to(REPO)}",
                flush=True,
            )
            continue
        out.mkdir(parents=True, exist_ok=True)
        before = trials_in(results_path)
        t0 = time.perf_counter()
        proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "mantaray.cli",
                "sim",
                "heatmap",
                "--object",
                obj,
                "--controller",
                controller,
                "--alpha",
                str(alpha),
                "--trials",
                str(args.trials),
                "--jobs",
                str(args.jobs),
                "--plant",
                args.plant,
                *stop,
                "--resolution",
                str(fidelity.resolution),
                "--timestep",
                str(fidelity.timestep_s),
                "--out",
                str(out),
                "--json",
            ],
            cwd=REPO,
            stdout=subprocess.PIPE,
        )
        try:
            stdout, _ = proc.communicate()
        except KeyboardInterrupt:  # Ctrl-C reaches sim heatmap too: it ends keeping every finished trial
            proc.wait()
        finally:  # and those, with this session's time, are written back
            wall = time.perf_counter() - t0
            if keep(results_path, committed) > before:
                entry = table.setdefault(name, {})
                entry["wall_s_sessions"] = [*entry.get("wall_s_sessions", []), round(wall, 1)]
                table_path.write_text(json.dumps(table, indent=1) + "\n")
        if proc.returncode != 0:
            print(
                f"{name}: heatmap ended with exit {proc.returncode} (its message is above); the trials it holds are "
                f"kept in {committed.relative_to(REPO)}",
                file=sys.stderr,
            )
            return proc.returncode
        times = table[name].get("wall_s_sessions", []) if name in table else []
        summary = json.loads(stdout)
        if not stop:  # a run that stops at eps has no map of "ends within eps at T"
            shutil.copyfile(out / "heatmap.png", figures / f"heatmap_{name}.png")
        shutil.copyfile(out / "heatmap_reach.png", figures / f"heatmap_{name}_reach.png")
        table[name] = {
            "object": obj,
            "controller": controller,
            "alpha_m": alpha,
            "plant": args.plant,
            "score": summary["score"],
            "reach_score": summary["reach_score"],
            "regions": summary["regions"],
            "trials": summary["trials"],
            "trials_per_cell": args.trials,
            "wall_s_sessions": times,
            "jobs": args.jobs,
            **zone_rates(out / "results.jsonl"),
        }
        table_path.write_text(json.dumps(table, indent=1) + "\n")
        print(
            f"{name}: score {summary['score']:.1f} (reach {summary['reach_score']:.1f}), "
            f"{summary['trials']} trials, this session {wall / 60:.1f} min",
            flush=True,
        )
    if args.collect:
        return 0
    sphere_runs = [
        REPO / args.out / (run + suffix) / "results.jsonl" for run in ("sphere_euclidean", "sphere_manhattan")
    ]
    if all(path.exists() for path in sphere_runs):
        for rule, rule_suffix in ((["--reached"], "_reach"),) if stop else (([], ""), (["--reached"], "_reach")):
            proc = subprocess.run(
                [
                    sys.executable,
                    "-m",
                    "mantaray.cli",
                    "sim",
                    "compare",
                    *map(str, sphere_runs),
                    *rule,
                    "--out",
                    str(figures / f"heatmap_sphere_euclidean_minus_manhattan{rule_suffix}{suffix}.png"),
                ],
                cwd=REPO,
            )
            if proc.returncode != 0:
                return proc.returncode
        table[f"findings_{args.plant}"] = findings(*sphere_runs)
        table_path.write_text(json.dumps(table, indent=1) + "\n")
        for rule, found in table[f"findings_{args.plant}"].items():
            print(
                f"findings on the {args.plant} plant, rule {rule}: "
                + "; ".join(f"{f['name']} {'holds' if f['holds'] else 'fails'} ({f['measured']})" for f in found)
            )
    return 0


def findings(euclidean_path: Path, manhattan_path: Path) -> dict:
    """F1-F5 on the full sphere maps, under each success rule."""
    from mantaray.sim.evaluation import findings as F
    from mantaray.sim.evaluation import results_file as R

    runs = {c: R.ResultsFile.load(p) for c, p in (("euclidean", euclidean_path), ("manhattan", manhattan_path))}
    out = {}
    stopped = any(r.experiment.stop_when_reached for r in runs.values())  # then "end" is not measured
    for rule in ("reached",) if stopped else F.RULES:
        stats = {c: F.map_stats(r.records.values(), r.experiment.cells, rule) for c, r in runs.items()}
        out[rule] = [
            {"name": f.name, "holds": f.holds, "measured": f.measured}
            for f in F.heatmap_findings(stats["manhattan"], stats["euclidean"])
        ]
    return out


if __name__ == "__main__":
    sys.exit(main())
