"""Writes protocol/vectors.json from the cases below: each is stated once (its message and seq, or its bytes) here.

Usage:  python protocol/make_vectors.py           write vectors.json
        python protocol/make_vectors.py --check   exit 1 if vectors.json differs from what this writes

A frame's wire bytes and payload come from the Python encoder; its `fields` are the payload decoded again, so a
float reads as the float32 the wire carries (0.02 is 0.019999999552965164). What each case must yield is stated
by hand below, not derived from the decoder: the decoders (Python and C++) are tested against it.
"""

from __future__ import annotations

import argparse
import json
import math
import struct
import sys
from pathlib import Path

if __package__ in (None, ""):  # run as a script: the checkout's package
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from protocol import messages as m  # noqa: E402
    from protocol.framing import cobs_encode, encode_frame, encode_packet  # noqa: E402
else:
    from . import messages as m
    from .framing import cobs_encode, encode_frame, encode_packet

VECTORS = Path(__file__).resolve().parent / "vectors.json"
ABOUT = (
    "Test vectors of the framed protocol: feeding `wire` (hex) to a fresh frame decoder yields exactly `yields`, "
    "in order. A frame's `fields` are its decoded payload in physical units; encoding them with `seq` gives "
    "`wire` back. Used by tests/test_vectors.py and firmware/tests/test_vectors.cpp."
)
IDENTIFY_1 = encode_frame(m.Identify(), 1)  # the frame the resynchronisation cases end with
SET_TARGET_6 = encode_frame(m.SetTarget(0.125, -0.0625), 6)

# (name, message, seq): one valid frame each, every message of the schema at least once
FRAMES = [
    ("identify, seq 1", m.Identify(), 1),
    ("configure, the paper's defaults", m.Configure(), 2),
    (
        "configure, euclidean with noise",
        m.Configure(
            controller=m.Controller.EUCLIDEAN,
            module_x=0.75,
            module_y=0.5,
            tilt_limit=20.0,
            tolerance=0.01,
            noise_amplitude=0.05,
            noise_seed=0xDEADBEEF,
            deadman=250,
            telemetry_period=0,
        ),
        3,
    ),
    ("configure_pid x, paper gains", m.ConfigurePid(m.Axis.X, **m.PID_DEFAULTS[m.Axis.X]), 4),
    (
        "configure_pid radial, paper gains",
        m.ConfigurePid(m.Axis.RADIAL, **{**m.PID_DEFAULTS[m.Axis.RADIAL], "integral_limit": 10.0}),
        5,
    ),
    ("set_target (0.125, -0.0625)", m.SetTarget(0.125, -0.0625), 6),
    ("set_target NaN x (frame-valid; the firmware refuses it)", m.SetTarget(math.nan, 0.0), 7),
    ("start", m.Start(), 8),
    ("stop", m.Stop(), 9),
    ("emergency_stop, seq wraps to 0", m.EmergencyStop(), 256),
    ("jog actuator 3 to -0.1 m", m.Jog(3, -0.1), 10),
    ("zero actuators 0 and 2 (homing)", m.Zero(0b0101), 9),
    ("zero actuators 0 and 8 (an array's)", m.Zero(0x0101), 16),
    ("configure_schedule, a schedule that acts", m.ConfigureSchedule(0.08, 0.5, 0.25, 2.0, 0.3), 14),
    ("configure_cascade", m.ConfigureCascade(4.0, 0.125), 15),
    ("sim_clock 83333 us", m.SimClock(83333), 11),
    ("object_position visible", m.ObjectPosition(513, 1234567, -0.03125, 0.2, m.PositionFlags(0)), 12),
    ("object_position not visible", m.ObjectPosition(514, 1317900, 0.0, 0.0, m.PositionFlags.NOT_VISIBLE), 13),
    (
        "identify_reply",
        m.IdentifyReply(
            protocol_version=2,
            firmware_major=0,
            firmware_minor=1,
            firmware_patch=0,
            schema_hash=m.SCHEMA_HASH,
            max_wire=46,
            clock=m.Clock.SIMULATED,
            actuator_count=4,
            actuator_range=0.25,
            encoder_counts=4096,
            pulley_circumference=0.04,
            actuator_period=4000,
            modules_x=1,
            modules_y=1,
        ),
        0,
    ),
    ("ack of set_target seq 6", m.Ack(m.SetTarget.ID, 6), 1),
    ("nack out_of_range field 3", m.Nack(m.Configure.ID, 3, m.ErrorCode.OUT_OF_RANGE, 3), 2),
    (
        "telemetry running",
        m.Telemetry(
            time=123456,
            state=m.State.RUNNING,
            faults=m.Faults(0),
            position_frame=513,
            position_age=42,
            tilt_zx=3.09,
            tilt_zy=-26.56,
            command=(0.0, 0.12345, -0.25, 0.25),
            measured=(0.00001, 0.1234, -0.2499, 0.25),
            crc_errors=2,
            frame_errors=65535,
            loop_overruns=7,
            module=3,
            fault_actuator=255,
        ),
        3,
    ),
    (
        "telemetry estop",
        m.Telemetry(
            time=0,
            state=m.State.ESTOP,
            faults=m.Faults.POSITION_TIMEOUT | m.Faults.ESTOP | m.Faults.STALL,
            position_frame=0,
            position_age=65535,
            tilt_zx=0.0,
            tilt_zy=0.0,
            command=(0.0,) * 4,
            measured=(0.0,) * 4,
            crc_errors=0,
            frame_errors=0,
            loop_overruns=0,
            module=0,
            fault_actuator=2,
        ),
        4,
    ),
    ("boot after watchdog", m.Boot(m.ResetCause.WATCHDOG), 0),
    (
        "array_commands of a 2 x 2 array",
        m.ArrayCommands(command=(0.125, -0.25, 0.25, 0.0, -0.0625, 0.1, 0.00001, -0.00001, 0.2) + (0.0,) * 7),
        5,
    ),
]


def _flip(wire: bytes, index: int, bit: int) -> bytes:
    return wire[:index] + bytes([wire[index] ^ (1 << bit)]) + wire[index + 1 :]


ERROR, BAD = {"yield": "frame_error"}, {"yield": "crc_error"}
# (name, wire bytes, what they yield): damaged and odd input; a frame of an unknown id or length yields its raw parts
RAW: list[tuple[str, bytes, list]] = [
    ("set_target with one flipped bit -> crc_error", _flip(SET_TARGET_6, 5, 0), [BAD]),
    ("set_target truncated before its CRC -> crc_error or frame_error", SET_TARGET_6[:8] + b"\x00", [BAD]),
    ("too short: 3 bytes -> frame_error", cobs_encode(bytes([1, 2, 3])) + b"\x00", [ERROR]),
    ("malformed COBS: code past the end -> frame_error", bytes([0x0A, 1, 2, 3, 4, 0]), [ERROR]),
    ("oversized: 60 non-zero bytes -> one frame_error", b"\x11" * 60 + b"\x00", [ERROR]),
    ("idle delimiters yield nothing", b"\x00" * 3, []),
    ("garbage, then a frame: resynchronised", bytes([0xFF, 0x13, 0x37, 0x7E, 0x00]) + IDENTIFY_1, [ERROR, "identify"]),
    ("oversized garbage then a frame", b"\x55" * 100 + b"\x00" + IDENTIFY_1, [ERROR, "identify"]),
    (
        "unknown id 0x7F, valid CRC: a frame (the firmware nacks unknown_message)",
        encode_packet(0x7F, 5, b""),
        [{"yield": "frame", "id": 0x7F, "seq": 5, "payload": ""}],
    ),
    (
        "set_target with a 4-byte payload, valid CRC: a frame (the firmware nacks bad_length)",
        encode_packet(m.SetTarget.ID, 6, struct.pack("<f", 0.25)),
        [{"yield": "frame", "id": m.SetTarget.ID, "seq": 6, "payload": "0000803e"}],
    ),
]


def _frame_yield(msg: m.Message, seq: int) -> dict:
    payload = msg.encode_payload()
    return {
        "yield": "frame",
        "id": msg.ID,
        "seq": seq & 0xFF,
        "payload": payload.hex(),
        "message": msg.NAME,
        "fields": type(msg).decode_payload(payload).as_dict(),
    }


def vectors() -> dict:
    cases = [
        {"name": name, "wire": encode_frame(msg, seq).hex(), "yields": [_frame_yield(msg, seq)]}
        for name, msg, seq in FRAMES
    ]
    for name, wire, yields in RAW:
        cases.append(
            {
                "name": name,
                "wire": wire.hex(),
                "yields": [_frame_yield(m.Identify(), 1) if y == "identify" else y for y in yields],
            }
        )
    return {
        "about": ABOUT,
        "crc16_check": {"algorithm": "CRC-16/CCITT-FALSE", "input_ascii": "123456789", "crc": "0x29B1"},
        "vectors": cases,
    }


def render() -> str:
    return json.dumps(vectors(), indent=1) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="exit 1 if vectors.json is not what this writes")
    args = parser.parse_args(argv)
    text = render()
    if args.check:
        if VECTORS.read_text() != text:
            print(f"{VECTORS} is stale: run python protocol/make_vectors.py", file=sys.stderr)
            return 1
        return 0
    VECTORS.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
