"""Benchmark: heatmap trials per wall second at each physics fidelity, side by side in one run on the same trials.

Run: python3 benchmarks/speed/heatmap_speed.py [--configs reference,15:0.001,15:0.002,fast] [--jobs 2] [--plant paper]
     [--variant plant --variant fabric.stretch=threads,contact.model=kernel]
Each config (a named fidelity of sim/model/rig.py, or RESOLUTION:TIMESTEP [vertices per side : s]), under each variant
of the plant (`plant`: as it is; else KEY=VALUE,... of sim/model/plant.toml fixed over it; the plant alone unless
--variant is given), runs the same
sample of cells (a 4 x 4 spread over the 20 x 20 grid, the paper's 10 trials each, T = 10 s) on --jobs workers,
firmware core in-process. Prints, per config: trials per wall second and its ratio to the first config,
simulated seconds per wall second, the share of the trials' wall time spent outside mj_step, the share of trials
ended early by a fall, and the projected wall time of the paper's 4,000-trial protocol on this many workers.
Speeds are only compared within one run (machines here vary by 2x from day to day). Whether a config keeps the
finer one's outcomes is the fidelity gate's question (`mantaray sim fidelity`), not this script's. The trials stay
in --out (one results file per config), so a rerun only adds what is missing: give a new --out to time again.
--batched first measures mujoco.rollout's batched stepping against a plain mj_step loop.
"""

from __future__ import annotations

import argparse
import itertools
import os
import sys
import time
from pathlib import Path

import numpy as np

from mantaray.sim.evaluation import executors as X
from mantaray.sim.evaluation import experiment as E
from mantaray.sim.evaluation import fidelity as G
from mantaray.sim.evaluation import results_file as R
from mantaray.sim.model.parameters import ParameterError
from mantaray.sim.model.plant import DEFAULT_PLANT, parse_setting

SAMPLE_IX = (2, 7, 12, 17)  # cells ix, iy of the sample: centres at -0.1875, -0.0625, 0.0625, 0.1875 m
FULL_TRIALS = 4000  # the paper's protocol: 20 x 20 cells x 10 trials


def sample_cells(cells: int = 20) -> tuple[int, ...]:
    return tuple(ix + iy * cells for iy in SAMPLE_IX for ix in SAMPLE_IX)


def batched_stepping(steps: int = 500) -> None:
    """The batched-stepping lever: mujoco.rollout over K copies on 1-2 threads against a plain mj_step loop."""
    import mujoco
    from mujoco import rollout

    from mantaray.sim.model import model as M

    fast = G.FIDELITIES["fast"]
    model, data = M.load(E.Experiment(resolution=fast.resolution, timestep_s=fast.timestep_s).rig())
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
            r.rollout(
                [model] * copies,
                [mujoco.MjData(model) for _ in range(threads)],
                np.tile(state, (copies, 1)),
                np.zeros((copies, steps, model.nu)),
            )
            rate = copies * steps / (time.perf_counter() - t)
        print(f"  rollout of {copies} copies on {threads} thread(s): {rate:,.0f} steps/s ({rate / plain:.2f}x)")


def parse_configs(text: str) -> list[G.Fidelity]:
    """Comma-separated fidelities, each once, in the order given."""
    out = []
    for part in text.split(","):
        try:
            fidelity = G.parse_fidelity(part.strip())
        except ValueError as exc:
            raise SystemExit(f"heatmap_speed: {exc}") from None
        if fidelity not in out:
            out.append(fidelity)
    return out


def parse_variant(text: str) -> tuple[tuple[str, float | str], ...]:
    """`plant` (nothing fixed) or comma-separated KEY=VALUE settings of the plant, each checked against its range."""
    if text == "plant":
        return ()
    try:
        return tuple(parse_setting(part.strip()) for part in text.split(","))
    except ParameterError as exc:
        raise SystemExit(f"heatmap_speed: --variant {text!r}: {exc}") from None


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--configs",
        default="reference,15:0.001,15:0.002,fast",
        help="comma-separated fidelities: fast, reference or RESOLUTION:TIMESTEP; the first is the "
        "one the others' speeds are given against",
    )
    parser.add_argument("--controller", default="manhattan")
    parser.add_argument("--object", default="sphere")
    parser.add_argument("--alpha", type=float, default=0.0)
    parser.add_argument("--plant", default=DEFAULT_PLANT, help="a named plant of sim/model/plant.toml")
    parser.add_argument(
        "--variant",
        action="append",
        help="a variant of the plant to run each config under: plant (as it is) or KEY=VALUE,... of "
        "sim/model/plant.toml (like fabric.stretch=threads,contact.model=kernel); repeatable",
    )
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--out", default="out/bench/heatmap_speed")
    parser.add_argument("--batched", action="store_true", help="also measure mujoco.rollout's batched stepping")
    args = parser.parse_args()
    if args.jobs < 1:
        raise SystemExit(f"heatmap_speed: --jobs must be at least 1, got {args.jobs}")
    configs = parse_configs(args.configs)
    variants = [parse_variant(text) for text in args.variant or ["plant"]]
    if args.batched:
        batched_stepping()

    cells = sample_cells()
    first = None
    print(
        f"sample: {len(cells)} cells x 10 trials, {args.object}, {args.controller}, α = {args.alpha:g} m, "
        f"{args.plant} plant, {args.jobs} workers"
    )
    print(
        f"{'config':>25s} {'trials/s':>9s} {'x first':>8s} {'sim s/wall s':>12s} {'outside mj_step':>15s} "
        f"{'fell early':>10s} {'4,000 trials':>12s}"
    )
    for fidelity, variant in itertools.product(configs, variants):
        experiment = E.Experiment(
            object_name=args.object,
            controller=args.controller,
            alpha_m=args.alpha,
            resolution=fidelity.resolution,
            timestep_s=fidelity.timestep_s,
            only_cells=cells,
            plant=args.plant,
            plant_set=variant,
        )
        named = f"{args.object}_{args.controller}_alpha{args.alpha:g}_{args.plant}_{fidelity.slug}"
        results = R.ResultsFile.open(Path(args.out) / f"{named}{G.fixed_slug(experiment.plant_set)}.jsonl", experiment)
        todo = results.missing()
        t0 = time.perf_counter()
        X.run(results, X.run_local(experiment, todo, args.jobs))
        wall = time.perf_counter() - t0
        done = {t.key for t in todo}
        new = [r for r in results.records.values() if r["key"] in done]
        line = f"{fidelity.label + ''.join(f', {v}' for _, v in variant):>25s}"
        if not new:
            print(line + "  (cached: give a new --out to time it)", flush=True)
            continue
        per_s = len(new) / wall
        first = first or per_s
        outside = 1 - sum(r["physics_wall_s"] for r in new) / sum(r["wall_time_s"] for r in new)
        fell = np.mean([r["fell_off"] for r in new])
        print(
            f"{line} {per_s:9.3f} {per_s / first:7.2f}x {sum(r['sim_time_s'] for r in new) / wall:12.1f} "
            f"{outside:15.1%} {fell:10.0%} {FULL_TRIALS / per_s / 60:8.1f} min",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
