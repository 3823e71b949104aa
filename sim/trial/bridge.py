"""The plant bridge: a firmware drives the simulated rig over the protocol, camera frames in lock-step or real time.

The bridge plays the host's part: it configures the firmware, streams the object's position at the
camera rate (with optional noise, latency and dropped frames) and applies the actuator commands
the firmware answers with to the simulated actuators. The firmware is whatever is on the link:
the native virtual MCU on a pty, the AVR image in simavr, or a board on a serial port.

Time: trial time t [s] starts at 0 when the controller starts. In lock-step the firmware's clock is
set by sim_clock to the delivery time of each frame, so a run never depends on this machine's
speed; in real time the firmware keeps its own wall clock and the bridge paces the physics to it.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from mantaray.host.controller_settings import ControllerSettings, max_tilt_deg
from mantaray.host.link import Link, LinkError
from mantaray.host.loop import U32, US_PER_S, CameraFrame, ClosedLoop, Tolerance
from mantaray.host.session import Setup
from mantaray.protocol import messages as m
from mantaray.protocol import rig as rig_description
from mantaray.protocol.codec import FieldRefused, choices

from ..model import model as M
from ..model.model import SimulationUnstable
from ..model.plant import boot_gains
from ..model.rig import Rig
from ..model.tracking import DEFAULT_TRACKING, Tracking

SPEC_NAMES = {
    "noise_amplitude": "noise amplitude alpha",
    "tolerance": "tolerance epsilon",
    "x": "target x",
    "y": "target y",
}  # a refused command field -> what a trial spec calls it
MODULE_M = (rig_description.default().module_size_x_m, rig_description.default().module_size_y_m)  # [m] m, n
CLOCK_GAP_US = 1_000_000  # [us] the firmware clock moves on this much between trials, so it never goes back
# [s] In lock-step nothing is real-time (the firmware's clock waits for the bridge), so the link may wait this
# long for each answer: it costs nothing when the firmware answers in ~0.1 ms, and rides out a loaded machine.
LOCKSTEP_ACK_TIMEOUT_S = 1.0


@dataclass(frozen=True)
class TrialSpec:
    """One target-reaching trial as the paper runs them (Results): success is judged at the end of duration_s."""

    start_m: tuple[float, float]
    target_m: tuple[float, float]
    controller: str = "manhattan"  # manhattan | euclidean | scheduled | cascade
    duration_s: float = 10.0  # [s] T
    alpha_m: float = 0.0  # [m] noise amplitude
    tolerance_m: float = 0.02  # [m] epsilon
    seed: int = 1  # camera noise, drops and the firmware's noise PRNG
    gain_scale: float = 1.0  # the plant's reading of the paper's gains (Plant.gain_scale): the PIDs the settings
    # leave out run the firmware's boot gains, the paper's, read so (plant.boot_gains)
    stop_when_reached: bool = False  # end at the first frame within epsilon, as the paper's loop does
    settings: tuple[tuple[str, float], ...] = ()  # the controller's own settings (host/controller_settings.py keys)
    # [m] where the objects beside the steered one start (objects 1, 2, ... of the rig, Rig.others): each left to lie
    # where the sheet takes it
    others_start_m: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        if self.controller.upper() not in m.Controller.__members__:
            raise ValueError(f"controller must be one of {', '.join(choices(m.Controller))}, got {self.controller!r}")
        if not (0 < self.duration_s <= 3600):
            raise ValueError(f"duration must be in (0, 3600] s, got {self.duration_s}")
        if not 0 <= self.seed <= U32:
            raise ValueError(f"seed must be 0..{U32}, got {self.seed}")
        if not 0 < self.gain_scale <= 1000:
            raise ValueError(f"gain scale must be in (0, 1000], got {self.gain_scale}")
        self.controller_settings()  # the keys and values of settings (SettingsError: a ValueError)
        for command in self.setup().commands():  # the schema's bounds, before any firmware sees them
            try:
                command.check()
            except FieldRefused as refused:
                axis = f" of the {command.axis.name.lower()} PID" if isinstance(command, m.ConfigurePid) else ""
                raise ValueError(
                    f"{SPEC_NAMES.get(refused.field, refused.field)}{axis}: {refused.reason} "
                    f"({refused.message_name}.{refused.field}, protocol/schema.toml)"
                ) from None

    def setup(self, module_m: tuple[float, float] = MODULE_M, telemetry_period_ms: int = 0) -> Setup:
        """The firmware's set-up for this trial: configure, every PID's gains (the paper's where not given), the
        target; sent as the rig's session sends its own (Setup.commands)."""
        configure = m.Configure(
            controller=m.Controller[self.controller.upper()],
            module_x=module_m[0],
            module_y=module_m[1],
            tilt_limit=min(m.Configure.tilt_limit, max_tilt_deg(*module_m)),  # a module larger than the paper's
            # tilts less: its steepest keeps every corner in range (PROTOCOL.md §5)
            tolerance=self.tolerance_m,
            noise_amplitude=self.alpha_m,
            noise_seed=self.seed or 1,
            telemetry_period=telemetry_period_ms,
        )
        settings = self.controller_settings()  # all of them every time: nothing stays from an earlier trial
        gains = settings.gains(boot_gains(self.gain_scale))
        return Setup(settings.configure(configure), gains, self.target_m, settings.commands())

    def controller_settings(self) -> ControllerSettings:
        return ControllerSettings(self.controller, self.settings)


def is_success(fell_off: bool, final_error_m: float, tolerance_m: float) -> bool:
    """A trial's success (the paper's Results): within epsilon at the end of T, and never fallen off."""
    return (not fell_off) and final_error_m < tolerance_m


@dataclass
class LinkWatch:
    """What the frame counters showed during a trial: each count is something the bridge reported."""

    firmware_resets: int = 0  # boot messages: the firmware restarted
    missed_replies: int = 0  # position frames whose telemetry never came
    duplicate_replies: int = 0  # telemetry for a frame already answered
    lost_firmware_frames: int = 0  # gaps in the firmware's sequence numbers
    dropped_frames: int = 0  # camera frames dropped on purpose (Tracking.drop_rate)
    unseen_frames: int = 0  # vision in the loop: frames in which the tracker found no object
    messages: list[str] = field(default_factory=list)

    def report(self, text: str) -> None:
        self.messages.append(text)

    @property
    def clean(self) -> bool:
        return not (self.firmware_resets or self.missed_replies or self.duplicate_replies or self.lost_firmware_frames)


@dataclass
class TrialResult:
    """Outcome and trajectory of one trial; arrays have one row per camera frame."""

    spec: TrialSpec
    object_name: str
    success: bool  # within tolerance at the end, not fallen off
    final_error_m: float  # [m] true distance to the target at the end
    final_xy_m: np.ndarray  # [m] object position at the end: the frame it was judged on (also the reach frame
    #     when the trial stopped there, which is not a row of true_xy_m)
    time_to_reach_s: float | None  # [s] first frame the true distance was within tolerance
    fell_off: bool
    sim_time_s: float  # [s] trial time simulated (shorter when the object fell off)
    wall_time_s: float  # [s] the whole trial, settling included
    physics_wall_s: float  # [s] of which MuJoCo stepping
    link_wall_s: float  # [s] of which the protocol exchange with the firmware
    t_s: np.ndarray  # [s] capture times
    true_xy_m: np.ndarray  # [m] object position (marker) at capture
    measured_xy_m: np.ndarray  # [m] what the firmware was sent (NaN: dropped)
    tilt_deg: np.ndarray  # [deg] theta_zx, theta_zy from telemetry (NaN: no answer)
    command_m: np.ndarray  # [m] a_0..a_3 from telemetry
    measured_m: np.ndarray  # [m] the actuators' measured positions from telemetry
    state: np.ndarray  # supervisor state per frame (-1: no answer)
    module: np.ndarray  # the module the firmware drove per frame (-1: no answer)
    watch: LinkWatch
    others_xy_m: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 2)))  # [m] (frames, others, 2): objects
    #     1, 2, ... at each capture, as true_xy_m
    others_final_xy_m: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # [m] (others, 2) at the end
    others_fell_off: tuple[bool, ...] = ()

    def summary(self) -> dict:
        """The machine-readable one-line result."""
        return {
            "success": self.success,
            "final_error_m": round(self.final_error_m, 5),
            "time_to_reach_s": None if self.time_to_reach_s is None else round(self.time_to_reach_s, 3),
            "fell_off": self.fell_off,
            "sim_time_s": round(self.sim_time_s, 3),
            "wall_time_s": round(self.wall_time_s, 3),
            "physics_share": round(self.physics_share, 3),
            "link_share": round(self.link_wall_s / max(self.wall_time_s, 1e-9), 3),
            "object": self.object_name,
            "controller": self.spec.controller,
            "start_m": list(self.spec.start_m),
            "target_m": list(self.spec.target_m),
            "seed": self.spec.seed,
            "link_clean": self.watch.clean,
            "camera_frames": len(self.t_s),
            "unseen_frames": self.watch.unseen_frames,
            "dropped_frames": self.watch.dropped_frames,
            "handovers": self.handovers,
            **({"others": self.others_summary()} if self.spec.others_start_m else {}),
        }

    def others_summary(self) -> list[dict]:
        """Each object beside the steered one: where it started and ended [m], how far it was moved [m] (at the end,
        and at most during the trial), and whether it fell off."""
        out = []
        for k, start in enumerate(self.spec.others_start_m):
            path = self.others_xy_m[:, k] if len(self.others_xy_m) else np.zeros((0, 2))
            moved = np.hypot(*(path - np.asarray(start)).T) if len(path) else np.zeros(0)
            final = self.others_final_xy_m[k]
            out.append(
                {
                    "start_m": list(start),
                    "final_xy_m": [round(float(v), 5) for v in final],
                    "displacement_m": round(float(np.hypot(*(final - np.asarray(start)))), 5),
                    "largest_displacement_m": round(float(moved.max(initial=0.0)), 5),
                    "fell_off": self.others_fell_off[k],
                }
            )
        return out

    @property
    def handovers(self) -> int:
        """How often the firmware passed the object to another module (an array's hand-overs; 0 on one module)."""
        return len(self.handover_rows)

    @property
    def handover_rows(self) -> np.ndarray:
        """The rows (camera frames) of the hand-overs: each the first answer from another module than the last."""
        answered = np.flatnonzero(self.module >= 0)
        return answered[1:][np.diff(self.module[answered]) != 0]

    @property
    def handover_xy_m(self) -> np.ndarray:
        """[m] Where the object was at each hand-over."""
        return self.true_xy_m[self.handover_rows].reshape(-1, 2)

    @property
    def physics_share(self) -> float:
        return self.physics_wall_s / max(self.wall_time_s, 1e-9)


class Bridge:
    """The simulated rig and one firmware link. Reuse it for many trials: the model loads once.

    lockstep=True needs a firmware on the simulated clock (identify says which); lockstep=False runs in
    real time against a wall-clock firmware (a board, or `mantaray-vmcu --clock wall`).
    """

    def __init__(self, link: Link, rig: Rig, tracking: Tracking = DEFAULT_TRACKING, lockstep: bool = True) -> None:
        self.link, self.rig, self.tracking, self.lockstep = link, rig, tracking, lockstep
        if lockstep:
            link.ack_timeout_s = max(link.ack_timeout_s, LOCKSTEP_ACK_TIMEOUT_S)
        identity = link.identify()
        if not math.isclose(identity.actuator_range, rig.actuators.range_m, rel_tol=1e-6):
            raise LinkError(
                f"the firmware was built for actuators of +-{identity.actuator_range:g} m, the simulated "
                f"rig's travel +-{rig.actuators.range_m:g} m: the commands would not mean the same"
            )
        shape = (rig.module.modules_x, rig.module.modules_y)
        if (identity.modules_x, identity.modules_y) != shape:
            raise LinkError(
                f"the firmware was built for {identity.modules_x} x {identity.modules_y} modules, the simulated rig "
                f"has {shape[0]} x {shape[1]}: run the build for its rig file "
                f"({rig_description.build_of(rig.module.build, 'mantaray-vmcu')})"
            )
        simulated = identity.clock == m.Clock.SIMULATED
        if lockstep and not simulated:
            raise LinkError(
                "lock-step needs a firmware on the simulated clock (mantaray-vmcu --clock sim); "
                "this one runs on its wall clock: use real-time mode"
            )
        if not lockstep and simulated:
            raise LinkError("real-time mode needs a wall-clock firmware; this one is on the simulated clock")
        if tracking.vision is not None:
            from .vision import check_scene

            check_scene(rig, tracking.vision)  # before the model's load, which takes a while
        self.model, self.data = M.load(rig)
        self.vision = None
        if tracking.vision is not None:
            from .vision import CameraVision

            self.vision = CameraVision(self.model, self.data, rig, tracking.vision)
        self.clock_us = 0  # the firmware's sim clock, last value sent
        self.frame = 0  # camera frame counter, runs on across trials
        if lockstep:
            # The firmware may have run before (another bridge, another host): its clock must never go back.
            # A not_visible frame steps nothing and feeds no deadman; its telemetry tells the time [ms].
            self.frame = 1
            probe = link.position(m.ObjectPosition(frame=self.frame, capture_time=0, flags=m.PositionFlags.NOT_VISIBLE))
            self.clock_us = (probe.time + 1) * 1000  # telemetry truncates to whole ms
        self._array_commands: m.ArrayCommands | None = None  # an array's, the last the firmware sent
        self.link.on_message = self._watch_message
        self._watch = LinkWatch()
        self._answered: set[int] = set()
        self.viewer = None  # a mujoco.viewer handle: synced after every camera frame
        self.recorder = None  # a video.Recorder: offered every physics step
        self.view = None  # a trial_view.TrialView: sees every camera frame with its answer

    def _watch_message(self, msg) -> None:
        if isinstance(msg, m.ArrayCommands):
            self._array_commands = msg
        elif isinstance(msg, m.Boot):
            self._watch.firmware_resets += 1
            self._watch.report(f"firmware reset ({msg.reset_cause.name.lower()}) during the trial")
        elif isinstance(msg, m.Telemetry) and self.lockstep:
            if msg.position_frame in self._answered:
                self._watch.duplicate_replies += 1
                self._watch.report(f"duplicate telemetry for camera frame {msg.position_frame}")

    # ------------------------------------------------------------------------------- firmware set-up
    def _set_clock(self, t_us: int) -> None:
        self.clock_us = t_us & U32
        self.link.command(m.SimClock(now=self.clock_us))

    def _configure(self, spec: TrialSpec) -> None:
        self.link.command(m.Stop())
        setup = spec.setup(
            (self.rig.module.size_x_m, self.rig.module.size_y_m), telemetry_period_ms=0 if self.lockstep else 100
        )
        for command in setup.commands():
            self.link.command(command)

    # ----------------------------------------------------------------------------------------- trial
    def run(self, spec: TrialSpec, progress=None) -> TrialResult:
        """One trial: drop the object at the start, control it for spec.duration_s, judge the end.

        progress, if given, is called with the trial time [s] after every camera frame.
        """
        self._watch, self._answered = LinkWatch(), set()
        resets0, lost0 = self.link.resets, self.link.lost_frames
        trial = self._start(spec)
        if self.view is not None:
            self.view.start(spec.tolerance_m)
        loop = ClosedLoop(lambda msg: self._send(msg, trial), time_base_us=trial.base_us, frame=self.frame)
        judge = Tolerance(spec.tolerance_m)  # on the true position: where the object really is
        plant = _SimulatedPlant(self, spec, trial, progress)
        loop.run(plant, judge, stop_when_reached=spec.stop_when_reached)
        self.frame = loop.frame
        self._stop(trial, resets0, lost0)
        result = self._result(spec, trial, loop.arrays(), np.asarray(plant.true_xy_m).reshape(-1, 2), judge, trial.fell)
        if self.rig.others:
            count = len(self.rig.others)
            result.others_xy_m = np.asarray(plant.others_xy_m, dtype=float).reshape(-1, count, 2)
            result.others_final_xy_m = np.array([M.object_xy(self.model, self.data, k) for k in range(1, count + 1)])
            result.others_fell_off = tuple(
                M.fell_off(self.model, self.data, self.rig.fall, k) for k in range(1, count + 1)
            )
        return result

    def _commands(self, reply: m.Telemetry) -> np.ndarray:
        """[m] Every actuator's command: one module's telemetry shows all four; an array's firmware sends them all
        in array_commands just before its telemetry."""
        count = self.rig.module.grid.actuator_count
        if count == len(reply.command):
            return np.asarray(reply.command, dtype=float)
        if self._array_commands is None:
            raise LinkError("an array's firmware sent telemetry without array_commands before it (PROTOCOL.md §5)")
        commands, self._array_commands = self._array_commands.command[:count], None
        return np.asarray(commands, dtype=float)

    def _start(self, spec: TrialSpec) -> _Trial:
        """Set the firmware up, drop the object, start the controller at trial time 0."""
        t = time.perf_counter()
        self._configure(spec)
        others = len(self.rig.others)
        if len(spec.others_start_m) != others:
            raise ValueError(
                f"the rig carries {others} object{'s' if others != 1 else ''} beside the steered one, the trial "
                f"gives {len(spec.others_start_m)} start{'s' if len(spec.others_start_m) != 1 else ''} for them"
            )
        M.drop_objects(self.model, self.data, [spec.start_m, *spec.others_start_m])
        base_us = (self.clock_us + CLOCK_GAP_US) & U32  # firmware time at trial time 0
        if self.lockstep:
            self._set_clock(base_us)
        self.link.command(m.Start())
        trial = _Trial(wall0_s=t, t0_sim_s=self.data.time, base_us=base_us, wall_start_s=time.perf_counter())
        trial.link_s = trial.wall_start_s - t
        if self.recorder is not None:
            self.recorder.mark_target(spec.target_m, spec.tolerance_m, self.rig.module.z0_m, trial.t0_sim_s)
        return trial

    def _advance(self, trial: _Trial, to_trial_s: float) -> bool:
        """Step physics to trial time to_trial_s; True if the object fell off on the way."""
        if not self.lockstep:  # hold the physics back to the wall clock
            ahead = to_trial_s - (time.perf_counter() - trial.wall_start_s)
            if ahead > 0:
                time.sleep(ahead)
        t = time.perf_counter()
        try:
            M.step_until(
                self.model,
                self.data,
                trial.t0_sim_s + to_trial_s,
                None if self.recorder is None else self.recorder.capture,
            )
        except SimulationUnstable:
            raise SimulationUnstable(
                f"the physics diverged before trial time {to_trial_s:.3f} s", self.rig.stiffest()
            ) from None
        trial.physics_s += time.perf_counter() - t
        if self.viewer is not None:
            self.viewer.sync()
        return M.fell_off(self.model, self.data, self.rig.fall)

    def _measure(self, capture_s: float, true_xy: np.ndarray, rng: np.random.Generator) -> np.ndarray | None:
        """What the camera reports of the object: the tracker on a rendered frame, or the truth with noise."""
        if self.vision is not None:
            seen = self.vision.measure(self.data, capture_s)
            self._watch.unseen_frames += seen is None
            return seen
        noise_m = self.tracking.noise_m
        return true_xy + (rng.normal(0.0, noise_m, 2) if noise_m else 0.0)

    def _send(self, msg: m.ObjectPosition, trial: _Trial) -> m.Telemetry | None:
        """One position frame, on the firmware's clock at its delivery in lock-step; None when none answered."""
        t = time.perf_counter()
        try:
            if self.lockstep:
                self._set_clock(trial.deliver_us)
            reply = self.link.position(msg)
        except LinkError:
            self._watch.missed_replies += 1
            self._watch.report(f"no telemetry answered camera frame {msg.frame}")
            reply = None
        else:
            self._answered.add(msg.frame)
        trial.link_s += time.perf_counter() - t
        return reply

    def _stop(self, trial: _Trial, resets0: int, lost0: int) -> None:
        """Level the surface and stop the controller; count what the link lost during the trial."""
        t = time.perf_counter()
        self.link.command(m.Stop())
        trial.link_s += time.perf_counter() - t
        self._watch.firmware_resets = max(self._watch.firmware_resets, self.link.resets - resets0)
        self._watch.lost_firmware_frames = self.link.lost_frames - lost0
        if self._watch.lost_firmware_frames:
            self._watch.report(f"{self._watch.lost_firmware_frames} firmware frames missing from its sequence")

    def _result(
        self, spec: TrialSpec, trial: _Trial, rows: dict, true_xy_m: np.ndarray, judge: Tolerance, fell: bool
    ) -> TrialResult:
        """The trial judged where the object is at the end (the paper's Results), with its trajectory."""
        final_xy = M.object_xy(self.model, self.data)
        final_error = float(np.hypot(*(final_xy - np.asarray(spec.target_m))))
        return TrialResult(
            spec=spec,
            object_name=self.rig.object.name,
            success=is_success(fell, final_error, spec.tolerance_m),
            final_error_m=final_error,
            final_xy_m=final_xy,
            time_to_reach_s=judge.first_s,
            fell_off=fell,
            sim_time_s=self.data.time - trial.t0_sim_s,
            wall_time_s=time.perf_counter() - trial.wall0_s,
            physics_wall_s=trial.physics_s,
            link_wall_s=trial.link_s,
            t_s=rows["t_s"],
            true_xy_m=true_xy_m,
            measured_xy_m=rows["measured_xy_m"],
            tilt_deg=rows["tilt_deg"],
            command_m=rows["command_m"],
            measured_m=rows["measured_m"],
            state=rows["state"],
            module=rows["module"],
            watch=self._watch,
        )


class _SimulatedPlant:
    """The simulated rig as one trial's ClosedLoop sees it (host/loop.py, LoopPlant): the physics stepped to each
    camera frame, the camera's drop, noise and latency at its delivery, the firmware's commands applied to the
    actuators when they answer."""

    def __init__(self, bridge: Bridge, spec: TrialSpec, trial: _Trial, progress) -> None:
        self.bridge, self.spec, self.trial, self.progress = bridge, spec, trial, progress
        self.rng = np.random.default_rng(spec.seed)
        self.true_xy_m: list = []  # [m] where the object was at each frame the loop recorded
        self.others_xy_m: list = []  # [m] where each object beside it was then

    def frames(self):
        """The camera's frames at its rate over T, the physics stepped to each; ends early if the object falls off.
        Each frame is judged on the true position."""
        bridge, trial = self.bridge, self.trial
        rate_hz = bridge.tracking.rate_hz
        period_s = 1.0 / rate_hz
        for k in range(int(math.floor(self.spec.duration_s * rate_hz + 1e-9)) + 1):
            capture_s = k * period_s
            if bridge._advance(trial, capture_s):
                trial.fell = True
                return
            yield CameraFrame(capture_s, None, self.spec.target_m, judged_xy_m=M.object_xy(bridge.model, bridge.data))

    def deliver(self, frame: CameraFrame) -> bool:
        """What the camera makes of a frame by the time it reaches the firmware (drawn drop, noise, the tracker on the
        rendered frame), the physics stepped on by the latency; False if the object fell meanwhile."""
        bridge, trial, tracking = self.bridge, self.trial, self.bridge.tracking
        frame.dropped = self.rng.random() < tracking.drop_rate
        frame.measured_xy_m = bridge._measure(frame.capture_s, frame.judged_xy_m, self.rng)
        deliver_s = frame.capture_s + tracking.latency_s
        if tracking.latency_s and bridge._advance(trial, deliver_s):
            trial.fell = True
            return False
        if frame.dropped:
            bridge._watch.dropped_frames += 1
        trial.deliver_us = trial.base_us + round(deliver_s * US_PER_S)
        return True

    def answered(self, frame: CameraFrame, telemetry: m.Telemetry | None) -> None:
        """The firmware's commands to the actuators; the frame to the view and the progress line."""
        bridge = self.bridge
        if telemetry is not None:
            M.set_commands(bridge.model, bridge.data, bridge._commands(telemetry))
        self.true_xy_m.append(frame.judged_xy_m)
        if bridge.rig.others:
            self.others_xy_m.append(
                [M.object_xy(bridge.model, bridge.data, k) for k in range(1, len(bridge.rig.objects))]
            )
        if bridge.view is not None:
            bridge.view.frame(frame, telemetry)
        if self.progress is not None:
            self.progress(frame.capture_s)


@dataclass
class _Trial:
    """One running trial's clocks and time accounts."""

    wall0_s: float  # [s] perf_counter when the trial began (set-up included)
    t0_sim_s: float  # [s] physics time at trial time 0
    base_us: int  # [us] the firmware's clock at trial time 0
    wall_start_s: float  # [s] perf_counter at trial time 0 (real time paces the physics to it)
    deliver_us: int = 0  # [us] the firmware's clock when the present frame arrives
    fell: bool = False  # the object fell off (the trial ended there)
    physics_s: float = 0.0  # [s] wall time spent stepping MuJoCo
    link_s: float = 0.0  # [s] wall time spent in the protocol exchange
