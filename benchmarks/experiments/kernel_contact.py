"""Benchmark: how the kernel contact's width sets where an object rests, on two meshes, against the flex's own contact.

Run: python3 benchmarks/experiments/kernel_contact.py [--object sphere] [--meshes reference,finer]
     [--widths 0.04,0.08,0.12] [--drops 12] [--seed 5] [--plant polyester] [--set KEY=VALUE ...]
The sweep behind contact.kernel_width_m (sim/model/plant.toml; sim/README.md, Convergence 9). The drops are
rest_positions.py's (the same points from the same seed, the same rule for at rest). For each width h [m] the object
meets the sheet through the kernel contact (contact.model kernel, sim/model/kernel_contact.py) with that support radius,
and the run prints the rest positions on each mesh, their gap to the finest mesh's (median, largest, within 1 cm),
and the wall time of each mesh against the flex's own contact (contact.model mesh) on it, measured in the same run.
The kernel contact wants the sheet free to stretch between vertices: pass --set fabric.stretch=threads.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # rest_positions.py's drops and their comparison

from rest_positions import plant_meshes_drops, print_gaps, rest_positions  # noqa: E402

from mantaray.sim.model import model as M
from mantaray.sim.model.objects import OBJECTS  # noqa: E402
from mantaray.sim.model.parameters import ParameterError, plant_names  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--plant", default="polyester", help="one of: " + ", ".join(plant_names()))
    parser.add_argument("--object", choices=sorted(OBJECTS), default="sphere")
    parser.add_argument("--drops", type=int, default=12, help="drop points, drawn from --seed")
    parser.add_argument("--seed", type=int, default=5)
    parser.add_argument("--meshes", default="reference,finer", help="as rest_positions.py's: the last is the finest")
    parser.add_argument("--widths", default="0.04,0.08,0.12", help="[m] kernel support radii, comma-separated")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a plant value; repeatable")
    args = parser.parse_args()
    plant, meshes, drops = plant_meshes_drops(parser, args)
    try:
        kernels = [
            plant.set({"contact.model": "kernel", "contact.kernel_width_m": float(w)}) for w in args.widths.split(",")
        ]
    except (ParameterError, ValueError) as exc:
        parser.error(str(exc))
    mesh_plant = plant.set({"contact.model": "mesh"})
    print(f"{args.object} on {args.plant} {' '.join(args.set)}: {args.drops} drops, seed {args.seed}", flush=True)
    try:
        sweep(kernels, args.widths.split(","), mesh_plant, args.object, meshes, drops)
    except M.SimulationUnstable as exc:
        print(f"diverged: {exc}", file=sys.stderr)
        return 1
    return 0


def sweep(kernels, widths, mesh_plant, object_name, meshes, drops) -> None:
    """Print each width's rests on each mesh, their gaps and wall times against the flex's own contact's."""
    native_s = {m.label: rest_positions(mesh_plant, object_name, m, drops)[1] for m in meshes}
    for kernel, width in zip(kernels, widths, strict=True):
        print(f"h = {float(width) * 100:g} cm:", flush=True)
        rests = {}
        for mesh in meshes:
            rests[mesh.label], wall_s = rest_positions(kernel, object_name, mesh, drops)
            at_rest = [
                f"({r[0] * 100:+.1f}, {r[1] * 100:+.1f})" if r is not None else "moving" for r in rests[mesh.label]
            ]
            print(
                f"  {mesh.label}: {wall_s:.0f} s wall ({wall_s / native_s[mesh.label]:.1f}x the flex's own contact's); "
                f"rests [cm] {' '.join(at_rest)}",
                flush=True,
            )
        print_gaps(rests, meshes, indent="  ")


if __name__ == "__main__":
    sys.exit(main())
