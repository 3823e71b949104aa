"""Test harness of the conformance suite: the firmware under test seen only through its serial link."""

from __future__ import annotations

import dataclasses
import struct
import time
from collections.abc import Iterable

from mantaray.host.link import CommandRefused, Link
from mantaray.host.session import CONTROLLER_AXES
from mantaray.protocol import messages as m
from mantaray.protocol import rig
from mantaray.protocol.codec import Message
from mantaray.protocol.framing import Frame, FrameDecoder, cobs_encode, crc16, encode_frame

# The known configuration every test starts from: the schema's boot values, but no unsolicited
# telemetry, so that every frame the firmware sends answers something the test sent.
DEFAULT_CONFIG = dataclasses.replace(m.Configure(), telemetry_period=0)

# Refusals name the field by its index in the command; these spell the indices out.
CONFIGURE_FIELD = {spec.name: i for i, spec in enumerate(m.Configure.FIELDS)}
CONFIGURE_PID_FIELD = {spec.name: i for i, spec in enumerate(m.ConfigurePid.FIELDS)}
POSITION_FIELD = {spec.name: i for i, spec in enumerate(m.ObjectPosition.FIELDS)}

TILT_TOL = 0.006  # [deg] tilt telemetry is an integer of 0.01 deg
COMMAND_TOL = 1e-5  # [m] command telemetry is an integer of 1e-5 m
ACTUATOR_RANGE = rig.default().actuator_range_m  # [m] jog bound and actuator travel (protocol/rig.toml)

STATES = ("idle", "running", "reached", "fault", "estop")


# ------------------------------------------------------------------------------------ float32 helpers
def f32(x: float) -> float:
    """x rounded to the nearest float32, as it travels on the wire."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def _f32_step(x: float, up: bool) -> float:
    v = f32(x)
    if v == 0.0:
        bits = 0x00000001 if up else 0x80000001
    else:
        bits = struct.unpack("<I", struct.pack("<f", v))[0]
        bits += 1 if (v > 0) == up else -1
    return struct.unpack("<f", struct.pack("<I", bits))[0]


def f32_above(x: float) -> float:
    """The smallest float32 greater than float32(x): the first value past an inclusive upper bound."""
    return _f32_step(x, up=True)


def f32_below(x: float) -> float:
    """The largest float32 less than float32(x): the first value past an inclusive lower bound."""
    return _f32_step(x, up=False)


# ---------------------------------------------------------------------------------------- framing
def packet_wire(message_id: int, seq: int, payload: bytes) -> bytes:
    """Wire bytes of a frame of any size (no MAX_PACKET check, for oversize and bad-length frames)."""
    body = bytes([message_id & 0xFF, seq & 0xFF]) + payload
    return cobs_encode(body + crc16(body).to_bytes(2, "little")) + b"\x00"


def reference_errors(data: bytes) -> tuple[int, int]:
    """(crc_errors, frame_errors) the host's reference frame decoder counts for these bytes."""
    decoder = FrameDecoder()
    decoder.feed(data)
    return decoder.crc_errors, decoder.frame_errors


def reference_frames(data: bytes) -> list:
    """What the host's reference frame decoder makes of these bytes (frames and FrameErrors)."""
    return FrameDecoder().feed(data)


def summary(t: m.Telemetry) -> tuple:
    """The behaviour-bearing part of a telemetry frame: state, faults, tilts, commands."""
    return (m.State(t.state).name, int(t.faults), t.tilt_zx, t.tilt_zy, tuple(t.command))


# ------------------------------------------------------------------------------------------ device
class Dut:
    """The firmware under test: commands, camera frames, time and raw bytes, all over the serial link."""

    def __init__(self, link: Link, identity: m.IdentifyReply) -> None:
        self.link = link
        self.identity = identity
        self.clock = m.Clock(identity.clock)
        self.log: list[Message] = []  # every message received, in arrival order, but an array's array_commands ...
        # ... which go here with the index in log of the message that came next (their telemetry)
        self.array_commands: list[tuple[int, m.ArrayCommands]] = []
        link.on_message = self._received
        self.sim_now_us = 0  # simulated clock: the firmware's time as last set (u32, wraps at 71.6 min)
        self.sim_total_us = 0  # ... and the same unwrapped: what telemetry's millisecond clock counts
        self.frame = 0  # camera frame counter of the last frame sent
        self.capture_us = 0  # capture time of the last frame sent [us]
        self.first_start: m.ErrorCode | None = None  # what start answered before any test set a target
        self.cache: dict = {}  # per-session results of deterministic reference runs

    def _received(self, msg: Message) -> None:
        if isinstance(msg, m.ArrayCommands):
            self.array_commands.append((len(self.log), msg))
        else:
            self.log.append(msg)

    @property
    def simulated(self) -> bool:
        return self.clock == m.Clock.SIMULATED

    # ---------------------------------------------------------------------------------- the rig's shape
    @property
    def actuator_count(self) -> int:
        return self.identity.actuator_count

    def grid(self, module_x: float = 0.5, module_y: float = 0.5) -> rig.Grid:
        """The rig's shape as identify reports it, for modules of module_x x module_y [m] (as configured)."""
        return rig.Grid(self.identity.modules_x, self.identity.modules_y, module_x, module_y)

    def half(self, module_x: float = 0.5, module_y: float = 0.5) -> tuple[float, float]:
        """[m] Half the surface along x and y for modules of module_x x module_y: targets live within it."""
        return self.grid(module_x, module_y).half_extent_m

    def corners(self, module: int = 0) -> tuple[int, int, int, int]:
        """Module k's four actuators in telemetry's order (PROTOCOL.md §5): on one module, 0 1 2 3."""
        return self.grid().module_corners(module)

    # ---------------------------------------------------------------------------------- commands
    def command(self, msg: Message) -> Message:
        """Sends a command; returns its ack; raises CommandRefused on a nack. Unchecked on the host: the firmware's
        own checks are what this suite tests."""
        return self.link.command(msg, checked=False)

    def result(self, msg: Message) -> m.ErrorCode:
        """Sends a command; returns OK or the nack's code (for runs that compare outcomes)."""
        try:
            self.link.command(msg, checked=False)
        except CommandRefused as exc:
            return exc.code
        return m.ErrorCode.OK

    def refuse(self, msg: Message, code: m.ErrorCode, field: int | Iterable[int] | None = m.NO_FIELD) -> m.Nack:
        """Sends a command that must be refused with `code` naming `field` (None: any; a set: one of them)."""
        try:
            reply = self.link.command(msg, checked=False)
        except CommandRefused as exc:
            nack = exc.nack
        else:
            raise AssertionError(f"{msg} was acknowledged ({reply}); expected nack {code.name.lower()}")
        got = m.ErrorCode(nack.code).name.lower() if nack.code in m.ErrorCode._value2member_map_ else nack.code
        assert nack.code == code, f"{msg.NAME} refused with {got}, expected {code.name.lower()} ({msg})"
        assert nack.ref_id == msg.ID
        if isinstance(field, int):
            assert nack.field == field, f"{msg.NAME} {got}: nack.field {nack.field}, expected {field} ({msg})"
        elif field is not None:
            allowed = set(field)
            assert nack.field in allowed, f"{msg.NAME} {got}: nack.field {nack.field}, expected one of {allowed}"
        return nack

    def configure(self, **changes) -> Message:
        """configure with DEFAULT_CONFIG's values except `changes`."""
        return self.command(dataclasses.replace(DEFAULT_CONFIG, **changes))

    def configure_pid(self, axis: m.Axis, **gains) -> Message:
        """configure_pid of `axis` with the boot gains except `gains`."""
        return self.command(m.ConfigurePid(axis, **{**m.PID_DEFAULTS[axis], **gains}))

    def set_target(self, x: float, y: float) -> Message:
        return self.command(m.SetTarget(x, y))

    def start(self) -> Message:
        return self.command(m.Start())

    def stop(self) -> Message:
        return self.command(m.Stop())

    def emergency_stop(self) -> Message:
        return self.command(m.EmergencyStop())

    # ------------------------------------------------------------------------------------ camera
    def forget_sequence(self) -> None:
        """identify: the firmware forgets the newest frame it took (and the camera history), so the next frame
        may carry any seq (PROTOCOL.md section 3)."""
        self.link.identify()
        self.reset_camera()

    def reset_camera(self) -> None:
        """A new camera history (after identify or start, the firmware has forgotten the old one)."""
        self.frame = 0
        self.capture_us = self.capture_now()

    def next_position(self, x: float, y: float, dt: float = 0.02, visible: bool = True) -> m.ObjectPosition:
        """The next camera frame: counter +1, capture time +dt [s] (at least 1 us)."""
        self.frame = (self.frame + 1) & 0xFFFF
        self.capture_us = (self.capture_us + max(1, round(dt * 1e6))) & 0xFFFFFFFF
        flags = m.PositionFlags(0) if visible else m.PositionFlags.NOT_VISIBLE
        return m.ObjectPosition(self.frame, self.capture_us, x, y, flags)

    def position(self, x: float, y: float, dt: float = 0.02, visible: bool = True) -> m.Telemetry:
        """Sends the next camera frame; returns the telemetry that answers it."""
        return self.send_position(self.next_position(x, y, dt, visible))

    def send_position(self, msg: m.ObjectPosition) -> m.Telemetry:
        t = self.link.position(msg)
        assert t.position_frame == msg.frame
        return t

    def refuse_position(self, msg: m.ObjectPosition, code: m.ErrorCode, field: int) -> m.Nack:
        try:
            t = self.link.position(msg)
        except CommandRefused as exc:
            nack = exc.nack
        else:
            raise AssertionError(f"{msg} was answered by telemetry ({t}); expected nack {code.name.lower()}")
        assert nack.code == code, f"object_position refused with code {nack.code}, expected {code.name.lower()}"
        assert nack.field == field, f"object_position {code.name.lower()}: nack.field {nack.field}, expected {field}"
        return nack

    def probe(self) -> m.Telemetry:
        """Current telemetry, asked with a not_visible frame: it steps nothing and feeds no deadman."""
        return self.position(0.0, 0.0, dt=1e-6, visible=False)

    # -------------------------------------------------------------------------------------- time
    def capture_now(self) -> int:
        """The time base for capture_time [us]: the simulated clock, or the host's monotonic clock."""
        if self.simulated:
            return self.sim_now_us
        return (time.monotonic_ns() // 1000) & 0xFFFFFFFF

    def set_sim_clock(self, now_us: int) -> Message:
        reply = self.command(m.SimClock(now_us & 0xFFFFFFFF))
        self.sim_total_us += (now_us - self.sim_now_us) & 0xFFFFFFFF
        self.sim_now_us = now_us & 0xFFFFFFFF
        return reply

    @property
    def sim_now_ms(self) -> int:
        """What telemetry.time must read on the simulated clock [ms]: every microsecond counted, wrapping at 2^32 ms."""
        return (self.sim_total_us // 1000) & 0xFFFFFFFF

    def advance(self, seconds: float) -> list[m.Telemetry]:
        """Lets `seconds` of firmware time pass (sim_clock, or sleeping while listening); returns the
        telemetry frames that arrived meanwhile."""
        mark = len(self.log)
        if self.simulated:
            self.set_sim_clock(self.sim_now_us + round(seconds * 1e6))
        else:
            deadline = time.monotonic() + seconds
            while (remaining := deadline - time.monotonic()) > 0:
                self.link.receive(remaining)
        return [msg for msg in self.log[mark:] if isinstance(msg, m.Telemetry)]

    # --------------------------------------------------------------------------------- raw bytes
    def next_seq(self) -> int:
        """A sequence number from the link's counter, for a hand-made frame."""
        self.link.seq = (self.link.seq + 1) & 0xFF
        return self.link.seq

    def frame_bytes(self, msg: Message, seq: int | None = None) -> tuple[bytes, int]:
        """(wire bytes, seq) of a command, with a fresh seq unless one is given."""
        seq = self.next_seq() if seq is None else seq
        return encode_frame(msg, seq), seq

    def send_raw(self, data: bytes, chunk: int | None = None) -> None:
        """Bytes straight to the device, all at once or `chunk` bytes per write. A hand-made frame numbered ahead
        of the link's counter moves the counter there, as the host's own counter would have been: the frames the
        harness sends next (a probe) are then newer, not stale (PROTOCOL.md section 3)."""
        for frame in FrameDecoder().feed(data):
            if isinstance(frame, Frame) and 1 <= ((frame.seq - self.link.seq) & 0xFF) <= 191:
                self.link.seq = frame.seq
        if chunk is None:
            self.link.send_raw(data)
            return
        for i in range(0, len(data), chunk):
            self.link.send_raw(data[i : i + chunk])

    def exchange(self, data: bytes, delimiter_first: bool = False) -> tuple[list[Message], m.Telemetry]:
        """Sends raw bytes, then a probe; returns (every frame answered before the probe, the probe's
        telemetry). The link is ordered, so an answer to `data` would have come before the probe's."""
        mark = len(self.log)
        self.send_raw(data)
        if delimiter_first:
            self.send_raw(b"\x00")
        t = self.probe()
        before = [msg for msg in self.log[mark:] if msg is not t]
        return before, t

    # ------------------------------------------------------------------------------------ states
    def enter(self, state: str) -> m.Telemetry:
        """From idle (the per-test state), drives the firmware into `state`; returns its telemetry."""
        if state == "idle":
            self.stop()
        elif state == "running":
            self.set_target(0.1, 0.0)
            self.start()
            self.position(0.0, 0.0)
        elif state == "reached":
            self.set_target(0.0, 0.0)
            self.start()
            self.position(0.001, 0.0)
        elif state == "fault":
            self.configure(deadman=20)
            self.set_target(0.1, 0.0)
            self.start()
            self.advance(0.06)
        elif state == "estop":
            self.emergency_stop()
        else:
            raise ValueError(state)
        t = self.probe()
        assert m.State(t.state).name.lower() == state, f"could not enter {state}: telemetry says {t}"
        return t


# ------------------------------------------------------------------ reference runs ("changes nothing")
# A configuration that differs from BASE_CONFIG in every field; config_fingerprint tells each apart. The base runs
# the cascade, whose steps read the velocity filter (the paper's controllers do not).
BASE_CONFIG = dataclasses.replace(DEFAULT_CONFIG, noise_amplitude=0.002, controller=m.Controller.CASCADE)
ALT_CONFIG = m.Configure(
    controller=m.Controller.EUCLIDEAN,
    module_x=0.4,
    module_y=0.3,
    tilt_limit=10.0,
    tolerance=0.2,
    noise_amplitude=0.05,
    noise_seed=7,
    deadman=20,
    telemetry_period=20,
    velocity_filter=1.0,
)


def config_fingerprint(dut: Dut) -> tuple:
    """Runs a short, fixed scenario from idle and returns what the firmware did, in a form that differs
    for every field of BASE_CONFIG vs ALT_CONFIG: module sizes (set_target bounds), controller,
    tilt_limit, noise and seed (first step's tilts and commands), tolerance (reached or not),
    telemetry_period (unsolicited telemetry), deadman (fault after 50 ms) and velocity_filter (the cascade's second
    step's tilts). The run stays in module 0, about its centre: a hand-over would start the controller afresh.
    Ends in idle."""
    r1 = dut.result(m.SetTarget(0.22, 0.0))
    r2 = dut.result(m.SetTarget(0.2, 0.2))
    cx, cy = dut.grid().module_centre(0)
    dut.set_target(cx + 0.18, cy + 0.12)
    dut.start()
    t1 = dut.position(cx - 0.2, cy - 0.12)
    t2 = dut.position(cx + 0.13, cy + 0.12)
    periodic = dut.advance(0.05)
    t3 = dut.probe()
    dut.stop()
    return (r1.name, r2.name, summary(t1), summary(t2)[:4], bool(periodic), summary(t3)[:2])


def base_config_fingerprint(dut: Dut) -> tuple:
    """config_fingerprint under BASE_CONFIG (computed once per session)."""
    if "config" not in dut.cache:
        dut.command(BASE_CONFIG)
        dut.cache["config"] = config_fingerprint(dut)
    return dut.cache["config"]


# PID gains that differ from the boot gains in every field; pid_fingerprint tells each apart.
ALT_GAINS = {"kp": 20.0, "ki": 100.0, "kd": 5.0, "integral_limit": 0.5}
PID_TARGET = {
    m.Axis.X: (0.2, 0.0),
    m.Axis.Y: (0.0, 0.2),
    m.Axis.RADIAL: (0.2, 0.0),
    m.Axis.VX: (0.2, 0.0),
    m.Axis.VY: (0.0, 0.2),
}
# (position along the axis [m], dt [s]) of the three steps; the cascade's slower ones wind its integral past 0.5 deg
PID_STEPS = {axis: ((0.0, 0.1), (0.02, 0.1), (0.02, 0.1)) for axis in m.Axis}
PID_STEPS.update({axis: ((0.0, 0.1), (0.02, 0.5), (0.02, 0.5)) for axis in (m.Axis.VX, m.Axis.VY)})


def pid_fingerprint(dut: Dut, axes: Iterable[m.Axis] = tuple(m.Axis)) -> dict:
    """For each axis, three controller steps (proportional only, then integral and derivative, then
    integral alone against its bound) under the controller that uses that axis's PID; returns the
    tilts of each step. Ends in idle with DEFAULT_CONFIG."""
    out = {}
    for axis in axes:
        controller = next(c for c, axes_of in CONTROLLER_AXES.items() if axis in axes_of)  # the first that runs it
        dut.configure(controller=controller)
        tx, ty = PID_TARGET[axis]
        dut.set_target(tx, ty)
        dut.start()
        along = (1.0, 0.0) if ty == 0.0 else (0.0, 1.0)
        steps = []
        for s, dt in PID_STEPS[axis]:
            t = dut.position(s * along[0], s * along[1], dt=dt)
            steps.append((t.tilt_zx, t.tilt_zy))
        dut.stop()
        out[axis.name] = tuple(steps)
    dut.configure()
    return out


def base_pid_fingerprint(dut: Dut) -> dict:
    """pid_fingerprint with the boot gains (computed once per session)."""
    if "pid" not in dut.cache:
        dut.cache["pid"] = pid_fingerprint(dut)
    return dut.cache["pid"]


def error_delta(before: m.Telemetry, after: m.Telemetry) -> tuple[int, int]:
    """(crc_errors, frame_errors) counted between two telemetry frames (the counters wrap)."""
    return ((after.crc_errors - before.crc_errors) & 0xFFFF, (after.frame_errors - before.frame_errors) & 0xFFFF)
