"""Pytest plugin of the conformance suite: --port/--rig/--vmcu-clock options, the session link and the per-test state."""

from __future__ import annotations

import time

import pytest

from mantaray.protocol import messages as m
from mantaray.protocol.conformance.harness import Dut

HANDSHAKE_TIMEOUT_S = 5.0  # [s] identify is retried this long before the device counts as silent
BOOT_WAIT_S = 2.0  # [s] longest wait for the boot message of a board that resets when its port opens


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("mantaray", "MANTA-RAY protocol conformance")
    group.addoption(
        "--port",
        default=None,
        metavar="PATH",
        help="serial device path of the firmware under test (board, simulator or pty); "
        "without it a virtual MCU is started for the session",
    )
    group.addoption(
        "--rig",
        default=None,
        metavar="FILE",
        help="the rig file the firmware was built for (default protocol/rig.toml); a self-started virtual MCU is "
        "that rig's build",
    )
    group.addoption(
        "--vmcu-clock",
        choices=("sim", "wall"),
        default="sim",
        help="clock of the self-started virtual MCU (no effect with --port): sim (default) or wall",
    )


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers",
        "clock(kind): run only against a firmware whose identify_reply.clock is kind "
        "('simulated' or 'wall'); skipped otherwise",
    )
    config.addinivalue_line(
        "markers",
        "wall_timing: times the firmware's clock against the host's wall clock, so it needs a firmware "
        "that keeps real time (a board, the virtual MCU; not an emulator on a busy machine): "
        "deselect with -m 'not wall_timing' where that does not hold",
    )


class ConnectError(Exception):
    """The firmware under test could not be reached; the message is one line for the user."""


class Connection:
    """The session's link to the firmware under test, and the virtual MCU behind it if we started one."""

    def __init__(self, config: pytest.Config) -> None:
        import serial

        from mantaray.host.link import IncompatibleFirmware, Link, LinkError
        from mantaray.host.transport import SerialTransport
        from mantaray.paths import NotBuilt
        from mantaray.protocol import rig

        self.vmcu = None
        self.link = None
        self.boot: m.Boot | None = None  # the boot message the firmware sent as the session began, if one came
        port = config.getoption("port")
        try:
            try:
                description = rig.load(config.getoption("rig")) if config.getoption("rig") else rig.default()
            except rig.RigDescriptionError as exc:
                raise ConnectError(f"--rig {exc}") from None
            if port is None:
                from mantaray.host.vmcu import VirtualMcu

                try:
                    self.vmcu = VirtualMcu(clock=config.getoption("vmcu_clock"), program=description.vmcu_program)
                except (NotBuilt, RuntimeError, OSError) as exc:
                    raise ConnectError(f"cannot start the virtual MCU: {exc}") from None
                port = self.vmcu.path
                self.where = f"virtual MCU on {port}"
            else:
                self.where = port
                if _is_pty(port):  # read before anything opens it with pyserial, which empties its queue
                    self.boot = _boot_waiting(port)
                from mantaray.host.ports import PortError, check_port

                try:
                    check_port(port)  # every form that is no serial device, in one line, as every command does
                except PortError as exc:
                    raise ConnectError(f"--port {exc}") from None
            if self.vmcu is not None:  # it booted as it started: its boot message waits on the pty unread
                self.boot = _boot_waiting(port)
            try:
                self.link = Link(SerialTransport(port), description=description)
            except (OSError, serial.SerialException) as exc:
                raise ConnectError(f"cannot open {port}: {exc}") from None
            if self.vmcu is None:
                self._await_boot()
            self.link.send_raw(b"\x00")  # flushes a half-received frame (PROTOCOL.md, framing)
            deadline = time.monotonic() + HANDSHAKE_TIMEOUT_S
            while True:
                try:
                    identity = self.link.identify()
                    break
                except IncompatibleFirmware as exc:
                    raise ConnectError(str(exc)) from None
                except LinkError as exc:
                    if time.monotonic() > deadline:
                        raise ConnectError(f"no answer to identify on {port}: {exc}") from None
            self.dut = Dut(self.link, identity)
            _prepare_session(self.dut)
        except BaseException:
            self.close()
            raise

    def _await_boot(self) -> None:
        """PROTOCOL.md, physical layer: opening a Uno's port resets it, and its bootloader must not be
        talked to; the host waits for the boot message (or BOOT_WAIT_S) before the handshake. A device
        that has already booted (a simulator, a board without auto-reset) just costs the wait; any
        frame it sends meanwhile ends the wait too."""
        deadline = time.monotonic() + BOOT_WAIT_S
        while (remaining := deadline - time.monotonic()) > 0:
            if (msg := self.link.receive(remaining)) is not None:
                if isinstance(msg, m.Boot):
                    self.boot = msg
                return

    def close(self) -> None:
        if self.link is not None:
            self.link.close()
            self.link = None
        if self.vmcu is not None:
            self.vmcu.close()
            self.vmcu = None


def _is_pty(port: str) -> bool:
    """A pseudo-terminal (a virtual MCU, simavr): no line to reset the firmware and no baud rate to set."""
    import os

    return os.path.realpath(port).startswith("/dev/pts/")


def _boot_waiting(port: str) -> m.Boot | None:
    """The boot message a firmware on a pty (a virtual MCU, simavr) wrote before anyone opened it, read raw: pyserial's
    open empties the input queue, so the link would never see it (PROTOCOL.md, physical layer)."""
    import os
    import select

    from mantaray.protocol.framing import Frame, FrameDecoder

    try:
        fd = os.open(port, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    except OSError:
        return None  # check_port names what is wrong with it
    try:
        decoder, deadline = FrameDecoder(), time.monotonic() + BOOT_WAIT_S
        while (remaining := deadline - time.monotonic()) > 0:
            if not select.select([fd], [], [], remaining)[0]:
                return None
            for item in decoder.feed(os.read(fd, 256)):
                if isinstance(item, Frame):
                    msg = item.message()
                    return msg if isinstance(msg, m.Boot) else None
        return None
    finally:
        os.close(fd)


_CONNECTION = pytest.StashKey[Connection]()


def _connect(config: pytest.Config) -> Connection:
    if _CONNECTION not in config.stash:
        config.stash[_CONNECTION] = Connection(config)
    return config.stash[_CONNECTION]


def pytest_collection_finish(session: pytest.Session) -> None:
    """Connects before the first test when any selected test needs the firmware, so that a missing or
    silent device ends the run with one clear line instead of an error per test."""
    if session.config.option.collectonly:
        return
    if not any("conformance_session" in getattr(item, "fixturenames", ()) for item in session.items):
        return
    try:
        _connect(session.config)
    except ConnectError as exc:
        raise pytest.UsageError(f"conformance: {exc}") from None


def pytest_unconfigure(config: pytest.Config) -> None:
    connection = config.stash.get(_CONNECTION, None)
    if connection is not None:
        connection.close()


@pytest.fixture(scope="session")
def conformance_session(request: pytest.FixtureRequest) -> Dut:
    """The firmware under test for the whole session: a Dut over a SerialTransport, handshake checked."""
    try:
        return _connect(request.config).dut
    except ConnectError as exc:
        pytest.exit(f"conformance: {exc}", returncode=pytest.ExitCode.USAGE_ERROR)


def _prepare_session(dut: Dut) -> None:
    """Once per session: align the simulated clock with the firmware's, and note whether the firmware
    has had a target yet (start answers no_target only before the first set_target)."""
    dut.stop()
    dut.reset_camera()
    if dut.simulated:
        t = dut.probe()  # the firmware's time [ms]; ours must never go behind it
        dut.set_sim_clock((t.time + 1) * 1000)
    dut.first_start = dut.result(m.Start())
    dut.stop()


@pytest.fixture
def session_boot(conformance_session: Dut, request: pytest.FixtureRequest) -> m.Boot:
    """The boot message the firmware sent as the session began: a board that resets when its port opens (an Uno),
    or a virtual MCU this session started; skipped where none came (a board that was up already)."""
    boot = _connect(request.config).boot
    if boot is None:
        pytest.skip(f"no boot message within {BOOT_WAIT_S:g} s of opening the port: the firmware was up already")
    return boot


@pytest.fixture
def dut(conformance_session: Dut, request: pytest.FixtureRequest):
    """The firmware in a known state: identified, idle, boot configuration (without unsolicited
    telemetry) and boot PID gains, a fresh camera history and an empty message log."""
    d = conformance_session
    marker = request.node.get_closest_marker("clock")
    if marker is not None and marker.args[0] != d.clock.name.lower():
        pytest.skip(f"needs a firmware with the {marker.args[0]} clock; this one has the {d.clock.name.lower()} clock")
    d.send_raw(b"\x00")  # ends whatever partial frame a previous test may have left
    d.link.identify()
    d.stop()
    d.configure()
    for axis in m.Axis:
        d.configure_pid(axis)
    d.reset_camera()
    d.log.clear()
    resets = d.link.resets
    yield d
    if d.link.resets != resets:
        pytest.fail("the firmware sent a boot message during this test: it restarted", pytrace=False)


@pytest.fixture
def advance(dut: Dut):
    """advance(seconds): lets firmware time pass (sim_clock on a simulated clock, else sleeping);
    returns the telemetry received meanwhile."""
    return dut.advance


@pytest.fixture
def capture_now(dut: Dut):
    """capture_now(): the time base [us] for object_position.capture_time (the simulated clock, or the
    host's monotonic clock)."""
    return dut.capture_now


def pytest_terminal_summary(terminalreporter, exitstatus, config: pytest.Config) -> None:
    connection = config.stash.get(_CONNECTION, None)
    if connection is None or connection.link is None:
        return
    where, identity = connection.where, connection.dut.identity
    terminalreporter.write_line(
        f"conformance: {where}: protocol {identity.protocol_version}, firmware {identity.firmware_major}."
        f"{identity.firmware_minor}.{identity.firmware_patch}, schema 0x{identity.schema_hash:08X}, "
        f"clock {m.Clock(identity.clock).name.lower()}"
    )
