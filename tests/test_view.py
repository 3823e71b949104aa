"""The run's view (host/view.py): recordings read back against the trajectory, the live view with real clients
(headless Chromium on the viewer's own web app, and the viewer's own protocol client), and the mistakes around it."""

from __future__ import annotations

import json
import os
import random
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from mantaray.host.view import LiveOptions, RunView, port_free
from mantaray.protocol import messages as m

SEED = 2029
MAIN_FIELDS = ("scalars", "blob", "text", "positions", "strips", "vertex_positions")  # each archetype's value
RUN = [sys.executable, "-m", "mantaray.cli", "sim", "run", "--json"]


def _streams(path: Path) -> dict[str, tuple[np.ndarray, list]]:
    """A recording's streams read back with Rerun's own reader: entity path -> (trial times [ns], one value per row).

    Rerun keeps a duration in whole nanoseconds: compare with _ns(t_s)."""
    from rerun.chunk import RrdReader

    rows: dict[str, list[tuple[float, object]]] = {}
    for chunk in RrdReader(path).stream().to_chunks():
        batch = chunk.to_record_batch()
        if "trial_time" not in batch.schema.names:
            continue  # static: series names, the module's border, the run's settings
        times = batch.column("trial_time").cast("int64").to_pylist()
        columns = [n for n in batch.schema.names if ":" in n and not n.startswith("rerun.")]
        value_column = next(n for n in columns if n.split(":")[1] in MAIN_FIELDS)
        values = batch.column(value_column).to_pylist()
        rows.setdefault(str(chunk.entity_path), []).extend(zip(times, values, strict=True))
    streams = {}
    for entity, pairs in rows.items():
        pairs.sort(key=lambda p: p[0])
        streams[entity] = (np.array([p[0] for p in pairs]), [p[1] for p in pairs])
    return streams


def _ns(t_s: np.ndarray) -> np.ndarray:
    """Trial times [s] as the recording keeps them [ns]."""
    return np.round(np.asarray(t_s) * 1e9).astype(np.int64)


def _scalars(values: list) -> np.ndarray:
    return np.array([v[0] for v in values], dtype=float)


def _free_ports() -> int:
    """A web port whose next port is free too, drawn from the seed below the kernel's ephemeral ports (32768 and up),
    which any outgoing connection may take between this check and the server's bind."""
    rng = random.Random(SEED)
    for _ in range(200):
        port = rng.randrange(20000, 32700)
        if port_free("127.0.0.1", port) and port_free("127.0.0.1", port + 1):
            return port
    raise RuntimeError("no two free ports in a row")


def _stopped(process: subprocess.Popen | None) -> bool:
    """End a process the test started as Ctrl-C would; whether it ended so within 30 s (else it is killed, so that a
    failed test leaves nothing holding its ports)."""
    if process is None or process.poll() is not None:
        return True
    process.send_signal(signal.SIGINT)
    try:
        process.wait(timeout=30)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
        return False
    return True


@pytest.fixture(scope="module")
def recorded(tmp_path_factory) -> tuple[dict, Path]:
    """One short sim run with its outputs: (its JSON summary, its folder)."""
    out = tmp_path_factory.mktemp("run")
    done = subprocess.run([*RUN, "--duration", "1.5", "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert done.returncode in (0, 1), done.stderr
    return json.loads(done.stdout), out


def test_a_recording_reads_back_stream_by_stream_equal_to_the_trajectory(recorded):
    summary, _ = recorded
    trajectory = np.load(summary["trajectory"])
    streams = _streams(Path(summary["recording"]))
    t_s = trajectory["t_s"]
    answered = trajectory["state"] != -1
    for entity, column in [
        ("/plots/tilt_deg/zx", trajectory["tilt_deg"][:, 0]),
        ("/plots/tilt_deg/zy", trajectory["tilt_deg"][:, 1]),
        *[(f"/plots/command_m/a{i}", trajectory["command_m"][:, i]) for i in range(4)],
        *[(f"/plots/measured_m/a{i}", trajectory["measured_m"][:, i]) for i in range(4)],
        ("/plots/state", trajectory["state"]),
    ]:
        times, values = streams[entity]
        assert len(times) == answered.sum(), entity
        np.testing.assert_array_equal(times, _ns(t_s[answered]), err_msg=entity)
        np.testing.assert_array_equal(_scalars(values), column[answered], err_msg=entity)
    seen = np.all(np.isfinite(trajectory["measured_xy_m"]), axis=1)
    for axis, name in enumerate("xy"):
        times, values = streams[f"/plots/position_m/{name}"]
        np.testing.assert_array_equal(times, _ns(t_s[seen]))
        np.testing.assert_array_equal(_scalars(values), trajectory["measured_xy_m"][seen, axis])
        times, values = streams[f"/plots/position_m/target_{name}"]
        np.testing.assert_array_equal(times, _ns(t_s))
        assert set(_scalars(values)) == {trajectory["target_m"][axis]}
    for entity in ("/camera/image", "/world/fabric", "/world/object"):
        np.testing.assert_array_equal(streams[entity][0], _ns(t_s), err_msg=entity)


def test_a_recording_holds_the_runs_settings_and_the_camera_as_jpeg(recorded):
    from rerun.chunk import RrdReader

    summary, _ = recorded
    properties = [
        c for c in RrdReader(summary["recording"]).stream().to_chunks() if "__properties" in str(c.entity_path)
    ]
    names = {n.split(":")[-1] for c in properties for n in c.to_record_batch().schema.names}
    assert {"controller", "object", "plant", "duration", "seed"} <= names
    _, images = _streams(Path(summary["recording"]))["/camera/image"]
    import cv2

    image = cv2.imdecode(np.frombuffer(bytes(images[0][0]), np.uint8), cv2.IMREAD_COLOR)
    assert image is not None and image.shape[0] > 100 and image.std() > 10  # a picture, not a blank


def _blue_share(png: Path) -> float:
    """The share of the camera panel (the layout's top left) that shows the rendered fabric's light blue."""
    import cv2

    shot = cv2.imread(str(png))
    h, w = shot.shape[:2]
    panel = shot[int(0.06 * h) : int(0.29 * h), : w // 2].astype(int)
    b, r = panel[..., 0], panel[..., 2]
    return float(np.mean((b > 170) & (b > r + 40)))


@pytest.mark.skipif(shutil.which("chromium") is None, reason="Debian's chromium is not installed (scripts/setup.sh)")
def test_a_live_run_reaches_a_browser_and_the_viewers_own_client_unchanged(recorded, tmp_path):
    from playwright.sync_api import sync_playwright

    from mantaray.host.view import _rerun_command

    summary, _ = recorded
    port = _free_ports()
    options = LiveOptions(web_port=port)
    run = subprocess.Popen(
        [*RUN, "--duration", "1.5", "--out", str(tmp_path), "--live", "--live-port", str(port), "--linger", "120"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    client = None
    try:
        line = run.stderr.readline()
        assert f"live view at {options.page_url}" in line, line
        client_file = tmp_path / "client.rrd"
        client = subprocess.Popen(
            [*_rerun_command(), options.grpc_url, "--save", str(client_file), "--port", "0", "--bind", "127.0.0.1"],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        with sync_playwright() as p:
            browser = p.chromium.launch(
                executable_path=shutil.which("chromium"),
                args=["--no-sandbox", "--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"],
            )
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.goto(options.page_url)
            deadline, share = time.monotonic() + 90, 0.0
            while time.monotonic() < deadline and share < 0.05:
                time.sleep(3)
                page.screenshot(path=str(tmp_path / "view.png"))
                share = _blue_share(tmp_path / "view.png")
            browser.close()
        assert share >= 0.05, f"the camera panel shows no image ({share:.1%} fabric blue): see {tmp_path}/view.png"
        while "stays at" not in run.stderr.readline():  # the run is over, the server lingers
            pass
        time.sleep(2)
        client.send_signal(signal.SIGINT)
        client.wait(timeout=30)
        received = _streams(client_file)
        written = _streams(Path(summary["recording"]))
        assert set(received) == set(written)
        for entity, (times, _) in received.items():
            assert np.all(np.diff(times) > 0), f"{entity}: timestamps not increasing"
            np.testing.assert_array_equal(times, written[entity][0], err_msg=entity)
    finally:
        assert all([_stopped(process) for process in (run, client)]), "a process did not end on Ctrl-C within 30 s"
    live_summary = json.loads(run.stdout.read())
    a, b = np.load(live_summary["trajectory"]), np.load(summary["trajectory"])
    for key in a.files:  # a browser and a client that came and went changed nothing in the run
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_a_live_port_in_use_is_refused_in_one_line_naming_another(tmp_path):
    port = _free_ports()
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", port))
        taken.listen()
        done = subprocess.run(
            [*RUN, "--duration", "0.2", "--out", str(tmp_path), "--live", "--live-port", str(port)],
            capture_output=True,
            text=True,
            timeout=120,
        )
    assert done.returncode == 2
    error = done.stderr.strip().splitlines()[-1]
    assert f"port {port}" in error and "--live-port" in error and "Traceback" not in done.stderr


@pytest.mark.parametrize("args", [["--linger", "5"], ["--bind", "127.0.0.2"], ["--live-port", "9300"]])
def test_live_options_without_live_are_refused_not_ignored(args, tmp_path):
    done = subprocess.run([*RUN, *args, "--out", str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "add --live" in done.stderr


def test_a_heatmaps_live_view_on_ray_is_refused_before_any_work(tmp_path):
    done = subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "sim", "heatmap", "--executor", "ray", "--live", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2 and "--executor local" in done.stderr and not (tmp_path / "results.jsonl").exists()


def test_a_view_that_listens_beyond_this_machine_says_so(tmp_path):
    from mantaray.host.view import LiveServer

    said = []
    server = LiveServer(LiveOptions("127.0.0.2", _free_ports()), said.append)
    try:
        assert any("warning" in text and "127.0.0.2" in text for text in said)
    finally:
        server.close()
    assert server.process.poll() is not None


def test_a_recording_that_cannot_be_written_is_reported_once_and_the_run_goes_on(tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    said = []
    view = RunView("test", blocker / "run.rrd", None, {"seed": 1}, 4, (0.5, 0.5), said.append)
    for k in range(3):
        view.frame(k / 12, (0.0, 0.0), (0.1, 0.1), 0.02, m.Telemetry())
    assert view.close() is None
    assert len(said) == 1 and "cannot write the recording" in said[0]


def test_the_viewers_server_ends_with_the_process_that_started_it(tmp_path):
    port = _free_ports()
    script = (
        "from mantaray.host.view import LiveOptions, LiveServer; import os, signal; "
        f"LiveServer(LiveOptions(web_port={port}), print); os.kill(os.getpid(), signal.SIGKILL)"
    )
    subprocess.run([sys.executable, "-c", script], timeout=60, env=os.environ)
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and not (port_free("127.0.0.1", port) and port_free("127.0.0.1", port + 1)):
        time.sleep(0.2)
    assert port_free("127.0.0.1", port) and port_free("127.0.0.1", port + 1)


def test_a_rig_run_records_the_camera_with_its_detection_and_the_loop_as_its_log(tmp_path):
    """`mantaray rig` on a video of the object standing still, against the virtual MCU: the recording beside the log
    holds every logged position and telemetry frame, and the camera with the detection at the marker's pixel."""
    import cv2
    from synthetic_camera import camera, intrinsics, write_video

    from mantaray.host.vmcu import VirtualMcu

    truth = (0.1, -0.05)
    video = write_video(tmp_path / "still.avi", lambda k: truth, 36, 12.0)
    with VirtualMcu(clock="wall") as vmcu:
        done = subprocess.run(
            [sys.executable, "-m", "mantaray.cli", "rig", "--port", vmcu.path, "--camera", video]
            + ["--target=-0.1,0.1", "--timeout", "2", "--out", str(tmp_path)],
            capture_output=True,
            text=True,
            timeout=300,
        )
    assert done.returncode == 1, done.stderr  # a timeout
    (log_path,) = tmp_path.glob("rig-*.jsonl")
    recording = log_path.with_suffix(".rrd")
    assert f"recording {recording}" in done.stdout
    log = [json.loads(line) for line in log_path.read_text().splitlines()]
    positions = [r for r in log if r["kind"] == "position"]
    telemetry = [r for r in log if r["kind"] == "telemetry"]
    streams = _streams(recording)
    times, xs = streams["/plots/position_m/x"]
    np.testing.assert_array_equal(_scalars(xs), [r["xy_m"][0] for r in positions])
    assert np.all(np.abs(times - _ns([r["capture_s"] for r in positions])) <= 1000)  # the log keeps whole us
    np.testing.assert_array_equal(_scalars(streams["/plots/tilt_deg/zx"][1]), [r["tilt_zx"] for r in telemetry])
    assert len(streams["/camera/image"][0]) == len(positions)
    marker_px, _ = cv2.projectPoints(np.array([[*truth, 0.0]]), *camera(1.0), intrinsics(), None)
    image = cv2.imdecode(np.frombuffer(bytes(streams["/camera/image"][1][-1][0]), np.uint8), cv2.IMREAD_GRAYSCALE)
    scale = image.shape[1] / 1280  # the view halves a 1280 px camera
    assert scale == 0.5
    detection = np.asarray(streams["/camera/detection"][1][-1][0])
    assert np.hypot(*(detection - marker_px.reshape(2) * scale)) < 1.0
    assert "/log/events" in streams  # the run's end, as the log's end line says it


@pytest.fixture(scope="module")
def small_heatmap(tmp_path_factory) -> Path:
    """A heatmap of 4 cells, 1 trial each, 1 s, on a cheap mesh (what is replayed is the mechanism, not physics)."""
    out = tmp_path_factory.mktemp("heatmap")
    done = subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "sim", "heatmap", "--cells", "2", "--trials", "1", "--duration", "1"]
        + ["--resolution", "11", "--timestep", "0.002", "--jobs", "1", "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    return out


def test_a_heatmap_trial_replays_by_cell_and_number_exactly_into_a_recording(small_heatmap, tmp_path):
    from rerun.chunk import RrdReader

    cell = random.Random(SEED).randrange(4)
    done = subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "sim", "replay", str(small_heatmap), "--cell", str(cell)]
        + ["--trial", "0", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0 and "as the results file has it" in done.stdout, done.stdout + done.stderr
    recording = tmp_path / f"results_cell{cell}_trial0.rrd"
    (entry,) = RrdReader(recording).recordings()
    assert entry.recording_id == f"cell{cell}_trial0"
    streams = _streams(recording)
    assert len(streams["/camera/image"][0]) == len(streams["/plots/position_m/target_x"][0]) > 0


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--cell", "4", "--trial", "0"], "--cell 4 is not a cell of this run (it has cells 0..3)"),
        (["--cell", "0", "--trial", "1"], "--trial 1: this run has trials 0..0"),
        (["--cell", "-1", "--trial", "0"], "must be >= 0"),
    ],
)
def test_a_replay_of_a_trial_not_in_the_run_is_refused_in_one_line(small_heatmap, args, needle):
    done = subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "sim", "replay", str(small_heatmap), *args],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2 and needle in done.stderr and "Traceback" not in done.stderr


def test_a_heatmaps_live_view_shows_one_workers_trials_each_as_its_own_recording(small_heatmap, tmp_path):
    from rerun.chunk import RrdReader

    from mantaray.host.view import _rerun_command

    port = _free_ports()
    options = LiveOptions(web_port=port)
    run = subprocess.Popen(
        [sys.executable, "-m", "mantaray.cli", "sim", "heatmap", "--cells", "2", "--trials", "2", "--duration", "1"]
        + ["--resolution", "11", "--timestep", "0.002", "--jobs", "2", "--out", str(tmp_path / "run")]
        + ["--live", "--live-port", str(port), "--linger", "60"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    client = None
    try:
        assert options.page_url in run.stderr.readline()
        client = subprocess.Popen(
            [*_rerun_command(), options.grpc_url, "--save", str(tmp_path / "client.rrd"), "--port", "0"]
            + ["--bind", "127.0.0.1"],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        while "stays at" not in run.stderr.readline():
            pass
        time.sleep(2)
    finally:
        assert all([_stopped(process) for process in (client, run)]), "a process did not end on Ctrl-C within 30 s"
    shown = {e.recording_id for e in RrdReader(tmp_path / "client.rrd").recordings()}
    every = {f"cell{c}_trial{k}" for c in range(4) for k in range(2)}
    assert shown and shown < every  # one worker's share of the 8 trials, not the other's


def test_a_viewer_that_comes_and_goes_mid_run_changes_nothing_in_the_run(tmp_path):
    """Rerun's own client connects, disconnects and connects again while a run streams; the trajectory is the one
    an unwatched run of the same trial gives."""
    from mantaray.host.view import _rerun_command

    port = _free_ports()
    options = LiveOptions(web_port=port)
    trial = ["--duration", "4", "--seed", "3"]
    run = subprocess.Popen(
        [*RUN, *trial, "--out", str(tmp_path / "live"), "--live", "--live-port", str(port)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert options.page_url in run.stderr.readline()
        for k in range(2):  # comes, goes, comes back
            client = subprocess.Popen(
                [*_rerun_command(), options.grpc_url, "--save", str(tmp_path / f"{k}.rrd"), "--port", "0"]
                + ["--bind", "127.0.0.1"],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
            time.sleep(1.5)
            client.kill()
            client.wait()
        assert run.poll() is None, "the run ended before the viewer came back: lengthen it"
        out, _ = run.communicate(timeout=300)
    finally:
        if run.poll() is None:
            run.kill()
    quiet = subprocess.run(
        [*RUN, *trial, "--out", str(tmp_path / "quiet")], capture_output=True, text=True, timeout=300
    )
    a, b = np.load(json.loads(out)["trajectory"]), np.load(json.loads(quiet.stdout)["trajectory"])
    for key in a.files:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_a_bind_address_not_of_this_machine_is_refused_in_one_line(tmp_path):
    done = subprocess.run(
        [*RUN, "--duration", "0.2", "--out", str(tmp_path), "--live", "--bind", "192.0.2.1"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2 and "--bind takes an address of this machine" in done.stderr
    assert "Traceback" not in done.stderr


def test_a_state_or_fault_this_host_does_not_know_is_shown_as_its_number(tmp_path):
    from rerun.chunk import RrdReader

    said = []
    view = RunView("mantaray_test", tmp_path / "r.rrd", None, {}, 4, (0.5, 0.5), said.append)
    view.frame(0.0, (0.0, 0.0), (0.1, 0.1), 0.02, m.Telemetry(state=200, faults=0x8000))
    assert view.close() == tmp_path / "r.rrd" and said == []
    (chunk,) = [c for c in RrdReader(tmp_path / "r.rrd").stream().to_chunks() if "supervisor" in str(c.entity_path)]
    assert chunk.to_record_batch().column("TextLog:text").to_pylist() == [["state 200, faults 0x8000"]]
