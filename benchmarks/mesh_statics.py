"""Benchmark: what the bare sheet settles to on each mesh (its sag and its edges' stretch), to tell mesh from plant.

Run: python3 benchmarks/mesh_statics.py [--plants polyester,paper] [--resolutions 11,15,21] [--clamps plant,0]
For each plant, mesh and corner clamp (the plant's own, or a length in metres) it loads the model at a 1 ms step,
lets the bare sheet settle as every trial does (sim/model.py, load), and prints the centre's sag below the corners
[mm], the edges' mean and largest strain [%], and the time constant MuJoCo is given for the edges on that mesh
(sim/rig.py, Fabric.edge_timeconst_s), marking one it runs longer than given (refsafe: two steps at least).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from mantaray.sim import model as M
from mantaray.sim.plant import Plant
from mantaray.sim.rig import MIN_STEPS_PER_TIMECONST

TIMESTEP_S = 0.001


def statics(plant: Plant, resolution: int) -> dict:
    rig = plant.rig(resolution=resolution, timestep_s=TIMESTEP_S)
    model, data = M.load(rig)
    flex = M._flex_id(model)
    v = M.fabric_vertices(model, data)
    adr, num = model.flex_edgeadr[flex], model.flex_edgenum[flex]
    edges = model.flex_edge[adr : adr + num]
    length = np.linalg.norm(v[edges[:, 0]] - v[edges[:, 1]], axis=1)
    rest = model.flexedge_length0[adr : adr + num]
    strain = (length - rest) / rest
    return {
        "sag_mm": (rig.frame.z0_m - v[:, 2].min()) * 1000,
        "mean_strain_pct": strain.mean() * 100,
        "max_strain_pct": strain.max() * 100,
        "edge_tau_ms": rig.fabric.edge_timeconst_s * 1000,
        "lengthened": rig.fabric.edge_timeconst_s < MIN_STEPS_PER_TIMECONST * TIMESTEP_S,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--plants", default="polyester,paper")
    parser.add_argument("--resolutions", default="11,15,21")
    parser.add_argument("--clamps", default="plant,0", help="comma-separated: plant (the plant's own) or metres")
    args = parser.parse_args()
    try:
        resolutions = [int(r) for r in args.resolutions.split(",")]
        clamps = [None if c == "plant" else float(c) for c in args.clamps.split(",")]
    except ValueError:
        parser.error("--resolutions are whole numbers and --clamps 'plant' or metres, comma-separated")
    print(
        f"{'plant':>10s} {'clamp':>9s} {'mesh':>8s} {'sag [mm]':>9s} {'strain mean / max [%]':>22s} "
        f"{'edge tau [ms]':>14s}"
    )
    for name in args.plants.split(","):
        own = Plant(name).values["fabric.corner_clamp_m"]
        for clamp in dict.fromkeys(own if c is None else c for c in clamps):  # each length once
            plant = Plant(name).set({"fabric.corner_clamp_m": clamp})
            for n in resolutions:
                s = statics(plant, n)
                print(
                    f"{name:>10s} {plant.values['fabric.corner_clamp_m'] * 100:7.2f} cm {n:>3d} x {n:<3d} "
                    f"{s['sag_mm']:9.1f} {s['mean_strain_pct']:11.3f} / {s['max_strain_pct']:.3f} "
                    f"{s['edge_tau_ms']:11.2f}{' (run at 2 steps)' if s['lengthened'] else ''}",
                    flush=True,
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())
