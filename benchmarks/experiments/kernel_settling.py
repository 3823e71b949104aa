"""Benchmark: whether an object on the kernel contact comes to rest at a given step, read from its speed over time.

Run: python3 benchmarks/experiments/kernel_settling.py [--object sphere] [--at 0.05,0.02] [--mesh fast]
     [--duration 6] [--every 0.5] [--plant polyester] [--set KEY=VALUE ...]
The object is placed at --at [m] on the settled level sheet (sim/model/model.py, place_object, given 0.05 s to settle so
that a contact which never settles still starts from the same state), then left for --duration s of simulated time;
its speed [mm/s] is printed every --every s, and its position at the end. The contact is the kernel's
(contact.model kernel) on threads unless --set says otherwise. This is how sim/README.md, Convergence 9, tells which
of the kernel contact's forces keeps an object moving at 1 and 2 ms: `--set contact.friction[0]=0.1` against
`--set contact.kernel_damping_ratio=0.25`.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import mujoco
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # rest_positions.py's plant from the arguments

from rest_positions import plant_of  # noqa: E402

from mantaray.sim.evaluation.fidelity import parse_fidelity  # noqa: E402
from mantaray.sim.model import model as M
from mantaray.sim.model.mjcf import OBJECT  # noqa: E402
from mantaray.sim.model.objects import OBJECTS  # noqa: E402
from mantaray.sim.model.parameters import plant_names  # noqa: E402

PLACE_S = 0.05  # [s, simulated] how long place_object may settle the object before the record starts


def speeds(plant, object_name: str, mesh, at_m: tuple[float, float], duration_s: float, every_s: float):
    """The object's speed [m/s] every every_s over duration_s after placing it at at_m, and its position [m]."""
    rig = plant.rig(resolution=mesh.resolution, timestep_s=mesh.timestep_s, object_name=object_name)
    model, data = M.load(rig)
    mujoco.mj_resetDataKeyframe(model, data, model.key(M.REST_KEY).id)
    mujoco.mj_forward(model, data)
    try:
        M.place_object(model, data, *at_m, rule=rig.fall, settle_max_s=PLACE_S)
    except M.ObjectNotSettled:
        pass  # the point: whether it settles is what is read below
    body, stride = model.body(OBJECT).id, max(1, round(every_s / mesh.timestep_s))
    out, velocity = [], np.zeros(6)
    for step in range(round(duration_s / mesh.timestep_s)):
        mujoco.mj_step(model, data)
        if step % stride == stride - 1:
            mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_BODY, body, velocity, 0)
            out.append(float(np.linalg.norm(velocity[3:])))
    return out, M.object_xy(model, data).copy()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--plant", default="polyester", help="one of: " + ", ".join(plant_names()))
    parser.add_argument("--object", choices=sorted(OBJECTS), default="sphere")
    parser.add_argument("--at", default="0.05,0.02", help="[m] x,y where the object is placed")
    parser.add_argument("--mesh", default="fast", help="fast, reference or RESOLUTION:TIMESTEP")
    parser.add_argument("--duration", type=float, default=6.0, help="[s, simulated] how long it is watched")
    parser.add_argument("--every", type=float, default=0.5, help="[s, simulated] how often its speed is printed")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a plant value; repeatable")
    args = parser.parse_args()
    args.set = ["fabric.stretch=threads", "contact.model=kernel", *args.set]  # later values win
    plant = plant_of(parser, args)
    try:
        mesh = parse_fidelity(args.mesh)
    except ValueError as exc:
        parser.error(str(exc))
    try:
        at_m = tuple(float(v) for v in args.at.split(","))
        if len(at_m) != 2 or max(abs(v) for v in at_m) > 0.2:
            raise ValueError
    except ValueError:
        parser.error(f"--at takes x,y [m] within ±0.2, got {args.at!r}")
    if not (0 < args.every <= args.duration <= 60):
        parser.error("--every and --duration: 0 < every <= duration <= 60 s")
    try:
        said, end = speeds(plant, args.object, mesh, at_m, args.duration, args.every)
    except M.SimulationUnstable as exc:
        print(f"diverged: {exc}", file=sys.stderr)
        return 1
    print(
        f"{args.object} on {args.plant} {' '.join(args.set)}, {mesh.label}: speed [mm/s] every "
        f"{args.every:g} s: {' '.join(f'{v * 1000:.1f}' for v in said)}; at ({end[0]:+.3f}, {end[1]:+.3f}) m at the end"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
