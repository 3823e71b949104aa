"""A run's streams in the Rerun viewer: a recording (.rrd) beside the run's outputs, and a live view in a browser.

One RunView serves the rig (host/rig_run.py) and the simulation (sim/trial/bridge.py): the same entity paths, so a recording
of either opens in the same layout. Time is the trial time [s] on the `trial_time` timeline; positions are [m] in
the fabric frame; tilts [deg]; commands and measured positions [m], + lowers the corner (protocol/schema.toml).

Streams (entity path: what):
    camera/image                  the camera frame (JPEG), with camera/detection, camera/target, camera/epsilon and
                                  camera/trail drawn over it in pixels
    fabric/object, fabric/target  where the object was seen and the target, seen from above [m]; fabric/epsilon,
                                  fabric/trail, fabric/module (the module's border, static)
    plots/position_m/{x,y}        the object's measured position (absent where not seen)
    plots/position_m/target_{x,y} the target
    plots/tilt_deg/{zx,zy}        theta_zx, theta_zy from telemetry
    plots/command_m/a{i}          each actuator's command a_i
    plots/measured_m/a{i}         each actuator's measured position
    plots/state                   the supervisor's state (protocol enum value); log/supervisor: its changes and faults
    plots/link/{name}             link counters (retransmissions, CRC errors, frame errors, lost frames)
    world/fabric, world/object    (simulation) the fabric as a mesh and the object [m, world]
    log/events                    what the rig's run reported (stops, refused targets, its end)
"""

from __future__ import annotations

import contextlib
import errno
import math
import os
import queue
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mantaray.protocol import messages as m

from .link import Link
from .processes import DIE_WITH_PARENT, end

LOOPBACK = "127.0.0.1"
DEFAULT_WEB_PORT = 9090  # the browser's page; the viewer's data server listens on the next port
START_TIMEOUT_S = 20.0  # [s] for the viewer's server to accept connections
SERVER_MEMORY = "1GiB"  # what the live server keeps for browsers that come late; beyond it the oldest goes
TRAIL_FRAMES = 600  # camera frames of trail drawn (50 s at the paper's 12 Hz)
CIRCLE_POINTS = 48  # points of the epsilon circle
JPEG_QUALITY = 80
# [px] A wider camera image is shown halved (or less): a 1280 x 720 camera at 30 Hz would record over 100 MB a minute.
CAMERA_MAX_WIDTH_PX = 640
TIMELINE = "trial_time"
FABRIC_RGB = (90, 160, 230)  # the fabric's colour in the 3D view
FLUSH_TIMEOUT_S = 10.0  # [s] for the streams to take what is left at the end
QUEUE_FRAMES = 4  # camera frames the view's thread may fall behind before the run waits for it


class ViewError(Exception):
    """The live view cannot start (a port in use, no viewer): one line that says why and what to do."""


def port_free(host: str, port: int) -> bool:
    """Whether a TCP port can be bound on host now (by a server, which may reuse a port that closed connections
    still hold in TIME_WAIT)."""
    return _bind_error(host, port) is None


def _bind_error(host: str, port: int) -> OSError | None:
    """Why a server could not bind host:port now, or None when it could."""
    try:
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        with socket.socket(family) as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            probe.bind((host, port))
    except OSError as exc:
        return exc
    return None


@dataclass(frozen=True)
class LiveOptions:
    """Where the live view listens: host (loopback unless --bind), the page's port and the data server's (next)."""

    host: str = LOOPBACK
    web_port: int = DEFAULT_WEB_PORT

    @property
    def grpc_port(self) -> int:
        return self.web_port + 1

    @property
    def grpc_url(self) -> str:
        """Where this machine reaches the data server (a wildcard bind is reached on the loopback)."""
        return f"rerun+http://{self._reach}:{self.grpc_port}/proxy"

    @property
    def page_url(self) -> str:
        return f"http://{self._reach}:{self.web_port}/?url={self.grpc_url.replace('+', '%2B')}"

    @property
    def _reach(self) -> str:
        host = LOOPBACK if self.host in ("0.0.0.0", "::") else self.host
        return f"[{host}]" if ":" in host else host


class LiveServer:
    """The Rerun viewer's own server (`rerun --serve-web`, from the rerun-sdk wheel) in a child process: it serves
    the web viewer and relays the run's streams to every browser that connects, keeping them for late ones.

    A browser that comes, goes or reconnects talks to this process only: the run never waits on it."""

    def __init__(self, options: LiveOptions, report: Callable[[str], None]) -> None:
        self.options = options
        for port, what in ((options.web_port, "web page"), (options.grpc_port, "data server")):
            error = _bind_error(options.host, port)
            if error is None:
                continue
            if error.errno == errno.EADDRINUSE:
                other = options.web_port + 10 if options.web_port + 11 <= 65535 else options.web_port - 10
                raise ViewError(
                    f"port {port} on {options.host} (the live view's {what}) is in use, perhaps by another live "
                    f"view: choose another with --live-port {other}"
                )
            raise ViewError(
                f"the live view cannot listen on {options.host}:{port} ({error.strerror or error}): --bind takes an "
                f"address of this machine"
            )
        if options.host != LOOPBACK:
            report(
                f"warning: the live view listens on {options.host}, not only this machine: anyone who can reach "
                f"it sees the run"
            )
        command = [
            *_rerun_command(),
            "--serve-web",
            "--bind",
            options.host,
            "--port",
            str(options.grpc_port),
            "--web-viewer-port",
            str(options.web_port),
            "--server-memory-limit",
            SERVER_MEMORY,
        ]
        self._errors = tempfile.TemporaryFile()  # its messages: a pipe nobody reads would fill and stop it
        self.process = subprocess.Popen(
            command,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=self._errors,
            start_new_session=True,  # a Ctrl-C at the terminal reaches the run only, which then closes the viewer
            preexec_fn=DIE_WITH_PARENT,
        )
        self._wait_until_serving()

    def _wait_until_serving(self) -> None:
        deadline = time.monotonic() + START_TIMEOUT_S
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                self._errors.seek(0)
                error = self._errors.read().decode(errors="replace").strip().splitlines()
                self.close()
                raise ViewError(f"the live view's server stopped at once: {error[-1] if error else 'no message'}")
            if not port_free(self.options.host, self.options.grpc_port) and not port_free(
                self.options.host, self.options.web_port
            ):
                return
            time.sleep(0.05)
        self.close()
        raise ViewError(f"the live view's server did not start within {START_TIMEOUT_S:g} s")

    def linger(self, seconds: float | None, report: Callable[[str], None]) -> None:
        """After the run: keep serving what it streamed for seconds (None: from a terminal until Enter, else not at
        all), so that a browser opened late still sees the whole run; Ctrl-C ends it sooner."""
        with contextlib.suppress(KeyboardInterrupt, EOFError):
            if seconds is not None and seconds > 0:
                report(f"the run is over; its live view stays at {self.options.page_url} for {seconds:g} s")
                time.sleep(seconds)
            elif seconds is None and _in_foreground():
                report(f"the run is over; its live view stays at {self.options.page_url} until you press Enter")
                input()

    def close(self) -> None:
        end(self.process)
        self._errors.close()


def _rerun_command() -> list[str]:
    """The viewer's own binary, as the rerun-sdk wheel ships it (not its `rerun` wrapper script, which would leave
    the binary running when the wrapper is stopped)."""
    try:
        import rerun_cli
    except ImportError:
        raise ViewError("the Rerun viewer is not installed (the rerun-sdk package): pip install rerun-sdk") from None
    folder = Path(rerun_cli.__file__).parent
    for binary in (folder / "rerun", folder / "rerun.exe", folder / "Rerun.app" / "Contents" / "MacOS" / "Rerun"):
        if binary.exists():
            return [str(binary)]
    raise ViewError(f"the rerun-sdk package has no viewer binary in {folder}: reinstall it (pip install rerun-sdk)")


def _in_foreground() -> bool:
    """stdin is a terminal this process may read (in the background, reading it would stop the process)."""
    try:
        return sys.stdin.isatty() and os.tcgetpgrp(sys.stdin.fileno()) == os.getpgrp()
    except OSError:
        return False


REPORTED_ACTUATORS = next(f.count for f in m.Telemetry.FIELDS if f.name == "command")  # the driven module's corners


class RunView:
    """One run's streams: to a recording file (unless None) and to a live server at live_url (unless None: a
    LiveOptions.grpc_url).

    properties: the run's settings, stored as the recording's metadata. actuators: how many there are (4 on one
    module, n on an array). module_m: the module's size [m] (x, y). report: where a problem with the recording is
    said, once; the run goes on without it. world: the run has a 3D scene (world/: the simulation's). name: the
    recording's id in the viewer's list (default: a fresh one); application: its group there (letters, digits, _)."""

    def __init__(
        self,
        application: str,
        recording: Path | None,
        live_url: str | None,
        properties: dict[str, object],
        actuators: int,
        module_m: tuple[float, float],
        report: Callable[[str], None],
        world: bool = False,
        name: str | None = None,
    ) -> None:
        import rerun as rr
        import rerun.blueprint

        self.rr, self.report, self.actuators = rr, report, actuators
        self.recording_path = recording
        sinks: list = []  # rerun sinks: the file, the live server
        if recording is not None:
            try:
                recording.parent.mkdir(parents=True, exist_ok=True)
                with open(recording, "wb"):
                    pass
                sinks.append(rr.FileSink(str(recording)))
            except OSError as exc:
                self._give_up_recording(f"cannot write the recording {recording}: {exc.strerror or exc}")
        if live_url is not None:
            sinks.append(rr.GrpcSink(live_url))
        # with nowhere to go, every log call is a no-op
        self.stream = rr.RecordingStream(
            application, recording_id=name, send_properties=False, default_enabled=bool(sinks)
        )
        if sinks:
            self.stream.set_sinks(*sinks, default_blueprint=_layout(rr.blueprint, world))
        self._trail_px: list[tuple[float, float]] = []
        self._trail_m: list[tuple[float, float]] = []
        self._state: tuple[int, int] | None = None
        self._static(properties, module_m)
        self._queue: queue.Queue = queue.Queue(maxsize=QUEUE_FRAMES)
        self._failed = False
        self.dropped = 0  # deferred work dropped because the view fell behind (defer(wait=False))
        self._thread = threading.Thread(target=self._work, name="run view", daemon=True)
        self._thread.start()

    def defer(self, t_s: float, work: Callable[[], None], *, wait: bool = True) -> None:
        """Run work (the camera image, the mesh: what costs milliseconds) on the view's own thread, at trial time
        t_s [s], while the run goes on. When the view is QUEUE_FRAMES frames behind, the run waits for it (wait=True:
        lock-step, where waiting changes nothing), or the work is dropped and counted (wait=False: a run on the wall
        clock, which must not act on stale frames for the view's sake)."""
        if wait:
            self._queue.put((t_s, work))
            return
        try:
            self._queue.put_nowait((t_s, work))
        except queue.Full:
            self.dropped += 1

    def _work(self) -> None:
        while (item := self._queue.get()) is not None:
            t_s, work = item
            self._at(t_s)  # the time is the thread's own
            try:
                work()
            except Exception as exc:  # the view is no reason to stop a run: said once, then it goes on without
                if not self._failed:
                    self.report(f"the view could not show a frame ({type(exc).__name__}: {exc}); the run goes on")
                self._failed = True

    def _give_up_recording(self, text: str) -> None:
        self.report(f"{text}; the run goes on without it")
        self.recording_path = None

    def _static(self, properties: dict[str, object], module_m: tuple[float, float]) -> None:
        rr, log = self.rr, self.stream.log
        if properties:
            self.stream.send_property("run", rr.AnyValues(**{k: _property(v) for k, v in properties.items()}))
        hx, hy = module_m[0] / 2, module_m[1] / 2
        log("fabric/module", rr.LineStrips2D([[(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy), (-hx, -hy)]]), static=True)
        for group, names in (("position_m", ("x", "y", "target_x", "target_y")), ("tilt_deg", ("zx", "zy"))):
            for name in names:
                log(f"plots/{group}/{name}", rr.SeriesLines(names=f"{group} {name}"), static=True)
        for i in range(self.actuators):
            log(f"plots/command_m/a{i}", rr.SeriesLines(names=f"command a{i}"), static=True)
            log(f"plots/measured_m/a{i}", rr.SeriesLines(names=f"measured a{i}"), static=True)

    def _at(self, t_s: float) -> None:
        self.stream.set_time(TIMELINE, duration=float(t_s))

    # ------------------------------------------------------------------------------------------ per frame
    def frame(
        self,
        t_s: float,
        seen_xy_m: Sequence[float] | None,
        target_m: Sequence[float],
        tolerance_m: float,
        telemetry: m.Telemetry | None,
        link: Link | None = None,
    ) -> None:
        """One camera frame's loop: where the object was seen (None: not seen or dropped), the target and epsilon,
        the firmware's answer (None: none came) and, with it, the link's counters."""
        rr, log = self.rr, self.stream.log
        self._at(t_s)
        if seen_xy_m is not None and all(math.isfinite(v) for v in seen_xy_m):
            x, y = float(seen_xy_m[0]), float(seen_xy_m[1])
            log("plots/position_m/x", rr.Scalars(x))
            log("plots/position_m/y", rr.Scalars(y))
            log("fabric/object", rr.Points2D([(x, y)], radii=0.01))
            self._trail_m = (self._trail_m + [(x, y)])[-TRAIL_FRAMES:]
            log("fabric/trail", rr.LineStrips2D([self._trail_m]))
        log("plots/position_m/target_x", rr.Scalars(float(target_m[0])))
        log("plots/position_m/target_y", rr.Scalars(float(target_m[1])))
        log("fabric/target", rr.Points2D([tuple(target_m)], radii=0.005))
        log("fabric/epsilon", rr.LineStrips2D([_circle(target_m, tolerance_m)]))
        if telemetry is not None:
            self._telemetry(telemetry)
            if link is not None:
                self._link(telemetry, link)

    def _telemetry(self, telemetry: m.Telemetry) -> None:
        """The firmware's state at the present time: tilts, commands, measured positions, supervisor state."""
        rr, log = self.rr, self.stream.log
        log("plots/tilt_deg/zx", rr.Scalars(telemetry.tilt_zx))
        log("plots/tilt_deg/zy", rr.Scalars(telemetry.tilt_zy))
        for i, (command, measured) in enumerate(zip(telemetry.command, telemetry.measured, strict=True)):
            log(f"plots/command_m/a{i}", rr.Scalars(command))
            log(f"plots/measured_m/a{i}", rr.Scalars(measured))
        log("plots/state", rr.Scalars(int(telemetry.state)))
        state = (int(telemetry.state), int(telemetry.faults))
        if state != self._state:
            # a firmware newer than this host may send a state or fault bit it does not know: shown as its number
            known = telemetry.state in m.State._value2member_map_
            text = f"state {m.State(telemetry.state).name.lower() if known else int(telemetry.state)}" + (
                f", faults 0x{int(telemetry.faults):04X}" if int(telemetry.faults) else ""
            )
            log("log/supervisor", rr.TextLog(text, level="ERROR" if int(telemetry.faults) else "INFO"))
            self._state = state

    def _link(self, telemetry: m.Telemetry, link: Link) -> None:
        """The link's counters: this host's retransmissions and lost frames, the firmware's CRC and frame errors."""
        counters = {
            "retransmissions": link.retransmissions,
            "crc_errors": telemetry.crc_errors,
            "frame_errors": telemetry.frame_errors,
            "lost_frames": link.lost_frames,
        }
        for name, value in counters.items():
            self.stream.log(f"plots/link/{name}", self.rr.Scalars(int(value)))

    def camera(
        self,
        t_s: float,
        image_bgr: np.ndarray,
        to_pixels: Callable[[np.ndarray], np.ndarray] | None,
        target_m: Sequence[float],
        tolerance_m: float,
        detection_px: Sequence[float] | None = None,
    ) -> None:
        """The camera's frame (BGR, as OpenCV gives it, or grey) as JPEG, at most CAMERA_MAX_WIDTH_PX wide, with the
        detection, the target, epsilon and the trail over it (costs milliseconds: defer it).

        to_pixels maps (k, 2) points [m] on the fabric's plane to (k, 2) pixels; None draws only the detection."""
        import cv2

        rr, log = self.rr, self.stream.log
        self._at(t_s)
        scale = min(1.0, CAMERA_MAX_WIDTH_PX / image_bgr.shape[1])
        if scale < 1.0:
            image_bgr = cv2.resize(image_bgr, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
        ok, jpeg = cv2.imencode(".jpg", image_bgr, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
        if ok:
            log("camera/image", rr.EncodedImage(contents=jpeg.tobytes(), media_type="image/jpeg"))
        if detection_px is not None:
            point = (float(detection_px[0]) * scale, float(detection_px[1]) * scale)
            self._trail_px = (self._trail_px + [point])[-TRAIL_FRAMES:]
            log("camera/detection", rr.Points2D([point], radii=6.0, colors=(0, 255, 0)))
            log("camera/trail", rr.LineStrips2D([self._trail_px], colors=(0, 200, 255)))
        if to_pixels is not None:
            target_px = to_pixels(np.asarray([target_m], dtype=float)) * scale
            log("camera/target", rr.Points2D(target_px, radii=5.0, colors=(255, 0, 255)))
            circle_px = to_pixels(np.asarray(_circle(target_m, tolerance_m), dtype=float)) * scale
            log("camera/epsilon", rr.LineStrips2D([circle_px], colors=(255, 0, 255)))

    def mesh(self, t_s: float, vertices_m: np.ndarray, triangles: np.ndarray) -> None:
        """The fabric as a triangle mesh [m, world] (the simulation's flex), shaded by its vertex normals."""
        self._at(t_s)
        corners = vertices_m[triangles]
        faces = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        normals = np.zeros_like(vertices_m)
        for k in range(3):
            np.add.at(normals, triangles[:, k], faces)
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
        self.stream.log(
            "world/fabric",
            self.rr.Mesh3D(
                vertex_positions=vertices_m,
                triangle_indices=triangles,
                vertex_normals=normals,
                albedo_factor=FABRIC_RGB,
            ),
        )

    def object3d(self, t_s: float, centres_m: Sequence[Sequence[float]], radii_m: Sequence[float]) -> None:
        """The objects as balls at their centres [m, world]: the steered one (the first) orange, any others blue."""
        self._at(t_s)
        colors = [(230, 120, 30)] + [(60, 120, 220)] * (len(centres_m) - 1)
        self.stream.log("world/object", self.rr.Points3D(centres_m, radii=radii_m, colors=colors))

    def event(self, t_s: float, text: str, level: str = "WARN") -> None:
        """Something the run reported."""
        self._at(t_s)
        self.stream.log("log/events", self.rr.TextLog(text, level=level))

    def close(self) -> Path | None:
        """Finish the deferred work, flush and end the streams; the recording's path, or None when there is none
        (said once)."""
        self._queue.put(None)
        self._thread.join()
        if self.dropped:
            self.report(f"the view fell behind and left out {self.dropped} camera frames; the run did not wait")
        try:
            self.stream.flush(timeout_sec=FLUSH_TIMEOUT_S)
            self.stream.disconnect()
        except RuntimeError as exc:  # the live server went away: the recording file is flushed all the same
            self.report(f"the live view could not take the last of the run ({exc})")
        path = self.recording_path
        if path is not None and (not path.exists() or path.stat().st_size == 0):
            self._give_up_recording(f"the recording {path} could not be written (disk full?)")
            return None
        return path


def _layout(rrb, world: bool):
    """The viewer's default layout: the camera and the scene on the left, the plots beside them, the logs below."""
    scenes = [rrb.Spatial2DView(origin="camera", name="camera"), rrb.Spatial2DView(origin="fabric", name="fabric")]
    if world:
        scenes.append(rrb.Spatial3DView(origin="world", name="fabric in 3D"))
    plots = [
        rrb.TimeSeriesView(origin=f"plots/{name}", name=title)
        for name, title in (
            ("position_m", "position [m]"),
            ("tilt_deg", "tilts [deg]"),
            ("command_m", "commands [m]"),
            ("measured_m", "measured positions [m]"),
            ("state", "supervisor state"),
            ("link", "link counters"),
        )
    ]
    return rrb.Blueprint(
        rrb.Vertical(
            rrb.Horizontal(rrb.Vertical(*scenes), rrb.Grid(*plots)),
            rrb.TextLogView(origin="log", name="events"),
            row_shares=[5, 1],
        ),
        collapse_panels=True,
    )


def _circle(centre: Sequence[float], radius: float) -> list[tuple[float, float]]:
    a = np.linspace(0.0, 2 * math.pi, CIRCLE_POINTS + 1)
    return list(zip(centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a), strict=True))


def _property(value: object) -> object:
    """A setting as the recording's metadata stores it: numbers and text as they are, anything else as text."""
    if isinstance(value, bool | int | float | str):
        return value
    return str(value)
