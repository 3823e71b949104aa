"""Benchmark: does a 2 x 2 array of the paper's modules carry objects across 1 x 1 m better than one 1 x 1 m module?

Run: python3 benchmarks/experiments/array_vs_module.py [--trials 24] [--objects sphere,cube,bunny] [--seed 11]
     [--fidelity 11:0.002] [--duration 20] [--jobs 2] [--out out/array_vs_module]
Two rigs cover the same 1 x 1 m, on the same fabric mesh spacing, with the firmware in the loop:
- array: protocol/rigs/array_2x2.toml, four 0.5 m modules on 9 actuators, its own build (mantaray-vmcu-array_2x2):
  the object's module drives it by the paper's transform, every other actuator on that plane, and the firmware routes
  it module by module (x first, then y) with a hand-over at each shared edge;
- module: one 1 x 1 m module on its 4 corner actuators, the one-module build configured for m = n = 1 m, driven by the
  paper's controller (its tilt limit the steepest that keeps the corners in range, atan(0.25 / 1) = 14.0 deg).
Every trial starts in one module (uniform within START_HALF_M of its centre) and has its target in another (uniform
within TARGET_HALF_M of that one's centre), drawn from (--seed, object, k) alone, so both rigs run the same trials
(paired). Each object runs the paper's Manhattan gains at its Fig. 3 alpha (sphere 0, cube 0.1, bunny 0.05).
--fidelity RESOLUTION:STEP is one module's vertices per side and the physics step: the array's sheet has
2 x (RESOLUTION - 1) + 1 a side, and the big module's the same, so their vertices are equally far apart. The default is
the fast mode (11 x 11 a module, 2 ms): the one-module reference (15 x 15, 0.5 ms) runs at 0.16 simulated s per wall
s on the array here, too slow for this many trials on 2 cores; its numbers are provisional as every fast-mode number.
--array-tilt-limit DEG runs the array at the big module's gentler tilt limit (14.04 deg: --array-tilt-limit 14.036).
--array-others level measures the first design: the actuators outside the driven module held level (0) instead of
on its plane (the simulated carriages take 0 for them; the firmware, its route and its corners are the same).
--speed instead measures how fast each rig simulates, in this one process, one after the other: the paper's 0.5 m
module, the array and the 1 m module each run the same three trials (starts and targets within 0.2 m of the
centre, so that each stays on every rig), and it prints simulated seconds per wall second and trials per wall
second side by side (compare rows of one run only).
Per trial it appends a line to OUT/results.jsonl (a rerun skips the trials there: interrupt and rerun to resume) and
prints it; at the end it prints per rig and object: success (within epsilon at T), reached (within epsilon at any
frame), median time to reach, median final error of successes, falls, the array's hand-overs and how its failed trials
failed, and trials per wall second of each rig in this run; and it writes OUT/array_vs_module.png (rates by rig and
object) and OUT/success_by_target.png (success by target cell over the 1 x 1 m workspace, each rig), each name with the
array's variant after it where it is not the default.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import dataclasses
import json
import math
import re
import sys
import time
from pathlib import Path

import numpy as np

from mantaray.host.link import Link
from mantaray.host.transport import InProcessTransport
from mantaray.protocol import messages as m
from mantaray.protocol import rig as rig_description
from mantaray.sim.evaluation.fidelity import parse_fidelity
from mantaray.sim.evaluation.findings import FIG3_ALPHA_M
from mantaray.sim.evaluation.paired import discordance
from mantaray.sim.model.objects import OBJECTS
from mantaray.sim.model.plant import Plant
from mantaray.sim.model.rig import Rig
from mantaray.sim.trial.bridge import Bridge, TrialSpec

ARRAY = rig_description.named("array_2x2")
GRID = ARRAY.grid  # the 2 x 2 array: the workspace both rigs cover
RIGS = ("array", "module")
START_HALF_M = 0.15  # [m] starts are uniform within this of their module's centre in x and y
TARGET_HALF_M = 0.2  # [m] targets the same about theirs: the paper's hardware targets, [-0.2, 0.2] about a centre
CELLS = 4  # [-] per side of the success-by-target map over the 1 x 1 m workspace
ROLL_BACK_S = 2.0  # [s] a hand-over followed by a fall within this is a fall at the hand-over
PLANT = "polyester"


@dataclasses.dataclass(frozen=True)
class Case:
    """One trial: the object, its number k, and where it starts and aims (the same for both rigs)."""

    object_name: str
    k: int
    start_m: tuple[float, float]
    target_m: tuple[float, float]
    seed: int


def cases(objects: list[str], trials: int, seed: int) -> list[Case]:
    """trials per object: start module, target module (another) and the points in them, from (seed, object, k)."""
    out = []
    for o, name in enumerate(objects):
        for k in range(trials):
            rng = np.random.default_rng([seed, o, k])
            start_module, target_module = (int(v) for v in rng.choice(GRID.module_count, 2, replace=False))
            sx, sy = GRID.module_centre(start_module)
            tx, ty = GRID.module_centre(target_module)
            start = (
                float(sx + rng.uniform(-START_HALF_M, START_HALF_M)),
                float(sy + rng.uniform(-START_HALF_M, START_HALF_M)),
            )
            target = (
                float(tx + rng.uniform(-TARGET_HALF_M, TARGET_HALF_M)),
                float(ty + rng.uniform(-TARGET_HALF_M, TARGET_HALF_M)),
            )
            out.append(Case(name, k, start, target, int(rng.integers(1, 2**31))))
    return out


def simulated_rig(which: str, object_name: str, resolution: int, timestep_s: float) -> Rig:
    """The array, or one module as large as the array whose sheet has the array's vertices, vertex masses and edges."""
    rig = Plant(PLANT).rig(object_name, resolution=resolution, timestep_s=timestep_s)
    if which == "array":
        return rig.with_description(ARRAY)
    f = rig.fabric
    wide = 2 * (resolution - 1) + 1  # [vertices per side] the array's sheet
    fabric = dataclasses.replace(
        f,
        size_m=2 * f.size_m,
        resolution=wide,
        mass_kg=4 * f.mass_kg,  # the same cloth: four modules' area
        # the edges' time constant goes as 1 / resolution on a sheet of one size (Fabric.edge_timeconst_s); this sheet's
        # edges and vertices are the array's, so they get the time constant they have there
        edge_solref=(f.edge_solref[0] * wide / resolution, f.edge_solref[1]),
    )
    module = dataclasses.replace(rig.module, size_x_m=2 * rig.module.size_x_m, size_y_m=2 * rig.module.size_y_m)
    return dataclasses.replace(rig, fabric=fabric, module=module)


class Variant(Bridge):
    """The bridge with the actuators outside the driven module held level (--array-others level)."""

    level = False

    def _commands(self, reply: m.Telemetry) -> np.ndarray:
        commands = super()._commands(reply)
        if self.level:
            driven = list(self.rig.module.grid.module_corners(reply.module))
            commands = np.where(np.isin(np.arange(len(commands)), driven), commands, 0.0)
        return commands


_bridges: dict = {}  # (rig, object, fidelity, hand-over) -> Bridge, one per worker process


DEFAULT_VARIANT = "the firmware's"  # the array as its firmware drives it


def variant(which: str, array_tilt_limit_deg: float | None, others: str = "plane") -> str:
    """What else than the rig and the trial decides an outcome: the array's tilt limit and other actuators (none for
    the module, which runs the paper's controller as it is)."""
    if which == "module":
        return ""
    parts = ([] if array_tilt_limit_deg is None else [f"tilt limit {array_tilt_limit_deg:g} deg"]) + (
        [] if others == "plane" else [f"others {others}"]
    )
    return ", ".join(parts) or DEFAULT_VARIANT


def run_trial(
    which: str,
    case: Case,
    resolution: int,
    timestep_s: float,
    duration_s: float,
    array_tilt_limit_deg: float | None,
    others: str = "plane",
) -> dict:
    key = (which, case.object_name, resolution, timestep_s, others)
    if key not in _bridges:
        rig = simulated_rig(which, case.object_name, resolution, timestep_s)
        description = ARRAY if which == "array" else rig_description.default()
        link = Link(InProcessTransport(True, build=rig.module.build), description=description)
        bridge = _bridges[key] = Variant(link, rig, Plant(PLANT).tracking())
        bridge.level = which == "array" and others == "level"
    bridge = _bridges[key]
    spec = TrialSpec(
        case.start_m,
        case.target_m,
        duration_s=duration_s,
        alpha_m=FIG3_ALPHA_M[case.object_name],
        seed=case.seed,
        gain_scale=Plant(PLANT).gain_scale,
        settings=(("configure.tilt_limit", array_tilt_limit_deg),)
        if which == "array" and array_tilt_limit_deg is not None
        else (),
    )
    started = time.perf_counter()
    result = bridge.run(spec)
    return {
        "rig": which,
        "object": case.object_name,
        "k": case.k,
        "start_m": list(case.start_m),
        "target_m": list(case.target_m),
        "success": bool(result.success),
        "reached_s": result.time_to_reach_s,
        "final_error_m": round(result.final_error_m, 5),
        "fell_off": bool(result.fell_off),
        "sim_time_s": round(result.sim_time_s, 3),
        "wall_s": round(time.perf_counter() - started, 3),
        "modules": [int(v) for v in result.module[result.module >= 0][[0, -1]]] if (result.module >= 0).any() else [],
        "final_xy_m": [round(float(v), 5) for v in result.final_xy_m],
        "peak_speed_m_per_s": round(peak_speed_m_per_s(result.t_s, result.true_xy_m), 4),
        "handover_s": [float(t) for t in result.t_s[result.handover_rows]],
        "handovers": result.handovers,
        "variant": variant(which, array_tilt_limit_deg, others),
    }


def speed(resolution: int, timestep_s: float, duration_s: float) -> None:
    """Simulated s and trials per wall s of the paper's module, the array and the big module, in this process."""
    rng = np.random.default_rng(0)
    trials = [(tuple(rng.uniform(-0.2, 0.2, 2)), tuple(rng.uniform(-0.2, 0.2, 2))) for _ in range(3)]
    print(f"{'rig':28s} {'sim s/wall s':>12s} {'trials/wall s':>13s}", flush=True)
    for which, label in (
        ("paper", "one 0.5 m module (4)"),
        ("array", "2 x 2 array (9)"),
        ("module", "one 1 m module (4)"),
    ):
        if which == "paper":
            rig = Plant(PLANT).rig("sphere", resolution=resolution, timestep_s=timestep_s)
        else:
            rig = simulated_rig(which, "sphere", resolution, timestep_s)
        description = ARRAY if which == "array" else rig_description.default()
        bridge = Bridge(Link(InProcessTransport(True, build=rig.module.build), description=description), rig)
        started, simulated = time.perf_counter(), 0.0
        for start, target in trials:
            simulated += bridge.run(TrialSpec(start, target, duration_s=duration_s)).sim_time_s
        wall = time.perf_counter() - started
        print(f"{label:28s} {simulated / wall:12.3f} {len(trials) / wall:13.4f}", flush=True)


def peak_speed_m_per_s(t_s: np.ndarray, xy_m: np.ndarray) -> float:
    """[m/s] The object's fastest between two camera frames (its true positions)."""
    if len(t_s) < 2:
        return 0.0
    return float(np.max(np.hypot(*np.diff(xy_m, axis=0).T) / np.diff(t_s)))


def failure(record: dict) -> str | None:
    """How an array's trial failed, or None for a success: fell at a hand-over (within ROLL_BACK_S after one), fell
    elsewhere, handed back (more hand-overs than the route has shared edges), stuck short of the target's module,
    or in the target's module but not within epsilon at T."""
    if record["success"]:
        return None
    if record["fell_off"]:
        end = record["sim_time_s"]
        return "fell at a hand-over" if any(end - t <= ROLL_BACK_S for t in record["handover_s"]) else "fell elsewhere"
    target_module = GRID.module_at(*record["target_m"])
    if record["handovers"] > _module_steps(GRID.module_at(*record["start_m"]), target_module):
        return "handed back"
    if GRID.module_at(*record["final_xy_m"]) != target_module:
        return "short of the target's module"
    return "in the target's module, not within epsilon at T"


def _module_steps(a: int, b: int) -> int:
    """Hand-overs on the route from module a to module b: one per shared edge crossed, x first, then y."""
    return abs(a % GRID.modules_x - b % GRID.modules_x) + abs(a // GRID.modules_x - b // GRID.modules_x)


def summarise(records: list[dict], objects: list[str]) -> dict:
    out = {}
    for which in RIGS:
        for name in objects:
            rs = [r for r in records if r["rig"] == which and r["object"] == name]
            if not rs:
                continue
            ok = [r for r in rs if r["success"]]
            reached = [r["reached_s"] for r in rs if r["reached_s"] is not None]
            kinds: dict[str, int] = {}
            for r in rs:
                if (why := failure(r)) is not None:
                    kinds[why] = kinds.get(why, 0) + 1
            out[(which, name)] = {
                "trials": len(rs),
                "success": len(ok),
                "reached": len(reached),
                "median_reach_s": float(np.median(reached)) if reached else math.nan,
                "median_error_cm": float(np.median([r["final_error_m"] for r in ok]) * 100) if ok else math.nan,
                "falls": sum(r["fell_off"] for r in rs),
                "handovers": sum(r["handovers"] for r in rs),
                "median_peak_speed_m_per_s": float(np.median([r["peak_speed_m_per_s"] for r in rs])),
                "failures": kinds,
                "trials_per_wall_s": len(rs) / sum(r["wall_s"] for r in rs),
            }
    return out


def paired(records: list[dict]) -> None:
    """Every object's trials pooled, the array against the module on the same trials: each rule's count on both, and
    McNemar's exact test on the trials where they differ (sim/evaluation/paired.py)."""
    by_rig = {which: {(r["object"], r["k"]): r for r in records if r["rig"] == which} for which in RIGS}
    both = sorted(set(by_rig["array"]) & set(by_rig["module"]))
    if not both:
        return
    rules = {
        "success": lambda r: r["success"],
        "reached": lambda r: r["reached_s"] is not None,
        "fell": lambda r: r["fell_off"],
    }
    for rule, holds in rules.items():
        a = [holds(by_rig["array"][key]) for key in both]
        b = [holds(by_rig["module"][key]) for key in both]
        d = discordance(a, b)
        ratio = f"{sum(a) / sum(b):.2f}x" if sum(b) else "inf"
        print(
            f"all objects, {rule}: array {sum(a)}/{len(both)}, module {sum(b)}/{len(both)} ({ratio}); "
            f"array alone {d.only_a}, module alone {d.only_b}, McNemar p = {d.p_two_sided:.3g}"
        )


def figures(records: list[dict], summary: dict, objects: list[str], out: Path, variant_name: str) -> list[Path]:
    """The rates by rig and object, and success by target cell; their names carry the array's variant (none for the
    firmware's own: the paper's tilt limit, the others on the plane)."""
    suffix = (
        "" if variant_name == DEFAULT_VARIANT else "_" + re.sub(r"[^a-z0-9.]+", "_", variant_name.lower()).strip("_")
    )
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6))
    width = 0.38
    x = np.arange(len(objects))
    for ax, (label, key) in zip(
        axes, (("success (within ε at T)", "success"), ("reached ε", "reached"), ("fell off", "falls")), strict=True
    ):
        for i, which in enumerate(RIGS):
            share = [
                summary[(which, o)][key] / summary[(which, o)]["trials"] if (which, o) in summary else 0
                for o in objects
            ]
            ax.bar(x + (i - 0.5) * width, share, width, label=which)
        ax.set_xticks(x, objects)
        ax.set_ylim(0, 1)
        ax.set_title(label, fontsize=10)
    axes[0].legend(fontsize=8)
    fig.suptitle(f"2 × 2 array (9 actuators; {variant_name}) vs one 1 × 1 m module (4): the same trials", fontsize=10)
    fig.tight_layout()
    rates = out / f"array_vs_module{suffix}.png"
    fig.savefig(rates, dpi=120)
    plt.close(fig)

    fig, axes = plt.subplots(1, 2, figsize=(8.4, 4.0))
    hx, hy = GRID.half_extent_m
    for ax, which in zip(axes, RIGS, strict=True):
        counts, wins = np.zeros((CELLS, CELLS)), np.zeros((CELLS, CELLS))
        for r in records:
            if r["rig"] != which:
                continue
            ix = min(int((r["target_m"][0] + hx) / (2 * hx) * CELLS), CELLS - 1)
            iy = min(int((r["target_m"][1] + hy) / (2 * hy) * CELLS), CELLS - 1)
            counts[iy, ix] += 1
            wins[iy, ix] += r["success"]
        share = np.where(counts > 0, wins / np.maximum(counts, 1), np.nan)
        image = ax.imshow(share, origin="lower", extent=(-hx, hx, -hy, hy), vmin=0, vmax=1, cmap="viridis")
        for iy in range(CELLS):
            for ix in range(CELLS):
                if counts[iy, ix]:
                    cx, cy = -hx + (ix + 0.5) * 2 * hx / CELLS, -hy + (iy + 0.5) * 2 * hy / CELLS
                    ax.text(
                        cx,
                        cy,
                        f"{int(wins[iy, ix])}/{int(counts[iy, ix])}",
                        ha="center",
                        va="center",
                        fontsize=7,
                        color="w",
                    )
        ax.axvline(0, color="w", lw=0.8, ls="--")
        ax.axhline(0, color="w", lw=0.8, ls="--")
        ax.set_title(f"{which}: success by target cell\n({', '.join(objects)})", fontsize=10)
        ax.set_xlabel("target x [m]")
    axes[0].set_ylabel("target y [m]")
    fig.colorbar(image, ax=axes, shrink=0.8, label="success share")
    cells = out / f"success_by_target{suffix}.png"
    fig.savefig(cells, dpi=120)
    plt.close(fig)
    return [rates, cells]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=24, help="trials per object (each run on both rigs)")
    parser.add_argument("--objects", default="sphere,cube,bunny", help="comma-separated, of: " + ", ".join(OBJECTS))
    parser.add_argument("--seed", type=int, default=11)
    parser.add_argument("--fidelity", default="11:0.002", help="one module's RESOLUTION:STEP [-:s]")
    parser.add_argument("--duration", type=float, default=20.0, help="T [s]: twice the paper's, for twice its span")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes")
    parser.add_argument("--out", type=Path, default=Path("out/array_vs_module"))
    parser.add_argument("--rigs", default="array,module", help="comma-separated, of: " + ", ".join(RIGS))
    parser.add_argument("--speed", action="store_true", help="measure each rig's simulation speed instead (above)")
    parser.add_argument(
        "--array-others", choices=("plane", "level"), default="plane", help="the array's other actuators (see above)"
    )
    parser.add_argument(
        "--array-tilt-limit", type=float, metavar="DEG", help="the array's tilt limit (default: the paper's 26.57 deg)"
    )
    args = parser.parse_args()
    objects, rigs = args.objects.split(","), args.rigs.split(",")
    unknown = [o for o in objects if o not in OBJECTS] + [r for r in rigs if r not in RIGS]
    if unknown or not 1 <= args.trials <= 1000 or not 1 <= args.jobs <= 64 or not 0 < args.duration <= 600:
        parser.error(
            f"objects of {', '.join(OBJECTS)}, rigs of {', '.join(RIGS)}, trials 1..1000, jobs 1..64, duration (0, 600] s"
        )
    try:
        fidelity = parse_fidelity(args.fidelity)
    except ValueError as exc:
        parser.error(f"--fidelity: {exc}")
    if args.speed:
        speed(fidelity.resolution, fidelity.timestep_s, args.duration)
        return 0
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "results.jsonl"
    done = {}
    if path.exists():
        for line in path.read_text().splitlines():
            r = json.loads(line)
            done[(r["rig"], r["object"], r["k"], r["variant"])] = r
    wanted = {w: variant(w, args.array_tilt_limit, args.array_others) for w in RIGS}
    todo = [
        (w, c)
        for c in cases(objects, args.trials, args.seed)
        for w in rigs
        if (w, c.object_name, c.k, wanted[w]) not in done
    ]
    print(
        f"{len(done)} trials in {path} already, {len(todo)} to run; {fidelity.label} a module, T = {args.duration:g} s, "
        f"{args.jobs} workers",
        flush=True,
    )
    with path.open("a") as results, concurrent.futures.ProcessPoolExecutor(args.jobs) as pool:
        futures = [
            pool.submit(
                run_trial,
                w,
                c,
                fidelity.resolution,
                fidelity.timestep_s,
                args.duration,
                args.array_tilt_limit,
                args.array_others,
            )
            for w, c in todo
        ]
        try:
            for n, future in enumerate(concurrent.futures.as_completed(futures), 1):
                r = future.result()
                results.write(json.dumps(r) + "\n")
                results.flush()
                done[(r["rig"], r["object"], r["k"], r["variant"])] = r
                print(f"[{n}/{len(todo)}] {json.dumps(r)}", flush=True)
        except KeyboardInterrupt:
            for f in futures:
                f.cancel()
            print(
                f"interrupted: {n - 1 if 'n' in locals() else 0} new trials kept in {path}; rerun to go on",
                file=sys.stderr,
            )
            return 130
    print(f"array: {wanted['array']}; module: the paper's controller")
    records = [
        r for r in done.values() if r["object"] in objects and r["k"] < args.trials and r["variant"] == wanted[r["rig"]]
    ]
    summary = summarise(records, objects)
    for (which, name), s in summary.items():
        print(
            f"{which:6s} {name:7s}: success {s['success']}/{s['trials']}, reached {s['reached']}/{s['trials']}, "
            f"median time to reach {s['median_reach_s']:.1f} s, median error of successes {s['median_error_cm']:.2f} cm, "
            f"falls {s['falls']}, median peak speed {s['median_peak_speed_m_per_s']:.2f} m/s, hand-overs "
            f"{s['handovers']}, failures {s['failures']}, "
            f"{s['trials_per_wall_s']:.3f} trials/wall s"
        )
    for name in objects:
        a, m = summary.get(("array", name)), summary.get(("module", name))
        if a and m:
            ratio = {key: (a[key] / m[key] if m[key] else math.inf) for key in ("success", "reached")}
            print(
                f"{name}: array / module success {ratio['success']:.2f}x, reached {ratio['reached']:.2f}x; falls {a['falls']} vs {m['falls']}"
            )
    paired(records)
    for figure in figures(records, summary, objects, args.out, wanted["array"]):
        print(f"figure {figure}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
