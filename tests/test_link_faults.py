"""The host's link and session against the virtual MCU: faults on the wire, garbage, board resets and unplugging."""

from __future__ import annotations

import itertools
import math
import os
import tempfile
import threading
import time

import numpy as np
import pytest

from mantaray.host.faults import FaultInjector
from mantaray.host.link import IncompatibleFirmware, Link, LinkError
from mantaray.host.session import BoardLost, RigSession, Setup, connect
from mantaray.host.transport import InProcessTransport, SerialTransport
from mantaray.host.vmcu import VirtualMcu
from mantaray.protocol import messages as m
from mantaray.protocol.codec import FieldRefused

WIRE_M = 1e-5  # [m] command telemetry resolution


def _probe(link: Link, frame: int, tries: int = 40) -> m.Telemetry:
    """Telemetry through a not-visible position (steps nothing), retried past injected faults: at 1 % drops and 1 %
    flips a byte each way, a position and its 45-byte telemetry both get through about one try in four, so 40 tries
    miss about once in 10^5 probes."""
    for k in range(tries):
        try:
            return link.position(
                m.ObjectPosition(
                    frame=(frame * 32 + k) & 0xFFFF, capture_time=frame * 32 + k + 1, flags=m.PositionFlags.NOT_VISIBLE
                ),
                timeout_s=0.05,
            )
        except LinkError:
            continue
    raise AssertionError("no telemetry through the faulty link")


def test_no_corrupted_command_is_ever_applied_through_drops_flips_and_bursts():
    rng = np.random.default_rng(7)
    with VirtualMcu(clock="wall") as vmcu:
        faulty = FaultInjector(SerialTransport(vmcu.path), p_drop=0.01, p_flip=0.01, p_burst=0.05, seed=3)
        link = Link(faulty, ack_timeout_s=0.05, retries=12)  # each lost frame costs a timeout: short ones keep it quick
        link.identify()
        link.command(m.Configure(telemetry_period=0))
        sent = {i: {0.0} for i in range(4)}
        applied = 0
        for k in range(150):
            actuator, position = int(rng.integers(4)), round(float(rng.uniform(-0.25, 0.25)), 4)
            sent[actuator].add(position)
            link.command(m.Jog(actuator=actuator, position=position))
            t = _probe(link, k + 1)
            assert t.command[actuator] == pytest.approx(position, abs=WIRE_M)  # the acked value is in force
            for i in range(4):  # and nothing else ever was
                assert min(abs(t.command[i] - v) for v in sent[i]) <= WIRE_M
            applied += 1
        counts = faulty.counts
        link.close()
    assert applied == 150
    assert counts.dropped > 20 and counts.flipped > 20 and counts.burst_bytes > 50  # faults really happened
    assert t.crc_errors + t.frame_errors > 10  # and the firmware saw them


def test_garbage_between_frames_costs_only_the_frame_it_hits():
    with VirtualMcu(clock="wall") as vmcu:
        link = Link(SerialTransport(vmcu.path))
        link.identify()
        before = _probe(link, 1)
        rng = np.random.default_rng(1)
        for k in range(20):
            link.send_raw(rng.integers(0, 256, 200, dtype=np.uint8).tobytes() + b"\x00")
            link.command(m.Jog(actuator=k % 4, position=0.01 * k))
        after = _probe(link, 2)
        link.close()
    assert after.frame_errors + after.crc_errors > before.frame_errors + before.crc_errors
    assert after.command[19 % 4] == pytest.approx(0.19, abs=WIRE_M)


def test_the_deadman_trips_within_its_configured_time_when_the_camera_goes_quiet():
    """Measured on the firmware's simulated clock, 1 ms at a time, so a busy machine cannot stretch it."""
    deadman_ms = 200
    with VirtualMcu(clock="sim") as vmcu:
        link = Link(SerialTransport(vmcu.path))
        link.identify()
        link.command(m.Configure(telemetry_period=0, deadman=deadman_ms))
        link.command(m.SetTarget(x=0.1, y=0.0))
        now_us, last = 1_000_000, None
        link.command(m.SimClock(now=now_us))
        link.command(m.Start())
        for k in range(1, 6):  # the camera at 12 Hz
            now_us += 83_333
            link.command(m.SimClock(now=now_us))
            last = link.position(m.ObjectPosition(frame=k, capture_time=now_us, x=0.0, y=0.0))
        frame, t = 100, last
        while m.State(t.state) != m.State.FAULT:  # the camera went quiet: only not-visible probes now
            frame += 1
            now_us += 1_000
            link.command(m.SimClock(now=now_us))
            t = link.position(m.ObjectPosition(frame=frame, capture_time=now_us, flags=m.PositionFlags.NOT_VISIBLE))
        link.close()
    assert t.faults == m.Faults.POSITION_TIMEOUT and t.command == (0.0, 0.0, 0.0, 0.0)  # levelled
    assert deadman_ms <= t.time - last.time <= deadman_ms + 1  # [ms] to the millisecond of the probes


def test_the_session_rides_out_a_board_reset_and_an_unplug_without_the_user():
    events = []
    with tempfile.TemporaryDirectory() as tmp:
        port = os.path.join(tmp, "ttyUNO")
        setup = Setup(
            m.Configure(telemetry_period=0), {m.Axis.X: {**m.PID_DEFAULTS[m.Axis.X], "kp": 50.0}}, target=(0.1, -0.05)
        )
        vmcu = VirtualMcu(clock="wall", path=port)
        session = RigSession(port, setup, reconnect_timeout_s=10, report=events.append).open()
        session.start()
        frame = 0

        def step() -> m.Telemetry | None:
            nonlocal frame
            frame += 1
            return session.position(m.ObjectPosition(frame=frame, capture_time=frame * 83333, x=0.0, y=0.0))

        assert m.State(step().state) == m.State.RUNNING
        vmcu.close()  # unplugged; plugged back in 0.5 s later, meanwhile
        done = threading.Event()  # the session keeps trying: a fresh, idle firmware

        def replug() -> None:  # a thread that lives as long as its virtual MCU
            time.sleep(0.5)  # (which dies with the thread that started it)
            with VirtualMcu(clock="wall", path=port):
                done.wait(30)

        board = threading.Thread(target=replug)
        board.start()
        t = None
        for _ in range(50):
            t = step()
            if t is not None and m.State(t.state) == m.State.RUNNING:
                break
        assert t is not None and m.State(t.state) == m.State.RUNNING
        assert t.tilt_zx > 0 and t.tilt_zy < 0  # steering to the restored target (0.1, -0.05)
        assert session.reconnects >= 1 and any("reconnecting" in e for e in events)
        session.close()
        done.set()
        board.join()


def _running_in_process_session(events: list):
    """A session on an in-process wall-clock firmware, running toward (-0.1, 0.1); (session, transport)."""
    from mantaray.host.transport import InProcessTransport

    transport = InProcessTransport(simulated_clock=False)
    session = RigSession(
        "in-process",
        Setup(m.Configure(telemetry_period=0), target=(-0.1, 0.1)),
        reset_wait_s=0.0,
        report=events.append,
        open_transport=lambda port: transport,
    ).open()
    session.start()
    t = session.position(m.ObjectPosition(frame=1, capture_time=1000, x=0.0, y=0.0))
    assert m.State(t.state) == m.State.RUNNING
    return session, transport


def test_an_emergency_stop_stays_latched_across_a_reset_until_the_user_clears_it():
    """A reconnect or a board reset must not undo an emergency stop (it restored the run before)."""
    from mantaray.host.session import EmergencyStopLatched

    events = []
    session, transport = _running_in_process_session(events)
    session.emergency_stop()
    transport.power_cycle()  # the board restarts: idle, powered, defaults
    session.position(m.ObjectPosition(frame=2, capture_time=84000, x=0.0, y=0.0))  # the session sees the reset
    t = session.position(m.ObjectPosition(frame=3, capture_time=168000, x=0.0, y=0.0))
    assert m.State(t.state) == m.State.ESTOP and any("latched again" in e for e in events)
    with pytest.raises(EmergencyStopLatched):
        session.start()
    session.stop()  # the user clears it: the setup goes to the new board
    session.start()
    t = session.position(m.ObjectPosition(frame=4, capture_time=252000, x=0.0, y=0.0))
    assert m.State(t.state) == m.State.RUNNING and t.tilt_zx < 0 and t.tilt_zy > 0  # the target came back


def test_an_emergency_stop_another_host_sent_is_latched_in_the_session_too():
    """`mantaray estop` from another terminal: the running session sees ESTOP in its telemetry and keeps it latched
    (no start, none restored after a reset, no stop at the end of a run) until its own stop()."""
    from mantaray.host.session import EmergencyStopLatched
    from mantaray.protocol.framing import encode_frame

    events = []
    session, transport = _running_in_process_session(events)
    transport.write(encode_frame(m.EmergencyStop(), (session.link.seq + 100) & 0xFF))  # the other host's frame
    t = session.position(m.ObjectPosition(frame=2, capture_time=84000, x=0.0, y=0.0))
    assert m.State(t.state) == m.State.ESTOP and session.estopped and not session.running
    assert any("emergency stop this host did not send" in e for e in events)
    with pytest.raises(EmergencyStopLatched):
        session.start()
    transport.power_cycle()  # a reset does not undo it either
    session.position(m.ObjectPosition(frame=3, capture_time=168000, x=0.0, y=0.0))
    assert m.State(session.probe().state) == m.State.ESTOP
    session.stop()
    assert m.State(session.probe().state) == m.State.IDLE


def test_a_session_that_finds_the_board_in_its_emergency_stop_keeps_it_latched():
    """Another host's emergency stop, met on opening (or a reset kept it): the setup must not clear it."""
    from mantaray.host.session import EmergencyStopLatched
    from mantaray.host.transport import InProcessTransport

    board, events = InProcessTransport(simulated_clock=False), []
    other = RigSession("in-process", Setup(m.Configure()), reset_wait_s=0.0, open_transport=lambda port: board)
    other.attach().emergency_stop()
    session = RigSession(
        "in-process",
        Setup(m.Configure(telemetry_period=0), target=(0.1, 0.0)),
        reset_wait_s=0.0,
        report=events.append,
        open_transport=lambda port: board,
    ).open()
    assert session.estopped and m.State(session.probe().state) == m.State.ESTOP
    assert any("an emergency stop this session did not send" in e for e in events), events
    with pytest.raises(EmergencyStopLatched, match="mantaray stop --port in-process"):
        session.start()
    session.stop()  # the user clears it: the setup goes to the board
    session.start()
    t = session.position(m.ObjectPosition(frame=1, capture_time=1000, x=0.0, y=0.0))
    assert m.State(t.state) == m.State.RUNNING


def test_an_attached_session_reconnects_and_sends_nothing_again():
    """What monitor, jog, zero, stop and estop use: a reconnection identifies the board and leaves it as it is."""
    from mantaray.host.transport import InProcessTransport

    board = InProcessTransport(simulated_clock=False)
    owner = RigSession(
        "in-process",
        Setup(m.Configure(telemetry_period=0, deadman=60_000), target=(0.1, 0.0)),
        reset_wait_s=0.0,
        open_transport=lambda port: board,
    ).open()  # no deadman in this test's time
    owner.start()
    events, opened = [], []

    class Unplugging:
        """The board's port, whose next read fails as an unplugged one's does once `unplugged` is set."""

        unplugged = False

        def write(self, data: bytes) -> None:
            board.write(data)

        def read(self, timeout_s: float) -> bytes:
            if Unplugging.unplugged:
                Unplugging.unplugged = False
                raise OSError("device disconnected")
            return board.read(timeout_s)

        def close(self) -> None:
            pass

    watcher = RigSession(
        "in-process",
        reset_wait_s=0.0,
        report=events.append,
        open_transport=lambda port: opened.append(port) or Unplugging(),
    ).attach()
    Unplugging.unplugged = True
    watcher.receive(0.1)
    assert watcher.reconnects == 1 and len(opened) == 2
    assert events[-1] == "reconnected to in-process" and watcher.restores == 0
    assert m.State(watcher.probe().state) == m.State.RUNNING  # still the owner's run, with its setup


def test_a_lost_telemetry_frame_is_skipped_not_a_reconnect():
    """At 0.3 % of bytes dropped about one round trip in six loses its answer: each is skipped (a reconnect
    levels the surface and resets the PIDs); only frames lost three in a row mean a lost board."""
    from mantaray.host.session import MISSES_BEFORE_RECONNECT

    with VirtualMcu(clock="wall") as vmcu:
        session = RigSession(
            vmcu.path,
            Setup(m.Configure(telemetry_period=0), target=(0.1, 0.0)),
            ack_timeout_s=0.05,
            open_transport=lambda port: FaultInjector(SerialTransport(port), p_drop=0.003, seed=5),
        )
        session.open()
        session.start()
        answered = sum(
            session.position(m.ObjectPosition(frame=k, capture_time=k * 83333, x=0.0, y=0.0)) is not None
            for k in range(1, 151)
        )
        session.close()
    assert session.lost_telemetry > 5 and answered + session.lost_telemetry == 150
    assert session.reconnects <= session.lost_telemetry // MISSES_BEFORE_RECONNECT < session.lost_telemetry


def test_a_board_that_resets_on_its_own_gets_its_setup_back():
    """A reset without unplugging (watchdog, brown-out): the boot message mid-session triggers the restore."""
    events = []
    session, transport = _running_in_process_session(events)
    transport.power_cycle()  # the board restarts: idle, no target, boot message
    t = session.position(m.ObjectPosition(frame=2, capture_time=84000, x=0.0, y=0.0))
    assert t is not None and m.State(t.state) == m.State.IDLE  # what the reset left; the session notices ...
    t = session.position(m.ObjectPosition(frame=3, capture_time=168000, x=0.0, y=0.0))
    assert m.State(t.state) == m.State.RUNNING and t.tilt_zx < 0 and t.tilt_zy > 0  # ... and restored it
    assert session.restores == 1 and any("reset" in e for e in events)


@pytest.mark.parametrize("constant", ["SCHEMA_HASH", "PROTOCOL_VERSION"])
def test_a_firmware_of_another_protocol_is_refused_at_once_saying_what_to_do(monkeypatch, constant):
    with VirtualMcu() as vmcu:
        monkeypatch.setattr(m, constant, getattr(m, constant) ^ 1)  # this host now speaks another protocol
        started = time.monotonic()
        with pytest.raises(IncompatibleFirmware, match="flash the firmware built from this checkout"):
            connect(vmcu.path, timeout_s=10.0)
        assert time.monotonic() - started < 2.0  # no waiting out the timeout


def test_a_firmware_built_with_other_boot_gains_is_accepted_and_the_difference_reported(monkeypatch):
    """The boot gains are outside the schema hash: a board built with retuned defaults still speaks this protocol,
    and identify says the PIDs a run leaves unset run the board's gains."""
    link = Link(InProcessTransport(simulated_clock=True))
    link.identify()
    assert not any("boots its PIDs" in text for text in link.rig_differences)
    monkeypatch.setattr(m, "BOOT_GAINS_CRC", m.BOOT_GAINS_CRC ^ 1)  # this host's schema has other defaults
    link.identify()
    assert any("boots its PIDs with other gains" in text for text in link.rig_differences), link.rig_differences
    link.close()


def test_a_port_that_goes_away_while_identifying_is_opened_again():
    class Unplugged:
        def write(self, data: bytes) -> None:
            raise OSError("device disconnected")

        def read(self, timeout_s: float) -> bytes:
            raise OSError("device disconnected")

        def close(self) -> None:
            pass

    opened = []

    def open_transport(port: str):
        opened.append(port)
        return Unplugged() if len(opened) == 1 else SerialTransport(port)

    with VirtualMcu() as vmcu:
        link, identity = connect(vmcu.path, timeout_s=5.0, open_transport=open_transport)
        link.close()
    assert len(opened) == 2 and identity.protocol_version == m.PROTOCOL_VERSION


class _Replay:
    """A transport that hands the link prepared bytes, once."""

    def __init__(self, data: bytes) -> None:
        self.data = data

    def write(self, data: bytes) -> None:
        pass

    def read(self, timeout_s: float) -> bytes:
        data, self.data = self.data, b""
        return data

    def close(self) -> None:
        pass


def test_duplicated_and_reordered_frames_are_not_counted_as_lost():
    """Sequence numbers compared in a wrap-safe window: a copy or a late frame is stale, not 255 frames lost."""
    from mantaray.protocol.framing import encode_frame

    seqs = [254, 255, 255, 0, 254, 3, 3, 2, 4]  # a copy, the wrap, a late 254, 1 and 2 lost, 2 late, in order
    wire = b"".join(encode_frame(m.Ack(ref_id=1, ref_seq=0), seq) for seq in seqs)
    link = Link(_Replay(wire))
    while link.receive() is not None:
        pass
    assert link.lost_frames == 2 and link.stale_frames == 4


class _Tapped:
    """An in-process board behind a link that can replay an old frame late, duplicate the next frame, and lose the
    next answer: the faults of a link that reorders and duplicates."""

    def __init__(self) -> None:
        from mantaray.host.transport import InProcessTransport

        self.board = InProcessTransport(simulated_clock=False)
        self.written: list[bytes] = []
        self.duplicate_next = False
        self.lose_next_answer = False

    def write(self, data: bytes) -> None:
        self.written.append(data)
        self.board.write(data)
        if self.duplicate_next:
            self.duplicate_next = False
            self.board.write(data)

    def read(self, timeout_s: float) -> bytes:
        data = self.board.read(timeout_s)
        if self.lose_next_answer and b"\x00" in data:
            self.lose_next_answer = False
            data = data[data.index(b"\x00") + 1 :]
        return data

    def close(self) -> None:
        pass


def _tapped_link() -> tuple[Link, _Tapped]:
    tap = _Tapped()
    link = Link(tap, ack_timeout_s=0.05)
    link.identify()
    link.command(m.Configure(telemetry_period=0))
    return link, tap


def _drain(link: Link) -> list:
    out = []
    while (msg := link.receive(0.01)) is not None:
        out.append(msg)
    return out


def test_a_late_copy_of_an_older_set_target_does_not_undo_the_newer_one():
    link, tap = _tapped_link()
    link.command(m.SetTarget(x=0.1, y=0.0))
    old = tap.written[-1]
    link.command(m.SetTarget(x=-0.1, y=0.0))
    tap.board.write(old)  # the delayed copy arrives after the newer command
    assert any(isinstance(x, m.Nack) and x.code == m.ErrorCode.STALE_SEQUENCE for x in _drain(link))
    link.command(m.Start())
    t = link.position(m.ObjectPosition(frame=1, capture_time=1000, x=0.0, y=0.0))
    assert t.tilt_zx < 0  # steering to x = -0.1, the newer target


def test_a_late_copy_of_an_older_stop_does_not_stop_a_newer_run():
    link, tap = _tapped_link()
    link.command(m.SetTarget(x=0.1, y=0.0))
    link.command(m.Stop())
    stop = tap.written[-1]
    link.command(m.Start())
    tap.board.write(stop)
    _drain(link)
    t = link.position(m.ObjectPosition(frame=1, capture_time=1000, x=0.0, y=0.0))
    assert m.State(t.state) == m.State.RUNNING


def test_a_duplicated_position_whose_answer_was_lost_is_answered_not_refused():
    """The first copy was applied and its telemetry lost: the second copy's answer is that telemetry again."""
    link, tap = _tapped_link()
    link.command(m.SetTarget(x=0.1, y=0.0))
    link.command(m.Start())
    link.position(m.ObjectPosition(frame=1, capture_time=1000, x=0.0, y=0.0))
    tap.duplicate_next, tap.lose_next_answer = True, True
    t = link.position(m.ObjectPosition(frame=2, capture_time=84000, x=0.01, y=0.0))
    assert t.position_frame == 2 and m.State(t.state) == m.State.RUNNING
    assert link.position(m.ObjectPosition(frame=3, capture_time=168000, x=0.02, y=0.0)).position_frame == 3


def test_a_host_whose_count_fell_behind_identifies_and_sends_again():
    link, tap = _tapped_link()
    link.command(m.SetTarget(x=0.1, y=0.0))
    link.seq = (link.seq - 10) & 0xFF  # as if this host's counter were behind the firmware's
    assert isinstance(link.command(m.SetTarget(x=-0.1, y=0.0)), m.Ack) and link.resyncs == 1
    link.command(m.Start())
    assert link.position(m.ObjectPosition(frame=1, capture_time=1000, x=0.0, y=0.0)).tilt_zx < 0  # it was applied
    link.seq = (link.seq - 10) & 0xFF
    with pytest.raises(LinkError, match="behind the firmware's count"):
        link.position(m.ObjectPosition(frame=2, capture_time=84000, x=0.0, y=0.0))
    assert link.resyncs == 2
    assert link.position(m.ObjectPosition(frame=3, capture_time=168000, x=0.0, y=0.0)).position_frame == 3


def _faulty_session(port: str, p_byte: float, seed: int, events: list) -> RigSession:
    """A session whose every (re)opened port drops and flips each byte with probability p_byte, its own draw each."""
    seeds = itertools.count(seed * 1000)
    return RigSession(
        port,
        Setup(m.Configure(telemetry_period=0), target=(0.1, 0.0)),
        ack_timeout_s=0.05,
        reconnect_timeout_s=5.0,
        report=events.append,
        open_transport=lambda path: FaultInjector(
            SerialTransport(path), p_drop=p_byte, p_flip=p_byte, seed=next(seeds)
        ),
    )


def test_a_session_rides_out_a_link_that_loses_every_other_round_trip():
    """0.5 % of bytes dropped and 0.5 % flipped: about half the position round trips fail. The session skips lost
    frames, reconnects when several in a row are lost, sets the board up again, and never lets an error out."""
    events = []
    with VirtualMcu(clock="wall") as vmcu:
        session = _faulty_session(vmcu.path, 0.005, 1, events)
        session.open()
        session.start()
        answered = sum(
            session.position(m.ObjectPosition(frame=k, capture_time=k * 83_333, x=0.0, y=0.0)) is not None
            for k in range(1, 151)
        )
        session.stop()
        session.close()
    assert 30 < answered < 140, answered  # the faults bit, and the run went on through them
    # every recovery ends restored; one may take several reconnects when its setup's round trips are lost too
    assert session.reconnects > 0 and 0 < session.restores <= session.reconnects
    assert any("sent again" in text for text in events)


def test_a_link_too_poor_to_set_a_board_up_ends_the_session_in_one_clear_error():
    """5 % of bytes dropped and 5 % flipped: neither the handshake nor a setup gets through. open() ends in one
    BoardLost that names the port once; nothing else escapes."""
    events = []
    with VirtualMcu(clock="wall") as vmcu:
        session = _faulty_session(vmcu.path, 0.05, 2, events)
        with pytest.raises(BoardLost) as lost:
            session.open()
        session.close()
    assert str(lost.value).startswith(f"{vmcu.path}: ") and str(lost.value).count(vmcu.path) == 1, lost.value


class _Recorder:
    """A transport that keeps what is written and never answers."""

    def __init__(self) -> None:
        self.written = b""

    def write(self, data: bytes) -> None:
        self.written += data

    def read(self, timeout_s: float) -> bytes:
        return b""

    def close(self) -> None:
        pass


@pytest.mark.parametrize(
    "command, field",
    [
        (m.Configure(tolerance=0.0), "tolerance"),
        (m.Configure(module_x=math.nan), "module_x"),
        (m.ConfigurePid(axis=m.Axis.X, kp=-1.0, ki=0.0, kd=0.0, integral_limit=1.0), "kp"),
        (m.Jog(actuator=16, position=0.0), "actuator"),
    ],
)
def test_the_link_sends_nothing_the_schema_refuses(command, field):
    wire = _Recorder()
    with pytest.raises(FieldRefused) as refused:
        Link(wire).command(command)
    assert refused.value.field == field and wire.written == b""
    with pytest.raises(LinkError):  # unchecked, it goes out (a test of the firmware's checks)
        Link(wire, ack_timeout_s=0.01, retries=0).command(command, checked=False)
    assert wire.written
