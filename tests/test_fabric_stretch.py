"""The sheet's two stretch models (fabric.stretch): edges hold their length both ways, threads only pull."""

from __future__ import annotations

import json
import subprocess
import sys

import mujoco
import numpy as np
import pytest

from mantaray.sim.evaluation import results_file as R
from mantaray.sim.model import mjcf as J
from mantaray.sim.model import model as M
from mantaray.sim.model.parameters import ParameterError
from mantaray.sim.model.plant import Plant

RESOLUTION = 11  # [vertices per side] the cheapest mesh: what is tested holds on every one
STEP_S = 0.0005  # [s]


def _loaded(stretch: str, resolution: int = RESOLUTION) -> tuple:
    rig = Plant("polyester").set({"fabric.stretch": stretch}).rig(resolution=resolution, timestep_s=STEP_S)
    return (rig, *M.load(rig))


def _thread_strain(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    """Each thread's length over its rest length (its range's top), minus 1."""
    return data.ten_length / model.tendon_range[:, 1] - 1


def test_threads_join_every_grid_neighbour_and_both_diagonals_of_every_cell_and_nothing_else_changes():
    rig, threads, _ = _loaded("threads")
    _, edges, _ = _loaded("edges")
    n, spacing = RESOLUTION, rig.fabric.spacing_m
    joined = {}  # the compiled tendons: (vertex, vertex) -> rest length [m]
    for t in range(threads.ntendon):
        adr = threads.tendon_adr[t]
        assert threads.tendon_num[t] == 2 and np.all(threads.wrap_type[adr : adr + 2] == mujoco.mjtWrap.mjWRAP_SITE)
        a, b = (int(threads.site(int(threads.wrap_objid[adr + k])).name.removeprefix(f"{J.FABRIC}_")) for k in (0, 1))
        joined[tuple(sorted((a, b)))] = threads.tendon_range[t, 1]
    assert threads.ntendon == len(joined) == 2 * n * (n - 1) + 2 * (n - 1) ** 2 and edges.ntendon == 0
    for (a, b), length in joined.items():  # each joins grid neighbours at their distance on the flat sheet
        (ia, ja), (ib, jb) = divmod(a, n), divmod(b, n)
        assert max(abs(ia - ib), abs(ja - jb)) == 1
        assert length == pytest.approx(spacing * np.hypot(ia - ib, ja - jb), rel=1e-5)
    assert np.all(threads.tendon_limited == 1) and np.all(threads.tendon_range[:, 0] == 0)
    flex = M._flex_id(threads)
    for name in ("flex_elem", "flex_radius", "flex_condim", "flex_friction", "flex_stiffness", "flex_bending"):
        assert np.array_equal(getattr(threads, name), getattr(edges, name)), name
    assert threads.flex_edgeequality[flex] == 0 and edges.flex_edgeequality[M._flex_id(edges)] == 1
    for i in range(n * n):  # the same point masses on the same slides, welded alike
        tb, eb = threads.body(f"{J.FABRIC}_{i}"), edges.body(f"{J.FABRIC}_{i}")
        assert np.array_equal(tb.pos, eb.pos) and tb.mass == pytest.approx(rig.fabric.mass_kg / n**2, rel=1e-5)
        assert tb.mass == pytest.approx(eb.mass, rel=1e-5)  # written to 6 digits, like every number of the MJCF
        tj, ej = (
            slice(m.body_jntadr[b.id], m.body_jntadr[b.id] + m.body_jntnum[b.id])
            for m, b in ((threads, tb), (edges, eb))
        )
        assert np.array_equal(threads.jnt_type[tj], edges.jnt_type[ej]) and np.array_equal(
            threads.jnt_axis[tj], edges.jnt_axis[ej]
        )
    welds = {
        m: sorted(
            (m.body(int(a)).name, m.body(int(b)).name)
            for a, b, kind in zip(m.eq_obj1id, m.eq_obj2id, m.eq_type, strict=True)
            if kind == mujoco.mjtEq.mjEQ_WELD
        )
        for m in (threads, edges)
    }
    assert welds[threads] == welds[edges] and len(welds[edges]) >= 4  # every corner to its carriage


def test_a_settled_sheet_of_threads_is_taut_where_it_pulls_and_slack_where_it_would_push():
    _, model, data = _loaded("threads")
    strain = _thread_strain(model, data)
    assert strain.max() < 5e-4  # a taut thread stretches less than 0.05 %
    assert (strain < -0.01).mean() > 0.1  # and many are more than 1 % slack: the sheet buckles there


def test_the_sheets_lowest_point_is_the_same_on_two_meshes_with_threads_and_not_with_edges():
    """sim/README.md, Convergence, item 7: threads sag 92.9 and 93.2 mm on 11 and 15 vertices a side; edges 83.9
    and 82.2, and 87.8 on 21 (benchmarks/experiments/mesh_statics.py)."""
    sag = {}
    for stretch in ("threads", "edges"):
        for n in (11, 15):
            rig, model, data = _loaded(stretch, n)
            sag[stretch, n] = rig.module.z0_m - M.fabric_vertices(model, data)[:, 2].min()
    assert sag["threads", 11] == pytest.approx(sag["threads", 15], abs=0.001)
    assert abs(sag["edges", 11] - sag["edges", 15]) > 0.001


def test_a_stretch_model_that_is_not_one_is_refused():
    with pytest.raises(ParameterError, match="fabric.stretch must be one of edges, threads"):
        Plant("polyester").set({"fabric.stretch": "wool"})


def test_a_sheet_of_threads_renders_as_the_same_scene_as_one_of_edges():
    """The threads and their sites are hidden: the camera, the video and the view show the same objects."""
    drawn = {}
    for stretch in ("edges", "threads"):
        _, model, data = _loaded(stretch)
        scene = mujoco.MjvScene(model, maxgeom=10_000)
        mujoco.mjv_updateScene(
            model, data, mujoco.MjvOption(), None, mujoco.MjvCamera(), mujoco.mjtCatBit.mjCAT_ALL, scene
        )
        drawn[stretch] = sorted((g.objtype, g.type) for g in scene.geoms[: scene.ngeom])
    assert drawn["threads"] == drawn["edges"]


def _sim(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "sim", *args], capture_output=True, text=True, timeout=300
    )


def test_sim_run_and_heatmap_run_a_sheet_of_threads_when_set(tmp_path):
    run = _sim("run", "--json", "--duration", "0.5", "--set", "fabric.stretch=threads", "--out", str(tmp_path / "run"))
    assert run.returncode in (0, 1), run.stderr
    assert json.loads(run.stdout)["plant_set"] == {"fabric.stretch": "threads"}
    heat = _sim(
        "heatmap", "--cells", "2", "--only-cells", "0", "--trials", "1", "--duration", "0.5", "--jobs", "1",
        "--set", "fabric.stretch=threads", "--out", str(tmp_path / "heat"),
    )  # fmt: skip
    assert heat.returncode == 0, heat.stderr
    results = R.ResultsFile.load(tmp_path / "heat" / "results.jsonl")
    assert results.experiment.plant_set == (("fabric.stretch", "threads"),) and len(results.records) == 1
    assert results.plant_values["fabric.stretch"] == "threads"


@pytest.mark.parametrize("command", ["run", "heatmap", "fidelity", "calibrate"])
def test_a_setting_that_is_not_one_is_refused_in_one_line_by_every_command_that_takes_it(command):
    done = _sim(command, "--set", "fabric.stretch=wool")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert done.stderr.strip().splitlines()[-1].endswith("fabric.stretch must be one of edges, threads, got 'wool'")
