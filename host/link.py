"""The host end of the protocol: handshake, acknowledged commands with retransmission, position frames, telemetry."""

from __future__ import annotations

import collections
import math
import time
from collections.abc import Callable

from mantaray.protocol import messages as m
from mantaray.protocol import rig
from mantaray.protocol.codec import Message
from mantaray.protocol.framing import Frame, FrameDecoder, FrameError, encode_frame

from .transport import Transport


class LinkError(RuntimeError):
    """The firmware did not answer as the protocol says it must."""


class IncompatibleFirmware(LinkError):
    """identify showed a protocol version or schema hash other than this host's, or another rig's actuators."""


# The rig constants that the host's commands depend on (their bounds, the tilt limit, which actuators make which
# module): a board built with others is refused at identify. The other reported constants only warn
# (Link.rig_differences).
BINDING_CONSTANTS = ("actuator_count", "actuator_range", "modules_x", "modules_y")


def rig_differences(reply: m.IdentifyReply, description: rig.RigDescription) -> dict[str, str]:
    """identify_reply field -> what differs, for each rig constant the firmware reports that the host's rig file
    states otherwise (floats compared at the wire's f32 precision)."""
    out = {}
    units = description.reported_units
    for name, expected in description.reported.items():
        got = getattr(reply, name)
        if not math.isclose(got, expected, rel_tol=1e-6):
            unit = f" {units[name]}" if units[name] else ""
            out[name] = f"{name} is {got:g}{unit} on the board, {expected:g}{unit} in {description.path.name}"
    return out


class CommandRefused(LinkError):
    """The firmware answered a command with a nack."""

    def __init__(self, command: Message, nack: m.Nack) -> None:
        self.command, self.nack = command, nack
        self.code = m.ErrorCode(nack.code) if nack.code in m.ErrorCode._value2member_map_ else nack.code
        field = ""
        if nack.field != m.NO_FIELD and nack.field < len(command.FIELDS):
            field = f" (field {command.FIELDS[nack.field].name})"
        name = self.code.name.lower() if isinstance(self.code, m.ErrorCode) else f"code {nack.code}"
        doc = m.ERROR_DOCS.get(self.code, "unknown error code")
        super().__init__(f"{command.NAME} refused: {name}{field}: {doc}")


SEQ_WINDOW = 128  # a sequence number 1..127 ahead of the newest is newer (lost between), the rest is older: wraps


class Link:
    """Talks to one firmware over a transport.

    Commands wait for their ack (or the identify_reply); without one within ack_timeout_s [s] the same
    frame, same sequence number, is sent again, up to `retries` times; the firmware answers a
    retransmission again without applying it twice. Frames that arrive while waiting (telemetry,
    boot) go to `on_message` and are kept in `received` (the last 1000).
    """

    def __init__(
        self,
        transport: Transport,
        ack_timeout_s: float = 0.2,
        retries: int = 3,
        on_message: Callable[[Message], None] | None = None,
        description: rig.RigDescription | None = None,
    ) -> None:
        self.transport = transport
        self.description = description or rig.default()  # the rig the host expects the board to drive
        self.ack_timeout_s = ack_timeout_s
        self.retries = retries
        self.on_message = on_message
        self.received: collections.deque[Message] = collections.deque(maxlen=1000)
        self.decoder = FrameDecoder()
        self.seq = 0
        self.last_rx_seq: int | None = None
        self.lost_frames = 0  # firmware frames missing from the firmware's sequence
        self.stale_frames = 0  # firmware frames that came twice or after a newer one (a duplicating or reordering link)
        # what identify reported otherwise than this host: rig constants, boot gains
        self.rig_differences: list[str] = []
        self.resyncs = 0  # times a frame came behind the firmware's count and the link identified again
        self.resets = 0  # boot messages seen
        self.retransmissions = 0  # commands sent again for want of an answer
        self._pending: collections.deque[Message] = collections.deque()

    # ---------------------------------------------------------------------------------- receiving
    def _pump(self, timeout_s: float) -> None:
        data = self.transport.read(timeout_s)
        for item in self.decoder.feed(data):
            if isinstance(item, FrameError):
                continue
            self._accept(item)

    def _accept(self, frame: Frame) -> None:
        ahead = None if self.last_rx_seq is None or frame.id == m.Boot.ID else (frame.seq - self.last_rx_seq) & 0xFF
        if ahead is not None and not 0 < ahead < SEQ_WINDOW:  # a copy, or older than the newest: out of order
            self.stale_frames += 1
        else:
            if ahead is not None:
                self.lost_frames += ahead - 1
            self.last_rx_seq = frame.seq
        try:
            msg = frame.message()
        except ValueError:
            return  # counted by the decoder's peers as garbage; nothing to act on
        if isinstance(msg, m.Boot):
            self.resets += 1
        self._pending.append(msg)

    def receive(self, timeout_s: float = 0.0) -> Message | None:
        """The next message from the firmware, waiting up to timeout_s [s]."""
        deadline = time.monotonic() + timeout_s
        while not self._pending:
            remaining = deadline - time.monotonic()
            self._pump(max(remaining, 0.0))
            if remaining <= 0:
                break
        if not self._pending:
            return None
        msg = self._pending.popleft()
        self.received.append(msg)
        if self.on_message is not None:
            self.on_message(msg)
        return msg

    # ------------------------------------------------------------------------------------ sending
    def _next_seq(self) -> int:
        self.seq = (self.seq + 1) & 0xFF
        return self.seq

    def _await_reply(self, frame: bytes, accept: Callable[[Message], bool]) -> Message:
        for attempt in range(self.retries + 1):
            self.retransmissions += attempt > 0
            self.transport.write(frame)
            deadline = time.monotonic() + self.ack_timeout_s
            while (remaining := deadline - time.monotonic()) > 0:
                msg = self.receive(remaining)
                if msg is not None and accept(msg):
                    return msg
        raise LinkError(f"no answer after {self.retries + 1} tries of {self.ack_timeout_s:.3f} s each")

    def command(self, msg: Message, *, resynced: bool = False, checked: bool = True) -> Message:
        """Sends a command and returns its ack (identify_reply for identify); raises CommandRefused on a nack.

        First the schema's own checks (Message.check): what the firmware would refuse by them raises FieldRefused
        and is not sent. Only a test of the firmware's refusals sends such a message, with checked=False.
        A command refused as stale_sequence was never applied: this host's counter fell behind the firmware's
        (PROTOCOL.md section 3). The link identifies, which starts the firmware's count afresh, and sends it again.
        """
        if checked:
            msg.check()
        seq = self._next_seq()

        def answers(reply: Message) -> bool:
            if isinstance(msg, m.Identify):
                return isinstance(reply, m.IdentifyReply)
            return isinstance(reply, (m.Ack, m.Nack)) and reply.ref_id == msg.ID and reply.ref_seq == seq

        reply = self._await_reply(encode_frame(msg, seq), answers)
        if isinstance(reply, m.Nack):
            if reply.code == m.ErrorCode.STALE_SEQUENCE and not resynced:
                self._resync()
                return self.command(msg, resynced=True, checked=False)
            raise CommandRefused(msg, reply)
        return reply

    def _resync(self) -> None:
        """identify: the firmware forgets the newest frame it took, so this host's next frame counts again."""
        self.resyncs += 1
        self.command(m.Identify(), resynced=True)

    def position(self, msg: m.ObjectPosition, timeout_s: float | None = None) -> m.Telemetry:
        """Sends one camera frame and returns the telemetry that answers it (not retransmitted: stale by then)."""
        seq = self._next_seq()
        self.transport.write(encode_frame(msg, seq))
        deadline = time.monotonic() + (self.ack_timeout_s if timeout_s is None else timeout_s)
        while (remaining := deadline - time.monotonic()) > 0:
            reply = self.receive(remaining)
            if isinstance(reply, m.Nack) and reply.ref_id == msg.ID and reply.ref_seq == seq:
                if reply.code == m.ErrorCode.STALE_SEQUENCE:  # never applied; the next frame will be
                    self._resync()
                    raise LinkError(
                        f"position frame {msg.frame} came behind the firmware's count: identified "
                        f"again, the next frame counts"
                    )
                raise CommandRefused(msg, reply)
            if isinstance(reply, m.Telemetry) and reply.position_frame == msg.frame:
                return reply
        raise LinkError(f"no telemetry answered position frame {msg.frame}")

    def send_raw(self, frame: bytes) -> None:
        """Bytes straight to the transport, for tests of garbage and corrupt frames."""
        self.transport.write(frame)

    def identify(self) -> m.IdentifyReply:
        """Handshake; raises IncompatibleFirmware unless version and schema hash match this host's."""
        reply = self.command(m.Identify())
        assert isinstance(reply, m.IdentifyReply)
        if reply.protocol_version != m.PROTOCOL_VERSION or reply.schema_hash != m.SCHEMA_HASH:
            raise IncompatibleFirmware(
                f"firmware speaks protocol {reply.protocol_version} (schema 0x{reply.schema_hash:08X}); this host "
                f"speaks {m.PROTOCOL_VERSION} (schema 0x{m.SCHEMA_HASH:08X}): flash the firmware built from "
                f"this checkout, or use the host that matches the firmware"
            )
        differences = rig_differences(reply, self.description)
        binding = [text for name, text in differences.items() if name in BINDING_CONSTANTS]
        if binding:
            raise IncompatibleFirmware(
                f"the firmware was built for another rig ({'; '.join(binding)}): give the host the board's rig file "
                f"(--rig), or describe your rig in {self.description.path.name}, run python3 protocol/generate.py, "
                f"and flash the firmware built from it"
            )
        self.rig_differences = list(differences.values())
        if reply.boot_gains_crc != m.BOOT_GAINS_CRC:  # not refused: every PID a run sets is sent, the rest boot so
            self.rig_differences.append(
                f"the firmware boots its PIDs with other gains than this host's protocol/schema.toml [pid_defaults] "
                f"(CRC 0x{reply.boot_gains_crc:08X}, here 0x{m.BOOT_GAINS_CRC:08X}): a PID the run does not set "
                f"runs the board's"
            )
        return reply

    def close(self) -> None:
        self.transport.close()
