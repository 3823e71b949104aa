"""The 2 x 2 array in simulation: its MuJoCo model from the rig file, its firmware in the loop, and `sim run --rig`."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from mantaray.host.link import Link, LinkError
from mantaray.host.transport import InProcessTransport
from mantaray.protocol import rig as rig_description
from mantaray.sim.model import mjcf as J
from mantaray.sim.model import model as M
from mantaray.sim.model.plant import Plant
from mantaray.sim.model.rig import Rig
from mantaray.sim.trial.bridge import Bridge, TrialSpec

REPO = Path(__file__).resolve().parents[1]
ARRAY = rig_description.named("array_2x2")
FAST = {"resolution": 11, "timestep_s": 0.002}  # the fast mode: a module's 11 x 11, the array's sheet 21 x 21


def _array(resolution: int = 11, timestep_s: float = 0.002) -> Rig:
    return Plant().rig(resolution=resolution, timestep_s=timestep_s).with_description(ARRAY)


@pytest.fixture(scope="module")
def array_bridge():
    return Bridge(Link(InProcessTransport(True, build=ARRAY.name), description=ARRAY), _array(), Plant().tracking())


def test_an_actuator_stands_on_every_node_and_holds_the_sheet_there():
    """Nine carriages where PROTOCOL.md §5 puts them; the sheet is two modules' patches a side, sharing their edge's
    vertices, and after settling each node's vertex hangs at its carriage."""
    rig = _array(resolution=5)
    model, data = M.load(rig, fabric_settle_s=0.5)
    assert model.nu == ARRAY.actuator_count == 9
    assert J.sheet_vertices(rig) == (9, 9) and len(M.fabric_vertices(model, data)) == 81
    for i in range(model.nu):
        carriage = data.body(f"carriage{i}").xpos
        assert carriage[:2] == pytest.approx(ARRAY.grid.actuator_xy(i))
        vertex = M.fabric_vertices(model, data)[J.vertex_id(rig, *J.node_vertex(rig, i))]
        assert np.linalg.norm(vertex - carriage) < 2e-3


def test_every_clamp_holds_the_sheet_along_each_grid_line_it_goes_on_in():
    """Two lines at a frame's corner, three on its edge, four inside (the centre actuator, 4)."""
    rig = _array(resolution=11)
    per_line = int(rig.fabric.corner_clamp_m // rig.fabric.spacing_m + 1e-9)
    for actuator, lines in ((0, 2), (1, 3), (4, 4), (8, 2)):
        assert len(J.clamped_vertices(rig, actuator)) == lines * per_line


def test_commands_are_one_per_actuator():
    rig = _array(resolution=5)
    model, data = M.load(rig, fabric_settle_s=0.1)
    with pytest.raises(ValueError, match="need 9 finite commands"):
        M.set_commands(model, data, np.zeros(4))
    M.set_commands(model, data, np.full(9, 1.0))
    assert np.all(data.ctrl == rig.actuators.range_m)  # clipped to the travel


def test_the_bridge_refuses_a_firmware_built_for_another_shape():
    with pytest.raises(LinkError, match="built for 2 x 2 modules, the simulated rig has 1 x 1"):
        Bridge(Link(InProcessTransport(True, build=ARRAY.name), description=ARRAY), Plant().rig(**FAST))


def test_an_array_trial_hands_the_object_over_and_moves_every_actuator_on_the_driven_plane(array_bridge):
    """From module 0 toward a target in module 1: the firmware drives module 0, then module 1; the simulated carriages
    follow array_commands, which puts the actuators outside the driven module on its plane too (none held level)."""
    result = array_bridge.run(TrialSpec((-0.25, -0.25), (0.25, -0.25), duration_s=6.0, seed=3))
    answered = result.module[result.module >= 0]
    assert answered[0] == 0 and 1 in answered and result.handovers >= 1
    x_at_handover = result.handover_xy_m[0, 0]
    assert abs(x_at_handover) < 0.05  # at the shared edge x = 0, within the band and a frame's roll
    lifts = np.array([array_bridge.data.joint(f"lift{i}").qpos[0] for i in range(9)])
    assert np.any(np.abs(lifts[[2, 5, 8]]) > 0.005)  # the +x column, outside module 0 and on its plane


def test_sim_run_takes_a_rig_file_from_any_folder_and_draws_the_array(tmp_path):
    """A user's own rig file, here a copy of the array's under another name, runs from where it is."""
    mine = tmp_path / "myrig.toml"
    mine.write_text(ARRAY.path.read_text())
    proc = subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "sim", "run", "--rig", str(mine), "--json",
         "--duration", "0.5", "--start=-0.3,-0.3", "--target", "0.3,0.3", "--out", str(tmp_path),
         "--resolution", "11", "--timestep", "0.002"],  # the file's path is the question, not the physics: fast mode
        cwd=REPO, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    result = json.loads(proc.stdout)
    assert result["sim_time_s"] == pytest.approx(0.5, abs=0.01) and "handovers" in result
    assert Path(result["figure"]).stat().st_size > 10_000
    with np.load(result["trajectory"]) as saved:
        assert set(saved["module"][saved["module"] >= 0]) == {0}  # the start's module drives first


@pytest.mark.parametrize(
    "args, needle",
    [
        (("--target", "0.6,0"), "outside the fabric (|x| <= 0.5 m"),
        (("--vision", "blob"), "an array (--rig) runs on the truth"),
    ],
)
def test_sim_run_refuses_what_an_array_cannot_do_before_any_work(args, needle):
    proc = subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "sim", "run", "--rig", "protocol/rigs/array_2x2.toml", *args],
        cwd=REPO, capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert proc.returncode == 2 and needle in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.parametrize(
    "text, needle",
    [
        (b"not toml [", "not a readable TOML file"),
        (bytes(range(256)) * 8, "not a text file"),
        (ARRAY.path.read_bytes().replace(b"module_size_x_m = 0.5", b"module_size_x_m = 1e-9"), "is outside 0.05..5 m"),
        (
            ARRAY.path.read_bytes().replace(b"module_size_x_m = 0.5", b"module_size_x_m = 0.6"),
            "no firmware is built for this rig (module_size_x_m is 0.6",
        ),
    ],
    ids=["not TOML", "binary", "no rig's size", "edited copy"],
)
def test_sim_run_refuses_a_rig_file_it_cannot_run_in_one_line(tmp_path, text, needle):
    bad = tmp_path / "array_2x2.toml"  # the committed file's name: an edited copy must not pass for it
    bad.write_bytes(text)
    proc = subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "sim", "run", "--rig", str(bad)],
        cwd=REPO, capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert proc.returncode == 2 and needle in proc.stderr and "Traceback" not in proc.stderr
    assert proc.stderr.strip().splitlines()[-1].startswith("mantaray sim run: error: ")


def test_a_rendered_frame_shows_the_borders_between_modules():
    """The video's overlay draws the line x = 0 between the modules: a column of pixels brighter than beside it."""
    from mantaray.sim.trial.video import Recorder

    rig = _array(resolution=5)
    model, data = M.load(rig, fabric_settle_s=0.1)
    plain, marked = Recorder(model, fps=10), Recorder(model, fps=10, grid=rig.module.grid)
    for recorder in (plain, marked):
        recorder.mark_target((0.3, 0.3), 0.02, rig.module.z0_m, 0.0)
        recorder.capture(data)
    difference = np.abs(marked.frames[0].astype(int) - plain.frames[0].astype(int)).sum(axis=2)
    columns = np.flatnonzero(difference.sum(axis=0))
    rows = np.flatnonzero(difference.sum(axis=1))
    centre = difference.shape[1] // 2
    assert np.any(np.abs(columns - centre) <= 2) and np.any(np.abs(rows - centre) <= 2)
    mujoco.mj_resetData(model, data)
