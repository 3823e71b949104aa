"""The paper's test objects (Table I) as MuJoCo geometry: shape, size [m], mass [kg] and where the tracking marker sits."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from pathlib import Path

ASSETS = Path(__file__).resolve().parent / "assets"

BUNNY_FILE = "bunny.obj"  # the Stanford bunny as shipped with MuJoCo's examples: metres, y up
BUNNY_SCALE = 0.58  # [-] 15.5 x 15.4 cm as stored -> 9.0 long x 8.9 high (paper: 9 x 9 cm)


@dataclass(frozen=True)
class Mesh:
    """A mesh asset: a file under assets/ or a MuJoCo built-in, scaled per axis."""

    name: str
    scale: tuple[float, float, float]  # [-] per-axis factor applied to the vertices
    file: str | None = None  # under ASSETS; None for a built-in
    builtin: str | None = None  # MuJoCo built-in generator, e.g. "cone"
    params: tuple[float, ...] = ()  # the built-in's parameters


@dataclass(frozen=True)
class ObjectSpec:
    """One object: a single geom on a free body whose origin is the object's geometric centre.

    size_m follows MuJoCo's geom size convention: sphere (radius,), box (half x, half y, half z),
    cylinder (radius, half height), ellipsoid (semi-axes x, y, z); unused for meshes.
    geom_pos_m / geom_euler_rad place the geom in the body (used to centre and stand up the bunny).
    half_height_m is the distance from the body origin to the lowest and to the highest point
    when resting upright: placement drops the object from that height, and the marker site
    (what the overhead camera tracks) sits at (0, 0, +half_height_m).
    """

    name: str
    mass_kg: float
    shape: str  # MuJoCo geom type: sphere, box, cylinder, ellipsoid, mesh
    half_height_m: float
    size_m: tuple[float, ...] = ()
    mesh: Mesh | None = None
    geom_pos_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    geom_euler_rad: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rgba: tuple[float, float, float, float] = (0.8, 0.2, 0.2, 1.0)
    source: str = ""  # where size and mass come from


@cache
def _bunny_bounds() -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Min and max corner [m] of bunny.obj's vertices as stored (y up), before scaling."""
    rows = [line.split()[1:4] for line in (ASSETS / BUNNY_FILE).read_text().splitlines() if line.startswith("v ")]
    lo = tuple(min(float(r[k]) for r in rows) for k in range(3))
    hi = tuple(max(float(r[k]) for r in rows) for k in range(3))
    return lo, hi


def _bunny() -> ObjectSpec:
    """The bunny stood z-up (+90 deg about x maps the file's y onto z) with its bounding box centred on the body."""
    lo, hi = _bunny_bounds()
    cx, cy, cz = (BUNNY_SCALE * (a + b) / 2 for a, b in zip(lo, hi, strict=True))
    height_m = BUNNY_SCALE * (hi[1] - lo[1])
    # Rotating by +90 deg about x sends (x, y, z) to (x, -z, y); the geom offset undoes the centre.
    return ObjectSpec(
        name="bunny",
        mass_kg=0.0503,
        shape="mesh",
        half_height_m=height_m / 2,
        mesh=Mesh("bunny", (BUNNY_SCALE,) * 3, file=BUNNY_FILE),
        geom_pos_m=(-cx, cz, -cy),
        geom_euler_rad=(math.pi / 2, 0.0, 0.0),
        rgba=(0.85, 0.15, 0.15, 1.0),
        source="paper Table I: 9 cm high, 9 cm long, 50.3 g; Stanford bunny scaled 0.58; contact on its convex hull",
    )


OBJECTS: dict[str, ObjectSpec] = {
    o.name: o
    for o in (
        ObjectSpec(
            "sphere",
            0.0125,
            "sphere",
            0.0255,
            size_m=(0.0255,),
            source="paper Table I: diameter 5.1 cm, 12.5 g (uniform density)",
        ),
        ObjectSpec(
            "cube", 0.066, "box", 0.025, size_m=(0.025, 0.025, 0.025), source="paper Table I: 5 x 5 x 5 cm, 66 g"
        ),
        ObjectSpec(
            "disk",
            0.0038,
            "mesh",
            0.002,
            mesh=Mesh("disk", (0.02, 0.02, 0.002), builtin="cone", params=(24, 1)),
            source="paper Table I: diameter 4 cm, 0.4 cm thick, 3.8 g; 24-sided prism "
            "(a primitive thin cylinder falls through the cloth, SIM-NOTES)",
        ),
        ObjectSpec(
            "cylinder",
            0.0257,
            "cylinder",
            0.0225,
            size_m=(0.0165, 0.0225),
            source="paper Table I: diameter 3.3 cm, height 4.5 cm, 25.7 g; placed standing",
        ),
        ObjectSpec(
            "apple",
            0.1314,
            "ellipsoid",
            0.030,
            size_m=(0.0325, 0.0325, 0.030),
            rgba=(0.7, 0.1, 0.1, 1.0),
            source="paper Table I: diameter 5-7.2 cm, 131.4 g; modelled 6.5 cm wide, 6.0 cm tall",
        ),
        ObjectSpec(
            "egg",
            0.0667,
            "ellipsoid",
            0.0205,
            size_m=(0.031, 0.0205, 0.0205),
            rgba=(0.80, 0.55, 0.35, 1.0),
            source="paper Table I: diameter 4.1-6.2 cm, 66.7 g; lying with its long axis along x; a brown egg, "
            "whose colour the blob tracker tells from the blue fabric (a white one it cannot)",
        ),
        _bunny(),
    )
}
