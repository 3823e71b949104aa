"""Benchmark: bystander displacement on the 2 x 2 array: how far a still object is moved while its neighbour is steered.

Run: python3 benchmarks/experiments/bystander.py [--pairs 12] [--seed 41] [--objects sphere,cube] [--plant paper]
     [--fidelity 15:0.001] [--set KEY=VALUE ...] [--duration 10]
     [--jobs 2] [--out out/bystander]
The rig is protocol/rigs/array_2x2.toml (four 0.5 m modules on 9 shared actuators, the firmware in the loop, in
process). Object 0 (the first of --objects) is steered in module 0 (x, y < 0) by the paper's Manhattan; object 1,
the bystander, lies in module 1 (x > 0, y < 0), which shares module 0's edge x = 0 and its two actuators there. Each
pair is two trials on the same starts and seed (drawn from --seed and the pair's number): "moved", object 0 steered
from one side of its module across to the other (start and target 0.15 m either side of its centre along x, within
0.05 m in y), and "held", object 0 steered to its own start. The plant is --plant with the reference candidate's
values (threads, the kernel contact: sim/README.md, Convergence 9) unless --set gives others; --fidelity is one
module's mesh and step, the candidate's by default, so the numbers are provisional until the reference is settled. The bystander's displacement [m] is its distance at the
end of T from where it was at t = 1 s (after the drop has settled), and the largest during the rest of the trial;
what the neighbour's motion moves it is the pair's difference, moved minus held. Today's firmware drives the
actuators of the object's module and puts every other actuator on the same plane (PROTOCOL.md §5): it knows one
object and compensates nothing, so this is the uncompensated side of the follow-up paper's comparison (its
compensation cut the displacement by 59 to 78 %). Per pair it appends a line to OUT/results.jsonl (a rerun skips the
pairs there: interrupt and rerun to resume) and prints it; at the end it prints the medians and the paired
difference with a bootstrap 90 % interval (also to OUT/summary.txt), and writes OUT/bystander.png (the displacement of each pair, held
against moved).
"""

from __future__ import annotations

import argparse
import concurrent.futures
import json
import sys
from pathlib import Path

import numpy as np

from mantaray.host.link import Link
from mantaray.host.transport import InProcessTransport
from mantaray.protocol import rig as rig_description
from mantaray.sim.evaluation.fidelity import parse_fidelity
from mantaray.sim.evaluation.paired import mean_interval
from mantaray.sim.evaluation.results_file import write_whole
from mantaray.sim.model.objects import OBJECTS
from mantaray.sim.model.parameters import ParameterError, plant_names
from mantaray.sim.model.plant import Plant, parse_setting
from mantaray.sim.trial.bridge import Bridge, TrialSpec

ARRAY = rig_description.named("array_2x2")
CENTRE_0_M = (-0.25, -0.25)  # [m] module 0's centre: the steered object's
CENTRE_1_M = (0.25, -0.25)  # [m] module 1's: the bystander's
ACROSS_M = 0.15  # [m] the steered object starts and ends this far either side of its module's centre along x
SPREAD_M = 0.05  # [m] starts are uniform within this of their line (y) and, for the bystander, of its centre
SETTLED_S = 1.0  # [s] the bystander's displacement counts from where it lies at this trial time
CANDIDATE = (("fabric.stretch", "threads"), ("contact.model", "kernel"))  # the reference candidate's plant values


def pair_specs(seed: int, k: int, duration_s: float) -> dict[str, TrialSpec]:
    """Pair k's two trials: the same starts and seed, object 0 moved across its module or held at its start."""
    rng = np.random.default_rng([seed, k])
    side = 1.0 if rng.random() < 0.5 else -1.0  # which way across
    y0 = CENTRE_0_M[1] + rng.uniform(-SPREAD_M, SPREAD_M)
    start = (CENTRE_0_M[0] - side * ACROSS_M, float(y0))
    target = (CENTRE_0_M[0] + side * ACROSS_M, float(y0 + rng.uniform(-SPREAD_M, SPREAD_M)))
    bystander = tuple(float(c + rng.uniform(-SPREAD_M, SPREAD_M)) for c in CENTRE_1_M)
    common = dict(duration_s=duration_s, seed=int(rng.integers(1, 2**31)), others_start_m=(bystander,))
    return {"moved": TrialSpec(start, target, **common), "held": TrialSpec(start, start, **common)}


def displacement(result) -> tuple[float, float]:
    """The bystander's displacement [m] at the end from where it lay at SETTLED_S, and the largest after SETTLED_S."""
    after = result.t_s >= SETTLED_S
    path = result.others_xy_m[after, 0]
    if not len(path):
        return float("nan"), float("nan")
    moved = np.hypot(*(path - path[0]).T)
    return float(np.hypot(*(result.others_final_xy_m[0] - path[0]))), float(moved.max())


def run_pair(args_tuple) -> dict:
    """Pair k on its own bridge (a worker's): both trials and what they did to the bystander."""
    rig, tracking, seed, k, duration_s = args_tuple
    bridge = Bridge(Link(InProcessTransport(True, build=ARRAY.name), description=ARRAY), rig, tracking)
    line = {"pair": k}
    for name, spec in pair_specs(seed, k, duration_s).items():
        result = bridge.run(spec)
        end, largest = displacement(result)
        line[name] = {
            "displacement_m": round(end, 5),
            "largest_displacement_m": round(largest, 5),
            "bystander_fell_off": result.others_fell_off[0],
            "steered_final_error_m": round(result.final_error_m, 5),
            "steered_fell_off": result.fell_off,
            "sim_s_per_wall_s": round(result.sim_time_s / result.wall_time_s, 3),
        }
    return line


def _figure(lines: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    held = [100 * line["held"]["displacement_m"] for line in lines]
    moved = [100 * line["moved"]["displacement_m"] for line in lines]
    fig, ax = plt.subplots(figsize=(4.5, 4.5))
    ax.scatter(held, moved, s=18)
    top = max([*held, *moved, 1.0]) * 1.1
    ax.plot([0, top], [0, top], color="grey", lw=0.8, ls="--")
    ax.set(
        xlim=(0, top), ylim=(0, top), xlabel="held: neighbour kept still [cm]", ylabel="moved: neighbour steered [cm]"
    )
    ax.set_title("bystander displacement at T, per pair")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--pairs", type=int, default=12)
    parser.add_argument("--seed", type=int, default=41)
    parser.add_argument("--objects", default="sphere,cube", help="the steered object, then the bystander")
    parser.add_argument("--plant", default="paper", choices=plant_names())
    parser.add_argument("--fidelity", default="15:0.001", help="one module's vertices a side : the step [s]")
    parser.add_argument(
        "--set",
        action="append",
        type=parse_setting,
        metavar="KEY=VALUE",
        help="plant values fixed (default: the reference candidate's, "
        + ", ".join(f"{k}={v}" for k, v in CANDIDATE)
        + ")",
    )
    parser.add_argument("--duration", type=float, default=10.0, help="T [s]")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", default="out/bystander")
    args = parser.parse_args()
    args.set = list(CANDIDATE) if args.set is None else args.set
    names = args.objects.split(",")
    if len(names) != 2 or any(n not in OBJECTS for n in names):
        parser.error(f"--objects: two of {', '.join(OBJECTS)}, the steered one first; got {args.objects!r}")
    if args.pairs < 1 or args.jobs < 1:
        parser.error("--pairs and --jobs must be at least 1")
    try:
        fidelity = parse_fidelity(args.fidelity)
        plant = Plant(args.plant).set(dict(args.set))
        rig = plant.rig(resolution=fidelity.resolution, timestep_s=fidelity.timestep_s).with_description(ARRAY)
        rig = rig.with_objects(names)
        pair_specs(args.seed, 0, args.duration)  # a T the trial refuses, before any work
    except (ValueError, ParameterError) as exc:
        parser.error(str(exc))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    results = out / "results.jsonl"
    done = (
        {json.loads(line)["pair"]: json.loads(line) for line in results.read_text().splitlines()}
        if results.exists()
        else {}
    )
    todo = [k for k in range(args.pairs) if k not in done]
    fixed = ", ".join(f"{k}={v}" for k, v in args.set) or "as declared"
    header = (
        f"bystander: {names[0]} steered in module 0, {names[1]} still in module 1; {args.plant} ({fixed}), "
        f"{fidelity.resolution} x {fidelity.resolution} a module at {fidelity.timestep_s * 1e3:g} ms, seed {args.seed}; "
        f"{len(done)} of {args.pairs} pairs done"
    )
    print(header, flush=True)
    work = [(rig, plant.tracking(), args.seed, k, args.duration) for k in todo]
    try:
        with concurrent.futures.ProcessPoolExecutor(args.jobs) as pool, results.open("a") as sink:
            for line in pool.map(run_pair, work):
                sink.write(json.dumps(line) + "\n")
                sink.flush()
                done[line["pair"]] = line
                print(json.dumps(line), flush=True)
    except KeyboardInterrupt:
        print(f"interrupted: {len(done)} pairs in {results}; the same command continues", file=sys.stderr)
        return 130
    lines = [done[k] for k in sorted(done) if k < args.pairs]
    held = np.array([line["held"]["displacement_m"] for line in lines])
    moved = np.array([line["moved"]["displacement_m"] for line in lines])
    interval = mean_interval(moved - held, level=0.90, seed=args.seed)
    estimate, low, high = interval.mean, interval.low, interval.high
    summary = (
        f"{len(lines)} pairs: bystander displacement at T, median held {np.median(held) * 100:.2f} cm, moved "
        f"{np.median(moved) * 100:.2f} cm; moved - held {estimate * 100:+.2f} cm [{low * 100:+.2f} .. {high * 100:+.2f}] "
        f"(mean, 90 % bootstrap); largest during the trial, median held "
        f"{np.median([line['held']['largest_displacement_m'] for line in lines]) * 100:.2f} cm, moved "
        f"{np.median([line['moved']['largest_displacement_m'] for line in lines]) * 100:.2f} cm; bystander fell off "
        f"{sum(line['moved']['bystander_fell_off'] for line in lines)} moved, "
        f"{sum(line['held']['bystander_fell_off'] for line in lines)} held"
    )
    print(summary)
    write_whole(out / "summary.txt", (header + "\n" + summary + "\n").encode())
    _figure(lines, out / "bystander.png")
    print(f"figure {out / 'bystander.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
