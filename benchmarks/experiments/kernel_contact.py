"""Experiment: a sphere's contact with the sheet through a smooth kernel of physical width, not the mesh's triangles.

Run: python3 benchmarks/experiments/kernel_contact.py [--meshes reference,finer] [--widths 0.04,0.06,0.08]
     [--drops 12] [--seed 5] [--plant polyester] [--stiffness 500] [--set KEY=VALUE ...]
A candidate for issue 39's part 2 (sim/README.md, Convergence 8: an object rests in a pocket at a vertex). The
sphere's collision with the flex is switched off, and a penalty contact takes its place, computed in MuJoCo's
passive-force callback at every step: the sheet's surface under the sphere is the vertices' heights averaged with
Wendland C2 weights of support radius h [m] (a smooth surface, whatever the mesh), the sphere presses into it
with a spring of --stiffness [N/m] and a critical damping for its mass, a regularised Coulomb friction acts at the
contact point, and the reaction is shared back to the vertices by the same weights. The drops are
rest_positions.py's (the same points from the same seed, the same rule for at rest); per width it prints the rest
positions on each mesh, their gap to the finest mesh's (median, largest, within 1 cm), and the wall time of each
mesh against rest_positions.py's native contact on it, measured in the same run. A prototype in Python, to learn
whether the kernel removes the pocket before it is written as an engine plugin in C.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import mujoco
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # rest_positions.py's drops

from rest_positions import CLOSE_M, DROP_HALF_WIDTH_M, rest_positions  # noqa: E402

from mantaray.sim.fidelity import parse_fidelity  # noqa: E402
from mantaray.sim.mjcf import FABRIC, OBJECT  # noqa: E402
from mantaray.sim.parameters import ParameterError, plant_names  # noqa: E402
from mantaray.sim.plant import Plant, parse_setting  # noqa: E402

SLIP_SPEED_M_PER_S = 1e-3  # [m/s] below this relative speed the friction grows linearly (regularised Coulomb)


class KernelContact:
    """The sphere against the kernel-smoothed sheet, as passive forces added at every step."""

    def __init__(self, model: mujoco.MjModel, width_m: float, stiffness_n_per_m: float, friction: float) -> None:
        self.h, self.k, self.mu = width_m, stiffness_n_per_m, friction
        self.body, self.geom = model.body(OBJECT).id, model.geom(OBJECT).id
        self.radius = float(model.geom_size[self.geom][0])
        flex = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_FLEX, FABRIC)
        self.first, self.count = int(model.flex_vertadr[flex]), int(model.flex_vertnum[flex])
        self.thickness = float(model.flex_radius[flex])
        bodies = model.flex_vertbodyid[self.first : self.first + self.count]
        self.dofs = np.array([model.body_dofadr[b] for b in bodies])[:, None] + np.arange(3)  # x, y, z slides
        self.b = 2 * math.sqrt(self.k * float(model.body_mass[self.body]))  # [N s/m] critical for the sphere
        model.flex_contype[flex] = 0  # the triangles no longer collide: the kernel is the contact
        model.flex_conaffinity[flex] = 0

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        c = data.geom_xpos[self.geom]
        p = data.flexvert_xpos[self.first : self.first + self.count]
        d = p[:, :2] - c[:2]
        r = np.hypot(d[:, 0], d[:, 1])
        near = r < self.h
        if not near.any():
            return
        q = r[near] / self.h
        w = (1 - q) ** 4 * (1 + 4 * q)
        dw_dr = -20 * q * (1 - q) ** 3 / self.h
        total = w.sum()
        z = p[near, 2]
        z_s = float(w @ z) / total
        dr_dc = -d[near] / np.maximum(r[near], 1e-12)[:, None]  # how each distance moves with the sphere's xy
        grad = ((dw_dr * (z - z_s))[:, None] * dr_dc).sum(axis=0) / total  # [-] the surface's slope under it
        n = np.array([-grad[0], -grad[1], 1.0])
        n /= np.linalg.norm(n)
        depth = self.radius + self.thickness - (c[2] - z_s) * n[2]
        if depth <= 0:
            return
        velocity = np.zeros(6)
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_GEOM, self.geom, velocity, 0)  # [rot, lin], world
        point = c - self.radius * n
        dofs = self.dofs[near]
        sheet_v = (w @ data.qvel[dofs]) / total
        relative = velocity[3:] + np.cross(velocity[:3], point - c) - sheet_v
        v_n = float(relative @ n)
        tangential = relative - v_n * n
        normal = max(0.0, self.k * depth - self.b * v_n)
        force = normal * n - self.mu * normal * tangential / math.sqrt(tangential @ tangential + SLIP_SPEED_M_PER_S**2)
        mujoco.mj_applyFT(model, data, force, np.zeros(3), point, self.body, data.qfrc_passive)
        np.add.at(data.qfrc_passive, dofs, -(w / total)[:, None] * force)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--plant", default="polyester", help="one of: " + ", ".join(plant_names()))
    parser.add_argument("--drops", type=int, default=12, help="drop points, drawn from --seed")
    parser.add_argument("--seed", type=int, default=5)
    parser.add_argument("--meshes", default="reference,finer", help="as rest_positions.py's: the last is the finest")
    parser.add_argument("--widths", default="0.04,0.06,0.08", help="[m] kernel support radii, comma-separated")
    parser.add_argument("--stiffness", type=float, default=500.0, help="[N/m] the contact's spring")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a plant value; repeatable")
    args = parser.parse_args()
    try:
        plant = Plant(args.plant).set(dict(parse_setting(text) for text in args.set))
        meshes = []
        for text in args.meshes.split(","):
            meshes.append(parse_fidelity(text, meshes[-1] if meshes else None))
        widths = [float(w) for w in args.widths.split(",")]
    except (ParameterError, ValueError) as exc:
        parser.error(str(exc))
    if len(meshes) < 2 or not all(0.005 <= w <= 0.25 for w in widths) or not 1 <= args.drops <= 1000:
        parser.error("--meshes needs two at least, --widths 0.005..0.25 m each, --drops 1..1000")
    if not 1.0 <= args.stiffness <= 1e5:
        parser.error("--stiffness must be 1..1e5 N/m")
    drops = np.random.default_rng(args.seed).uniform(-DROP_HALF_WIDTH_M, DROP_HALF_WIDTH_M, size=(args.drops, 2))
    friction = plant.rig(object_name="sphere").contact.friction[0]
    print(f"sphere on {args.plant}: {args.drops} drops, seed {args.seed}, k = {args.stiffness:g} N/m, μ = {friction}")
    native_s = {}
    for mesh in meshes:
        _, native_s[mesh.label] = rest_positions(plant, "sphere", mesh, drops)
    for width_m in widths:
        rests, wall_s = {}, {}
        for mesh in meshes:
            contacts = []

            def prepare(model, data, contacts=contacts, width_m=width_m):
                contacts.append(KernelContact(model, width_m, args.stiffness, friction))
                mujoco.set_mjcb_passive(contacts[-1])

            started = time.perf_counter()
            try:
                rests[mesh.label], _ = rest_positions(plant, "sphere", mesh, drops, prepare=prepare)
            finally:
                mujoco.set_mjcb_passive(None)
            wall_s[mesh.label] = time.perf_counter() - started
        finest = meshes[-1].label
        print(f"h = {width_m * 100:g} cm:")
        for mesh in meshes:
            at_rest = [
                f"({r[0] * 100:+.1f}, {r[1] * 100:+.1f})" if r is not None else "moving" for r in rests[mesh.label]
            ]
            print(
                f"  {mesh.label}: {wall_s[mesh.label]:.0f} s wall ({wall_s[mesh.label] / native_s[mesh.label]:.1f}x "
                f"the native contact's); rests [cm] {' '.join(at_rest)}"
            )
        for mesh in meshes[:-1]:
            pairs = [
                (a, b) for a, b in zip(rests[mesh.label], rests[finest], strict=True) if a is not None and b is not None
            ]
            if not pairs:
                print(f"  {mesh.label} against {finest}: no drop at rest on both")
                continue
            gap_m = np.array([np.hypot(*(a - b)) for a, b in pairs])
            print(
                f"  {mesh.label} against {finest}: rest positions {np.median(gap_m) * 1000:.1f} mm apart (median), "
                f"{gap_m.max() * 1000:.1f} mm at most; within {CLOSE_M * 100:.0f} cm in {int((gap_m <= CLOSE_M).sum())} "
                f"of {len(pairs)} drops",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
