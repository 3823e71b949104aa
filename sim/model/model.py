"""The rig's MuJoCo model as it runs: compiled from the MJCF files mjcf.py writes, stepped, commanded, and asked where things are."""

from __future__ import annotations

import tempfile
from collections.abc import Sequence

import mujoco
import numpy as np

from . import kernel_contact
from .mjcf import FABRIC, REST_KEY, object_names, write_model
from .rig import FallRule, Rig

ANY_FALL = FallRule()  # the fall rule's defaults, for callers that pass no rig's

AT_REST_SPEED_M_PER_S = 0.01  # [m/s] object linear speed below which it counts as at rest ...
AT_REST_SPIN_RAD_PER_S = 0.5  # [rad/s] ... with its angular speed below this ...
AT_REST_HOLD_S = 0.2  # [s] ... for this long without a break
DROP_CLEARANCE_M = 0.002  # [m] gap left under the object when it is placed above the fabric
PARK_OFFSET_M = 0.35  # [m] the objects wait on the floor this far beyond the +x edge while the fabric settles ...
PARK_SPACING_M = 0.15  # [m] ... object k at y = k times this


class SimulationUnstable(RuntimeError):
    """MuJoCo reported a diverging step (NaN or huge accelerations) and reset its state: the physics is not valid."""

    def __init__(self, when: str, why: str = "") -> None:
        self.when, self.why = when, why
        super().__init__(f"{when}; the rig's parameters are too stiff for the timestep: {why or 'see sim/README.md'}")

    def __reduce__(self):  # across processes (a worker's trial) with its message once
        return type(self), (self.when, self.why)


def _object_qpos_adr(model: mujoco.MjModel, k: int = 0) -> int:
    """Where object k's 7 qpos (x, y, z [m], then its orientation quaternion) start."""
    return int(model.jnt_qposadr[model.joint(object_names(k).slides[0]).id])


def _object_dof_adr(model: mujoco.MjModel, k: int = 0) -> int:
    """Where object k's 6 qvel (world velocity [m/s], then angular velocity in its own frame [rad/s]) start."""
    return int(model.jnt_dofadr[model.joint(object_names(k).slides[0]).id])


def object_count(model: mujoco.MjModel) -> int:
    """How many objects the scene holds (Rig.objects)."""
    k = 0
    while mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, object_names(k).body) >= 0:
        k += 1
    return k


def load(rig: Rig, fabric_settle_s: float = 2.0) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """Compile the scene write_model() writes, as written; let the bare fabric settle and keep that as REST_KEY.

    The objects are parked on the floor beside the frame while the fabric settles; place_objects()
    starts from REST_KEY. The returned data is in the REST_KEY state.
    """
    if rig.contact.model == "kernel":
        kernel_contact.load_plugin()
    with tempfile.TemporaryDirectory() as tmp:
        model = mujoco.MjModel.from_xml_path(str(write_model(rig, tmp)))
    data = mujoco.MjData(model)
    park_x_m = rig.module.grid.half_extent_m[0] + PARK_OFFSET_M
    for k, o in enumerate(rig.objects):
        qadr = _object_qpos_adr(model, k)
        data.qpos[qadr : qadr + 7] = [park_x_m, k * PARK_SPACING_M, o.half_height_m + 0.01, 1, 0, 0, 0]  # dropped 1 cm
    diverged = data.warning[mujoco.mjtWarning.mjWARN_BADQACC]  # a live view of MuJoCo's counter
    for _ in range(round(fabric_settle_s / model.opt.timestep)):
        mujoco.mj_step(model, data)
        if diverged.number:  # MuJoCo restarts a diverged state from zero: nothing after it is valid
            raise SimulationUnstable("the physics diverged while the bare fabric settled", rig.stiffest())
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
    diverged = data.warning[mujoco.mjtWarning.mjWARN_BADQACC]  # a live view of MuJoCo's counter
    before = diverged.number
    end = until_s - 0.5 * model.opt.timestep
    while data.time < end:
        mujoco.mj_step(model, data)
        if after_step is not None:
            after_step(data)
        if diverged.number != before:
            raise SimulationUnstable(f"the physics diverged before t = {until_s:.3f} s")


def set_commands(model: mujoco.MjModel, data: mujoco.MjData, a_m) -> None:
    """Set every actuator's command a_i [m] (+ = lowered, PROTOCOL.md §5), clipped to ±range."""
    a = np.asarray(a_m, dtype=float)
    if a.shape != (model.nu,) or not np.all(np.isfinite(a)):
        raise ValueError(f"need {model.nu} finite commands in metres, got {a_m!r}")
    lo, hi = model.actuator_ctrlrange.T
    data.ctrl[:] = np.clip(a, lo, hi)


def _flex_id(model: mujoco.MjModel) -> int:
    return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_FLEX, FABRIC)


def fabric_vertices(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    """The fabric's vertices now: (x, y, z) [m, world frame; x, y as the fabric frame's], one row each (a view)."""
    flex = _flex_id(model)
    return data.flexvert_xpos[model.flex_vertadr[flex] : model.flex_vertadr[flex] + model.flex_vertnum[flex]]


def fabric_triangles(model: mujoco.MjModel) -> np.ndarray:
    """The fabric's triangles: (k, 3) indices into fabric_vertices' rows."""
    flex = _flex_id(model)
    adr, num = model.flex_elemdataadr[flex], model.flex_elemnum[flex]
    return model.flex_elem[adr : adr + 3 * num].reshape(-1, 3)


def fabric_height(model: mujoco.MjModel, data: mujoco.MjData, x_m: float, y_m: float) -> float:
    """Height [m, world z] of the fabric's top surface at (x, y): the highest triangle above that point (with the mesh
    contact, the surface the object meets); a ValueError where no triangle is under it."""
    flex = _flex_id(model)
    tri = fabric_vertices(model, data)[fabric_triangles(model)]
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


def object_xy(model: mujoco.MjModel, data: mujoco.MjData, k: int = 0) -> np.ndarray:
    """Object k's position: its centre's (x, y) [m] in the fabric frame (origin at the module's centre).

    The centre, not the marker site on its top: a rolling sphere carries the site round with it (up to a
    radius off the centre), while a camera sees the sphere where its centre is. For an object standing
    upright the two agree.
    """
    return data.body(object_names(k).body).xpos[:2].copy()


def object_speed(model: mujoco.MjModel, data: mujoco.MjData, k: int = 0) -> tuple[float, float]:
    """(linear speed [m/s] of object k's origin, angular speed [rad/s])."""
    dadr = _object_dof_adr(model, k)
    return float(np.linalg.norm(data.qvel[dadr : dadr + 3])), float(np.linalg.norm(data.qvel[dadr + 3 : dadr + 6]))


def fell_off(model: mujoco.MjModel, data: mujoco.MjData, rule: FallRule = ANY_FALL, k: int = 0) -> bool:
    """Whether object k has left the fabric, by rule (pass rig.fall); any one of:

    - its marker is outside the frame by more than rule.outside_margin_m in x or y (the frame's
      half-sizes are read from the last carriage's position: PROTOCOL.md §5 numbers it at the (+x, +y) corner);
    - its centre is more than rule.below_fabric_m below the fabric's lowest vertex (it went over an
      edge or through the cloth);
    - its centre is below rule.floor_z_m (on the floor).
    """
    half = np.abs(model.body(f"carriage{model.nu - 1}").pos[:2])
    x, y = object_xy(model, data, k)
    z = data.body(object_names(k).body).xpos[2]
    lowest = fabric_vertices(model, data)[:, 2].min()
    return bool(
        abs(x) > half[0] + rule.outside_margin_m
        or abs(y) > half[1] + rule.outside_margin_m
        or z < lowest - rule.below_fabric_m
        or z < rule.floor_z_m
    )


class ObjectNotSettled(RuntimeError):
    """place_object() gave up: the object fell off or was still moving at the time limit."""


def drop_object(model: mujoco.MjModel, data: mujoco.MjData, x_m: float, y_m: float, *, yaw_rad: float = 0.0) -> None:
    """drop_objects() for a scene of one object."""
    drop_objects(model, data, [(x_m, y_m)], yaws_rad=[yaw_rad])


def drop_objects(
    model: mujoco.MjModel, data: mujoco.MjData, starts_m: Sequence[tuple[float, float]], *, yaws_rad=None
) -> None:
    """Reset to REST_KEY and put every object upright, DROP_CLEARANCE_M above the fabric it meets at its start
    (x, y) [m] (object k at starts_m[k], turned by yaws_rad[k] [rad] about z), at rest in the air."""
    count = object_count(model)
    if len(starts_m) != count:
        raise ValueError(f"the scene holds {count} object{'s' if count > 1 else ''}, given {len(starts_m)} starts")
    yaws_rad = [0.0] * count if yaws_rad is None else list(yaws_rad)
    mujoco.mj_resetDataKeyframe(model, data, model.key(REST_KEY).id)
    mujoco.mj_forward(model, data)
    heights_m = [model.site(object_names(k).marker).pos[2] for k in range(count)]  # [m] each one's centre to top
    for k, ((x_m, y_m), yaw) in enumerate(zip(starts_m, yaws_rad, strict=True)):
        z = fabric_height(model, data, x_m, y_m) + heights_m[k] + DROP_CLEARANCE_M
        qadr = _object_qpos_adr(model, k)
        data.qpos[qadr : qadr + 7] = [x_m, y_m, z, np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)]
    mujoco.mj_forward(model, data)
    if kernel_contact.surface_height(model, data) is None:
        return
    for k in range(count):  # the surface the kernel contact meets, under each
        qadr = _object_qpos_adr(model, k)
        data.qpos[qadr + 2] = (
            kernel_contact.surface_height(model, data, k)
            + model.flex_radius[_flex_id(model)]
            + heights_m[k]
            + DROP_CLEARANCE_M
        )
    mujoco.mj_forward(model, data)


def place_object(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    x_m: float,
    y_m: float,
    *,
    yaw_rad: float = 0.0,
    settle_max_s: float = 3.0,
    rule: FallRule = ANY_FALL,
) -> float:
    """place_objects() for a scene of one object: its settling time [s] (simulated)."""
    return place_objects(model, data, [(x_m, y_m)], yaws_rad=[yaw_rad], settle_max_s=settle_max_s, rule=rule)


def place_objects(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    starts_m: Sequence[tuple[float, float]],
    *,
    yaws_rad=None,
    settle_max_s: float = 3.0,
    rule: FallRule = ANY_FALL,
) -> float:
    """drop_objects() at their starts, then step until every object is at rest.

    Returns the settling time [s] (simulated). At rest: linear speed below AT_REST_SPEED_M_PER_S and
    angular speed below AT_REST_SPIN_RAD_PER_S for AT_REST_HOLD_S, every object at once. Raises ObjectNotSettled
    if one falls off (rule) or one is still moving after settle_max_s. data.time is left at the settling time.
    """
    drop_objects(model, data, starts_m, yaws_rad=yaws_rad)
    count = len(starts_m)
    hold_steps = round(AT_REST_HOLD_S / model.opt.timestep)
    still, moving = 0, []
    while data.time < settle_max_s:
        mujoco.mj_step(model, data)
        moving = []
        for k in range(count):
            if fell_off(model, data, rule, k):
                raise ObjectNotSettled(f"{_which([k], count)}fell off at t = {data.time:.3f} s")
            v, w = object_speed(model, data, k)
            if not (v < AT_REST_SPEED_M_PER_S and w < AT_REST_SPIN_RAD_PER_S):
                moving.append(k)
        still = 0 if moving else still + 1
        if still >= hold_steps:
            return float(data.time)
    raise ObjectNotSettled(f"{_which(moving or list(range(count)), count)}still moving after {settle_max_s} s")


def _which(ks: Sequence[int], count: int) -> str:
    """How a message names objects ks: 'object ' alone in a scene of one, else by their numbers."""
    if count == 1:
        return "object "
    return f"object{'s' if len(ks) > 1 else ''} {', '.join(map(str, ks))} "
