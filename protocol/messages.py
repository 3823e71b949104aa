"""Protocol messages, enums and error codes. Generated from protocol/schema.toml by protocol/generate.py; do not edit."""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import ClassVar

from .codec import FieldSpec, Message

PROTOCOL_VERSION = 2
SCHEMA_HASH = 0xFDED63ED
BOOT_GAINS_CRC = 0x6DD8DF21  # of PID_DEFAULTS, as identify_reply reports the board's
MAX_PACKET = 44  # [bytes] id + seq + payload + CRC
MAX_WIRE = 46  # [bytes] COBS packet + delimiter
NO_FIELD = 255


class ErrorCode(enum.IntEnum):
    """nack.code values."""

    OK = 0
    UNKNOWN_MESSAGE = 1
    BAD_LENGTH = 2
    NOT_FINITE = 3
    OUT_OF_RANGE = 4
    BAD_STATE = 5
    NO_TARGET = 6
    UNSUPPORTED = 7
    STALE_POSITION = 8
    STALE_SEQUENCE = 9


ERROR_DOCS = {
    ErrorCode.UNKNOWN_MESSAGE: 'The message id is not one the firmware handles in this direction.',
    ErrorCode.BAD_LENGTH: "The payload length differs from the schema's length for that message id.",
    ErrorCode.NOT_FINITE: 'A float field is NaN or infinite (nack.field names it).',
    ErrorCode.OUT_OF_RANGE: 'A field is outside its documented bounds, or an enum value is unknown (nack.field names it).',
    ErrorCode.BAD_STATE: 'The command is not allowed in the current supervisor state (see PROTOCOL.md, state table).',
    ErrorCode.NO_TARGET: 'start was sent before any set_target.',
    ErrorCode.UNSUPPORTED: 'The command exists but this build cannot do it (sim_clock on a wall-clock or real board).',
    ErrorCode.STALE_POSITION: 'object_position whose frame counter repeats the last one or whose capture time does not advance.',
    ErrorCode.STALE_SEQUENCE: 'A frame whose sequence number is 1 to 64 behind the newest one taken, or equals it with other content: a delayed or duplicated copy of an older frame, not applied (PROTOCOL.md section 3).',
}


class State(enum.IntEnum):
    """Supervisor state."""

    IDLE = 0
    RUNNING = 1
    REACHED = 2
    FAULT = 3
    ESTOP = 4


class Controller(enum.IntEnum):
    """Tilt controller: the paper's Manhattan (Algorithm 1, PIDs x and y) or Euclidean (Algorithm 2, PID radial); beyond the paper, scheduled (Manhattan's PIDs with gains and tilt limits scheduled on the position and speed, configure_schedule) or cascade (a position loop asking for a velocity, PIDs vx and vy tilting for it, configure_cascade)."""

    MANHATTAN = 0
    EUCLIDEAN = 1
    SCHEDULED = 2
    CASCADE = 3


class Axis(enum.IntEnum):
    """Which PID configure_pid sets: x and y are Manhattan's and scheduled's, radial is Euclidean's, vx and vy the cascade's inner loops (their error is a velocity: kp in deg s/m, ki in deg/m, kd in deg s^2/m)."""

    X = 0
    Y = 1
    RADIAL = 2
    VX = 3
    VY = 4


class Clock(enum.IntEnum):
    """Where the firmware's time comes from."""

    WALL = 0
    SIMULATED = 1


class ResetCause(enum.IntEnum):
    """Why the firmware (re)started, reported in boot."""

    POWER_ON = 0
    EXTERNAL = 1
    BROWN_OUT = 2
    WATCHDOG = 3
    UNKNOWN = 4


class PositionFlags(enum.IntFlag):
    """object_position.flags bits."""

    NOT_VISIBLE = 1 << 0


class Faults(enum.IntFlag):
    """telemetry.faults bits; latched until stop."""

    POSITION_TIMEOUT = 1 << 0
    ESTOP = 1 << 1
    STALL = 1 << 2
    ENCODER = 1 << 3


# Boot gains of each PID: kp [deg/m], ki [deg/(m s)], kd [deg s/m], integral_limit [deg].
PID_DEFAULTS = {
    Axis.X: {'kp': 30.9, 'ki': 26.78, 'kd': 15.45, 'integral_limit': 26.565051},
    Axis.Y: {'kp': 30.9, 'ki': 26.78, 'kd': 15.45, 'integral_limit': 26.565051},
    Axis.RADIAL: {'kp': 86.72, 'ki': 27.91, 'kd': 10.19, 'integral_limit': 26.565051},
    Axis.VX: {'kp': 100.0, 'ki': 30.0, 'kd': 0.0, 'integral_limit': 26.565051},
    Axis.VY: {'kp': 100.0, 'ki': 30.0, 'kd': 0.0, 'integral_limit': 26.565051},
}


@dataclass(frozen=True)
class Identify(Message):
    """Handshake: ask for protocol version, firmware version and schema hash."""

    ID: ClassVar[int] = 0x01
    NAME: ClassVar[str] = 'identify'
    DIRECTION: ClassVar[str] = 'host_to_mcu'
    REPLY: ClassVar[str | None] = 'identify_reply'
    SIZE: ClassVar[int] = 0  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset({State.IDLE, State.RUNNING, State.REACHED, State.FAULT, State.ESTOP})
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
    )


@dataclass(frozen=True)
class Configure(Message):
    """Controller-wide settings. Validated whole: any bad field refuses the lot and changes nothing."""

    ID: ClassVar[int] = 0x02
    NAME: ClassVar[str] = 'configure'
    DIRECTION: ClassVar[str] = 'host_to_mcu'
    REPLY: ClassVar[str | None] = 'ack'
    SIZE: ClassVar[int] = 33  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset({State.IDLE})
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('controller', 'B', 1, None, Controller, None, None, ''),
        FieldSpec('module_x', 'f', 1, None, None, 0.1, 10.0, 'm'),
        FieldSpec('module_y', 'f', 1, None, None, 0.1, 10.0, 'm'),
        FieldSpec('tilt_limit', 'f', 1, None, None, 0.1, 89.0, 'deg'),
        FieldSpec('tolerance', 'f', 1, None, None, 0.001, 0.5, 'm'),
        FieldSpec('noise_amplitude', 'f', 1, None, None, 0.0, 0.25, 'm'),
        FieldSpec('noise_seed', 'I', 1, None, None, None, None, ''),
        FieldSpec('deadman', 'H', 1, None, None, 20, 60000, 'ms'),
        FieldSpec('telemetry_period', 'H', 1, None, None, 0, 60000, 'ms'),
        FieldSpec('velocity_filter', 'f', 1, None, None, 0.0, 10.0, 's'),
    )

    controller: Controller = Controller.MANHATTAN  # The tilt controller: manhattan, euclidean, scheduled or cascade. (enum controller)
    module_x: float = 0.5  # [m] Module size m along x (actuators at x = +-m/2).
    module_y: float = 0.5  # [m] Module size n along y (actuators at y = +-n/2).
    tilt_limit: float = 26.565051  # [deg] Saturation of each tilt angle; at most atan(range / ((m + n) / 2)), which keeps every corner in range.
    tolerance: float = 0.02  # [m] epsilon: the object counts as reached within this distance of the target.
    noise_amplitude: float = 0.0  # [m] alpha: each command gets alpha * delta, delta ~ U(-1, 1), drawn every control step.
    noise_seed: int = 1  # Seed of the noise PRNG (xorshift32; 0 is replaced by 1); reseeded at every start.
    deadman: int = 500  # [ms] Longest time without a valid position while running before the surface levels and a position_timeout fault latches.
    telemetry_period: int = 100  # [ms] Period of unsolicited telemetry; 0 = only in answer to object_position. Nonzero values below 5 ms are refused (the link cannot carry them).
    velocity_filter: float = 0.05  # [s] Time constant of the first-order low-pass on the camera-frame velocity (scheduled and cascade); 0: the raw frame difference.


@dataclass(frozen=True)
class ConfigurePid(Message):
    """Gains of one PID. Output unit is degrees of tilt (see PROTOCOL.md, units)."""

    ID: ClassVar[int] = 0x03
    NAME: ClassVar[str] = 'configure_pid'
    DIRECTION: ClassVar[str] = 'host_to_mcu'
    REPLY: ClassVar[str | None] = 'ack'
    SIZE: ClassVar[int] = 17  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset({State.IDLE})
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('axis', 'B', 1, None, Axis, None, None, ''),
        FieldSpec('kp', 'f', 1, None, None, 0.0, 10000.0, 'deg/m'),
        FieldSpec('ki', 'f', 1, None, None, 0.0, 10000.0, 'deg/(m s)'),
        FieldSpec('kd', 'f', 1, None, None, 0.0, 10000.0, 'deg s/m'),
        FieldSpec('integral_limit', 'f', 1, None, None, 0.0, 90.0, 'deg'),
    )

    axis: Axis = Axis.X  # Which PID: x, y (manhattan, scheduled), radial (euclidean), vx, vy (cascade). (enum axis)
    kp: float = 0.0  # [deg/m] Proportional gain.
    ki: float = 0.0  # [deg/(m s)] Integral gain.
    kd: float = 0.0  # [deg s/m] Derivative gain (on measurement: no kick when the target changes).
    integral_limit: float = 0.0  # [deg] Anti-windup bound on the integral term's contribution.


@dataclass(frozen=True)
class SetTarget(Message):
    """Target position p_d in the fabric frame. Must lie on the surface: |x| <= modules_x m/2, |y| <= modules_y n/2 (one module: m/2, n/2)."""

    ID: ClassVar[int] = 0x04
    NAME: ClassVar[str] = 'set_target'
    DIRECTION: ClassVar[str] = 'host_to_mcu'
    REPLY: ClassVar[str | None] = 'ack'
    SIZE: ClassVar[int] = 8  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset({State.IDLE, State.RUNNING, State.REACHED, State.FAULT})
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('x', 'f', 1, None, None, None, None, 'm'),
        FieldSpec('y', 'f', 1, None, None, None, None, 'm'),
    )

    x: float = 0.0  # [m] x_d.
    y: float = 0.0  # [m] y_d.


@dataclass(frozen=True)
class Start(Message):
    """idle -> running: reset the PIDs, reseed the noise, start the deadman."""

    ID: ClassVar[int] = 0x05
    NAME: ClassVar[str] = 'start'
    DIRECTION: ClassVar[str] = 'host_to_mcu'
    REPLY: ClassVar[str | None] = 'ack'
    SIZE: ClassVar[int] = 0  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset({State.IDLE})
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
    )


@dataclass(frozen=True)
class Stop(Message):
    """Any state -> idle: level the surface. Also how a fault or an emergency stop is cleared."""

    ID: ClassVar[int] = 0x06
    NAME: ClassVar[str] = 'stop'
    DIRECTION: ClassVar[str] = 'host_to_mcu'
    REPLY: ClassVar[str | None] = 'ack'
    SIZE: ClassVar[int] = 0  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset({State.IDLE, State.RUNNING, State.REACHED, State.FAULT, State.ESTOP})
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
    )


@dataclass(frozen=True)
class EmergencyStop(Message):
    """Any state -> estop: actuator power cut at once; latched until stop."""

    ID: ClassVar[int] = 0x07
    NAME: ClassVar[str] = 'emergency_stop'
    DIRECTION: ClassVar[str] = 'host_to_mcu'
    REPLY: ClassVar[str | None] = 'ack'
    SIZE: ClassVar[int] = 0  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset({State.IDLE, State.RUNNING, State.REACHED, State.FAULT, State.ESTOP})
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
    )


@dataclass(frozen=True)
class Jog(Message):
    """Move one actuator to a position, for calibration; stop or start ends the jog."""

    ID: ClassVar[int] = 0x08
    NAME: ClassVar[str] = 'jog'
    DIRECTION: ClassVar[str] = 'host_to_mcu'
    REPLY: ClassVar[str | None] = 'ack'
    SIZE: ClassVar[int] = 5  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset({State.IDLE})
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('actuator', 'B', 1, None, None, 0, 15, ''),
        FieldSpec('position', 'f', 1, None, None, None, None, 'm'),
    )

    actuator: int = 0  # Actuator index (PROTOCOL.md §5); one the firmware's rig does not have is refused (out_of_range).
    position: float = 0.0  # [m] Command, + lowers the corner; within the actuator range.


@dataclass(frozen=True)
class SimClock(Message):
    """Simulated clock only: set the firmware's time; it must not go backwards. Real boards answer unsupported."""

    ID: ClassVar[int] = 0x09
    NAME: ClassVar[str] = 'sim_clock'
    DIRECTION: ClassVar[str] = 'host_to_mcu'
    REPLY: ClassVar[str | None] = 'ack'
    SIZE: ClassVar[int] = 4  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset({State.IDLE, State.RUNNING, State.REACHED, State.FAULT, State.ESTOP})
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('now', 'I', 1, None, None, None, None, 'us'),
    )

    now: int = 0  # [us] New time of the firmware clock.


@dataclass(frozen=True)
class Zero(Message):
    """Homing: take the present position of each actuator in the mask as 0 m, the reference height z0."""

    ID: ClassVar[int] = 0x0A
    NAME: ClassVar[str] = 'zero'
    DIRECTION: ClassVar[str] = 'host_to_mcu'
    REPLY: ClassVar[str | None] = 'ack'
    SIZE: ClassVar[int] = 2  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset({State.IDLE})
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('actuators', 'H', 1, None, None, 1, None, ''),
    )

    actuators: int = 0  # Bit i set: zero actuator i (PROTOCOL.md §5); a bit for an actuator the firmware's rig does not have is refused (out_of_range).


@dataclass(frozen=True)
class ConfigureSchedule(Message):
    """The position-scheduled Manhattan controller's schedule (PROTOCOL.md, controllers). Its defaults schedule nothing: it then steps as Manhattan."""

    ID: ClassVar[int] = 0x0B
    NAME: ClassVar[str] = 'configure_schedule'
    DIRECTION: ClassVar[str] = 'host_to_mcu'
    REPLY: ClassVar[str | None] = 'ack'
    SIZE: ClassVar[int] = 20  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset({State.IDLE})
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('edge_zone', 'f', 1, None, None, 0.001, 5.0, 'm'),
        FieldSpec('edge_gain', 'f', 1, None, None, 0.0, 1.0, ''),
        FieldSpec('edge_tilt', 'f', 1, None, None, 0.0, 1.0, ''),
        FieldSpec('edge_brake', 'f', 1, None, None, 0.0, 100.0, ''),
        FieldSpec('brake_speed', 'f', 1, None, None, 0.0, 10.0, 'm/s'),
    )

    edge_zone: float = 0.05  # [m] Width of the band along each edge where the schedule acts, growing linearly to the edge.
    edge_gain: float = 1.0  # kp and ki at the edge the object is nearest to along the axis, relative to the axis's own.
    edge_tilt: float = 1.0  # Tilt limit toward an edge, at that edge, relative to tilt_limit (the tilt away from the nearest edge keeps the whole limit unless edge_zone is wider than half the module).
    edge_brake: float = 0.0  # kd at the edge is (1 + edge_brake) times the axis's own.
    brake_speed: float = 0.0  # [m/s] Speed at which the tilt along the object's motion on an axis has faded to 0 (a tilt against it, which brakes, stays free); 0: no such limit.


@dataclass(frozen=True)
class ConfigureCascade(Message):
    """The cascaded controller's outer loop (PROTOCOL.md, controllers); its inner PIDs are configure_pid's vx and vy."""

    ID: ClassVar[int] = 0x0C
    NAME: ClassVar[str] = 'configure_cascade'
    DIRECTION: ClassVar[str] = 'host_to_mcu'
    REPLY: ClassVar[str | None] = 'ack'
    SIZE: ClassVar[int] = 8  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset({State.IDLE})
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('position_gain', 'f', 1, None, None, 0.0, 100.0, '1/s'),
        FieldSpec('speed_limit', 'f', 1, None, None, 0.001, 5.0, 'm/s'),
    )

    position_gain: float = 3.0  # [1/s] Velocity asked for per metre of error, on each axis.
    speed_limit: float = 0.15  # [m/s] The most the outer loop asks for, on each axis.


@dataclass(frozen=True)
class ObjectPosition(Message):
    """One camera measurement. Answered by telemetry (or a nack); one controller step when running."""

    ID: ClassVar[int] = 0x10
    NAME: ClassVar[str] = 'object_position'
    DIRECTION: ClassVar[str] = 'host_to_mcu'
    REPLY: ClassVar[str | None] = 'telemetry'
    SIZE: ClassVar[int] = 15  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset({State.IDLE, State.RUNNING, State.REACHED, State.FAULT, State.ESTOP})
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('frame', 'H', 1, None, None, None, None, ''),
        FieldSpec('capture_time', 'I', 1, None, None, None, None, 'us'),
        FieldSpec('x', 'f', 1, None, None, None, None, 'm'),
        FieldSpec('y', 'f', 1, None, None, None, None, 'm'),
        FieldSpec('flags', 'B', 1, None, PositionFlags, None, None, ''),
    )

    frame: int = 0  # Camera frame counter, +1 per frame (wraps).
    capture_time: int = 0  # [us] When the frame was captured, host clock; the controller's dt is the difference of these.
    x: float = 0.0  # [m] Object x in the fabric frame; on the fabric or at most half a module beside it (one module: within +-module_x), else out_of_range.
    y: float = 0.0  # [m] Object y in the fabric frame; on the fabric or at most half a module beside it (one module: within +-module_y), else out_of_range.
    flags: PositionFlags = PositionFlags(0)  # not_visible: the camera lost the object; x and y are ignored. (flags position_flags)


@dataclass(frozen=True)
class IdentifyReply(Message):
    """Answer to identify."""

    ID: ClassVar[int] = 0x81
    NAME: ClassVar[str] = 'identify_reply'
    DIRECTION: ClassVar[str] = 'mcu_to_host'
    REPLY: ClassVar[str | None] = None
    SIZE: ClassVar[int] = 32  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset()
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('protocol_version', 'H', 1, None, None, None, None, ''),
        FieldSpec('firmware_major', 'B', 1, None, None, None, None, ''),
        FieldSpec('firmware_minor', 'B', 1, None, None, None, None, ''),
        FieldSpec('firmware_patch', 'B', 1, None, None, None, None, ''),
        FieldSpec('schema_hash', 'I', 1, None, None, None, None, ''),
        FieldSpec('max_wire', 'B', 1, None, None, None, None, 'bytes'),
        FieldSpec('clock', 'B', 1, None, Clock, None, None, ''),
        FieldSpec('actuator_count', 'B', 1, None, None, None, None, ''),
        FieldSpec('actuator_range', 'f', 1, None, None, None, None, 'm'),
        FieldSpec('encoder_counts', 'H', 1, None, None, None, None, ''),
        FieldSpec('pulley_circumference', 'f', 1, None, None, None, None, 'm/rev'),
        FieldSpec('actuator_period', 'I', 1, None, None, None, None, 'us'),
        FieldSpec('modules_x', 'B', 1, None, None, None, None, ''),
        FieldSpec('modules_y', 'B', 1, None, None, None, None, ''),
        FieldSpec('boot_gains_crc', 'I', 1, None, None, None, None, ''),
    )

    protocol_version: int = 0  # [protocol] version of the firmware's schema.
    firmware_major: int = 0  # Firmware version, major.
    firmware_minor: int = 0  # Firmware version, minor.
    firmware_patch: int = 0  # Firmware version, patch.
    schema_hash: int = 0  # CRC-32 of the canonical schema; the host refuses a mismatch.
    max_wire: int = 0  # [bytes] Largest frame the firmware accepts, delimiter included.
    clock: Clock = Clock.WALL  # Wall or simulated clock. (enum clock)
    actuator_count: int = 0  # Actuators the firmware drives (protocol/rig.toml, as every field below).
    actuator_range: float = 0.0  # [m] Travel of each actuator about z0 the firmware was built for.
    encoder_counts: int = 0  # Counts per encoder revolution the firmware was built for.
    pulley_circumference: float = 0.0  # [m/rev] Belt travel per motor revolution the firmware was built for.
    actuator_period: int = 0  # [us] Period of the firmware's actuator position loops.
    modules_x: int = 0  # Modules along x: the firmware drives a modules_x x modules_y array (1 x 1: one module).
    modules_y: int = 0  # Modules along y.
    boot_gains_crc: int = 0  # CRC-32 of the PIDs' boot gains the firmware was built with ([pid_defaults] as f32, in axis order); outside schema_hash, so a retuned default is reported, not refused.


@dataclass(frozen=True)
class Ack(Message):
    """The command with this id and seq was applied (or was a retransmission of one that was)."""

    ID: ClassVar[int] = 0x82
    NAME: ClassVar[str] = 'ack'
    DIRECTION: ClassVar[str] = 'mcu_to_host'
    REPLY: ClassVar[str | None] = None
    SIZE: ClassVar[int] = 2  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset()
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('ref_id', 'B', 1, None, None, None, None, ''),
        FieldSpec('ref_seq', 'B', 1, None, None, None, None, ''),
    )

    ref_id: int = 0  # Message id of the command.
    ref_seq: int = 0  # Sequence number of the command.


@dataclass(frozen=True)
class Nack(Message):
    """The command with this id and seq was refused and changed nothing."""

    ID: ClassVar[int] = 0x83
    NAME: ClassVar[str] = 'nack'
    DIRECTION: ClassVar[str] = 'mcu_to_host'
    REPLY: ClassVar[str | None] = None
    SIZE: ClassVar[int] = 4  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset()
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('ref_id', 'B', 1, None, None, None, None, ''),
        FieldSpec('ref_seq', 'B', 1, None, None, None, None, ''),
        FieldSpec('code', 'B', 1, None, None, None, None, ''),
        FieldSpec('field', 'B', 1, None, None, None, None, ''),
    )

    ref_id: int = 0  # Message id of the command.
    ref_seq: int = 0  # Sequence number of the command.
    code: int = 0  # Error code (errors above).
    field: int = 0  # Index of the offending field in the command, 255 if none.


@dataclass(frozen=True)
class Telemetry(Message):
    """Firmware state; after every accepted object_position and every telemetry_period."""

    ID: ClassVar[int] = 0x84
    NAME: ClassVar[str] = 'telemetry'
    DIRECTION: ClassVar[str] = 'mcu_to_host'
    REPLY: ClassVar[str | None] = None
    SIZE: ClassVar[int] = 39  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset()
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('time', 'I', 1, None, None, None, None, 'ms'),
        FieldSpec('state', 'B', 1, None, State, None, None, ''),
        FieldSpec('faults', 'H', 1, None, Faults, None, None, ''),
        FieldSpec('position_frame', 'H', 1, None, None, None, None, ''),
        FieldSpec('position_age', 'H', 1, None, None, None, None, 'ms'),
        FieldSpec('tilt_zx', 'h', 1, 0.01, None, None, None, 'deg'),
        FieldSpec('tilt_zy', 'h', 1, 0.01, None, None, None, 'deg'),
        FieldSpec('command', 'h', 4, 1e-05, None, None, None, 'm'),
        FieldSpec('measured', 'h', 4, 1e-05, None, None, None, 'm'),
        FieldSpec('crc_errors', 'H', 1, None, None, None, None, ''),
        FieldSpec('frame_errors', 'H', 1, None, None, None, None, ''),
        FieldSpec('loop_overruns', 'H', 1, None, None, None, None, ''),
        FieldSpec('module', 'B', 1, None, None, None, None, ''),
        FieldSpec('fault_actuator', 'B', 1, None, None, None, None, ''),
    )

    time: int = 0  # [ms] Firmware clock: every microsecond counted, so it wraps at 2^32 ms (49.7 days).
    state: State = State.IDLE  # Supervisor state. (enum state)
    faults: Faults = Faults(0)  # Latched fault flags. (flags faults)
    position_frame: int = 0  # Frame counter of the last accepted object_position.
    position_age: int = 0  # [ms] Time since the last valid position (65535: none, or longer).
    tilt_zx: float = 0.0  # [deg] theta_zx after saturation (Euclidean: theta resolved along x). (wire = value / 0.01)
    tilt_zy: float = 0.0  # [deg] theta_zy after saturation (Euclidean: theta resolved along y). (wire = value / 0.01)
    command: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0)  # [m] Commands a_i of module `module`'s four actuators (its corners in PROTOCOL.md §5's order), + lowers the corner. (wire = value / 1e-05)
    measured: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0)  # [m] Measured positions of the same four actuators, same convention. (wire = value / 1e-05)
    crc_errors: int = 0  # Frames dropped for a bad CRC since boot (wraps).
    frame_errors: int = 0  # Frames dropped for bad COBS, oversize or truncation since boot (wraps).
    loop_overruns: int = 0  # Actuator-loop runs that started a whole period or more late since boot (saturates at 65535; 0 where the actuators are ideal).
    module: int = 0  # The module whose actuators command and measured are (PROTOCOL.md §5): the one the controller drives; after a jog, the lowest-numbered module the jogged actuator is a corner of; 0 on one module.
    fault_actuator: int = 0  # The actuator whose stall or encoder fault latched first, 255 if none: on an array it stops every module.


@dataclass(frozen=True)
class ArrayCommands(Message):
    """An array's commands to every actuator, sent just before each telemetry by a firmware of more than one module (one module's telemetry shows all four): the driven module's plane goes on over the others (PROTOCOL.md §5, Arrays)."""

    ID: ClassVar[int] = 0x86
    NAME: ClassVar[str] = 'array_commands'
    DIRECTION: ClassVar[str] = 'mcu_to_host'
    REPLY: ClassVar[str | None] = None
    SIZE: ClassVar[int] = 32  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset()
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('command', 'h', 16, 1e-05, None, None, None, 'm'),
    )

    command: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)  # [m] Command a_i of actuator i (PROTOCOL.md §5's numbering), + lowers it; 0 past actuator_count. (wire = value / 1e-05)


@dataclass(frozen=True)
class Boot(Message):
    """Sent once when the firmware starts, so the host notices a reset."""

    ID: ClassVar[int] = 0x85
    NAME: ClassVar[str] = 'boot'
    DIRECTION: ClassVar[str] = 'mcu_to_host'
    REPLY: ClassVar[str | None] = None
    SIZE: ClassVar[int] = 1  # [bytes] payload
    STATES: ClassVar[frozenset[int]] = frozenset()
    FIELDS: ClassVar[tuple[FieldSpec, ...]] = (
        FieldSpec('reset_cause', 'B', 1, None, ResetCause, None, None, ''),
    )

    reset_cause: ResetCause = ResetCause.POWER_ON  # Why it started. (enum reset_cause)


MESSAGES: dict[int, type[Message]] = {m.ID: m for m in (Identify, Configure, ConfigurePid, SetTarget, Start, Stop, EmergencyStop, Jog, SimClock, Zero, ConfigureSchedule, ConfigureCascade, ObjectPosition, IdentifyReply, Ack, Nack, Telemetry, ArrayCommands, Boot)}

STATE_ERROR = ErrorCode.BAD_STATE  # nack.code outside a message's STATES

# What each controller reads (schema.toml, [controllers]): the PIDs it runs, the messages with its own settings,
# the configure fields that are its settings.
CONTROLLER_AXES: dict[Controller, tuple[Axis, ...]] = {
    Controller.MANHATTAN: (Axis.X, Axis.Y),
    Controller.EUCLIDEAN: (Axis.RADIAL,),
    Controller.SCHEDULED: (Axis.X, Axis.Y),
    Controller.CASCADE: (Axis.VX, Axis.VY),
}
CONTROLLER_SETTINGS: dict[Controller, tuple[type[Message], ...]] = {
    Controller.MANHATTAN: (),
    Controller.EUCLIDEAN: (),
    Controller.SCHEDULED: (ConfigureSchedule,),
    Controller.CASCADE: (ConfigureCascade,),
}
CONTROLLER_CONFIGURE: dict[Controller, tuple[str, ...]] = {
    Controller.MANHATTAN: ('tilt_limit',),
    Controller.EUCLIDEAN: ('tilt_limit',),
    Controller.SCHEDULED: ('tilt_limit', 'velocity_filter'),
    Controller.CASCADE: ('tilt_limit', 'velocity_filter'),
}
SETTINGS_MESSAGES: tuple[type[Message], ...] = (ConfigureSchedule, ConfigureCascade)  # every controller's, in schema order
PAPER_AXES: tuple[Axis, ...] = (Axis.X, Axis.Y, Axis.RADIAL)  # the PIDs of the paper's controllers, whose gains it gives
