"""MJCF for the rig (the model file, Menagerie-style) and its scene (floor, light, overhead camera, object, markers)."""

from __future__ import annotations

import hashlib
import shutil
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from . import kernel_contact
from .objects import ASSETS, ObjectSpec
from .rig import Contact, Rig

MODEL_FILE = "manta_ray.xml"
FABRIC = "fabric"  # the flex; its vertex bodies and their sites are fabric_<id>


@dataclass(frozen=True)
class ObjectNames:
    """The MJCF names of one object of the scene (object k of Rig.objects): its body (and its geom), its six dofs:
    slides along world x, y, z [m], then a ball joint (its rotation, which alone is damped; MuJoCo steps them bit for
    bit as it steps a free joint, tests/test_sim_model.py, whose MJCF damping would also brake the object's fall and
    slide; qpos and qvel are laid out as a free joint's), the site on its top the overhead camera tracks, and its
    marker plate."""

    body: str
    slides: tuple[str, str, str]
    turn: str
    marker: str
    plate: str


def object_names(k: int) -> ObjectNames:
    """Object k's names: object 0's are those a one-object scene has always had (object, object_x, ..., marker)."""
    s = "" if k == 0 else str(k)
    return ObjectNames(
        f"object{s}",
        (f"object{s}_x", f"object{s}_y", f"object{s}_z"),
        f"object{s}_turn",
        f"marker{s}",
        f"object{s}_marker",
    )


OBJECT, OBJECT_SLIDES, OBJECT_TURN, MARKER = (lambda n: (n.body, n.slides, n.turn, n.marker))(object_names(0))
REST_KEY = "rest"  # the scene's keyframe, filled by model.load(): fabric settled, commands zero, objects parked
OVERHEAD = "overhead"  # the scene's camera looking straight down at the fabric
POST_OFFSET_M = 0.03  # [m] visual frame posts stand this far outboard of each actuator on the frame (no collisions)
UNDER_TRAVEL_M = 0.05  # [m] an actuator inside an array stands on a post this far below its travel's end
CARRIAGE_HALF_SIZE_M = (0.02, 0.02, 0.03)  # [m] visual carriage block (no collisions; mass from the rig)
VERTEX_INERTIA_BOX_M = 0.01  # [m] side of the box whose inertia each fabric vertex is given (as flexcomp's default)
HIDDEN_GROUP = 3  # visual group MuJoCo's renderer hides by default: the threads and their vertices' sites
OFFSCREEN_PX = (1920, 1920)  # [px] offscreen framebuffer: the largest image the renderer can make


def _v(*values: float) -> str:
    """Numbers as an MJCF attribute value."""
    return " ".join(f"{float(x):.6g}" for x in values)


def _exact(*values: float) -> str:
    """Numbers as an MJCF attribute value that reads back as the same doubles."""
    return " ".join(repr(float(x)) for x in values)


def sheet_vertices(rig: Rig) -> tuple[int, int]:
    """Vertices of the whole sheet along x and y: each module's patch has fabric.resolution a side, and neighbouring
    patches share the vertices of their common edge."""
    n = rig.fabric.resolution
    return rig.module.modules_x * (n - 1) + 1, rig.module.modules_y * (n - 1) + 1


def node_vertex(rig: Rig, actuator: int) -> tuple[int, int]:
    """(ix, iy) of the flex vertex actuator i holds (PROTOCOL.md §5's node (i, j)); vertex ids are ix * Ny + iy."""
    row, step = rig.module.modules_x + 1, rig.fabric.resolution - 1
    return actuator % row * step, actuator // row * step


def vertex_id(rig: Rig, ix: int, iy: int) -> int:
    return ix * sheet_vertices(rig)[1] + iy


def clamped_vertices(rig: Rig, actuator: int) -> list[tuple[int, float, float]]:
    """(vertex id, x, y [m] relative to the carriage) of the sheet vertices actuator i's clamp holds, its own excluded.

    The clamp holds fabric.corner_clamp_m of the sheet straight from the actuator's vertex, at the fabric's own
    spacing, along every grid line the sheet goes on in (two at a frame's corner, three on its edge, four inside).
    """
    nx, ny = sheet_vertices(rig)
    ix0, iy0 = node_vertex(rig, actuator)
    spacing, n = rig.fabric.spacing_m, rig.fabric.resolution
    along_x = [d for d in (1, -1) if 0 <= ix0 + d < nx]
    along_y = [d for d in (1, -1) if 0 <= iy0 + d < ny]
    held = []
    for k in range(1, n // 2):
        if k * spacing > rig.fabric.corner_clamp_m + 1e-9:
            break
        held += [(vertex_id(rig, ix0 + d * k, iy0), d * k * spacing, 0.0) for d in along_x]
        held += [(vertex_id(rig, ix0, iy0 + d * k), 0.0, d * k * spacing) for d in along_y]
    return held


def alternating_elements(nx: int, ny: int) -> np.ndarray:
    """Triangles (counter-clockwise seen from +z) of an Nx x Ny grid with diagonals alternating cell by cell.

    flexcomp puts every diagonal the same way, which makes corners 1 and 2 behave differently from
    0 and 3 (SIM-NOTES). With a checkerboard of diagonals and odd Nx, Ny, the corner cells' diagonals all
    touch their corner vertex and the mesh is symmetric under both mirror planes.
    """
    tris = []
    for ix in range(nx - 1):
        for iy in range(ny - 1):
            v00, v10 = ix * ny + iy, (ix + 1) * ny + iy
            v01, v11 = v00 + 1, v10 + 1
            if (ix + iy) % 2 == 0:
                tris += [(v00, v10, v11), (v00, v11, v01)]
            else:
                tris += [(v00, v10, v01), (v10, v11, v01)]
    return np.array(tris, dtype=np.int32)


def grid_points(nx: int, ny: int, spacing_m: float) -> np.ndarray:
    """(Nx*Ny, 3) vertex positions [m] of the flat sheet around its centre, numbered ix * Ny + iy (ix along x).

    The spacing is taken as written to 6 digits, like every length in these files.
    """
    spacing = float(_v(spacing_m))
    along_x = [spacing * (i - (nx - 1) / 2) for i in range(nx)]
    along_y = [spacing * (i - (ny - 1) / 2) for i in range(ny)]
    return np.array([(x, y, 0.0) for x in along_x for y in along_y])


def threads(nx: int, ny: int, spacing_m: float) -> list[tuple[int, int, float]]:
    """(vertex, vertex, rest length [m]) of the sheet's threads (Fabric.stretch "threads"): every edge of the grid and
    both diagonals of every cell. Each is a tension-only length limit: it holds the sheet's stretch and shear, and
    lets it buckle under compression as cloth does (sim/README.md, Convergence, item 7)."""
    spacing = float(_v(spacing_m))
    diagonal = float(_v(spacing * np.sqrt(2.0)))
    out = []
    for ix in range(nx):
        for iy in range(ny):
            v = ix * ny + iy
            if ix + 1 < nx:
                out.append((v, v + ny, spacing))
            if iy + 1 < ny:
                out.append((v, v + 1, spacing))
            if ix + 1 < nx and iy + 1 < ny:
                out += [(v, v + ny + 1, diagonal), (v + 1, v + ny, diagonal)]
    return out


def _fabric_xml(rig: Rig) -> tuple[str, str]:
    """The sheet as MJCF: what goes in the worldbody, and what follows it (before the equalities).

    With edges, a flexcomp: its vertex bodies, and its flex whose edges hold their lengths both ways. With threads,
    the same bodies written out (each with a site for its threads), the flex without edge constraints, and one
    tension-only tendon per thread. Either way each vertex is a point mass on three slides, the whole sheet's mass
    shared evenly, and the flex's triangles carry the bending and, with contact.model mesh, the contacts."""
    fab, c = rig.fabric, rig.contact
    (nx, ny), z0 = sheet_vertices(rig), rig.module.z0_m
    sheet_kg = fab.mass_kg * rig.module.grid.module_count  # [kg] every module's patch weighs one module's sheet
    elements = " ".join(map(str, alternating_elements(nx, ny).ravel()))
    collides = "" if c.model == "mesh" else 'contype="0" conaffinity="0" '  # the kernel is then the contact
    contact = (
        f'<contact {collides}condim="{c.condim}" friction="{_v(*c.friction)}" solref="{_v(*c.solref)}"\n'
        f'               solimp="{_v(*c.solimp)}" selfcollide="none"/>'
    )
    elasticity = (
        f'<elasticity young="{_v(fab.young_pa)}" poisson="{_v(fab.poisson)}" thickness="{_v(fab.thickness_m)}"\n'
        f'                  damping="{_v(fab.damping_s)}" elastic2d="bend"/>'
    )
    solref = _v(fab.edge_timeconst_s, fab.edge_solref[1])
    if fab.stretch == "edges":
        return (
            f"""    <flexcomp name="{FABRIC}" type="direct" dim="2" dof="full" pos="{_v(0, 0, z0)}"
              point="{_exact(*grid_points(nx, ny, fab.spacing_m).ravel())}"
              element="{elements}"
              radius="{_v(fab.radius_m)}" mass="{_v(sheet_kg)}" rgba="0.25 0.45 0.85 1">
      {contact}
      <edge equality="true" solref="{solref}" solimp="{_v(*fab.edge_solimp)}"/>
      {elasticity}
    </flexcomp>""",
            "",
        )
    mass = sheet_kg / (nx * ny)
    inertia = mass * VERTEX_INERTIA_BOX_M**2 / 6  # [kg m^2] required by MuJoCo, unused: a vertex only slides
    bodies = "\n".join(
        f'    <body name="{FABRIC}_{i}" pos="{_exact(x, y, z0 + z)}">\n'
        f'      <inertial pos="0 0 0" mass="{_v(mass)}" diaginertia="{_v(inertia, inertia, inertia)}"/>\n'
        f'      <joint type="slide" axis="1 0 0"/>\n      <joint type="slide" axis="0 1 0"/>\n'
        f'      <joint type="slide" axis="0 0 1"/>\n      <site name="{FABRIC}_{i}" group="{HIDDEN_GROUP}"/>\n    </body>'
        for i, (x, y, z) in enumerate(grid_points(nx, ny, fab.spacing_m))
    )
    limit = f'solreflimit="{solref}" solimplimit="{_v(*fab.edge_solimp)}" group="{HIDDEN_GROUP}"'
    tendons = "\n".join(
        f'    <spatial range="0 {_v(length)}" {limit}><site site="{FABRIC}_{a}"/><site site="{FABRIC}_{b}"/></spatial>'
        for a, b, length in threads(nx, ny, fab.spacing_m)
    )
    return bodies, (
        f"""  <deformable>
    <flex name="{FABRIC}" dim="2" radius="{_v(fab.radius_m)}" rgba="0.25 0.45 0.85 1"
          body="{" ".join(f"{FABRIC}_{i}" for i in range(nx * ny))}"
          element="{elements}">
      {contact}
      {elasticity}
    </flex>
  </deformable>
  <tendon>
{tendons}
  </tendon>
"""
    )


def model_xml(rig: Rig) -> str:
    """The rig alone: options, frame, an actuated carriage on every node of the modules' grid, the fabric and its
    welds to the carriages."""
    f, a, fab, s = rig.module, rig.actuators, rig.fabric, rig.solver
    grid = f.grid
    (hx, hy), z0 = grid.half_extent_m, f.z0_m
    post_top = z0 + a.range_m + 0.05
    posts, carriages, welds, actuators = [], [], [], []
    for i in range(grid.actuator_count):
        x, y = grid.actuator_xy(i)
        sx = (x > hx - 1e-9) - (x < -hx + 1e-9)  # -1, 0, 1: on the frame's -x edge, inside, on its +x edge
        sy = (y > hy - 1e-9) - (y < -hy + 1e-9)
        px, py = x + sx * POST_OFFSET_M, y + sy * POST_OFFSET_M
        top = post_top if sx or sy else z0 - a.range_m - UNDER_TRAVEL_M  # inside an array: a post from below
        posts.append(f'    <geom class="frame" type="box" size="0.01 0.01 {top / 2:.6g}" pos="{_v(px, py, top / 2)}"/>')
        carriages.append(
            f'    <body name="carriage{i}" pos="{_v(x, y, z0)}" gravcomp="1">\n'
            f'      <joint name="lift{i}" type="slide" axis="0 0 -1" range="{_v(-a.range_m, a.range_m)}"/>\n'
            f'      <inertial pos="0 0 0" mass="{_v(a.carriage_mass_kg)}" diaginertia="1e-4 1e-4 1e-4"/>\n'
            f'      <geom class="carriage" type="box" size="{_v(*CARRIAGE_HALF_SIZE_M)}" '
            f'pos="{_v(sx * CARRIAGE_HALF_SIZE_M[0], sy * CARRIAGE_HALF_SIZE_M[1], 0)}"/>\n'
            f"    </body>"
        )
        welds.append(
            f'    <weld name="corner{i}" body1="carriage{i}" '
            f'body2="{FABRIC}_{vertex_id(rig, *node_vertex(rig, i))}" relpose="0 0 0 1 0 0 0" '
            f'solref="{_v(*fab.corner_weld_solref)}"/>'
        )
        for k, (vertex, dx, dy) in enumerate(clamped_vertices(rig, i)):
            welds.append(
                f'    <weld name="clamp{i}_{k}" body1="carriage{i}" body2="{FABRIC}_{vertex}" '
                f'relpose="{_v(dx, dy, 0)} 1 0 0 0" solref="{_v(*fab.corner_weld_solref)}"/>'
            )
        actuators.append(
            f'    <pid name="actuator{i}" joint="lift{i}" input="pos" kp="{_v(a.kp_n_per_m)}" '
            f'dampratio="{_v(a.damping_ratio)}" slewmax="{_v(a.speed_m_per_s)}" '
            f'ctrlrange="{_v(-a.range_m, a.range_m)}"/>'
        )
    rails = [
        f'    <geom class="frame" type="box" size="{_v(hx + 0.04, 0.01, 0.01)}" pos="{_v(0, sy * (hy + POST_OFFSET_M), post_top)}"/>'
        for sy in (-1, 1)
    ]
    fabric, after_worldbody = _fabric_xml(rig)
    nl = "\n"
    return f"""<!-- MANTA-RAY rig, generated by mantaray.sim.model.mjcf from sim/model/rig.py: do not edit by hand. -->
<mujoco model="manta_ray">
  <compiler angle="radian" autolimits="true" meshdir="assets" texturedir="assets"/>
  <option timestep="{_v(s.timestep_s)}" integrator="{s.integrator}" solver="{s.solver}" tolerance="{_v(s.tolerance)}"/>
  <default>
    <default class="frame">
      <geom contype="0" conaffinity="0" group="1" rgba="0.75 0.75 0.78 1"/>
    </default>
    <default class="carriage">
      <geom contype="0" conaffinity="0" group="1" mass="0" rgba="0.2 0.2 0.25 1"/>
    </default>
  </default>
  <worldbody>
{nl.join(posts + rails)}
{nl.join(carriages)}
{fabric}
  </worldbody>
{after_worldbody}  <equality>
{nl.join(welds)}
  </equality>
  <actuator>
{nl.join(actuators)}
  </actuator>
</mujoco>
"""


def _object_body(o: ObjectSpec, c: Contact, names: ObjectNames, joints: str = "", marker_geom: str = "") -> str:
    """An object's body: joints, one geom, the tracking site and the marker plate (if the camera asks for it)."""
    shape = f'type="mesh" mesh="{o.mesh.name}"' if o.mesh else f'type="{o.shape}" size="{_v(*o.size_m)}"'
    return f"""    <body name="{names.body}">
{joints}      <geom name="{names.body}" {shape} mass="{_v(o.mass_kg)}" pos="{_v(*o.geom_pos_m)}"
            euler="{_v(*o.geom_euler_rad)}" rgba="{_v(*o.rgba)}" condim="{c.condim}"
            friction="{_v(*c.friction)}" solref="{_v(*c.solref)}" solimp="{_v(*c.solimp)}"/>
      <site name="{names.marker}" pos="{_v(0, 0, o.half_height_m)}" size="0.005" rgba="0 0 0 1"/>
{marker_geom}    </body>"""


def _mesh_asset(o: ObjectSpec) -> str:
    m = o.mesh
    if m is None:
        return ""
    src = f'file="{m.file}"' if m.file else f'builtin="{m.builtin}" params="{_v(*m.params)}"'
    return f'    <mesh name="{m.name}" {src} scale="{_v(*m.scale)}" inertia="convex"/>'


def _object_alone(o: ObjectSpec, c: Contact) -> mujoco.MjModel:
    """An object compiled alone (named as object 0): MuJoCo's own inertia and (for a mesh) vertices of it."""
    return mujoco.MjSpec.from_string(f"""<mujoco><compiler angle="radian" meshdir="{ASSETS}"/>
  <asset>{_mesh_asset(o)}</asset><worldbody>{_object_body(o, c, object_names(0))}</worldbody></mujoco>""").compile()


def rolling_damping(rig: Rig, k: int = 0) -> float:
    """Damping [N m s/rad] on the object's rotation: rig.contact.rolling_damping_per_s x its inertia about its lowest point.

    For a sphere rolling on a level sheet that makes its speed decay at exactly that rate (I + m r^2 is the
    rolling inertia about the contact). The inertia is MuJoCo's own, from compiling the object alone. Object k's.
    """
    o = rig.objects[k]
    alone = _object_alone(o, rig.contact)
    body = alone.body(OBJECT).id
    about_contact = float(np.mean(alone.body_inertia[body])) + alone.body_mass[body] * o.half_height_m**2
    return rig.contact.rolling_damping_per_s * about_contact


def _object_xml(rig: Rig, k: int, marker_geom: str = "") -> tuple[str, str]:
    """(asset lines, body) for object k; qpos0 puts it at the world's origin, place_objects() puts it on the fabric."""
    names = object_names(k)
    joints = "".join(
        f'      <joint name="{name}" type="slide" axis="{_v(*axis)}"/>\n'
        for name, axis in zip(names.slides, np.eye(3), strict=True)
    )
    joints += f'      <joint name="{names.turn}" type="ball" damping="{_exact(rolling_damping(rig, k))}"/>\n'
    o = rig.objects[k]
    return _mesh_asset(o), _object_body(o, rig.contact, names, joints, marker_geom)


MARKER_TEXTURE_PX = 256  # [px] side of each ArUco texture (a multiple of the marker's 8 cells with its quiet zone)
MARKER_PLATE_M = 0.001  # [m] half thickness of a marker plate (visual only)


def marker_layout(rig: Rig):
    """The tracker's marker layout for the rig's scene: object k carries the marker of id first + k (first: the
    layout's default object id)."""
    from mantaray.host.markers import MarkerLayout

    first = MarkerLayout().object_ids[0]
    return MarkerLayout(object_ids=tuple(range(first, first + len(rig.objects))))


def _marker_xml(rig: Rig) -> tuple[str, str, list[str]]:
    """(assets, world geoms, each object's geom) drawing the tracker's ArUco markers that the rig's camera asks for."""
    if not (rig.camera.corner_markers or rig.camera.object_marker):
        return "", "", [""] * len(rig.objects)
    from mantaray.host.markers import quiet_scale

    layout = marker_layout(rig)
    ids = [*layout.corner_ids, *layout.object_ids]
    assets = "\n".join(
        f'    <texture name="aruco{i}" type="2d" file="aruco_{i}.png"/>\n'
        f'    <material name="aruco{i}" texture="aruco{i}" texrepeat="1 1" specular="0" shininess="0"/>'
        for i in ids
    )
    half_corner = layout.corner_size_m * quiet_scale(layout) / 2
    z0 = rig.module.z0_m
    world = "\n".join(
        f'    <geom name="corner_marker{k}" type="box" size="{_v(half_corner, half_corner, MARKER_PLATE_M)}" '
        f'pos="{_v(x, y, z0 - MARKER_PLATE_M)}" material="aruco{i}" contype="0" conaffinity="0"/>'
        for k, (i, (x, y)) in enumerate(zip(layout.corner_ids, layout.corner_centres_m(), strict=True))
        if rig.camera.corner_markers
    )
    half_object = layout.object_size_m * quiet_scale(layout) / 2
    on_objects = [
        (
            f'      <geom name="{object_names(k).plate}" type="box" '
            f'size="{_v(half_object, half_object, MARKER_PLATE_M)}" '
            f'pos="{_v(0, 0, o.half_height_m + MARKER_PLATE_M)}" material="aruco{i}" mass="0" contype="0" '
            f'conaffinity="0"/>\n'
        )
        if rig.camera.object_marker
        else ""
        for k, (o, i) in enumerate(zip(rig.objects, layout.object_ids, strict=True))
    ]  # on each object's top
    return assets, world, on_objects


def write_marker_textures(rig: Rig, directory: Path) -> None:
    """The ArUco textures the rig's scene refers to, as PNG files in directory."""
    import imageio.v2 as imageio

    from mantaray.host.markers import marker_image

    layout = marker_layout(rig)
    directory.mkdir(parents=True, exist_ok=True)
    for i in (*layout.corner_ids, *layout.object_ids):
        imageio.imwrite(directory / f"aruco_{i}.png", marker_image(layout, i, MARKER_TEXTURE_PX))


def scene_xml(rig: Rig) -> str:
    """The scene: includes the model file, adds floor, light, the overhead camera and the object."""
    z0, cam = rig.module.z0_m, rig.camera
    zoom_out = max(rig.module.modules_x, rig.module.modules_y)  # an array is seen as the camera sees one module
    marker_assets, marker_geoms, object_markers = _marker_xml(rig)
    parts = [_object_xml(rig, k, plate) for k, plate in enumerate(object_markers)]
    asset = "\n".join(a for a in dict.fromkeys(a for a, _ in parts) if a)  # a mesh two objects share, once
    body = "\n".join(b for _, b in parts)
    extension = (
        kernel_contact.plugin_xml(
            rig,
            [_object_alone(o, rig.contact) for o in rig.objects],
            FABRIC,
            [object_names(k).body for k in range(len(rig.objects))],
        )
        if rig.contact.model == "kernel"
        else ""
    )
    what = ", ".join(o.name for o in rig.objects)
    return f"""<!-- MANTA-RAY scene with the {what}, generated by mantaray.sim.model.mjcf: do not edit by hand. -->
<mujoco model="manta_ray scene ({what})">
  <include file="{MODEL_FILE}"/>
{extension}  <statistic center="{_v(0, 0, z0 - 0.2)}" extent="1.2"/>
  <visual>
    <global offwidth="{OFFSCREEN_PX[0]}" offheight="{OFFSCREEN_PX[1]}"/>
    <headlight diffuse="0.6 0.6 0.6" ambient="0.3 0.3 0.3" specular="0 0 0"/>
  </visual>
  <asset>
    <texture type="2d" name="floor" builtin="checker" mark="edge" rgb1="0.2 0.3 0.4" rgb2="0.1 0.2 0.3"
             markrgb="0.8 0.8 0.8" width="300" height="300"/>
    <material name="floor" texture="floor" texuniform="true" texrepeat="5 5" reflectance="0.2"/>
{asset}
{marker_assets}
  </asset>
  <worldbody>
    <light pos="{_v(0, 0, z0 + 2)}" dir="0 0 -1" directional="true"/>
    <geom name="floor" type="plane" size="0 0 0.05" material="floor"/>
    <camera name="{OVERHEAD}" pos="{_v(0, 0, z0 + cam.height_above_z0_m * zoom_out)}" xyaxes="1 0 0 0 1 0"
            fovy="{_v(cam.fovy_deg)}"/>
{marker_geoms}
{body}
  </worldbody>
  <keyframe>
    <key name="{REST_KEY}"/>  <!-- filled by mantaray.sim.model.model.load() once the bare fabric has settled -->
  </keyframe>
</mujoco>
"""


def model_identity(rig: Rig) -> dict[str, str]:
    """What a trial's physics is: a digest of the MJCF the rig generates (model and scene, every number as written)
    and the MuJoCo version that steps it. Two runs with the same identity step the same model."""
    text = (model_xml(rig) + scene_xml(rig)).encode()
    return {"mjcf_sha1": hashlib.sha1(text).hexdigest()[:16], "mujoco": mujoco.__version__}


def write_model(rig: Rig, directory: str | Path) -> Path:
    """Write manta_ray.xml, scene_<object>.xml and the object's mesh file into directory; return the scene path.

    These files are the model that runs: load() compiles them as they are, then lets the fabric settle.
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    (directory / MODEL_FILE).write_text(model_xml(rig))
    for mesh in {o.mesh for o in rig.objects if o.mesh is not None and o.mesh.file}:
        (directory / "assets").mkdir(exist_ok=True)
        shutil.copyfile(ASSETS / mesh.file, directory / "assets" / mesh.file)
    if rig.camera.corner_markers or rig.camera.object_marker:
        write_marker_textures(rig, directory / "assets")
    scene = directory / f"scene_{'_'.join(o.name for o in rig.objects)}.xml"
    scene.write_text(scene_xml(rig))
    return scene
