"""Benchmark: heatmap trials per wall second on this machine, and whether faster physics keeps per-cell success.

Run: python3 benchmarks/heatmap_speed.py [--configs 15:0.001,15:0.001:7,11:0.002] [--controller manhattan] [--jobs 2]
     [--plant NAME]
Each config (fabric resolution : timestep [s]) runs the same sample of cells (a 4 x 4 spread over the
20 x 20 grid, the paper's 10 trials each, T = 10 s) on all cores, in-process firmware core. The first
config is the reference. Prints, per config: trials per wall second, simulated seconds per wall second,
the share of trials ended early by a fall, the projected wall time of the full 4,000-trial protocol, and,
for each of the three per-cell rates (ends within eps at T, reached eps at some frame, fell off), the
mean and largest absolute difference from the reference and the bias, with the verdict against the
stated tolerance (MEAN_ABS_TOLERANCE, BIAS_TOLERANCE). Results stay in --out (one heatmap results file
per config), so a rerun only adds what is missing. A config with a third field, a seed (15:0.001:7), draws
other trials in the same cells: the reference against itself on another draw is the noise floor that
sampling alone leaves between two maps of the same model.
--batched first measures mujoco.rollout's batched stepping against a plain mj_step loop.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from mantaray.sim import executors as X
from mantaray.sim import experiment as E
from mantaray.sim import results_file as R
from mantaray.sim import summary as S
from mantaray.sim.plant import DEFAULT_PLANT

SAMPLE_IX = (2, 7, 12, 17)   # cells ix, iy of the sample: centres at -0.1875, -0.0625, 0.0625, 0.1875 m
FULL_TRIALS = 4000           # the paper's protocol: 20 x 20 cells x 10 trials
# The tolerance a fidelity shortcut must keep against the reference, per rate, over the sample's cells:
MEAN_ABS_TOLERANCE = 0.16    # [-] mean |per-cell difference|: one standard deviation of a 10-trial rate at p = 0.5
BIAS_TOLERANCE = 0.05        # [-] |mean per-cell difference|: the map as a whole neither better nor worse
RATES = (("ends within", "rates"), ("reached", "reach_rates"), ("fell off", "fell_rates"))   # (label, Summary field)


def sample_cells(cells: int = 20) -> tuple[int, ...]:
    return tuple(ix + iy * cells for iy in SAMPLE_IX for ix in SAMPLE_IX)


def batched_stepping(steps: int = 500) -> None:
    """The batched-stepping lever: mujoco.rollout over K copies on 1-2 threads against a plain mj_step loop."""
    import mujoco
    from mujoco import rollout

    from mantaray.sim import model as M

    model, data = M.load(E.Experiment().rig())
    M.drop_object(model, data, 0.05, 0.02)
    for _ in range(200):
        mujoco.mj_step(model, data)
    t = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(model, data)
    plain = steps / (time.perf_counter() - t)
    print(f"batched stepping (fast-mode model, object on the sheet): plain mj_step loop {plain:,.0f} steps/s")
    kind = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, kind))
    mujoco.mj_getState(model, data, state, kind)
    for copies, threads in ((1, 1), (4, 1), (4, 2), (8, 2)):
        with rollout.Rollout(nthread=threads) as r:
            t = time.perf_counter()
            r.rollout([model] * copies, [mujoco.MjData(model) for _ in range(threads)], np.tile(state, (copies, 1)),
                      np.zeros((copies, steps, model.nu)))
            rate = copies * steps / (time.perf_counter() - t)
        print(f"  rollout of {copies} copies on {threads} thread(s): {rate:,.0f} steps/s ({rate / plain:.2f}x)")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--configs", default="15:0.001,11:0.002,11:0.004,15:0.002",
                        help="comma-separated RESOLUTION:TIMESTEP[:SEED] (seed of the trials' draw, default "
                             f"{E.Experiment.seed}); the first is the reference")
    parser.add_argument("--controller", default="manhattan")
    parser.add_argument("--object", default="sphere")
    parser.add_argument("--alpha", type=float, default=0.0)
    parser.add_argument("--plant", default=DEFAULT_PLANT, help="a named plant of sim/plant.toml")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--out", default="out/bench/heatmap_speed")
    parser.add_argument("--batched", action="store_true", help="also measure mujoco.rollout's batched stepping")
    args = parser.parse_args()
    if args.batched:
        batched_stepping()

    configs = [parse_config(c) for c in args.configs.split(",")]
    cells = sample_cells()
    reference = None
    print(f"sample: {len(cells)} cells x 10 trials, {args.object}, {args.controller}, α = {args.alpha:g} m, "
          f"{args.jobs} workers")
    print(f"{'config':>12s} {'trials/s':>9s} {'sim s/wall s':>12s} {'fell early':>10s} {'4,000 trials':>12s}  "
          f"per rate: mean, and against the reference mean |Δ| / max |Δ| / bias "
          f"(tolerance {MEAN_ABS_TOLERANCE} / - / ±{BIAS_TOLERANCE})")
    for resolution, timestep, seed in configs:
        protocol = E.Experiment(object_name=args.object, controller=args.controller, alpha_m=args.alpha,
                              resolution=resolution, timestep_s=timestep, seed=seed, only_cells=cells,
                              plant=args.plant)
        drawn = "" if seed == E.Experiment.seed else f"_seed{seed}"
        plant = "" if args.plant == DEFAULT_PLANT else f"_{args.plant}"
        results = R.ResultsFile.open(
            Path(args.out) / f"{args.object}_{args.controller}_{resolution}_{timestep:g}{drawn}{plant}.jsonl", protocol)
        todo = results.missing()
        t0 = time.perf_counter()
        X.run(results, X.run_local(protocol, todo, args.jobs))
        wall = time.perf_counter() - t0
        records = list(results.records.values())
        new = [r for r in records if r["key"] in {t.key for t in todo}]
        summary = S.summarize(results)
        rates = {label: getattr(summary, name).ravel()[list(cells)] for label, name in RATES}
        fell = np.mean([r["fell_off"] for r in records])
        line = f"{resolution:>4d} {timestep * 1000:g} ms" + (f" seed {seed}" if drawn else "")
        if new:
            per_s = len(new) / wall
            sim_per_wall = sum(r["sim_time_s"] for r in new) / wall
            line += f" {per_s:9.3f} {sim_per_wall:12.1f} {fell:10.0%} {FULL_TRIALS / per_s / 60:10.1f} min"
        else:
            line += f" {'(cached: rerun with a new --out to time it)':>45s}"
        if reference is None:
            reference = rates
            line += "  reference: " + ", ".join(f"{label} {np.mean(r):.2f}" for label, r in rates.items())
        else:
            line += "  " + "; ".join(fidelity(label, rates[label], reference[label]) for label in rates)
        print(line, flush=True)
    return 0


def parse_config(text: str) -> tuple[int, float, int]:
    """RESOLUTION:TIMESTEP[:SEED] -> (resolution, timestep [s], seed)."""
    fields = text.split(":")
    try:
        if len(fields) not in (2, 3):
            raise ValueError
        return int(fields[0]), float(fields[1]), int(fields[2]) if len(fields) == 3 else E.Experiment.seed
    except ValueError:
        raise SystemExit(f"heatmap_speed: a config is RESOLUTION:TIMESTEP[:SEED] (like 15:0.001:7), got {text!r}") from None


def fidelity(label: str, rates: np.ndarray, reference: np.ndarray) -> str:
    """One rate of a config against the reference's, per cell, with the verdict against the stated tolerance."""
    d = rates - reference
    mean_abs, bias = float(np.mean(np.abs(d))), float(np.mean(d))
    holds = mean_abs <= MEAN_ABS_TOLERANCE and abs(bias) <= BIAS_TOLERANCE
    return (f"{label} {np.mean(rates):.2f}: {mean_abs:.3f} / {np.max(np.abs(d)):.2f} / {bias:+.3f} "
            f"{'holds' if holds else 'OUTSIDE'}")


if __name__ == "__main__":
    sys.exit(main())
