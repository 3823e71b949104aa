"""Benchmark: where an object dropped on the level sheet comes to rest, on each mesh: the loaded sheet's statics.

Run: python3 benchmarks/experiments/rest_positions.py [--plant polyester] [--object sphere] [--drops 12] [--seed 5]
     [--meshes 11:0.00025,15:0.00025,21:0.00025] [--set KEY=VALUE ...]
The bare sheet's sag converges with the mesh on threads (mesh_statics.py); this asks the same of the sheet with an
object on it, which is what a trial's outcome rests on. --drops points are drawn from --seed, uniformly over
|x|, |y| <= 0.15 m (the drop points do not depend on the mesh). On each mesh the object is dropped at each point on
the settled sheet with the actuators level (sim/model/model.py, place_object: at rest means slower than 1 cm/s and 0.5 rad/s
for 0.2 s, simulated; a drop still moving after 6 s is reported) and its rest position [cm] is printed; the last mesh
is the finest. Per coarser mesh it then prints
how far each rest position lies from the finest mesh's [mm] (median, largest) and in how many drops that distance
is within half the protocol's epsilon (1 cm). The wall time of each mesh (compile, settle, every drop) is printed
for comparing rows of one run only.
"""

from __future__ import annotations

import argparse
import sys
import time

import mujoco
import numpy as np

from mantaray.sim.evaluation.fidelity import parse_fidelity
from mantaray.sim.model import model as M
from mantaray.sim.model.objects import OBJECTS
from mantaray.sim.model.parameters import ParameterError, plant_names
from mantaray.sim.model.plant import Plant, parse_setting

DROP_HALF_WIDTH_M = 0.15  # [m] drops are uniform over |x|, |y| within this
SETTLE_MAX_S = 6.0  # [s, simulated] a drop still moving after this is reported as such
CLOSE_M = 0.01  # [m] half the protocol's epsilon


def rest_positions(plant: Plant, object_name: str, fidelity, drops: np.ndarray) -> tuple[list, float]:
    """Each drop's rest position [m] (None where the object fell or kept moving), and the wall time [s]."""
    rig = plant.rig(resolution=fidelity.resolution, timestep_s=fidelity.timestep_s, object_name=object_name)
    started = time.perf_counter()
    model, data = M.load(rig)
    key = model.key(M.REST_KEY).id
    out = []
    for x_m, y_m in drops:
        mujoco.mj_resetDataKeyframe(model, data, key)
        mujoco.mj_forward(model, data)
        try:
            M.place_object(model, data, float(x_m), float(y_m), rule=rig.fall, settle_max_s=SETTLE_MAX_S)
        except M.ObjectNotSettled:
            out.append(None)
            continue
        out.append(M.object_xy(model, data).copy())
    return out, time.perf_counter() - started


def print_gaps(rests: dict, meshes: list, indent: str = "") -> None:
    """Per coarser mesh, how far its rest positions lie from the finest mesh's [mm] (median, largest) and in how many
    drops that is within CLOSE_M; rests maps each mesh's label to rest_positions' list."""
    finest = meshes[-1].label
    for mesh in meshes[:-1]:
        pairs = [
            (a, b) for a, b in zip(rests[mesh.label], rests[finest], strict=True) if a is not None and b is not None
        ]
        if not pairs:
            print(f"{indent}{mesh.label} against {finest}: no drop at rest on both", flush=True)
            continue
        gap_m = np.array([np.hypot(*(a - b)) for a, b in pairs])
        print(
            f"{indent}{mesh.label} against {finest}: rest positions {np.median(gap_m) * 1000:.1f} mm apart (median), "
            f"{gap_m.max() * 1000:.1f} mm at most; within {CLOSE_M * 100:.0f} cm in {int((gap_m <= CLOSE_M).sum())} "
            f"of {len(pairs)} drops",
            flush=True,
        )


def plant_of(parser: argparse.ArgumentParser, args: argparse.Namespace) -> Plant:
    """The plant --plant names with --set's values over it; what is wrong with them is a usage error."""
    if args.plant not in plant_names():
        parser.error(f"--plant: unknown {args.plant!r}; known: {', '.join(plant_names())}")
    try:
        return Plant(args.plant).set(dict(parse_setting(text) for text in args.set))
    except (ParameterError, ValueError) as exc:
        parser.error(str(exc))


def plant_meshes_drops(parser: argparse.ArgumentParser, args: argparse.Namespace) -> tuple[Plant, list, np.ndarray]:
    """From --plant, --set, --meshes, --drops and --seed: the plant, the meshes (coarsest first) and the drop points
    [m]; what is wrong with them is a usage error."""
    if not 1 <= args.drops <= 1000:
        parser.error("--drops must be 1..1000")
    plant = plant_of(parser, args)
    try:
        meshes: list = []
        for text in args.meshes.split(","):
            meshes.append(parse_fidelity(text, meshes[-1] if meshes else None))
    except (ParameterError, ValueError) as exc:
        parser.error(str(exc))
    if len(meshes) < 2:
        parser.error("--meshes needs two at least: the last is compared with the others")
    drops = np.random.default_rng(args.seed).uniform(-DROP_HALF_WIDTH_M, DROP_HALF_WIDTH_M, size=(args.drops, 2))
    return plant, meshes, drops


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--plant", default="polyester", help="one of: " + ", ".join(plant_names()))
    parser.add_argument("--object", choices=sorted(OBJECTS), default="sphere")
    parser.add_argument("--drops", type=int, default=12, help="drop points, drawn from --seed")
    parser.add_argument("--seed", type=int, default=5)
    parser.add_argument(
        "--meshes",
        default="11:0.00025,15:0.00025,21:0.00025",
        help="fast, reference, RESOLUTION:TIMESTEP or finer (the one before it, 6 vertices a side finer at half the "
        "step), comma-separated, coarsest first: the last is the finest",
    )
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a plant value; repeatable")
    args = parser.parse_args()
    plant, meshes, drops = plant_meshes_drops(parser, args)
    print(f"{args.object} on {args.plant} {' '.join(args.set)}: {args.drops} drops, seed {args.seed}", flush=True)
    print(f"{'drop [cm]':>16s} " + " ".join(f"{m.label:>18s}" for m in meshes), flush=True)
    rests = {}
    for mesh in meshes:
        try:
            rests[mesh.label], wall_s = rest_positions(plant, args.object, mesh, drops)
        except M.SimulationUnstable as exc:
            print(f"{mesh.label}: diverged ({exc})", flush=True)
            return 1
        print(f"  {mesh.label}: {wall_s:.0f} s wall", flush=True)
    for i, (x_m, y_m) in enumerate(drops):
        cells = []
        for mesh in meshes:
            r = rests[mesh.label][i]
            cells.append(f"{'not at rest':>18s}" if r is None else f"({r[0] * 100:+6.1f}, {r[1] * 100:+6.1f})    ")
        print(f"({x_m * 100:+6.1f}, {y_m * 100:+6.1f}) " + " ".join(cells), flush=True)
    print_gaps(rests, meshes)
    return 0


if __name__ == "__main__":
    sys.exit(main())
