"""The object's contact with the sheet through a smooth kernel of physical width, so it rests where the cloth would, not at a vertex.

With contact.model = "kernel" (sim/model/plant.toml) the flex's triangles collide with nothing, and this penalty contact
takes their place as a passive force at every step: a MuJoCo engine plugin in C (sim/model/plugin/kernel_contact.c, built
by the project's CMake), an instance of it in each scene that plugin_xml configures. A plugin, not MuJoCo's Python
passive callback: that callback is one per process and breaks every model compiled while it is set.
- The sheet's surface under a point (x, y) is the vertices' heights averaged with Wendland C2 weights of support
  radius h = contact.kernel_width_m [m]: a C2 surface whatever the mesh, so no vertex makes a pocket.
- Each of the object's contact points (surface_points: a sphere its centre with its radius, a box or ellipsoid 26
  points over its faces, a cylinder its rims and cap centres, a mesh 48 of its hull's vertices) that lies below that
  surface plus the flex's radius presses into it with a spring of k = contact.kernel_stiffness_n_per_m [N/m] (shared
  by the FACE_POINTS points of a face for any object but the sphere, so an object resting on a face feels k), and a
  damping of contact.kernel_damping_ratio times critical for the reduced mass of the point's share of the object and
  the patch of sheet under it (the vertices' masses by the kernel's squared weights), along the surface's normal.
- Friction (contact.friction[0]) is a stick spring at each point in contact: its stretch [m] is how far the point has
  moved along the sheet under it since it touched (the plugin's state), pulled back with the same k and damping,
  and cut to the Coulomb limit mu N where it would pull harder, so the point slips. An object friction should hold
  is held at any step; a friction regularised by a slip speed let it creep, the more the longer the step.
- Each point's force is shared back to the vertices by the same weights, so the sheet carries the object's load spread
  over h, and momentum is kept.
Rolling resistance is the object's rotational damping (contact.rolling_damping_per_s), as with the mesh contact; the
contact's torsional and rolling friction (contact.friction[1:]) act only on the mesh contact. Measured against the
pocket in sim/README.md, Convergence 9.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from mantaray.paths import native_artifact

if TYPE_CHECKING:
    from .rig import Rig

MESH_POINTS = 48  # a mesh object's contact points: this many of its convex hull's vertices, spread apart
LATTICE = 3  # a box's contact points: a LATTICE^3 lattice's surface points (26: corners, edges, face centres); a
# cylinder's rims at the same density
FACE_POINTS = LATTICE**2  # the points of one face, which share the spring when an object rests on it

PLUGIN = "mantaray.kernel_contact"  # the plugin's name (sim/model/plugin/kernel_contact.c), and its library's below
LIBRARY = "libmantaray_kernel_contact.so"
INSTANCE = "kernel_contact"  # the plugin instance in a scene
_loaded = False  # whether this process has registered the plugin


def surface_points(model: mujoco.MjModel, geom: int) -> tuple[np.ndarray, float]:
    """A geom's contact points in its own frame [m] and the radius about each [m]: a sphere is its centre with its
    radius; a box or ellipsoid a lattice over its surface, a cylinder its rims and cap centres, a mesh its hull's
    vertices spread apart (farthest-point order from the lowest), each of radius 0."""
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
    raise ValueError(f"no kernel contact points for a geom of type {kind.name}")


def load_plugin() -> None:
    """Register the plugin with MuJoCo in this process (once): the library CMake builds from sim/model/plugin/."""
    global _loaded
    if not _loaded:
        mujoco.mj_loadPluginLibrary(str(native_artifact(LIBRARY)))
        _loaded = True


def instance_name(k: int) -> str:
    """The plugin instance of object k of the scene: object 0's is INSTANCE."""
    return INSTANCE if k == 0 else f"{INSTANCE}{k}"


def plugin_xml(rig: Rig, alones: list[mujoco.MjModel], flex: str, geoms: list[str]) -> str:
    """The <extension> element that makes each object (geoms[k], whose compiled model alone is alones[k]) meet the
    flex through the kernel, one plugin instance an object: each one's configuration from the rig's contact, in
    physical units."""
    instances = "\n".join(
        _instance_xml(rig, k, alone, flex, geom) for k, (alone, geom) in enumerate(zip(alones, geoms, strict=True))
    )
    return f"""  <extension>
    <plugin plugin="{PLUGIN}">
{instances}
    </plugin>
  </extension>
"""


def _instance_xml(rig: Rig, k: int, alone: mujoco.MjModel, flex: str, geom: str) -> str:
    c = rig.contact
    geom_id = alone.geom(0).id  # the object alone: its one geom
    points, radius_m = surface_points(alone, geom_id)
    share = 1.0 if len(points) == 1 else 1.0 / FACE_POINTS  # the points that bear the object share its spring
    config = {
        "flex": flex,
        "geom": geom,
        "width_m": repr(c.kernel_width_m),
        "stiffness_n_per_m": repr(c.kernel_stiffness_n_per_m),
        "share": repr(share),
        "damping_ratio": repr(c.kernel_damping_ratio),
        "friction": repr(float(c.friction[0])),
        "radius_m": repr(radius_m),
        "points_m": " ".join(repr(float(x)) for x in points.ravel()),
    }
    keys = "\n".join(f'        <config key="{key}" value="{value}"/>' for key, value in config.items())
    return f"""      <instance name="{instance_name(k)}">
{keys}
      </instance>"""


def surface_height(model: mujoco.MjModel, data: mujoco.MjData, k: int = 0) -> float | None:
    """The kernel surface's height [m, world z] under object k's geom centre at the last mj_forward or step (NaN
    off the sheet), or None where the object meets the flex's triangles (no kernel contact in the model)."""
    instance = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_PLUGIN, instance_name(k))
    if instance < 0:
        return None
    return float(data.plugin_state[model.plugin_stateadr[instance]])
