"""MuJoCo model of the rig: every scene compiles and steps without warnings, objects rest, corners roll the sphere."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from mantaray.sim.model import mjcf as J
from mantaray.sim.model import model as M
from mantaray.sim.model.objects import OBJECTS
from mantaray.sim.model.rig import STRETCH_MODELS, Rig

RIG = Rig()
GRID = RIG.module.grid  # one module: actuators 0..3 at its corners (PROTOCOL.md §5)
REST_SPEED_M_PER_S = 0.02  # [m/s] "at rest" for the test: well below rolling, above the fabric's jitter
REST_SPIN_RAD_PER_S = 0.5  # [rad/s]
STEP_S = 2.0  # [s] each scene is stepped this long after the object is placed
CORNER_DROP_M = 0.1  # [m] how far one corner is lowered in the rolling test
ROLL_S = 2.5  # [s] the drop takes 0.5 s at 0.2 m/s; the sphere rolls in the rest


def _warnings(data: mujoco.MjData) -> dict[str, int]:
    return {mujoco.mjtWarning(i).name: w.number for i, w in enumerate(data.warning) if w.number}


def test_alternating_mesh_is_mirror_symmetric():
    n = RIG.fabric.resolution
    tris = J.alternating_elements(n, n)
    assert tris.shape == (2 * (n - 1) ** 2, 3)
    xy = np.array([divmod(v, n) for v in range(n * n)], dtype=float)
    edges = {tuple(sorted((t[i], t[(i + 1) % 3]))) for t in tris for i in range(3)}
    for mirror in (lambda p: (n - 1 - p[0], p[1]), lambda p: (p[0], n - 1 - p[1])):
        mapped = {tuple(sorted(int(q[0] * n + q[1]) for q in (mirror(xy[a]), mirror(xy[b])))) for a, b in edges}
        assert mapped == edges
    for i in range(GRID.actuator_count):  # every corner cell's diagonal ends on the corner vertex
        assert sum(J.vertex_id(RIG, *J.node_vertex(RIG, i)) in t for t in tris) == 2


@pytest.mark.parametrize("name", OBJECTS)
def test_written_scene_compiles_as_plain_xml(tmp_path, name):
    scene = J.write_model(RIG.with_object(name), tmp_path)
    model = mujoco.MjModel.from_xml_path(str(scene))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert model.nu == GRID.actuator_count == 4 and model.nflex == 1
    assert np.allclose(data.cam("overhead").xmat.reshape(3, 3)[:, 2], [0, 0, 1])  # looks straight down (-z)
    for i, (sx, sy) in enumerate(((-1, -1), (1, -1), (-1, 1), (1, 1))):
        assert np.allclose(
            data.body(f"carriage{i}").xpos,
            [sx * RIG.module.size_x_m / 2, sy * RIG.module.size_y_m / 2, RIG.module.z0_m],
        )


def _seeded_steps(model: mujoco.MjModel, data: mujoco.MjData, seed: int, steps: int) -> np.ndarray:
    """qpos after each of `steps` steps under corner commands drawn from seed, changed every 0.25 s."""
    rng, out = np.random.default_rng(seed), []
    for k in range(steps):
        if k % round(0.25 / model.opt.timestep) == 0:
            M.set_commands(model, data, rng.uniform(-0.15, 0.15, model.nu))
        mujoco.mj_step(model, data)
        out.append(data.qpos.copy())
    return np.array(out)


def _same_start(source: tuple[mujoco.MjModel, mujoco.MjData], model: mujoco.MjModel) -> mujoco.MjData:
    """Data for model in exactly the state source's data is in."""
    spec = mujoco.mjtState.mjSTATE_INTEGRATION
    state = np.empty(mujoco.mj_stateSize(source[0], spec))
    mujoco.mj_getState(source[0], source[1], state, spec)
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, state, spec)
    return data


@pytest.mark.parametrize("stretch", STRETCH_MODELS)
def test_the_written_scene_is_the_model_that_runs(tmp_path, stretch):
    rng = np.random.default_rng(13)
    rig = RIG.with_object(str(rng.choice(list(OBJECTS))))
    rig = dataclasses.replace(rig, fabric=dataclasses.replace(rig.fabric, stretch=stretch))
    loaded, data = M.load(rig)
    written = mujoco.MjModel.from_xml_path(str(J.write_model(rig, tmp_path)))
    for name in dir(loaded):  # every compiled array but the keyframe load() fills and the asset paths (other folders)
        a = getattr(loaded, name)
        if isinstance(a, np.ndarray) and not name.startswith(("key_", "paths", "_sizes")):
            assert np.array_equal(a, getattr(written, name), equal_nan=True), name
    M.place_object(loaded, data, *rng.uniform(-0.1, 0.1, 2), rule=rig.fall)
    from_disk = _same_start((loaded, data), written)
    steps = round(1.0 / loaded.opt.timestep)
    assert np.array_equal(_seeded_steps(loaded, data, 5, steps), _seeded_steps(written, from_disk, 5, steps))


def test_the_object_joints_step_as_a_free_joint_with_its_rotation_damped(sphere_scene, tmp_path):
    """Three slides and a ball (mjcf.OBJECT_SLIDES, OBJECT_TURN) are a free joint whose rotation alone is damped."""
    model, data = sphere_scene[0], mujoco.MjData(sphere_scene[0])  # the fixture's data stays in the rest state
    spec = mujoco.MjSpec.from_file(str(J.write_model(RIG, tmp_path)))
    body = spec.body(J.OBJECT)
    for joint in list(body.joints):
        spec.delete(joint)
    body.add_freejoint()
    free = spec.compile()
    dof = free.jnt_dofadr[free.body_jntadr[free.body(J.OBJECT).id]]
    free.dof_damping[dof + 3 : dof + 6] = J.rolling_damping(RIG)
    assert np.array_equal(free.dof_damping, model.dof_damping)
    M.place_object(model, data, 0.03, -0.02, rule=RIG.fall)
    as_free = _same_start((model, data), free)
    steps = round(1.0 / model.opt.timestep)
    assert np.array_equal(_seeded_steps(model, data, 8, steps), _seeded_steps(free, as_free, 8, steps))


def test_rolling_damping_is_the_rate_times_the_inertia_about_the_contact():
    """For the sphere, I + m r^2 = 7/5 m r^2: damped at rate beta, a rolling sphere slows at beta."""
    o = RIG.object
    r = o.size_m[0]
    assert J.rolling_damping(RIG) == pytest.approx(RIG.contact.rolling_damping_per_s * 1.4 * o.mass_kg * r**2, rel=1e-9)


@pytest.fixture(scope="module")
def sphere_scene():
    return M.load(RIG)


@pytest.mark.parametrize("name", OBJECTS)
def test_object_comes_to_rest_on_the_fabric(name, sphere_scene):
    model, data = sphere_scene if name == "sphere" else M.load(RIG.with_object(name))
    assert M.fell_off(model, data, RIG.fall)  # parked on the floor in the rest keyframe
    M.place_object(model, data, 0.0, 0.0, rule=RIG.fall)
    while data.time < STEP_S:
        mujoco.mj_step(model, data)
    assert _warnings(data) == {}
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))
    assert not M.fell_off(model, data, RIG.fall)
    v, w = M.object_speed(model, data)
    assert v < REST_SPEED_M_PER_S and w < REST_SPIN_RAD_PER_S
    x, y = M.object_xy(model, data)
    assert np.hypot(x, y) < 0.05
    assert data.body(J.OBJECT).xpos[2] > M.fabric_height(model, data, x, y)


@pytest.mark.parametrize("corner", range(GRID.actuator_count))
def test_lowering_a_corner_rolls_the_sphere_toward_it(corner, sphere_scene):
    model, data = sphere_scene
    M.place_object(model, data, 0.0, 0.0, rule=RIG.fall)
    start_xy, start_s = M.object_xy(model, data), data.time
    commands = np.zeros(model.nu)
    commands[corner] = CORNER_DROP_M
    M.set_commands(model, data, commands)
    lift = model.jnt_qposadr[model.joint(f"lift{corner}").id]
    half_way_s = 0.5 * CORNER_DROP_M / RIG.actuators.speed_m_per_s  # [s] at top speed, half the drop by now
    while data.time < start_s + half_way_s:
        mujoco.mj_step(model, data)
    assert data.qpos[lift] <= 0.5 * CORNER_DROP_M * 1.05  # speed-limited: no further than that
    while data.time < start_s + ROLL_S:
        mujoco.mj_step(model, data)
    carriage = data.body(f"carriage{corner}").xpos
    assert carriage[2] == pytest.approx(RIG.module.z0_m - CORNER_DROP_M, abs=2e-3)  # + command lowers
    vertex = data.flexvert_xpos[J.vertex_id(RIG, *J.node_vertex(RIG, corner))]
    assert np.linalg.norm(vertex - carriage) < 2e-3  # corner stays welded
    toward = np.array(GRID.actuator_xy(corner)) / np.hypot(*GRID.actuator_xy(corner))
    assert (M.object_xy(model, data) - start_xy) @ toward > 0.01  # sim/README.md: 0.235 m in 4 s
    assert _warnings(data) == {} and not M.fell_off(model, data, RIG.fall)


def test_a_fabric_too_stiff_for_the_timestep_is_refused_not_simulated():
    """MuJoCo resets a diverging state and carries on; load() must say so instead of returning garbage."""
    import dataclasses

    stiff = dataclasses.replace(RIG, fabric=dataclasses.replace(RIG.fabric, young_pa=5e8))
    with pytest.raises(M.SimulationUnstable, match="diverged"):
        M.load(stiff)
