"""A firmware session that survives the serial link: waits out the Uno's reset, re-applies its setup after a reset or replug.

The rig command talks through this rather than a bare Link. Opening an Uno's USB port resets the board,
so the session waits for its boot message before the handshake (a pty has no such reset). When the board
resets (a boot message mid-session) or the link fails (unplugged, or no answers), the session reopens
the port as soon as it is back, identifies the firmware again, and re-sends the configuration, the gains
and the target, and `start` if it was running: the user restarts nothing. A session that only attached (monitor,
jog, zero, stop, estop) reconnects the same way and sends nothing again: it set nothing up.
"""

from __future__ import annotations

import os
import shlex
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from mantaray.protocol import messages as m
from mantaray.protocol import rig

from .link import CommandRefused, IncompatibleFirmware, Link, LinkError
from .transport import SerialTransport, Transport


class EmergencyStopLatched(RuntimeError):
    """A start while the session's emergency stop is latched: the user clears it with stop() first."""


PROBE_STEP_US = 50_000  # [us] capture time between two probes' not-visible frames (any step forward will do)
MISSES_BEFORE_RECONNECT = 3  # camera frames in a row without telemetry that mean a lost board, not a lost frame
SETUP_ATTEMPTS = 5  # times a session sets a board up (reconnecting between tries) before it counts as lost


class BoardLost(LinkError):
    """The session could not reach its board, or set it up again, within its retries: the run cannot go on."""


UNO_RESET_WAIT_S = 2.5  # [s] the stock bootloader's delay after the DTR reset, with margin


def is_pty(port: str) -> bool:
    """A pseudo-terminal (virtual MCU, simulator) resets nothing when opened."""
    return os.path.realpath(port).startswith("/dev/pts/")


def controller_axes(controller: str) -> tuple[m.Axis, ...]:
    """The PIDs the controller named so runs (schema.toml, [controllers] axes)."""
    return CONTROLLER_AXES[m.Controller[controller.upper()]]


CONTROLLER_AXES = m.CONTROLLER_AXES  # controller -> the PIDs it runs (schema.toml, [controllers])
PAPER_AXES = m.PAPER_AXES  # the PIDs whose gains the paper gives (a plant may read them per rad)


def connect(
    port: str,
    *,
    reset_wait_s: float | None = None,
    timeout_s: float = 30.0,
    ack_timeout_s: float = 0.2,
    open_transport: Callable[[str], Transport] = SerialTransport,
    description: rig.RigDescription | None = None,
) -> tuple[Link, m.IdentifyReply]:
    """Opens the port (waiting up to timeout_s for it to appear), waits out the Uno's reset, identifies.

    Changes nothing on the firmware: a monitor can attach to a running rig. IncompatibleFirmware is raised
    at once (also for a board built for another rig than description, the default rig if None); a port that does
    not open or a firmware that does not answer raise LinkError at the timeout.
    """
    deadline = time.monotonic() + timeout_s
    while True:
        link = Link(_open(port, deadline, open_transport), ack_timeout_s=ack_timeout_s, description=description)
        try:
            # judged once the port is there: a replugged pty is briefly missing, and is no Uno that resets
            wait_s = reset_wait_s if reset_wait_s is not None else 0.0 if is_pty(port) else UNO_RESET_WAIT_S
            boot_deadline = time.monotonic() + wait_s
            while (remaining := boot_deadline - time.monotonic()) > 0:  # the Uno's bootloader runs first
                if isinstance(link.receive(remaining), m.Boot):
                    break
            while True:
                try:
                    return link, link.identify()
                except IncompatibleFirmware:
                    raise
                except LinkError:
                    if time.monotonic() > deadline:
                        raise LinkError(f"{port}: the firmware does not answer identify") from None
        except OSError:  # the port went away (unplugged) after it opened: open it again
            _close_quietly(link)
            if time.monotonic() > deadline:
                raise LinkError(f"{port}: the port went away and did not come back") from None
        except BaseException:
            _close_quietly(link)
            raise


def _open(port: str, deadline: float, open_transport: Callable[[str], Transport]) -> Transport:
    """The port's transport, retried every 0.2 s until the deadline (the port may not exist yet)."""
    while True:
        try:
            return open_transport(port)
        except OSError as exc:  # serial.SerialException is an OSError: no such port (yet)
            if time.monotonic() > deadline:
                raise LinkError(f"{port}: cannot open it ({exc}); is the board plugged in?") from None
            time.sleep(0.2)


def _close_quietly(link: Link) -> None:
    try:
        link.close()
    except OSError:
        pass


@dataclass
class Setup:
    """A firmware's set-up for a run: what the session re-applies after every (re)connection, and what the
    simulation sends before each trial."""

    configure: m.Configure = field(default_factory=m.Configure)
    gains: dict[m.Axis, dict] = field(default_factory=dict)  # axis -> configure_pid fields (the rest: as booted)
    target: tuple[float, float] | None = None  # [m]
    controller_commands: list[m.Message] = field(default_factory=list)  # configure_schedule, configure_cascade

    def commands(self) -> list[m.Message]:
        """In the order the firmware takes them (in idle): configure, the controller's own settings, each PID's
        gains, the target."""
        out: list[m.Message] = [self.configure, *self.controller_commands]
        out += [m.ConfigurePid(axis=axis, **gains) for axis, gains in self.gains.items()]
        if self.target is not None:
            out.append(m.SetTarget(x=self.target[0], y=self.target[1]))
        return out


class RigSession:
    """One firmware on one serial path; use as a context manager."""

    def __init__(
        self,
        port: str,
        setup: Setup | None = None,
        *,
        reset_wait_s: float | None = None,
        reconnect_timeout_s: float = 30.0,
        ack_timeout_s: float = 0.2,
        report: Callable[[str], None] = lambda text: None,
        open_transport: Callable[[str], Transport] = SerialTransport,
        description: rig.RigDescription | None = None,
    ) -> None:
        self.port = port
        self.description = description or rig.default()  # the rig the board must have been built for
        self.setup = setup or Setup()
        self.reset_wait_s = reset_wait_s  # [s] None: connect() decides by the kind of port
        self.reconnect_timeout_s = reconnect_timeout_s
        self.ack_timeout_s = ack_timeout_s
        self.report = report
        self._open_transport = open_transport
        self.link: Link | None = None
        self.identity: m.IdentifyReply | None = None
        self.sets_up = True  # open() set the board up, and a reconnection sets it up again; attach(): not
        self.running = False
        self.estopped = False  # emergency_stop() latched it; only stop() clears it
        self._setup_pending = False  # a (re)connection during the emergency stop sent only the stop
        self._last_position: m.ObjectPosition | None = None  # the last frame sent: a probe's comes after it
        self.reconnects = 0  # times the link was reopened
        self.lost_telemetry = 0  # camera frames whose telemetry never came (skipped)
        self._missed_in_a_row = 0
        self.restores = 0  # times the setup was re-applied after a reset or reconnection
        self._resets_seen = 0

    # ----------------------------------------------------------------------------------- connection
    def open(self) -> RigSession:
        """Connects and sets the board up; raises BoardLost when it cannot (IncompatibleFirmware at once)."""
        self.sets_up = True
        self._connect(self.reconnect_timeout_s)
        self._set_up("connected")
        return self

    def attach(self) -> RigSession:
        """Connects without setting the board up: changes nothing on it (a monitor may watch a running rig). Its
        reconnections send nothing again; raises BoardLost when the board does not answer (IncompatibleFirmware at
        once)."""
        self.sets_up = False
        self._connect(self.reconnect_timeout_s)
        return self

    @property
    def _live(self) -> Link:
        """The link of a connected session (a bug to ask before open() or after close())."""
        if self.link is None:
            raise RuntimeError("the session has no link: open() it first")
        return self.link

    def _connect(self, timeout_s: float) -> None:
        """Open and identify; a board that does not come back in timeout_s raises BoardLost (IncompatibleFirmware
        as it is)."""
        first = self.identity is None
        try:
            self.link, self.identity = connect(
                self.port,
                reset_wait_s=self.reset_wait_s,
                timeout_s=timeout_s,
                ack_timeout_s=self.ack_timeout_s,
                open_transport=self._open_transport,
                description=self.description,
            )
        except IncompatibleFirmware:
            raise
        except (LinkError, OSError) as exc:
            raise BoardLost(str(exc)) from None  # it names the port
        self._resets_seen = self._live.resets
        if first:
            for text in self._live.rig_differences:
                self.report(f"warning: {text}")

    def _keep_board_estop(self) -> None:
        """A board met in its emergency stop (another host's, or one its reset kept) stays in it: latched here too."""
        if not self.estopped and m.State(self.probe().state) == m.State.ESTOP:
            self.running, self.estopped = False, True
            self.report(
                f"{self.port}: the board is in an emergency stop this session did not send: it stays latched until "
                f"`mantaray stop --port {shlex.quote(self.port)}`"
            )

    def _apply(self) -> None:
        if self.estopped:  # latched across resets and replugs: nothing is powered until stop() clears it
            self._live.command(m.EmergencyStop())
            self._setup_pending = True
            return
        self._live.command(m.Stop())
        for command in self.setup.commands():
            self._live.command(command)
        if self.running:
            self._live.command(m.Start())

    def _set_up(self, why: str) -> None:
        """Apply the setup, reconnecting and trying again (SETUP_ATTEMPTS in all) when a command of it is lost.

        A refused command (CommandRefused) is the user's setup, not the link: it is raised at once. A board that
        does not come back within reconnect_timeout_s, or a setup lost every time, raises BoardLost."""

        def apply() -> None:
            self._keep_board_estop()
            self._apply()
            self._resets_seen = self._live.resets

        def reconnect(exc: Exception) -> None:
            self.report(f"{why}: the setup did not get through ({exc}); reconnecting to {self.port}")
            self._reconnect()

        self._retried(apply, "the setup", reconnect)

    def _retried(self, action: Callable[[], object], what: str, between: Callable[[Exception], None]):
        """action(), tried SETUP_ATTEMPTS times in all; between(exc) runs after each lost try (a nack, CommandRefused,
        is raised at once); the last lost try raises BoardLost."""
        for attempt in range(1, SETUP_ATTEMPTS + 1):
            try:
                return action()
            except CommandRefused:
                raise
            except (LinkError, OSError) as exc:
                if attempt == SETUP_ATTEMPTS:
                    raise BoardLost(
                        f"{self.port}: {what} did not get through in {SETUP_ATTEMPTS} tries (the last: {exc})"
                    ) from None
                between(exc)

    def _reconnect(self) -> None:
        if self.link is not None:
            _close_quietly(self.link)
        self.link = None
        self._connect(self.reconnect_timeout_s)
        self.reconnects += 1

    def _recover(self, why: str) -> None:
        """Reopen the link and re-apply the setup (an attached session: nothing to re-apply)."""
        self.report(f"{why}: reconnecting to {self.port}")
        self._reconnect()
        if self.sets_up:
            self._restore("reconnected")
        else:
            self.report(f"reconnected to {self.port}")

    def _restore(self, why: str) -> None:
        self._set_up(why)
        self.restores += 1
        if self.estopped:
            self.report(f"{why}: the emergency stop is latched again; stop() clears it")
        else:
            self.report(f"{why}: configuration, gains, target{' and start' if self.running else ''} sent again")

    # ----------------------------------------------------------------------------------- commands
    def command(self, msg) -> m.Message:
        """A command through the session: on a failed link it reconnects, restores and sends it again, SETUP_ATTEMPTS
        times in all; then BoardLost. A nack (CommandRefused) is raised as it is."""
        return self._retried(
            lambda: self._live.command(msg), msg.NAME, lambda exc: self._recover(f"link failed ({exc})")
        )

    def set_target(self, x_m: float, y_m: float) -> None:
        self.setup.target = (x_m, y_m)
        self.command(m.SetTarget(x=x_m, y=y_m))

    def start(self) -> None:
        if self.estopped:
            raise EmergencyStopLatched(
                f"the emergency stop is latched: `mantaray stop --port {shlex.quote(self.port)}` clears it before a "
                "start"
            )
        self.command(m.Start())
        self.running = True

    def stop(self) -> None:
        """Levels the surface and stops the controller; also how the user clears an emergency stop."""
        self.running = False
        self.estopped = False
        if self._setup_pending:  # a board met during the emergency stop has not had its setup yet
            self._setup_pending = False
            self._apply()
        else:
            self.command(m.Stop())

    def emergency_stop(self) -> None:
        """Cuts the actuators' power at once; latched, also across resets and replugs, until stop()."""
        self.running = False
        self.estopped = True
        self.command(m.EmergencyStop())

    def receive(self, timeout_s: float) -> m.Message | None:
        """The board's next message within timeout_s [s], None when none came; a port that fails (unplugged) is
        reconnected as a command's would be, within reconnect_timeout_s, else BoardLost."""
        try:
            return self._live.receive(timeout_s)
        except OSError as exc:
            self._recover(f"the port failed ({exc})")
            return None

    def probe(self) -> m.Telemetry:
        """The board's telemetry now, asked for with a not-visible position after the last frame sent: it steps
        nothing and feeds no deadman. LinkError when none answers."""
        last = self._last_position or m.ObjectPosition(frame=0, capture_time=0)
        self._last_position = m.ObjectPosition(
            frame=(last.frame + 1) & 0xFFFF,
            capture_time=(last.capture_time + PROBE_STEP_US) & 0xFFFFFFFF,
            flags=m.PositionFlags.NOT_VISIBLE,
        )
        return self._live.position(self._last_position)

    def position(self, msg: m.ObjectPosition) -> m.Telemetry | None:
        """One camera frame; None when it got no answer. A lost answer is skipped (the next frame carries fresh
        news, and a reconnect would level the surface and reset the PIDs); a port that fails, or
        MISSES_BEFORE_RECONNECT answers lost in a row, mean a lost board: the session reconnects and restores. A board
        that reports an emergency stop this session did not send (`mantaray estop` from another terminal) has it
        latched here too: no restore or end of run undoes it, only stop()."""
        self._last_position = msg
        try:
            telemetry = self._live.position(msg)
        except CommandRefused:
            raise
        except OSError as exc:
            self._recover(f"the port failed ({exc})")
            return None
        except LinkError as exc:
            self.lost_telemetry += 1
            self._missed_in_a_row += 1
            if self._missed_in_a_row >= MISSES_BEFORE_RECONNECT:
                self._missed_in_a_row = 0
                self._recover(f"{MISSES_BEFORE_RECONNECT} camera frames in a row got no telemetry ({exc})")
            return None
        self._missed_in_a_row = 0
        if self._live.resets != self._resets_seen and self.sets_up:  # the board restarted (its boot came in)
            self.report("the firmware reset")
            self._restore("after the reset")  # BoardLost when the board cannot be set up again
        elif m.State(telemetry.state) == m.State.ESTOP and not self.estopped:
            self.running, self.estopped = False, True
            self.report("the board reports an emergency stop this host did not send: latched; stop() clears it")
        return telemetry

    def close(self) -> None:
        if self.link is not None:
            self.link.close()
            self.link = None

    def __enter__(self) -> RigSession:
        return self.open()

    def __exit__(self, *exc) -> None:
        self.close()
