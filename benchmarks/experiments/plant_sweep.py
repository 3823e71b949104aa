"""The plant sweep: the central-region trials for the sphere over a grid of plant parameters, firmware in the loop.

The acceptance protocol of the model (sim/README.md, Calibration): N trials whose starts and targets
are drawn uniformly within RADIUS of the centre; success = within the tolerance at the end of T.
Each grid point runs those same trials (same seeds) with each controller, over the pty, in lock-step.

Run:  python3 benchmarks/experiments/plant_sweep.py --set fabric.size_m=0.5,0.55,0.6 --set 'contact.friction[2]=0.0001,0.001'
      (keys and ranges of sim/model/plant.toml; several --set make the Cartesian product; --jobs splits grid points
      over cores). `mantaray sim calibrate` searches the whole space; this sweeps a grid of a few parameters.
Prints one line per grid point and controller, and writes them as JSON lines to --out.
"""

from __future__ import annotations

import argparse
import itertools
import json
import multiprocessing
import sys
import time

import numpy as np

from mantaray.host.link import Link
from mantaray.host.transport import SerialTransport
from mantaray.host.vmcu import VirtualMcu
from mantaray.sim.model.model import SimulationUnstable
from mantaray.sim.model.plant import Plant
from mantaray.sim.model.tracking import Tracking
from mantaray.sim.trial.bridge import Bridge, TrialSpec

RADIUS_M = 0.10  # [m] starts and targets within this distance of the centre (the central region)


def central_trials(n: int, seed: int) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """n (start, target) pairs, each point uniform in the disk of RADIUS_M."""
    rng = np.random.default_rng(seed)

    def point() -> tuple[float, float]:
        r, a = RADIUS_M * np.sqrt(rng.random()), 2 * np.pi * rng.random()
        return round(float(r * np.cos(a)), 4), round(float(r * np.sin(a)), 4)

    return [(point(), point()) for _ in range(n)]


def parse_value(text: str) -> float | str:
    try:
        return float(text)
    except ValueError:
        return text


def run_point(job: tuple) -> list[dict]:
    settings, controllers, trials, duration_s, rate_hz, latency_s = job
    rig = Plant().set(dict(settings)).rig()
    rows = []
    with VirtualMcu(clock="sim") as vmcu:
        try:
            bridge = Bridge(Link(SerialTransport(vmcu.path)), rig, Tracking(rate_hz=rate_hz, latency_s=latency_s))
        except SimulationUnstable as exc:
            return [{"settings": dict(settings), "controller": c, "unstable": str(exc)} for c in controllers]
        for controller in controllers:
            t = time.perf_counter()
            try:
                results = [
                    bridge.run(TrialSpec(s, g, controller=controller, duration_s=duration_s, seed=i + 1))
                    for i, (s, g) in enumerate(trials)
                ]
            except SimulationUnstable as exc:
                rows.append({"settings": dict(settings), "controller": controller, "unstable": str(exc)})
                continue
            rows.append(
                {
                    "settings": dict(settings),
                    "controller": controller,
                    "success": sum(r.success for r in results),
                    "trials": len(results),
                    "fell": sum(r.fell_off for r in results),
                    "final_error_m": [round(r.final_error_m, 4) for r in results],
                    "median_error_m": round(float(np.median([r.final_error_m for r in results])), 4),
                    "reached": sum(r.time_to_reach_s is not None for r in results),
                    "sim_per_wall": round(sum(r.sim_time_s for r in results) / sum(r.wall_time_s for r in results), 2),
                    "wall_s": round(time.perf_counter() - t, 1),
                }
            )
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=V1,V2",
        help="a parameter of sim/model/plant.toml and the values to try (e.g. fabric.size_m=0.5,0.55)",
    )
    parser.add_argument("--controllers", default="manhattan,euclidean")
    parser.add_argument("--trials", type=int, default=10)
    parser.add_argument("--seed", type=int, default=2026, help="seed of the start/target draw")
    parser.add_argument("--duration", type=float, default=10.0, help="T [s]")
    parser.add_argument("--rate", type=float, default=12.0, help="camera rate [Hz]")
    parser.add_argument("--latency", type=float, default=0.0, help="camera latency [s]")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", default="out/calibration.jsonl")
    args = parser.parse_args()

    axes = []
    for item in args.set:
        key, _, values = item.partition("=")
        axes.append([(key, parse_value(v)) for v in values.split(",")])
        try:
            for _, value in axes[-1]:
                Plant().set({key: value})
        except ValueError as exc:
            parser.error(str(exc))
    trials = central_trials(args.trials, args.seed)
    jobs = [
        (list(combo), args.controllers.split(","), trials, args.duration, args.rate, args.latency)
        for combo in itertools.product(*axes)
    ]
    from pathlib import Path

    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    with open(args.out, "a") as out, multiprocessing.Pool(args.jobs) as pool:
        for rows in pool.imap_unordered(run_point, jobs):
            for row in rows:
                out.write(json.dumps(row) + "\n")
                if "unstable" in row:
                    print(f"{row['settings']} {row['controller']:9s} UNSTABLE: {row['unstable']}", flush=True)
                    continue
                print(
                    f"{row['settings']} {row['controller']:9s} {row['success']}/{row['trials']} "
                    f"(reached {row['reached']}) fell {row['fell']} median error {row['median_error_m']:.3f} m "
                    f"({row['sim_per_wall']} sim s/wall s, {row['wall_s']} s)",
                    flush=True,
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())
