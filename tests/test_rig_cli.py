"""The rig's commands without a rig: the loop on a recorded video against the virtual MCU, and the bench's tools.

The loop with its keys and logs; monitor, stop and estop, jog and zero, markers, calibrate-camera."""

from __future__ import annotations

import fcntl
import json
import os
import re
import signal
import subprocess
import sys
import termios
import time

import cv2
import numpy as np
import pytest
from synthetic_camera import H, W, camera, intrinsics, write_video

from mantaray.host.controller_settings import ControllerSettings
from mantaray.host.link import Link
from mantaray.host.markers import MarkerLayout
from mantaray.host.transport import SerialTransport
from mantaray.host.vmcu import VirtualMcu
from mantaray.paths import REPO
from mantaray.protocol import messages as m
from mantaray.protocol import rig as rig_description

FPS = 12.0


def _video(path, xy_of_frame, frames: int) -> str:
    return write_video(path, xy_of_frame, frames, FPS)


def _mantaray(*args: str, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mantaray.cli", *args], cwd=REPO, capture_output=True, text=True, timeout=300, **kwargs
    )


def _rig(vmcu: VirtualMcu, camera: str, *args: str) -> subprocess.CompletedProcess:
    """`mantaray rig` on the virtual MCU, its camera a video file."""
    return _mantaray("rig", "--port", vmcu.path, "--camera", camera, *args)


def _log(out) -> list[dict]:
    (path,) = out.glob("rig-*.jsonl")
    return [json.loads(line) for line in path.read_text().splitlines()]


@pytest.fixture(scope="module")
def still_video(tmp_path_factory):
    """14 s of the object standing at (0.1, -0.05): the longest use (a board lost at 4 s, 2 s to reconnect) and
    room for a slow start."""
    return _video(tmp_path_factory.mktemp("video") / "still.avi", lambda k: (0.1, -0.05), int(14 * FPS))


def test_rig_runs_the_loop_on_a_video_logs_every_frame_and_plots(still_video, tmp_path):
    with VirtualMcu(clock="wall") as vmcu:
        proc = _mantaray(
            "rig",
            "--port",
            vmcu.path,
            "--camera",
            still_video,
            "--target=-0.1,0.1",
            "--timeout",
            "2",
            "--out",
            str(tmp_path),
        )
    assert proc.returncode == 1, proc.stderr  # not reached: a timeout
    assert proc.stdout.startswith("timeout")
    log = _log(tmp_path)
    kinds = [r["kind"] for r in log]
    assert kinds[0] == "config" and kinds[1] == "identify" and kinds[-1] == "end"
    positions = [r for r in log if r["kind"] == "position"]
    telemetry = [r for r in log if r["kind"] == "telemetry"]
    assert 20 <= len(positions) <= 26 and len(telemetry) == len(positions)
    assert all(r["status"] == "ok" and abs(r["xy_m"][0] - 0.1) < 0.002 for r in positions)
    assert telemetry[-1]["tilt_zx"] < 0 and telemetry[-1]["tilt_zy"] > 0  # steering toward (-0.1, 0.1)
    assert len(list(tmp_path.glob("rig-*.png"))) == 1


def test_rig_reports_when_the_tracker_loses_the_object_and_finds_it_again(tmp_path):
    """The object hidden from the camera for 4 frames (0.33 s, inside the firmware's 0.5 s deadman) of a 3 s video:
    one loss and one return, in the log and on stderr, and the run goes on to its timeout."""
    video = _video(tmp_path / "hidden.avi", lambda k: None if 12 <= k < 16 else (0.1, -0.05), int(3 * FPS))
    with VirtualMcu(clock="wall") as vmcu:
        proc = _rig(vmcu, video, "--target=-0.1,0.1", "--timeout", "2.5", "--out", str(tmp_path))
    assert proc.stdout.startswith("timeout"), proc.stdout + proc.stderr
    events = [r["text"] for r in _log(tmp_path) if r["kind"] == "event" and r["text"].startswith("tracker:")]
    assert events == [
        "tracker: object 0 (marker 10) lost at 1.25 s (last seen at 0.92 s)",
        "tracker: object 0 (marker 10) found again at 1.33 s, after 0.42 s unseen",
    ]
    assert all(e in proc.stderr for e in events)


def test_rig_takes_the_gains_it_is_given(still_video, tmp_path):
    """--gains reaches the firmware's PIDs: with kP alone the tilt is kP times the error [deg/m x m]."""
    with VirtualMcu(clock="wall") as vmcu:
        proc = _mantaray(
            "rig",
            "--port",
            vmcu.path,
            "--camera",
            still_video,
            "--target=-0.1,0.1",
            "--gains",
            "20,0,0",
            "--alpha",
            "0",
            "--timeout",
            "1",
            "--out",
            str(tmp_path),
        )
    assert proc.returncode == 1, proc.stderr
    telemetry = [r for r in _log(tmp_path) if r["kind"] == "telemetry"]
    assert telemetry and all(r["tilt_zx"] == pytest.approx(20 * (-0.1 - 0.1), abs=0.1) for r in telemetry[1:])


def test_rig_takes_a_settings_file_as_the_tuner_writes_it(still_video, tmp_path):
    """The file's controller and gains reach the firmware: the cascade with kP alone tilts kP times the velocity it
    asks for, here its speed limit on both axes [deg s/m x m/s]; at the first frame exactly (no velocity known yet),
    later within what the tracker's jitter makes of the velocity."""
    settings = tmp_path / "settings.toml"
    settings.write_text(
        ControllerSettings(
            "cascade",
            (
                ("configure_cascade.speed_limit", 0.1),
                ("pid.vx.kp", 50.0),
                ("pid.vx.ki", 0.0),
                ("pid.vy.kp", 50.0),
                ("pid.vy.ki", 0.0),
            ),
        ).dumps()
    )
    with VirtualMcu(clock="wall") as vmcu:
        proc = _mantaray(
            "rig",
            "--port",
            vmcu.path,
            "--camera",
            still_video,
            "--target=-0.1,0.1",
            "--settings",
            str(settings),
            "--alpha",
            "0",
            "--timeout",
            "1",
            "--out",
            str(tmp_path),
        )
    assert proc.returncode == 1, proc.stderr  # a timeout: the object stands still
    telemetry = [r for r in _log(tmp_path) if r["kind"] == "telemetry"]
    first, later = telemetry[0], telemetry[1:]
    assert (first["tilt_zx"], first["tilt_zy"]) == (pytest.approx(-5.0, abs=0.006), pytest.approx(5.0, abs=0.006))
    assert later and np.mean([r["tilt_zx"] for r in later]) == pytest.approx(-5.0, abs=0.5)
    assert np.mean([r["tilt_zy"] for r in later]) == pytest.approx(5.0, abs=0.5)


def test_rig_stops_when_the_object_holds_the_target(still_video, tmp_path):
    with VirtualMcu(clock="wall") as vmcu:
        proc = _mantaray(
            "rig",
            "--port",
            vmcu.path,
            "--camera",
            still_video,
            "--target",
            "0.105,-0.05",
            "--hold",
            "0.5",
            "--out",
            str(tmp_path),
        )
    assert proc.returncode == 0 and proc.stdout.startswith("reached"), proc.stderr
    assert _log(tmp_path)[-1]["outcome"] == "reached"


def test_ctrl_c_levels_the_surface_and_stops(still_video, tmp_path):
    with VirtualMcu(clock="wall") as vmcu:
        rig = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "mantaray.cli",
                "rig",
                "--port",
                vmcu.path,
                "--camera",
                still_video,
                "--target=-0.2,0.2",
                "--out",
                str(tmp_path),
            ],
            cwd=REPO,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        time.sleep(4)
        rig.send_signal(signal.SIGINT)
        out, err = rig.communicate(timeout=60)
        assert rig.returncode == 130, err
        link = Link(SerialTransport(vmcu.path))
        link.identify()
        t = link.position(m.ObjectPosition(frame=1, capture_time=1, flags=m.PositionFlags.NOT_VISIBLE))
        link.close()
    assert m.State(t.state) == m.State.IDLE and t.command == (0.0, 0.0, 0.0, 0.0)  # level, motors stopped
    assert _log(tmp_path)[-1]["outcome"] == "interrupted" and out.startswith("interrupted")


def test_a_board_that_goes_away_ends_the_run_with_its_log_and_figure(still_video, tmp_path):
    vmcu = VirtualMcu(clock="wall")
    vmcu.__enter__()
    rig = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "mantaray.cli",
            "rig",
            "--port",
            vmcu.path,
            "--camera",
            still_video,
            "--target=-0.2,0.2",
            "--reconnect-timeout",
            "2",
            "--out",
            str(tmp_path),
        ],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(4)
    vmcu.__exit__(None, None, None)  # unplugged for good
    out, err = rig.communicate(timeout=120)
    assert rig.returncode == 1 and out.startswith("board lost"), err
    assert "the run ended: " in err and "Traceback" not in err
    assert _log(tmp_path)[-1]["outcome"] == "board lost" and len(list(tmp_path.glob("rig-*.png"))) == 1


def test_rig_follows_a_circle(tmp_path):
    video = _video(tmp_path / "c.avi", lambda k: (0.0, 0.0), int(3 * FPS))
    with VirtualMcu(clock="wall") as vmcu:
        proc = _rig(
            vmcu,
            video,
            "--target",
            "0,0",
            "--path",
            "circle",
            "--radius",
            "0.1",
            "--period",
            "4",
            "--out",
            str(tmp_path),
        )
    assert proc.returncode == 1 and proc.stdout.startswith("camera stopped"), proc.stderr
    tilts = [(r["tilt_zx"], r["tilt_zy"]) for r in _log(tmp_path) if r["kind"] == "telemetry"]
    angles = np.unwrap([np.arctan2(ty, tx) for tx, ty in tilts[2:]])
    assert angles[-1] - angles[0] > 1.5  # the tilt turns with the target


@pytest.mark.parametrize(
    "args, needle",
    [
        (("--target", "0.4,0"), "not on the fabric"),
        (("--target", "0,0", "--blob", "1,2:3"), "expected H,S,V:H,S,V"),
        (("--target", "0,0", "--path", "circle", "--radius", "0.3"), "not on the fabric"),
        (("--rig", "protocol/rigs/array_2x2.toml", "--target", "0.6,0"), "not on the fabric (|x| <= 0.5 m"),
    ],
)
def test_rig_refuses_bad_input_in_one_line(args, needle):
    proc = _mantaray("rig", "--port", "/nonexistent", "--camera", "0", *args)
    assert proc.returncode == 2 and needle in proc.stderr and "Traceback" not in proc.stderr


def test_an_arrays_target_may_lie_in_any_of_its_modules(still_video):
    """On the 2 x 2 array's 1 x 1 m surface, 0.4 m off centre is on the fabric (one module's is 0.25 m)."""
    proc = _mantaray(
        "rig",
        "--port",
        "/nonexistent",
        "--camera",
        still_video,
        "--rig",
        "protocol/rigs/array_2x2.toml",
        "--target",
        "0.4,-0.45",
    )
    assert "not on the fabric" not in proc.stderr and "no such device" in proc.stderr  # refused for the port only


@pytest.mark.parametrize("command", ["rig", "monitor"])
@pytest.mark.parametrize(
    "port, needle",
    [
        ("/dev/nonexistent-uno", "no such device; is the board plugged in?"),
        ("/etc/hostname", "is a regular file, not a serial device"),
        ("/tmp", "is a folder, not a serial device"),
    ],
)
def test_a_port_that_is_no_serial_device_is_refused_at_once_in_one_line(still_video, command, port, needle):
    extra = ("--camera", still_video, "--target", "0,0", "--timeout", "1") if command == "rig" else ("--count", "1")
    t0 = time.monotonic()
    proc = _mantaray(command, "--port", port, *extra)
    assert proc.returncode == 2 and needle in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
    assert time.monotonic() - t0 < 20  # not the 30 s reconnection wait (a loaded machine starts slowly)


@pytest.mark.parametrize(
    "args, needle",
    [
        (("markers", "--dpi", "0"), "--dpi must be 72..2400"),
        (("markers", "--out", "sheet.svg"), "the file type must be one of .pdf, .png"),
        (("markers", "--out", "/proc/version/sheet.pdf"), "cannot write into /proc/version"),
        (("calibrate-camera", "--board-out", "board.svg"), "the file type must be one of .png"),
        (("calibrate-camera", "--board-out", "board.png", "--squares", "1x1"), "at least 2 x 2 squares"),
        (("calibrate-camera", "--board-out", "board.png", "--squares", "seven"), "expected squares like 7x5"),
        (
            ("calibrate-camera", "--board-out", "board.png", "--marker-mm", "40", "--square-mm", "30"),
            "must be smaller than",
        ),
        (("calibrate-camera", "--camera", "0", "--out", "camera.txt"), "the file type must be one of .npz"),
        (
            ("rig", "--port", "/dev/null", "--camera", "0", "--target", "0,0", "--alpha", "1"),
            "noise_amplitude: 1 m is outside 0..0.25 m",
        ),
        (("jog", "--port", "/dev/null", "--actuator", "16", "--position", "0.1"), "invalid choice: 16"),
        (
            ("jog", "--port", "/dev/null", "--actuator", "4", "--position", "0.1"),
            "--actuator must be 0..3 (one 0.5 x 0.5 m module on 4 actuators, rig.toml), got 4",
        ),
        (
            ("jog", "--port", "/dev/null", "--rig", "nowhere.toml", "--actuator", "4", "--position", "0.1"),
            "argument --rig: nowhere.toml: no such rig file",
        ),
        (
            ("jog", "--port", "/dev/null", "--actuator", "0", "--position", "nan"),
            "jog.position: must be a finite number",
        ),
        (("jog", "--port", "/dev/null", "--actuator", "0", "--position", "0.3"), "--position must be within ±0.25 m"),
        (
            ("jog", "--port", "/dev/null", "--actuator", "0", "--position", "0.1", "--wait", "-1"),
            "argument --wait: must be > 0, got -1",
        ),
        (("monitor", "--port", "/dev/null", "--count", "-1"), "argument --count: must be >= 0, got -1"),
        (("monitor", "--port", "/dev/null", "--seconds", "-1"), "argument --seconds: must be >= 0, got -1"),
        (
            ("rig", "--port", "/dev/null", "--camera", "0", "--target", "0,0", "--hold", "-1"),
            "argument --hold: must be >= 0, got -1",
        ),
        (
            ("rig", "--port", "/dev/null", "--camera", "0", "--target", "0,0", "--timeout", "0"),
            "argument --timeout: must be > 0, got 0",
        ),
        (
            ("rig", "--port", "/dev/null", "--camera", "0", "--target", "0,0", "--marker-height", "-1"),
            "argument --marker-height: must be >= 0, got -1",
        ),
        (
            ("rig", "--port", "/dev/null", "--camera", "0", "--target", "0,0", "--camera-height", "0"),
            "argument --camera-height: must be > 0, got 0",
        ),
        (
            ("rig", "--port", "/dev/null", "--camera", "0", "--target", "0,0", "--marker-height", "1.5"),
            "must be below the camera",
        ),
        (
            ("rig", "--port", "/dev/null", "--camera", "/nonexistent/video.avi", "--target", "0,0"),
            "cannot open video file '/nonexistent/video.avi'",
        ),
        (
            ("calibrate-camera", "--board-out", "board.png", "--square-mm", "0"),
            "argument --square-mm: must be > 0, got 0",
        ),
        (("zero", "--port", "/dev/null", "--actuators", "0,16"), "actuators are 0..15"),
        (("zero", "--port", "/dev/null", "--actuators", "0,9"), "--actuators must be within 0..3"),
        (("zero", "--port", "/dev/null", "--actuators", "one"), "expected actuator indices"),
    ],
)
def test_rig_tools_refuse_bad_input_in_one_line_before_any_work(args, needle, tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "mantaray.cli", *args], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 2 and needle in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_monitor_shows_decoded_telemetry_without_changing_anything():
    with VirtualMcu(clock="wall") as vmcu:
        proc = _mantaray("monitor", "--port", vmcu.path, "--count", "3")
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert "clock wall" in lines[0] and len(lines) == 4
    assert all(re.search(r"\d+\.\d{3} s  idle", line) for line in lines[1:])


def test_jog_moves_one_carriage_and_zero_takes_it_as_the_reference():
    """The bring-up pair (firmware/README.md): each carriage goes where it is told, then counts from there."""
    with VirtualMcu(clock="wall") as vmcu:
        jog = _mantaray("jog", "--port", vmcu.path, "--actuator", "2", "--position", "0.03")
        assert jog.returncode == 0 and "actuator 2: commanded +0.0300 m, measured +0.0300 m" in jog.stdout, jog
        far = _mantaray("jog", "--port", vmcu.path, "--actuator", "2", "--position", "0.3")
        assert far.returncode == 2 and "--position must be within ±0.25 m" in far.stderr  # before connecting
        zero = _mantaray("zero", "--port", vmcu.path, "--actuators", "2")
        assert zero.returncode == 0 and "actuators 2: their present positions are now 0 m" in zero.stdout
        link = Link(SerialTransport(vmcu.path))
        link.identify()
        t = link.position(m.ObjectPosition(frame=1, capture_time=1000, flags=m.PositionFlags.NOT_VISIBLE))
        link.close()
    assert t.measured[2] == pytest.approx(0.0, abs=1e-4) and t.command[2] == 0.0


def test_markers_sheet_is_at_true_size(tmp_path):
    png, pdf = tmp_path / "sheet.png", tmp_path / "sheet.pdf"
    assert _mantaray("markers", "--out", str(png)).returncode == 0
    assert _mantaray("markers", "--out", str(pdf)).returncode == 0
    assert re.search(rb"/MediaBox \[ *0 0 595\.?\d* 841\.?\d* *\]", pdf.read_bytes())  # A4 in points
    image = cv2.imread(str(png), cv2.IMREAD_GRAYSCALE)
    assert np.allclose(image.shape, (297 / 25.4 * 300, 210 / 25.4 * 300), atol=1)  # A4 at 300 dpi
    layout = MarkerLayout()
    detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, layout.dictionary)))
    corners, ids, _ = detector.detectMarkers(image)
    sizes = {}
    for c, i in zip(corners, ids.ravel(), strict=True):
        side_px = np.mean(np.linalg.norm(np.diff(np.vstack([c[0], c[0][:1]]), axis=0), axis=1))
        sizes.setdefault(int(i), []).append(side_px / 300 * 25.4)
    for i in layout.corner_ids:
        assert sizes[i] == [pytest.approx(40.0, abs=0.3)]
    assert sizes[layout.object_ids[0]] == [pytest.approx(30.0, abs=0.3)] * 2


def test_calibrate_recovers_a_cameras_intrinsics_from_charuco_views(tmp_path):
    from mantaray.host.charuco import charuco_board

    board = charuco_board((7, 5), 30.0, 22.0)
    board_px = board.generateImage((1400, 1000))  # 0.21 x 0.15 m at 6667 px/m
    k = intrinsics()
    rng = np.random.default_rng(5)
    writer = cv2.VideoWriter(str(tmp_path / "board.avi"), cv2.VideoWriter_fourcc(*"MJPG"), FPS, (W, H))
    for _ in range(30):
        rvec, tvec = camera(0.5 + rng.uniform(0, 0.2), xy_m=rng.uniform(-0.05, 0.05, 2), tilt_deg=rng.uniform(-25, 25))
        rvec = cv2.Rodrigues(
            cv2.Rodrigues(rvec)[0] @ cv2.Rodrigues(np.array([0, rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5)]))[0]
        )[0]
        world = np.array([[-0.105, 0.075, 0], [0.105, 0.075, 0], [0.105, -0.075, 0], [-0.105, -0.075, 0]])
        pixels, _ = cv2.projectPoints(world, rvec, tvec, k, None)
        src = np.float32([[0, 0], [1400, 0], [1400, 1000], [0, 1000]])
        warp = cv2.getPerspectiveTransform(src, pixels.reshape(4, 2).astype(np.float32))
        frame = cv2.warpPerspective(board_px, warp, (W, H), borderValue=128)
        writer.write(cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR))
    writer.release()
    out = tmp_path / "camera.npz"
    proc = _mantaray("calibrate-camera", "--camera", str(tmp_path / "board.avi"), "--out", str(out))
    assert proc.returncode == 0, proc.stderr + proc.stdout
    found = np.load(out)["camera_matrix"]
    assert found[0, 0] == pytest.approx(k[0, 0], rel=0.03) and found[1, 1] == pytest.approx(k[1, 1], rel=0.03)
    assert found[0, 2] == pytest.approx(k[0, 2], abs=15) and found[1, 2] == pytest.approx(k[1, 2], abs=15)


def _board_state(port: str) -> m.Telemetry:
    """The board's telemetry, asked for as another host would: identify, then a not-visible frame."""
    link = Link(SerialTransport(port))
    link.identify()
    t = link.position(m.ObjectPosition(frame=1, capture_time=1, flags=m.PositionFlags.NOT_VISIBLE))
    link.close()
    return t


def test_estop_latches_the_emergency_stop_and_stop_clears_it():
    with VirtualMcu(clock="wall") as vmcu:
        estop = _mantaray("estop", "--port", vmcu.path)
        assert (
            estop.returncode == 0
            and f"the board is in ESTOP: `mantaray stop --port {vmcu.path}` clears it" in estop.stdout
        ), estop.stderr
        t = _board_state(vmcu.path)
        assert m.State(t.state) == m.State.ESTOP and t.faults & m.Faults.ESTOP and t.command == (0.0,) * 4
        assert m.State(_board_state(vmcu.path).state) == m.State.ESTOP  # latched: a new host sees it
        stop = _mantaray("stop", "--port", vmcu.path)
        assert stop.returncode == 0 and "the board is in IDLE" in stop.stdout, stop.stderr
        t = _board_state(vmcu.path)
    assert m.State(t.state) == m.State.IDLE and t.faults == 0


def test_a_run_on_a_board_in_its_emergency_stop_does_not_start_and_leaves_it_latched(still_video, tmp_path):
    """Only the user clears an emergency stop (`mantaray stop`): a run that finds one must not set the board up."""
    with VirtualMcu(clock="wall") as vmcu:
        assert _mantaray("estop", "--port", vmcu.path).returncode == 0
        rig = _mantaray(
            "rig", "--port", vmcu.path, "--camera", still_video, "--target=-0.1,0.1", "--timeout", "2",
            "--out", str(tmp_path),
        )  # fmt: skip
        t = _board_state(vmcu.path)
    assert rig.returncode == 1 and rig.stdout.startswith("emergency stop"), rig.stderr
    assert f"`mantaray stop --port {vmcu.path}`" in rig.stderr and "Traceback" not in rig.stderr, rig.stderr
    assert m.State(t.state) == m.State.ESTOP and t.command == (0.0,) * 4


def _faulted(port: str) -> None:
    """A deadman fault: the board started, and no camera frame after it for longer than the deadman (0.5 s)."""
    link = Link(SerialTransport(port))
    link.identify()
    link.command(m.SetTarget(x=0.1, y=0.0))
    link.command(m.Start())
    time.sleep(0.8)
    t = link.position(m.ObjectPosition(frame=1, capture_time=1, flags=m.PositionFlags.NOT_VISIBLE))
    link.close()
    assert m.State(t.state) == m.State.FAULT and t.faults == m.Faults.POSITION_TIMEOUT


def test_jog_and_zero_on_a_board_not_idle_name_its_state_and_the_command_that_leaves_it():
    with VirtualMcu(clock="wall") as vmcu:
        _faulted(vmcu.path)
        leave = f"clear it with `mantaray stop --port {vmcu.path}` first"
        zero = _mantaray("zero", "--port", vmcu.path)
        assert (
            zero.returncode == 2
            and f"mantaray zero: zero refused: the board is in FAULT (position_timeout): {leave}" in zero.stderr
        ), zero.stderr
        jog = _mantaray("jog", "--port", vmcu.path, "--actuator", "1", "--position", "0.01")
        assert jog.returncode == 2 and "the board is in FAULT (position_timeout)" in jog.stderr, jog.stderr
        assert _mantaray("stop", "--port", vmcu.path).returncode == 0  # as the message says
        assert _mantaray("estop", "--port", vmcu.path).returncode == 0
        jog = _mantaray("jog", "--port", vmcu.path, "--actuator", "1", "--position", "0.01")
        assert (
            jog.returncode == 2
            and f"jog refused: the board is in ESTOP, the emergency stop (latched): {leave}" in jog.stderr
        ), jog.stderr
        assert _mantaray("stop", "--port", vmcu.path).returncode == 0
        jog = _mantaray("jog", "--port", vmcu.path, "--actuator", "1", "--position", "0.01")
        assert jog.returncode == 0 and "measured +0.0100 m" in jog.stdout, jog.stderr
    assert "Traceback" not in zero.stderr + jog.stderr


def _rig_on_a_terminal(port: str, video: str, out) -> tuple[subprocess.Popen, int]:
    """mantaray rig with a pty as its controlling terminal and stdin, as from a shell: (process, the pty's master)."""
    master, slave = os.openpty()

    def terminal() -> None:
        os.setsid()
        fcntl.ioctl(0, termios.TIOCSCTTY, 0)

    rig = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "mantaray.cli",
            "rig",
            "--port",
            port,
            "--camera",
            video,
            "--target=-0.2,0.2",
            "--out",
            str(out),
        ],
        cwd=REPO,
        stdin=slave,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=terminal,
    )
    os.close(slave)
    return rig, master


@pytest.mark.parametrize(
    "key, outcome, state",
    [(b"e", "emergency stop", m.State.ESTOP), (b" ", "emergency stop", m.State.ESTOP), (b"s", "stopped", m.State.IDLE)],
)
def test_a_key_during_the_run_stops_it_or_latches_the_emergency_stop(still_video, tmp_path, key, outcome, state):
    with VirtualMcu(clock="wall") as vmcu:
        rig, master = _rig_on_a_terminal(vmcu.path, still_video, tmp_path)
        before = termios.tcgetattr(master)
        time.sleep(4)
        os.write(master, key)
        out, err = rig.communicate(timeout=60)
        after = termios.tcgetattr(master)
        os.close(master)
        t = _board_state(vmcu.path)
    assert rig.returncode == 1 and out.startswith(outcome), err
    assert "keys: s stops" in err and _log(tmp_path)[-1]["outcome"] == outcome
    assert m.State(t.state) == state and t.command == (0.0,) * 4  # levelled, or its power cut
    assert after[3] == before[3]  # the terminal echoes again


def test_a_target_typed_during_the_run_is_taken_and_the_run_goes_on(still_video, tmp_path):
    """The nearest thing to clicking a target in the view (Rerun's viewer sends nothing back): t X,Y Enter, from a
    terminal; what any typed text does (taken or refused) is tests/test_typed_target.py's."""
    typed, said, target = b"t-0.1,0.05\r", "new target -0.100,+0.050 m", (-0.1, 0.05)
    with VirtualMcu(clock="wall") as vmcu:
        rig, master = _rig_on_a_terminal(vmcu.path, still_video, tmp_path)
        time.sleep(4)
        os.write(master, typed)
        time.sleep(2)
        os.write(master, b"s")
        out, err = rig.communicate(timeout=60)
        os.close(master)
        t = _board_state(vmcu.path)
    assert rig.returncode == 1 and out.startswith("stopped"), err  # the run went on until the s key
    events = [r["text"] for r in _log(tmp_path) if r["kind"] == "event"]
    assert any(said in e for e in events), events
    positions = [r for r in _log(tmp_path) if r["kind"] == "position"]
    assert positions[-1]["target_m"] == pytest.approx(target)
    assert m.State(t.state) == m.State.IDLE


def test_without_a_terminal_the_rig_reads_no_keys_and_runs_on(still_video, tmp_path):
    """Under nohup or from a pipe stdin is no terminal: what comes in on it is no key."""
    with VirtualMcu(clock="wall") as vmcu:
        proc = _mantaray(
            "rig",
            "--port",
            vmcu.path,
            "--camera",
            still_video,
            "--target=-0.1,0.1",
            "--timeout",
            "1",
            "--out",
            str(tmp_path),
            input="e s e\n",
        )
    assert proc.returncode == 1 and proc.stdout.startswith("timeout"), proc.stderr
    assert "keys:" not in proc.stderr


def test_two_runs_started_in_the_same_second_write_a_log_each(still_video, tmp_path):
    """The clock says the same second to both (faked in each process); each log is whole and reads back."""
    from mantaray.host.runlog import read_run_log

    code = (
        "import sys, time\n"
        "real = time.strftime\n"
        "time.strftime = lambda f, *t: '20260101-120000' if f == '%Y%m%d-%H%M%S' else real(f, *t)\n"
        "from mantaray.cli import main\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    with VirtualMcu(clock="wall") as one, VirtualMcu(clock="wall") as two:
        runs = [
            subprocess.Popen(
                [
                    sys.executable,
                    "-c",
                    code,
                    "rig",
                    "--port",
                    vmcu.path,
                    "--camera",
                    still_video,
                    "--target=-0.1,0.1",
                    "--timeout",
                    "1",
                    "--out",
                    str(tmp_path),
                ],
                cwd=REPO,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
            )
            for vmcu in (one, two)
        ]
        done = [run.communicate(timeout=120) for run in runs]
    assert [run.returncode for run in runs] == [1, 1], done
    logs = sorted(tmp_path.glob("rig-*.jsonl"))
    assert [p.name for p in logs] == ["rig-20260101-120000-2.jsonl", "rig-20260101-120000.jsonl"]
    assert all(len(read_run_log(p).t_s) >= 8 for p in logs)
    assert {p.with_suffix(".png").exists() for p in logs} == {True}
    assert sorted(out.split("; log ")[1].split(";")[0] for out, _ in done) == [str(p) for p in logs]


def test_monitor_waits_for_a_board_that_goes_away_as_the_rig_does(tmp_path):
    """Unplugged and plugged back in: the monitor reconnects and goes on (it exited at once)."""
    port = str(tmp_path / "ttyUNO")
    vmcu = VirtualMcu(clock="wall", path=port)
    monitor = subprocess.Popen(
        [sys.executable, "-m", "mantaray.cli", "monitor", "--port", port, "--count", "30", "--reconnect-timeout", "10"],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    monitor.stdout.readline()  # identified
    for _ in range(5):  # telemetry comes
        assert "idle" in monitor.stdout.readline()
    vmcu.close()
    time.sleep(0.5)
    with VirtualMcu(clock="wall", path=port):
        out, err = monitor.communicate(timeout=60)
    assert monitor.returncode == 0 and "Traceback" not in err, err
    assert f"reconnecting to {port}" in err and f"reconnected to {port}" in err
    assert len([line for line in out.splitlines() if " s  idle" in line]) == 30 - 5


def test_monitor_ends_in_one_line_when_the_board_does_not_come_back(tmp_path):
    port = str(tmp_path / "ttyUNO")
    with VirtualMcu(clock="wall", path=port) as vmcu:
        monitor = subprocess.Popen(
            [sys.executable, "-m", "mantaray.cli", "monitor", "--port", port, "--reconnect-timeout", "1"],
            cwd=REPO,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        monitor.stdout.readline()
        monitor.stdout.readline()
        vmcu.close()
        t0 = time.monotonic()
        out, err = monitor.communicate(timeout=60)
    assert monitor.returncode == 1 and "mantaray monitor: board lost: " in err and "Traceback" not in err, err
    assert time.monotonic() - t0 < 15


def test_an_object_lost_on_an_array_ends_the_run_in_the_deadmans_safe_stop(tmp_path):
    """On the 2 x 2 array as on one module: the object seen for 1 s, then not at all; after the deadman (0.5 s) the
    firmware shuts every actuator down (telemetry: FAULT, position_timeout, level), and the run ends there saying
    so, with its log."""
    video = _video(tmp_path / "lost.avi", lambda k: (0.1, -0.05) if k < FPS else None, int(4 * FPS))
    with VirtualMcu(clock="wall", program="mantaray-vmcu-array_2x2") as vmcu:
        proc = _mantaray(
            "rig", "--port", vmcu.path, "--rig", "protocol/rigs/array_2x2.toml", "--camera", video,
            "--target", "0.3,0.3", "--timeout", "10", "--out", str(tmp_path),
        )  # fmt: skip
        t = _state_of(vmcu.path)
    assert proc.returncode == 1 and proc.stdout.startswith("fault"), (proc.stdout, proc.stderr)
    assert "the board stopped: FAULT (position_timeout)" in proc.stderr and "Traceback" not in proc.stderr
    log = _log(tmp_path)
    faulted = [r for r in log if r["kind"] == "telemetry" and r["state"] == int(m.State.FAULT)]
    assert faulted and faulted[0]["faults"] == int(m.Faults.POSITION_TIMEOUT) and faulted[0]["command"] == [0.0] * 4
    assert log[-1]["kind"] == "end" and t.command == (0.0,) * 4  # the run's end leaves the surface level


def _state_of(port: str) -> m.Telemetry:
    link = Link(SerialTransport(port), description=rig_description.named("array_2x2"))
    try:
        link.identify()
        return link.position(m.ObjectPosition(frame=60000, capture_time=1, flags=m.PositionFlags.NOT_VISIBLE))
    finally:
        link.close()
