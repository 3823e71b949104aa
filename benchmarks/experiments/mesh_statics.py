"""Benchmark: what the bare sheet settles to on each mesh (its sag and its edges' stretch), to tell mesh from plant.

Run: python3 benchmarks/experiments/mesh_statics.py [--plants polyester,paper] [--meshes 11:0.001,15:0.001,21:0.001]
     [--clamps plant,0] [--stretch edges,threads] [--set KEY=VALUE ...]
For each plant, corner clamp (the plant's own, or a length in metres), stretch model (sim/model/plant.toml,
fabric.stretch) and mesh (RESOLUTION:TIMESTEP, or a named fidelity), with any other --set value fixed over the
plant, it loads the model, lets the bare sheet settle as every trial does (sim/model/model.py, load), and prints the
lowest vertex's depth below the corners and the sheet's mean depth [mm], the edges' (or threads') least, mean and
largest strain [%] (a thread pulls only when stretched: one shorter than its rest length is slack), the wall time
of compiling the model and settling it (2 s simulated; compare rows of one run), and the time constant MuJoCo is
given for the edges or threads on that mesh (sim/model/rig.py, Fabric.edge_timeconst_s), marking one it runs longer
than given (refsafe: two steps at least). A mesh whose physics diverges (threads under Euler need a smaller step on
a finer mesh: the bending is explicit) is reported as such.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from mantaray.sim.evaluation.fidelity import parse_fidelity
from mantaray.sim.model import model as M
from mantaray.sim.model.parameters import ParameterError
from mantaray.sim.model.plant import Plant, parse_setting
from mantaray.sim.model.rig import MIN_STEPS_PER_TIMECONST, STRETCH_MODELS, Fidelity


def statics(plant: Plant, fidelity: Fidelity) -> dict:
    rig = plant.rig(resolution=fidelity.resolution, timestep_s=fidelity.timestep_s)
    started = time.perf_counter()
    model, data = M.load(rig)
    wall_s = time.perf_counter() - started
    flex = M._flex_id(model)
    v = M.fabric_vertices(model, data)
    if rig.fabric.stretch == "threads":  # each thread's length against its rest length, its range's top
        strain = data.ten_length / model.tendon_range[:, 1] - 1
    else:
        adr, num = model.flex_edgeadr[flex], model.flex_edgenum[flex]
        edges = model.flex_edge[adr : adr + num]
        length = np.linalg.norm(v[edges[:, 0]] - v[edges[:, 1]], axis=1)
        rest = model.flexedge_length0[adr : adr + num]
        strain = (length - rest) / rest
    return {
        "sag_mm": (rig.module.z0_m - v[:, 2].min()) * 1000,
        "mean_depth_mm": (rig.module.z0_m - v[:, 2].mean()) * 1000,
        "strain_pct": (strain.min() * 100, strain.mean() * 100, strain.max() * 100),
        "edge_tau_ms": rig.fabric.edge_timeconst_s * 1000,
        "lengthened": rig.fabric.edge_timeconst_s < MIN_STEPS_PER_TIMECONST * fidelity.timestep_s,
        "load_s": wall_s,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--plants", default="polyester,paper")
    parser.add_argument("--meshes", default="11:0.001,15:0.001,21:0.001", help="RESOLUTION:TIMESTEP, comma-separated")
    parser.add_argument("--clamps", default="plant,0", help="comma-separated: plant (the plant's own) or metres")
    parser.add_argument("--stretch", default="edges", help=f"comma-separated: {', '.join(STRETCH_MODELS)}")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a plant value; repeatable")
    args = parser.parse_args()
    try:
        fixed = dict(parse_setting(text) for text in args.set)
    except ParameterError as exc:
        parser.error(str(exc))
    try:
        meshes = [parse_fidelity(m) for m in args.meshes.split(",")]
        clamps = [None if c == "plant" else float(c) for c in args.clamps.split(",")]
    except ValueError as exc:
        parser.error(f"--meshes are RESOLUTION:TIMESTEP and --clamps 'plant' or metres, comma-separated ({exc})")
    stretches = args.stretch.split(",")
    if not set(stretches) <= set(STRETCH_MODELS):
        parser.error(f"--stretch takes {', '.join(STRETCH_MODELS)}, comma-separated, got {args.stretch!r}")
    print(
        f"{'plant':>10s} {'stretch':>8s} {'clamp':>9s} {'mesh':>16s} {'sag [mm]':>9s} {'mean [mm]':>10s} "
        f"{'strain min / mean / max [%]':>28s} {'load [s]':>9s} {'tau [ms]':>9s}"
    )
    for name in args.plants.split(","):
        own = Plant(name).values["fabric.corner_clamp_m"]
        for stretch in stretches:
            for clamp in dict.fromkeys(own if c is None else c for c in clamps):  # each length once
                plant = Plant(name).set({**fixed, "fabric.corner_clamp_m": clamp, "fabric.stretch": stretch})
                for mesh in meshes:
                    head = f"{name:>10s} {stretch:>8s} {clamp * 100:7.2f} cm {mesh.label:>16s}"
                    try:
                        s = statics(plant, mesh)
                    except M.SimulationUnstable:
                        print(f"{head} diverged", flush=True)
                        continue
                    lo, mean, hi = s["strain_pct"]
                    print(
                        f"{head} {s['sag_mm']:9.1f} {s['mean_depth_mm']:10.1f} {lo:10.3f} / {mean:.3f} / {hi:.3f} "
                        f"{s['load_s']:9.2f} {s['edge_tau_ms']:9.2f}{' (run at 2 steps)' if s['lengthened'] else ''}",
                        flush=True,
                    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
