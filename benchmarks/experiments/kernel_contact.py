"""Experiment: an object's contact with the sheet through a smooth kernel of physical width, not the mesh's triangles.

Run: python3 benchmarks/experiments/kernel_contact.py [--object sphere] [--meshes reference,finer]
     [--widths 0.04,0.06,0.08] [--drops 12] [--seed 5] [--plant polyester] [--stiffness 500] [--set KEY=VALUE ...]
A candidate for issue 39's part 2 (sim/README.md, Convergence 8: an object rests in a pocket at a vertex). The
object's collision with the flex is switched off, and a penalty contact takes its place, computed in MuJoCo's
passive-force callback at every step: the sheet's surface is the vertices' heights averaged with Wendland C2 weights
of support radius h [m] (a smooth surface, whatever the mesh). Each of the object's contact points (a sphere: its
centre, with its radius; a box: 26 points over its faces; a mesh: 48 of its hull's vertices) presses into the
surface under it with a spring (--stiffness [N/m], shared by the 9 points of a face for any object but the sphere)
and a damping critical for the object's mass, a regularised Coulomb friction acts at the point, and the reaction
is shared back to the vertices by the same weights. The drops are rest_positions.py's (the same points from the
same seed, the same rule for at rest); per width it prints the rest positions on each mesh, their gap to the
finest mesh's (median, largest, within 1 cm), and the wall time of each mesh against rest_positions.py's native
contact on it, measured in the same run. A prototype in Python, to learn whether the kernel removes the pocket
before it is written into the model.
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
from mantaray.sim.objects import OBJECTS  # noqa: E402
from mantaray.sim.parameters import ParameterError, plant_names  # noqa: E402
from mantaray.sim.plant import Plant, parse_setting  # noqa: E402

SLIP_SPEED_M_PER_S = 1e-3  # [m/s] below this relative speed the friction grows linearly (regularised Coulomb)


MESH_POINTS = 48  # a mesh object's contact points: this many of its convex hull's vertices, spread apart
LATTICE = 3  # a box's or another shape's contact points: a LATTICE^3 lattice's surface points (26: corners, edges,
# face centres), or a cylinder's rims and cap centres, at the same density
FACE_POINTS = LATTICE**2  # the points of one face, which share the spring when an object rests on it


def surface_points(model: mujoco.MjModel, geom: int) -> tuple[np.ndarray, float]:
    """A geom's contact points in its own frame [m] and the radius about each [m]: a sphere is its centre with its
    radius; a box a lattice over its faces, a cylinder its rims and cap centres, a mesh its hull's vertices spread
    apart (farthest-point order from the lowest), each of radius 0."""
    kind, size = mujoco.mjtGeom(model.geom_type[geom]), model.geom_size[geom]
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return np.zeros((1, 3)), float(size[0])
    if kind in (mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_ELLIPSOID):
        axis = np.linspace(-1.0, 1.0, LATTICE)
        cube = np.array([(a, b, c) for a in axis for b in axis for c in axis])
        surface = cube[np.abs(cube).max(axis=1) == 1.0]
        if kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
            surface = surface / np.linalg.norm(surface, axis=1)[:, None]
        return surface * size[:3], 0.0
    if kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
        turn = np.linspace(0.0, 2 * math.pi, 4 * (LATTICE - 1), endpoint=False)
        rim = np.column_stack([np.cos(turn), np.sin(turn)]) * size[0]
        caps = [np.column_stack([rim, np.full(len(rim), z)]) for z in (-size[1], size[1])]
        return np.vstack([*caps, [[0.0, 0.0, -size[1]], [0.0, 0.0, size[1]]]]), 0.0
    if kind == mujoco.mjtGeom.mjGEOM_MESH:
        from scipy.spatial import ConvexHull

        mesh = int(model.geom_dataid[geom])
        start, count = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
        vertices = np.asarray(model.mesh_vert[start : start + count], dtype=float)
        hull = vertices[ConvexHull(vertices).vertices]
        chosen = [int(np.argmin(hull[:, 2]))]
        gap = np.linalg.norm(hull - hull[chosen[0]], axis=1)
        while len(chosen) < min(MESH_POINTS, len(hull)):
            chosen.append(int(np.argmax(gap)))
            gap = np.minimum(gap, np.linalg.norm(hull - hull[chosen[-1]], axis=1))
        return hull[chosen], 0.0
    raise ValueError(f"no contact points for a geom of type {kind.name}")


class KernelContact:
    """The object against the kernel-smoothed sheet, as passive forces added at every step: each of its contact
    points (surface_points) presses into the surface interpolated under it."""

    def __init__(self, model: mujoco.MjModel, width_m: float, stiffness_n_per_m: float, friction: float) -> None:
        self.h, self.mu = width_m, friction
        self.body, self.geom = model.body(OBJECT).id, model.geom(OBJECT).id
        self.points, self.radius = surface_points(model, self.geom)
        share = 1.0 if len(self.points) == 1 else 1.0 / FACE_POINTS  # the points that bear the object share k
        self.k = stiffness_n_per_m * share  # [N/m] each point's spring
        self.b = 2 * math.sqrt(stiffness_n_per_m * float(model.body_mass[self.body])) * share  # [N s/m] critical
        flex = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_FLEX, FABRIC)
        self.first, self.count = int(model.flex_vertadr[flex]), int(model.flex_vertnum[flex])
        self.thickness = float(model.flex_radius[flex])
        bodies = model.flex_vertbodyid[self.first : self.first + self.count]
        self.dofs = np.array([model.body_dofadr[b] for b in bodies])[:, None] + np.arange(3)  # x, y, z slides
        model.flex_contype[flex] = 0  # the triangles no longer collide: the kernel is the contact
        model.flex_conaffinity[flex] = 0

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        p = data.flexvert_xpos[self.first : self.first + self.count]
        rotation = data.geom_xmat[self.geom].reshape(3, 3)
        centres = data.geom_xpos[self.geom] + self.points @ rotation.T  # [m] the points in the world
        low = centres[:, 2] - self.radius < p[:, 2].max() + self.thickness  # only these can touch the sheet
        if not low.any():
            return
        centres = centres[low]
        d = p[None, :, :2] - centres[:, None, :2]  # [point, vertex, xy]
        r = np.hypot(d[..., 0], d[..., 1])
        q = np.minimum(r / self.h, 1.0)
        w = (1 - q) ** 4 * (1 + 4 * q)  # Wendland C2: zero beyond h
        total = w.sum(axis=1)
        under = total > 0
        if not under.any():
            return
        centres, d, r, q, w, total = centres[under], d[under], r[under], q[under], w[under], total[under]
        z_s = (w @ p[:, 2]) / total
        dw_dr = -20 * q * (1 - q) ** 3 / self.h
        dr_dc = -d / np.maximum(r, 1e-12)[..., None]  # how each distance moves with the point's xy
        grad = ((dw_dr * (p[None, :, 2] - z_s[:, None]))[..., None] * dr_dc).sum(axis=1) / total[:, None]
        n = np.column_stack([-grad, np.ones(len(grad))])
        n /= np.linalg.norm(n, axis=1)[:, None]
        depth = self.radius + self.thickness - (centres[:, 2] - z_s) * n[:, 2]
        touching = depth > 0
        if not touching.any():
            return
        velocity = np.zeros(6)
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_GEOM, self.geom, velocity, 0)  # [rot, lin], world
        centre = data.geom_xpos[self.geom]
        for i in np.flatnonzero(touching):
            share = w[i] / total[i]
            near = share > 0
            point = centres[i] - self.radius * n[i]
            sheet_v = share[near] @ data.qvel[self.dofs[near]]
            relative = velocity[3:] + np.cross(velocity[:3], point - centre) - sheet_v
            v_n = float(relative @ n[i])
            tangential = relative - v_n * n[i]
            normal = max(0.0, self.k * depth[i] - self.b * v_n)
            slip = math.sqrt(tangential @ tangential + SLIP_SPEED_M_PER_S**2)
            force = normal * n[i] - self.mu * normal * tangential / slip
            mujoco.mj_applyFT(model, data, force, np.zeros(3), point, self.body, data.qfrc_passive)
            np.add.at(data.qfrc_passive, self.dofs[near], -share[near][:, None] * force)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--plant", default="polyester", help="one of: " + ", ".join(plant_names()))
    parser.add_argument("--object", choices=sorted(OBJECTS), default="sphere")
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
    friction = plant.rig(object_name=args.object).contact.friction[0]
    print(
        f"{args.object} on {args.plant}: {args.drops} drops, seed {args.seed}, k = {args.stiffness:g} N/m, μ = {friction}"
    )
    native_s = {}
    for mesh in meshes:
        _, native_s[mesh.label] = rest_positions(plant, args.object, mesh, drops)
    for width_m in widths:
        rests, wall_s = {}, {}
        for mesh in meshes:
            contacts = []

            def prepare(model, data, contacts=contacts, width_m=width_m):
                contacts.append(KernelContact(model, width_m, args.stiffness, friction))
                mujoco.set_mjcb_passive(contacts[-1])

            started = time.perf_counter()
            try:
                rests[mesh.label], _ = rest_positions(plant, args.object, mesh, drops, prepare=prepare)
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
