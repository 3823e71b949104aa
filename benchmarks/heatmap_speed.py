"""Benchmark: heatmap trials per wall second on this machine, and whether faster physics keeps per-cell success.

Run: python3 benchmarks/heatmap_speed.py [--configs 15:0.001,11:0.002] [--controller manhattan] [--jobs 2]
Each config (fabric resolution : timestep [s]) runs the same sample of cells (a 4 x 4 spread over the
20 x 20 grid, the paper's 10 trials each, T = 10 s) on all cores, in-process firmware core. The first
config is the reference. Prints, per config: trials per wall second, simulated seconds per wall second,
the share of trials ended early by a fall, the projected wall time of the full 4,000-trial protocol, and
the per-cell success rates against the reference (mean and largest absolute difference, and the bias).
Results stay in --out (one heatmap results file per config), so a rerun only adds what is missing.
--batched first measures mujoco.rollout's batched stepping against a plain mj_step loop.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from mantaray.sim import heatmap as H

SAMPLE_IX = (2, 7, 12, 17)   # cells ix, iy of the sample: centres at -0.1875, -0.0625, 0.0625, 0.1875 m
FULL_TRIALS = 4000           # the paper's protocol: 20 x 20 cells x 10 trials


def sample_cells(cells: int = 20) -> tuple[int, ...]:
    return tuple(ix + iy * cells for iy in SAMPLE_IX for ix in SAMPLE_IX)


def batched_stepping(steps: int = 500) -> None:
    """The batched-stepping lever: mujoco.rollout over K copies on 1-2 threads against a plain mj_step loop."""
    import mujoco
    from mujoco import rollout

    from mantaray.sim import model as M

    model, data = M.load(H.Protocol().rig())
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
                        help="comma-separated RESOLUTION:TIMESTEP; the first is the reference")
    parser.add_argument("--controller", default="manhattan")
    parser.add_argument("--object", default="sphere")
    parser.add_argument("--alpha", type=float, default=0.0)
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--out", default="out/bench/heatmap_speed")
    parser.add_argument("--batched", action="store_true", help="also measure mujoco.rollout's batched stepping")
    args = parser.parse_args()
    if args.batched:
        batched_stepping()

    configs = [(int(r), float(s)) for r, s in (c.split(":") for c in args.configs.split(","))]
    cells = sample_cells()
    reference = None
    print(f"sample: {len(cells)} cells x 10 trials, {args.object}, {args.controller}, α = {args.alpha:g} m, "
          f"{args.jobs} workers")
    print(f"{'config':>12s} {'trials/s':>9s} {'sim s/wall s':>12s} {'fell early':>10s} {'4,000 trials':>12s} "
          f"{'mean rate':>9s} {'mean |Δ|':>8s} {'max |Δ|':>7s} {'bias':>6s}")
    for resolution, timestep in configs:
        protocol = H.Protocol(object_name=args.object, controller=args.controller, alpha_m=args.alpha,
                              resolution=resolution, timestep_s=timestep, only_cells=cells)
        results = H.ResultsFile.open(Path(args.out) / f"{args.object}_{args.controller}_{resolution}_{timestep:g}.jsonl",
                                     protocol)
        todo = results.missing()
        t0 = time.perf_counter()
        H.run(results, H.run_local(protocol, todo, args.jobs))
        wall = time.perf_counter() - t0
        records = list(results.records.values())
        new = [r for r in records if r["key"] in {t.key for t in todo}]
        rates = H.summarize(results).rates.ravel()[list(cells)]
        fell = np.mean([r["fell_off"] for r in records])
        line = f"{resolution:>4d} {timestep * 1000:g} ms"
        if new:
            per_s = len(new) / wall
            sim_per_wall = sum(r["sim_time_s"] for r in new) / wall
            line += f" {per_s:9.3f} {sim_per_wall:12.1f} {fell:10.0%} {FULL_TRIALS / per_s / 60:10.1f} min"
        else:
            line += f" {'(cached: rerun with a new --out to time it)':>45s}"
        line += f" {np.mean(rates):9.2f}"
        if reference is None:
            reference = rates
        else:
            d = rates - reference
            line += f" {np.mean(np.abs(d)):8.2f} {np.max(np.abs(d)):7.2f} {np.mean(d):+6.2f}"
        print(line, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
