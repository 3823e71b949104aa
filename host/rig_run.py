"""One closed-loop run on the rig, what `mantaray rig` runs: the rig's counterpart of the simulation's Bridge.run.

Camera -> tracker -> firmware through a RigSession, logged frame by frame, until a stop rule, a key or Ctrl-C ends it."""

from __future__ import annotations

import math
import shlex
import signal
import sys
import time
from dataclasses import dataclass

from mantaray.protocol import messages as m
from mantaray.protocol.rig import RigDescription

from .board_state import state_text
from .keys import Keys
from .link import LinkError
from .loop import STOPPED_REACHED, CameraFrame, ClosedLoop, Tolerance
from .runlog import RunLog
from .session import BoardLost, EmergencyStopLatched, RigSession, Setup
from .tracker import FrameSource, Observation, Presence, Tracker
from .view import RunView

STOP, EMERGENCY_STOP = "stopped", "emergency stop"  # the outcomes of the keys
KEYS = {"s": STOP, "e": EMERGENCY_STOP, " ": EMERGENCY_STOP}  # key (either case) -> how it ends the run
KEYS_HELP = (
    "keys: s stops (levels the surface), e or space is the emergency stop (latched), Ctrl-C ends (levels); "
    "t X,Y Enter sends the object to a new target [m]"
)
TARGET_KEY, ENTER, ESCAPE = "t", ("\r", "\n"), "\x1b"  # typing a target: t, then X,Y, then Enter (Escape: cancel)
TARGET_CHARACTERS = set("0123456789.,+-")  # what a typed target is made of: any other key keeps its own meaning
BACKSPACE = ("\x7f", "\b")
EXIT_STATUS = {"reached": 0, "interrupted": 130}  # every other outcome: 1
FAULT = "fault"  # the outcome when the board's supervisor shut down (a deadman, a stall, an encoder fault)


def fabric_point(text: str, half_m: tuple[float, float]) -> tuple[float, float]:
    """X,Y [m] as typed (comma or space between): a point on the fabric (|x| <= half_m[0], |y| <= half_m[1]), or a
    ValueError that says what is wrong in words."""
    try:
        x, y = (float(v) for v in text.replace(",", " ").split())
    except ValueError:
        raise ValueError(f"expected two numbers X,Y in metres, got {text!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)) or abs(x) > half_m[0] or abs(y) > half_m[1]:
        raise ValueError(f"{text!r} is not on the fabric (|x| <= {half_m[0]:g} m, |y| <= {half_m[1]:g} m)")
    return x, y


@dataclass(frozen=True)
class Course:
    """Where the object is sent: a fixed target, or round a circle about it (--path circle, the paper's Fig. 1A)."""

    centre_m: tuple[float, float]  # [m] the target, or the circle's centre
    radius_m: float = 0.0  # [m] 0: a fixed target
    period_s: float = 30.0  # [s] one lap of the circle

    @property
    def moving(self) -> bool:
        return self.radius_m > 0

    def at(self, t_s: float) -> tuple[float, float]:
        """The target at run time t_s [s]."""
        if not self.moving:
            return self.centre_m
        a = 2 * math.pi * t_s / self.period_s
        return self.centre_m[0] + self.radius_m * math.cos(a), self.centre_m[1] + self.radius_m * math.sin(a)


@dataclass(frozen=True)
class StopRules:
    """When a run ends by itself."""

    tolerance_m: float  # [m] epsilon about a fixed target
    hold_s: float  # [s] within epsilon this long: reached
    timeout_s: float  # [s] run time after which it gives up
    half_surface_m: tuple[float, float]  # [m] half the fabric's sides: targets lie within these
    half_module_m: tuple[float, float]  # [m] seen farther than this beyond the fabric (half a module): fell off


class RigRun:
    """The run: the session is opened and set up, the controller started, and each camera frame tracked and sent
    until the object holds the target (reached), the timeout, the end of a video (camera stopped), the object off
    the fabric (fell off), a key (stopped, emergency stop), Ctrl-C (interrupted) or a board the session could not
    keep (board lost, refused). Then the surface is levelled and the motors stopped, or an emergency stop stays
    latched. What happens is reported on stderr and in the log's event lines."""

    def __init__(
        self,
        port: str,
        setup: Setup,
        source: FrameSource,
        tracker: Tracker,
        log: RunLog,
        course: Course,
        rules: StopRules,
        *,
        reconnect_timeout_s: float = 30.0,
        view: RunView | None = None,
        description: RigDescription | None = None,
    ) -> None:
        self.source, self.tracker, self.log, self.course, self.rules = source, tracker, log, course, rules
        self.view = view  # the run's streams (recording, live view): fed after every frame
        self.session = RigSession(
            port, setup, report=self.report, reconnect_timeout_s=reconnect_timeout_s, description=description
        )
        self.loop = ClosedLoop(self.session.position)
        self.outcome = "timeout"
        self._interrupted = False
        self._keys: Keys | None = None
        self._seen: Observation | None = None  # the tracker's last observation, for the log
        self._image = None  # the camera's last image (BGR or grey), for the view
        self._run_s = 0.0  # [s] run time of the last frame
        self._typed: str | None = None  # a target being typed after the t key; None: not typing

    def report(self, text: str) -> None:
        self.log.write("event", {"text": text})
        if self.view is not None:
            self.view.event(self._run_s, text)
        print(f"mantaray rig: {text}", file=sys.stderr)

    def run(self) -> str:
        """The run from connecting to its end; returns its outcome (the first word `mantaray rig` prints)."""
        previous = signal.getsignal(signal.SIGINT)
        try:
            self.session.open()
            self.log.write(
                "identify", {k: v if isinstance(v, float) else int(v) for k, v in vars(self.session.identity).items()}
            )
            signal.signal(signal.SIGINT, self._on_sigint)
            self._keys = Keys()
            if self._keys.active:
                print(f"mantaray rig: {KEYS_HELP}", file=sys.stderr)
            self.session.start()
            if (
                self.loop.run(self, Tolerance(self.rules.tolerance_m, self.rules.hold_s), stop_when_reached=True)
                == STOPPED_REACHED
            ):
                self.outcome = "reached"
            if self._interrupted:
                self.outcome = "interrupted"
        except KeyboardInterrupt:  # while connecting, or a second Ctrl-C
            self.outcome = "interrupted"
        except EmergencyStopLatched as exc:  # the board was found in it: only the user clears it
            self.report(f"the run did not start: {exc}")
            self.outcome = EMERGENCY_STOP
        except LinkError as exc:  # what the session's retries could not absorb: the run ends
            self.report(f"the run ended: {exc}")
            self.outcome = "board lost" if isinstance(exc, BoardLost) else "refused"
        finally:
            signal.signal(signal.SIGINT, previous)
            if self._keys is not None:
                self._keys.close()
            self._finish()
        return self.outcome

    def _on_sigint(self, signum, frame) -> None:
        """The first Ctrl-C ends the loop after this frame; a second one (say, while reconnecting) at once."""
        self._interrupted = True
        signal.signal(signal.SIGINT, signal.default_int_handler)

    # ------------------------------------------------------------------ the rig as the loop's plant (LoopPlant)
    def frames(self):
        """The camera's frames, tracked, until Ctrl-C, a key, the end of the video, the timeout or the object off
        the fabric."""
        t0 = wall0 = None
        reach = [s + m for s, m in zip(self.rules.half_surface_m, self.rules.half_module_m, strict=True)]
        presence = Presence(self.tracker.object_names())  # when the tracker loses an object, and finds it again
        while not self._interrupted and self.outcome != FAULT and not self._stopped_by_key():
            grabbed = self.source.read()
            if grabbed is None:
                self.outcome = "camera stopped"
                return
            image, capture_s = grabbed
            if t0 is None:
                t0, wall0 = capture_s, time.monotonic()
            run_s = self._run_s = capture_s - t0
            if self.source.is_file:  # a recording plays at its own pace, as a camera would
                time.sleep(max(0.0, run_s - (time.monotonic() - wall0)))
            if run_s > self.rules.timeout_s:
                return
            self._image = image
            obs = self._seen = self.tracker.observe(image, capture_s)
            for line in presence.update(run_s, obs):
                self.report(f"tracker: {line}")
            if obs.visible and (abs(obs.xy_m[0]) > reach[0] or abs(obs.xy_m[1]) > reach[1]):
                self.report(
                    f"the object was seen at {obs.xy_m[0]:+.3f},{obs.xy_m[1]:+.3f} m, off the fabric by "
                    f"more than half a module"
                )  # what the firmware refuses
                self.outcome = "fell off"
                return
            target = self.course.at(run_s)
            judged = obs.xy_m if not self.course.moving and obs.visible else None  # what the camera sees: the rig
            yield CameraFrame(
                run_s,
                obs.xy_m if obs.visible else None,
                target,
                judged_xy_m=judged,  # knows no better
            )

    def _stopped_by_key(self) -> bool:
        """A key pressed since the last frame, or an emergency stop the board reported: True when the run ends."""
        assert self._keys is not None  # run() opens them first
        for key in self._keys.read():
            typing = self._typed is not None and (key in TARGET_CHARACTERS or key in ENTER + BACKSPACE + (ESCAPE,))
            if typing or (self._typed is None and key.lower() == TARGET_KEY):
                self._type_target(key)
                continue
            if self._typed is not None:  # a stop key while typing: it stops, and the target is dropped
                self._typed = None
                print("(target dropped)", file=sys.stderr)
            outcome = KEYS.get(key.lower())
            if outcome == EMERGENCY_STOP:
                self.session.emergency_stop()  # at once, through the session: latched across reconnections
            if outcome is not None:
                self.report(f"{outcome} (key {key!r})")
                self.outcome = outcome
                return True
        if self.session.estopped:  # sent from elsewhere: the run cannot go on
            self.outcome = EMERGENCY_STOP
            return True
        return False

    def _type_target(self, key: str) -> None:
        """One key of a target being typed: t starts it, digits . , + - make it, Backspace takes one back, Enter
        sends it, Escape drops it."""
        if self._typed is None:
            self._typed = ""
            print("mantaray rig: new target X,Y [m], then Enter: ", end="", file=sys.stderr, flush=True)
        elif key in BACKSPACE:
            if self._typed:
                self._typed = self._typed[:-1]
                print("\b \b", end="", file=sys.stderr, flush=True)
        elif key == ESCAPE:
            self._typed = None
            print("(cancelled)", file=sys.stderr)
        elif key in ENTER:
            typed, self._typed = self._typed, None
            print(file=sys.stderr)
            self.new_target(typed)
        else:
            self._typed += key
            print(key, end="", file=sys.stderr, flush=True)

    def new_target(self, text: str) -> bool:
        """A target typed while the run goes on, as X,Y [m]: sent to the firmware when it lies on the fabric; a
        mistake is reported (terminal, log, view) and the run goes on to the old target."""
        if self.course.moving:
            self.report("target refused: the run follows a path, which moves the target itself; the run goes on")
            return False
        try:
            x, y = fabric_point(text, self.rules.half_surface_m)
        except ValueError as exc:
            self.report(f"target refused: {exc}; the run goes on")
            return False
        self.session.set_target(x, y)
        self.course = Course((x, y))
        self.report(f"new target {x:+.3f},{y:+.3f} m")
        return True

    def deliver(self, frame: CameraFrame) -> bool:
        """Before a frame along a path: the target moves on (the run goes on)."""
        if self.course.moving:
            self.session.set_target(*frame.target_m)
        return True

    def answered(self, frame: CameraFrame, telemetry: m.Telemetry | None) -> None:
        """The frame and its answer logged and shown."""
        obs = self._seen
        assert obs is not None  # a frame is recorded after it was observed
        self.log.write(
            "position",
            {
                "frame": self.loop.frame,
                "capture_s": round(frame.capture_s, 6),
                "status": obs.status,
                "xy_m": obs.xy_m,
                "target_m": list(frame.target_m),
                "corners_seen": list(obs.corners_seen),
            },
        )
        if telemetry is not None:
            self.log.write(
                "telemetry",
                {
                    k: (list(v) if isinstance(v, tuple) else int(v) if isinstance(v, int) else v)
                    for k, v in vars(telemetry).items()
                },
            )
        if telemetry is not None and telemetry.state == m.State.FAULT:  # the supervisor shut every actuator down
            self.report(f"the board stopped: {state_text(telemetry, self.session.identity)}")
            self.outcome = FAULT
        if self.view is not None:
            self._show(frame, telemetry, obs)

    def _show(self, frame: CameraFrame, telemetry: m.Telemetry | None, obs: Observation) -> None:
        """The frame in the view: the loop's values, the link's counters and the camera image with the target."""
        view, t = self.view, frame.capture_s
        assert view is not None
        view.frame(
            t, obs.xy_m if obs.visible else None, frame.target_m, self.rules.tolerance_m, telemetry, self.session.link
        )
        to_pixels = self.tracker.projection(self.tracker.marker_height_m)  # this image's fit, the detection's height
        image, target, tolerance = self._image, frame.target_m, self.rules.tolerance_m
        assert image is not None  # a frame is shown after its image was tracked
        # on the wall clock: a view that falls behind drops pictures rather than hold the loop back
        view.defer(t, lambda: view.camera(t, image, to_pixels, target, tolerance, obs.pixel), wait=False)

    def _finish(self) -> None:
        """The board left safe: levelled and stopped (once, without recoveries, when the board was lost), or its
        emergency stop latched; then the port, the camera and the log closed."""
        session = self.session
        try:
            if session.link is not None and session.estopped:
                self.report(
                    f"the emergency stop stays latched: `mantaray stop --port {shlex.quote(session.port)}` clears it"
                )
            elif session.link is not None and self.outcome == "board lost":
                session.link.command(m.Stop())  # once: the session's recoveries are spent
            elif session.link is not None:
                session.stop()  # level the surface, controller off
        except LinkError as exc:
            self.report(f"could not level the surface and stop ({exc}): the firmware's deadman stops it")
        finally:
            session.close()
            self.source.close()
            self.log.write("end", {"outcome": self.outcome})
            self.log.close()
            if self.view is not None:
                self.view.event(self._run_s, f"end: {self.outcome}", level="INFO")

    def figure(self, path):
        """The run's figure (the paper's Fig. 3: path, phase plot of the tilts, and the error, tilts and commands over
        time) at path; returns where it went."""
        from mantaray.plots import path_phase_figure

        rows = self.loop.arrays()
        xy = rows["measured_xy_m"]
        configure = self.session.setup.configure
        fixed = [tuple(t) for t in dict.fromkeys(map(tuple, rows["target_m"]))]  # each target in turn
        targets = rows["target_m"] if self.course.moving and len(xy) else (fixed or [self.course.centre_m])
        return path_phase_figure(
            xy,
            rows["tilt_deg"],
            xy[0] if len(xy) and math.isfinite(xy[0][0]) else None,
            targets,
            self.rules.tolerance_m,
            f"rig: {self.outcome}",
            (configure.module_x, configure.module_y),
            configure.tilt_limit,
            path,
            t_s=rows["t_s"] if len(xy) else None,
            command_m=rows["command_m"] if len(xy) else None,
        )
