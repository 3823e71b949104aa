"""MJCF for the rig (model file) and its scene (floor, light, overhead camera, object), loading, and scene helpers."""
from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import mujoco
import numpy as np

from .objects import ASSETS
from .rig import FallRule, Rig

MODEL_FILE = "manta_ray.xml"
FABRIC = "fabric"             # flexcomp name; its vertex bodies are fabric_<id>
OBJECT = "object"             # the object's body, free joint and geom
MARKER = "marker"             # site on top of the object: the point the overhead camera tracks
OVERHEAD = "overhead"         # the scene's camera looking straight down at the fabric
REST_KEY = "rest"             # keyframe filled by load(): fabric settled, commands zero, object parked
N_ACTUATORS = 4
# Corner signs (x, y) of actuators 0..3, PROTOCOL.md §5: 0 (-x,-y), 1 (+x,-y), 2 (-x,+y), 3 (+x,+y).
CORNERS = ((-1, -1), (1, -1), (-1, 1), (1, 1))

AT_REST_SPEED_M_PER_S = 0.01   # [m/s] object linear speed below which it counts as at rest ...
AT_REST_SPIN_RAD_PER_S = 0.5   # [rad/s] ... with its angular speed below this ...
AT_REST_HOLD_S = 0.2           # [s] ... for this long without a break
DROP_CLEARANCE_M = 0.002       # [m] gap left under the object when it is placed above the fabric
POST_OFFSET_M = 0.03           # [m] visual frame posts stand this far outboard of each corner (no collisions)
CARRIAGE_HALF_SIZE_M = (0.02, 0.02, 0.03)  # [m] visual carriage block (no collisions; mass from the rig)
OFFSCREEN_PX = (1920, 1920)    # [px] offscreen framebuffer: the largest image the renderer can make
PARK_OFFSET_M = 0.35           # [m] the object waits on the floor this far beyond the +x edge while the fabric settles


def _v(*values: float) -> str:
    """Numbers as an MJCF attribute value."""
    return " ".join(f"{float(x):.6g}" for x in values)


def corner_vertex(resolution: int, actuator: int) -> int:
    """Flex vertex id at actuator's corner: flexcomp grids number vertices ix * N + iy (ix along x)."""
    sx, sy = CORNERS[actuator]
    ix = 0 if sx < 0 else resolution - 1
    iy = 0 if sy < 0 else resolution - 1
    return ix * resolution + iy


def clamped_vertices(resolution: int, spacing_m: float, clamp_m: float, actuator: int) -> list[tuple[int, float, float]]:
    """(vertex id, x, y [m] relative to the carriage) of the edge vertices the corner's clamp holds, corner excluded.

    The clamp holds clamp_m of both edges from the corner straight, at the fabric's own spacing, pointing along
    the frame's edges toward the neighbouring corners.
    """
    sx, sy = CORNERS[actuator]
    held = []
    for k in range(1, resolution // 2):
        if k * spacing_m > clamp_m + 1e-9:
            break
        ix0 = 0 if sx < 0 else resolution - 1
        iy0 = 0 if sy < 0 else resolution - 1
        held.append(((ix0 - sx * k) * resolution + iy0, -sx * k * spacing_m, 0.0))   # along the x edge
        held.append((ix0 * resolution + iy0 - sy * k, 0.0, -sy * k * spacing_m))     # along the y edge
    return held


def alternating_elements(resolution: int) -> np.ndarray:
    """Triangles (counter-clockwise seen from +z) of an N x N grid with diagonals alternating cell by cell.

    flexcomp puts every diagonal the same way, which makes corners 1 and 2 behave differently from
    0 and 3 (SIM-NOTES). With a checkerboard of diagonals and an odd N, the corner cells' diagonals all
    touch their corner vertex and the mesh is symmetric under both mirror planes.
    """
    n = resolution
    tris = []
    for ix in range(n - 1):
        for iy in range(n - 1):
            v00, v10 = ix * n + iy, (ix + 1) * n + iy
            v01, v11 = v00 + 1, v10 + 1
            if (ix + iy) % 2 == 0:
                tris += [(v00, v10, v11), (v00, v11, v01)]
            else:
                tris += [(v00, v10, v01), (v10, v11, v01)]
    return np.array(tris, dtype=np.int32)


def model_xml(rig: Rig) -> str:
    """The rig alone: options, frame, four actuated carriages, the fabric and its corner welds."""
    f, a, fab, c, s = rig.frame, rig.actuators, rig.fabric, rig.contact, rig.solver
    hx, hy, z0 = f.size_x_m / 2, f.size_y_m / 2, f.z0_m
    post_top = z0 + a.range_m + 0.05
    posts, carriages, welds, actuators = [], [], [], []
    for i, (sx, sy) in enumerate(CORNERS):
        x, y = sx * hx, sy * hy
        px, py = sx * (hx + POST_OFFSET_M), sy * (hy + POST_OFFSET_M)
        posts.append(f'    <geom class="frame" type="box" size="0.01 0.01 {post_top / 2:.6g}" '
                     f'pos="{_v(px, py, post_top / 2)}"/>')
        carriages.append(
            f'    <body name="carriage{i}" pos="{_v(x, y, z0)}" gravcomp="1">\n'
            f'      <joint name="lift{i}" type="slide" axis="0 0 -1" range="{_v(-a.range_m, a.range_m)}"/>\n'
            f'      <inertial pos="0 0 0" mass="{_v(a.carriage_mass_kg)}" diaginertia="1e-4 1e-4 1e-4"/>\n'
            f'      <geom class="carriage" type="box" size="{_v(*CARRIAGE_HALF_SIZE_M)}" '
            f'pos="{_v(sx * CARRIAGE_HALF_SIZE_M[0], sy * CARRIAGE_HALF_SIZE_M[1], 0)}"/>\n'
            f'    </body>')
        welds.append(f'    <weld name="corner{i}" body1="carriage{i}" '
                     f'body2="{FABRIC}_{corner_vertex(fab.resolution, i)}" relpose="0 0 0 1 0 0 0" '
                     f'solref="{_v(*fab.corner_weld_solref)}"/>')
        for k, (vertex, dx, dy) in enumerate(clamped_vertices(fab.resolution, fab.spacing_m, fab.corner_clamp_m, i)):
            welds.append(f'    <weld name="clamp{i}_{k}" body1="carriage{i}" body2="{FABRIC}_{vertex}" '
                         f'relpose="{_v(dx, dy, 0)} 1 0 0 0" solref="{_v(*fab.corner_weld_solref)}"/>')
        actuators.append(
            f'    <pid name="actuator{i}" joint="lift{i}" input="pos" kp="{_v(a.kp_n_per_m)}" '
            f'dampratio="{_v(a.damping_ratio)}" slewmax="{_v(a.speed_m_per_s)}" '
            f'ctrlrange="{_v(-a.range_m, a.range_m)}"/>')
    rails = [f'    <geom class="frame" type="box" size="{_v(hx + 0.04, 0.01, 0.01)}" pos="{_v(0, sy * (hy + POST_OFFSET_M), post_top)}"/>'
             for sy in (-1, 1)]
    nl = "\n"
    return f"""<!-- MANTA-RAY rig, generated by mantaray.sim.model from sim/rig.py: do not edit by hand. -->
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
    <flexcomp name="{FABRIC}" type="grid" dim="2" dof="full" count="{fab.resolution} {fab.resolution} 1"
              spacing="{_v(fab.spacing_m, fab.spacing_m, fab.spacing_m)}" pos="{_v(0, 0, z0)}"
              radius="{_v(fab.radius_m)}" mass="{_v(fab.mass_kg)}" rgba="0.25 0.45 0.85 1">
      <contact condim="{c.condim}" friction="{_v(*c.friction)}" solref="{_v(*c.solref)}"
               solimp="{_v(*c.solimp)}" selfcollide="none"/>
      <edge equality="true" solref="{_v(*fab.edge_solref)}" solimp="{_v(*fab.edge_solimp)}"/>
      <elasticity young="{_v(fab.young_pa)}" poisson="{_v(fab.poisson)}" thickness="{_v(fab.thickness_m)}"
                  damping="{_v(fab.damping_s)}" elastic2d="bend"/>
    </flexcomp>
  </worldbody>
  <equality>
{nl.join(welds)}
  </equality>
  <actuator>
{nl.join(actuators)}
  </actuator>
</mujoco>
"""


def _object_xml(rig: Rig) -> tuple[str, str]:
    """(asset lines, body) for the rig's object, dropped above the fabric's centre."""
    o, c = rig.object, rig.contact
    asset = ""
    if o.mesh is not None:
        m = o.mesh
        src = f'file="{m.file}"' if m.file else f'builtin="{m.builtin}" params="{_v(*m.params)}"'
        asset = f'    <mesh name="{m.name}" {src} scale="{_v(*m.scale)}" inertia="convex"/>'
    shape = f'type="mesh" mesh="{o.mesh.name}"' if o.mesh else f'type="{o.shape}" size="{_v(*o.size_m)}"'
    body = f"""    <body name="{OBJECT}" pos="{_v(0, 0, rig.frame.z0_m + 0.1)}">
      <freejoint name="{OBJECT}"/>
      <geom name="{OBJECT}" {shape} mass="{_v(o.mass_kg)}" pos="{_v(*o.geom_pos_m)}"
            euler="{_v(*o.geom_euler_rad)}" rgba="{_v(*o.rgba)}" condim="{c.condim}"
            friction="{_v(*c.friction)}" solref="{_v(*c.solref)}" solimp="{_v(*c.solimp)}"/>
      <site name="{MARKER}" pos="{_v(0, 0, o.half_height_m)}" size="0.005" rgba="0 0 0 1"/>
    </body>"""
    return asset, body


MARKER_TEXTURE_PX = 256        # [px] side of each ArUco texture (a multiple of the marker's 8 cells with its quiet zone)
MARKER_PLATE_M = 0.001         # [m] half thickness of a marker plate (visual only)


def _marker_xml(rig: Rig) -> tuple[str, str, str]:
    """(assets, world geoms, object geom) drawing the tracker's ArUco markers that the rig's camera asks for."""
    if not (rig.camera.corner_markers or rig.camera.object_marker):
        return "", "", ""
    from mantaray.host.markers import MarkerLayout, quiet_scale

    layout = MarkerLayout()
    ids = [*layout.corner_ids, layout.object_id]
    assets = "\n".join(f'    <texture name="aruco{i}" type="2d" file="aruco_{i}.png"/>\n'
                       f'    <material name="aruco{i}" texture="aruco{i}" texrepeat="1 1" specular="0" shininess="0"/>'
                       for i in ids)
    half_corner = layout.corner_size_m * quiet_scale(layout) / 2
    z0 = rig.frame.z0_m
    world = "\n".join(f'    <geom name="corner_marker{k}" type="box" size="{_v(half_corner, half_corner, MARKER_PLATE_M)}" '
                      f'pos="{_v(x, y, z0 - MARKER_PLATE_M)}" material="aruco{i}" contype="0" conaffinity="0"/>'
                      for k, (i, (x, y)) in enumerate(zip(layout.corner_ids, layout.corner_centres_m()))
                      if rig.camera.corner_markers)
    half_object = layout.object_size_m * quiet_scale(layout) / 2
    top = rig.object.half_height_m
    on_object = (f'      <geom name="object_marker" type="box" size="{_v(half_object, half_object, MARKER_PLATE_M)}" '
                 f'pos="{_v(0, 0, top + MARKER_PLATE_M)}" material="aruco{layout.object_id}" mass="0" contype="0" '
                 f'conaffinity="0"/>') if rig.camera.object_marker else ""  # on the object's top
    return assets, world, on_object


def write_marker_textures(directory: Path) -> None:
    """The ArUco textures the scene refers to, as PNG files in directory."""
    import imageio.v2 as imageio

    from mantaray.host.markers import MarkerLayout, marker_image

    layout = MarkerLayout()
    directory.mkdir(parents=True, exist_ok=True)
    for i in (*layout.corner_ids, layout.object_id):
        imageio.imwrite(directory / f"aruco_{i}.png", marker_image(layout, i, MARKER_TEXTURE_PX))


def scene_xml(rig: Rig) -> str:
    """The scene: includes the model file, adds floor, light, the overhead camera and the object."""
    z0, cam = rig.frame.z0_m, rig.camera
    asset, body = _object_xml(rig)
    marker_assets, marker_geoms, object_marker = _marker_xml(rig)
    if object_marker:
        body = body.replace("    </body>", f"{object_marker}\n    </body>")
    return f"""<!-- MANTA-RAY scene with the {rig.object.name}, generated by mantaray.sim.model: do not edit by hand. -->
<mujoco model="manta_ray scene ({rig.object.name})">
  <include file="{MODEL_FILE}"/>
  <statistic center="{_v(0, 0, z0 - 0.2)}" extent="1.2"/>
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
    <camera name="{OVERHEAD}" pos="{_v(0, 0, z0 + cam.height_above_z0_m)}" xyaxes="1 0 0 0 1 0"
            fovy="{_v(cam.fovy_deg)}"/>
{marker_geoms}
{body}
  </worldbody>
</mujoco>
"""


def write_model(rig: Rig, directory: str | Path) -> Path:
    """Write manta_ray.xml, scene_<object>.xml and the object's mesh file into directory; return the scene path.

    The files carry flexcomp's own triangulation; load() re-meshes it with alternating diagonals.
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    (directory / MODEL_FILE).write_text(model_xml(rig))
    mesh = rig.object.mesh
    if mesh is not None and mesh.file:
        (directory / "assets").mkdir(exist_ok=True)
        shutil.copyfile(ASSETS / mesh.file, directory / "assets" / mesh.file)
    if rig.camera.corner_markers or rig.camera.object_marker:
        write_marker_textures(directory / "assets")
    scene = directory / f"scene_{rig.object.name}.xml"
    scene.write_text(scene_xml(rig))
    return scene


class SimulationUnstable(RuntimeError):
    """MuJoCo reported a diverging step (NaN or huge accelerations) and reset its state: the physics is not valid."""

    def __init__(self, when: str) -> None:
        self.when = when
        super().__init__(f"{when}; the rig's parameters are too stiff for the timestep (see sim/README.md)")

    def __reduce__(self):              # across processes (a worker's trial) with its message once
        return type(self), (self.when,)


def _set_rolling_damping(model: mujoco.MjModel, rig: Rig) -> None:
    """Damping on the object's three rotational dofs: rig.contact.rolling_damping_per_s x its inertia about its lowest point.

    For a sphere rolling on a level sheet that makes its speed decay at exactly that rate (I + m r^2 is
    the rolling inertia about the contact). MJCF cannot damp only the rotation of a free joint, so this
    is set on the compiled model; the files write_model() writes leave it out.
    """
    body = model.body(OBJECT).id
    mass_kg, inertia = model.body_mass[body], model.body_inertia[body]
    about_contact = float(np.mean(inertia)) + mass_kg * rig.object.half_height_m ** 2   # [kg m^2]
    dof = model.jnt_dofadr[model.joint(OBJECT).id]
    model.dof_damping[dof + 3:dof + 6] = rig.contact.rolling_damping_per_s * about_contact


def load(rig: Rig, fabric_settle_s: float = 2.0) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """Compile the scene through MjSpec with the alternating mesh, let the bare fabric settle, keep that as REST_KEY.

    The object is parked on the floor beside the frame while the fabric settles; place_object()
    starts from REST_KEY. The returned data is in the REST_KEY state.
    """
    with tempfile.TemporaryDirectory() as tmp:
        spec = mujoco.MjSpec.from_file(str(write_model(rig, tmp)))
        spec.flexes[0].elem = alternating_elements(rig.fabric.resolution).ravel().tolist()
        spec.add_key(name=REST_KEY)
        model = spec.compile()
    _set_rolling_damping(model, rig)
    data = mujoco.MjData(model)
    qadr = model.jnt_qposadr[model.joint(OBJECT).id]
    park_x_m = rig.frame.size_x_m / 2 + PARK_OFFSET_M
    data.qpos[qadr:qadr + 7] = [park_x_m, 0.0, rig.object.half_height_m + 0.01, 1, 0, 0, 0]  # dropped 1 cm
    diverged = data.warning[mujoco.mjtWarning.mjWARN_BADQACC]   # a live view of MuJoCo's counter
    for _ in range(round(fabric_settle_s / model.opt.timestep)):
        mujoco.mj_step(model, data)
        if diverged.number:            # MuJoCo restarts a diverged state from zero: nothing after it is valid
            raise SimulationUnstable("the physics diverged while the bare fabric settled")
    key = model.key(REST_KEY).id
    model.key_time[key] = 0.0
    model.key_qpos[key] = data.qpos
    model.key_qvel[key] = data.qvel
    model.key_act[key] = data.act
    model.key_ctrl[key] = data.ctrl
    mujoco.mj_resetDataKeyframe(model, data, key)
    mujoco.mj_forward(model, data)
    return model, data


def step_until(model: mujoco.MjModel, data: mujoco.MjData, until_s: float, after_step=None) -> None:
    """Step until data.time is within half a step of until_s [s, physics time], calling after_step(data) after each
    step; raise SimulationUnstable at the step MuJoCo reports a diverged state (it resets it to time 0, so the loop
    would otherwise start over)."""
    diverged = data.warning[mujoco.mjtWarning.mjWARN_BADQACC]   # a live view of MuJoCo's counter
    before = diverged.number
    end = until_s - 0.5 * model.opt.timestep
    while data.time < end:
        mujoco.mj_step(model, data)
        if after_step is not None:
            after_step(data)
        if diverged.number != before:
            raise SimulationUnstable(f"the physics diverged before t = {until_s:.3f} s")


def set_commands(model: mujoco.MjModel, data: mujoco.MjData, a_m) -> None:
    """Set the four actuator commands a_i [m] (+ = corner lowered, PROTOCOL.md §5), clipped to ±range."""
    a = np.asarray(a_m, dtype=float)
    if a.shape != (N_ACTUATORS,) or not np.all(np.isfinite(a)):
        raise ValueError(f"need 4 finite commands in metres, got {a_m!r}")
    lo, hi = model.actuator_ctrlrange[:N_ACTUATORS].T
    data.ctrl[:N_ACTUATORS] = np.clip(a, lo, hi)


def _flex_id(model: mujoco.MjModel) -> int:
    return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_FLEX, FABRIC)


def fabric_height(model: mujoco.MjModel, data: mujoco.MjData, x_m: float, y_m: float) -> float:
    """Height [m, world z] of the fabric's top surface at (x, y): highest triangle above that point."""
    flex = _flex_id(model)
    v = data.flexvert_xpos[model.flex_vertadr[flex]:model.flex_vertadr[flex] + model.flex_vertnum[flex]]
    adr, num = model.flex_elemdataadr[flex], model.flex_elemnum[flex]
    tri = v[model.flex_elem[adr:adr + 3 * num].reshape(-1, 3)]
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    ok = np.abs(det) > 1e-12
    det = np.where(ok, det, 1.0)
    u = ((x_m - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (y_m - a[:, 1])) / det
    w = ((b[:, 0] - a[:, 0]) * (y_m - a[:, 1]) - (x_m - a[:, 0]) * (b[:, 1] - a[:, 1])) / det
    inside = ok & (u >= 0) & (w >= 0) & (u + w <= 1)
    if not inside.any():
        raise ValueError(f"({x_m}, {y_m}) is not over the fabric")
    z = a[:, 2] + u * (b[:, 2] - a[:, 2]) + w * (c[:, 2] - a[:, 2])
    return float(z[inside].max() + model.flex_radius[flex])


def object_xy(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    """The object's position: its centre's (x, y) [m] in the fabric frame (origin at the module's centre).

    The centre, not the marker site on its top: a rolling sphere carries the site round with it (up to a
    radius off the centre), while a camera sees the sphere where its centre is. For an object standing
    upright the two agree.
    """
    return data.body(OBJECT).xpos[:2].copy()


def object_speed(model: mujoco.MjModel, data: mujoco.MjData) -> tuple[float, float]:
    """(linear speed [m/s] of the object's origin, angular speed [rad/s])."""
    dadr = model.jnt_dofadr[model.joint(OBJECT).id]
    return float(np.linalg.norm(data.qvel[dadr:dadr + 3])), float(np.linalg.norm(data.qvel[dadr + 3:dadr + 6]))


def fell_off(model: mujoco.MjModel, data: mujoco.MjData, rule: FallRule = FallRule()) -> bool:
    """Whether the object has left the fabric, by rule (pass rig.fall); any one of:

    - its marker is outside the frame by more than rule.outside_margin_m in x or y (the frame's
      half-sizes are read from the carriages' positions);
    - its centre is more than rule.below_fabric_m below the fabric's lowest vertex (it went over an
      edge or through the cloth);
    - its centre is below rule.floor_z_m (on the floor).
    """
    half = np.abs(model.body("carriage3").pos[:2])
    x, y = object_xy(model, data)
    z = data.body(OBJECT).xpos[2]
    flex = _flex_id(model)
    lowest = data.flexvert_xpos[model.flex_vertadr[flex]:model.flex_vertadr[flex] + model.flex_vertnum[flex], 2].min()
    return bool(abs(x) > half[0] + rule.outside_margin_m or abs(y) > half[1] + rule.outside_margin_m
                or z < lowest - rule.below_fabric_m or z < rule.floor_z_m)


class ObjectNotSettled(RuntimeError):
    """place_object() gave up: the object fell off or was still moving at the time limit."""


def drop_object(model: mujoco.MjModel, data: mujoco.MjData, x_m: float, y_m: float, *, yaw_rad: float = 0.0) -> None:
    """Reset to REST_KEY and put the object upright, DROP_CLEARANCE_M above the fabric at (x, y), at rest in the air."""
    mujoco.mj_resetDataKeyframe(model, data, model.key(REST_KEY).id)
    mujoco.mj_forward(model, data)
    half_height_m = model.site(MARKER).pos[2]
    z = fabric_height(model, data, x_m, y_m) + half_height_m + DROP_CLEARANCE_M
    qadr = model.jnt_qposadr[model.joint(OBJECT).id]
    data.qpos[qadr:qadr + 7] = [x_m, y_m, z, np.cos(yaw_rad / 2), 0.0, 0.0, np.sin(yaw_rad / 2)]
    mujoco.mj_forward(model, data)


def place_object(model: mujoco.MjModel, data: mujoco.MjData, x_m: float, y_m: float, *,
                 yaw_rad: float = 0.0, settle_max_s: float = 3.0, rule: FallRule = FallRule()) -> float:
    """drop_object() at (x, y), then step until the object is at rest.

    Returns the settling time [s] (simulated). At rest: linear speed below AT_REST_SPEED_M_PER_S and
    angular speed below AT_REST_SPIN_RAD_PER_S for AT_REST_HOLD_S. Raises ObjectNotSettled if it
    falls off (rule) or is still moving after settle_max_s. data.time is left at the settling time.
    """
    drop_object(model, data, x_m, y_m, yaw_rad=yaw_rad)
    hold_steps = round(AT_REST_HOLD_S / model.opt.timestep)
    still = 0
    while data.time < settle_max_s:
        mujoco.mj_step(model, data)
        if fell_off(model, data, rule):
            raise ObjectNotSettled(f"object fell off at t = {data.time:.3f} s")
        v, w = object_speed(model, data)
        still = still + 1 if v < AT_REST_SPEED_M_PER_S and w < AT_REST_SPIN_RAD_PER_S else 0
        if still >= hold_steps:
            return float(data.time)
    raise ObjectNotSettled(f"object still moving after {settle_max_s} s")
