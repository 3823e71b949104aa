"""The Uno's ELF in the AVR simulator: conformance over a pty, the actuator loops on modelled motors, the closed loop."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time

import pytest
from conformance_result import assert_suite_passed

from mantaray.host.avr_image import ensure_elf
from mantaray.host.controller_settings import ControllerSettings
from mantaray.host.link import CommandRefused, Link
from mantaray.host.simavr import SimulatedUno
from mantaray.host.transport import SerialTransport
from mantaray.paths import REPO
from mantaray.protocol import messages as m
from mantaray.protocol import rig

RX_BUFFER_CYCLES = (
    64 * 10 * rig.default().board.f_cpu_hz // 115_200
)  # [cycles] 64 bytes of 10 bits at 115200 baud: 5.6 ms
LOOP_PERIOD_CYCLES = 4000 * 16  # [cycles] the 250 Hz actuator loop period
ARRAY_RIG = rig.named("array_2x2")  # the Mega 2560 and its nine actuators
# the rig side's conformance tests: those whose module (clock-marked tests, timed replies) or own name holds one of
# these words
RIG_SIDE_KEYWORDS = ("handshake", "deadman", "object_position", "sim_clock", "telemetry_period")


@pytest.fixture(scope="module")
def elf():
    return ensure_elf(rig.default())


def _conformance(port: str, *pytest_args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "conformance", "--port", port, *pytest_args],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=600,
    )


@pytest.mark.parametrize("bench, clock", [(True, "simulated"), (False, "wall")], ids=["bench", "rig"])
def test_the_protocol_conformance_suite_passes_against_the_avr_binary(elf, bench, clock):
    """The whole suite on the bench side (simulated clock: every timing test runs on it). On the rig side, in real
    time, the tests that read the firmware's clock (RIG_SIDE_KEYWORDS): every other test sends the same
    bytes and reads the same replies whichever clock the firmware keeps, and the bench side has run them. The
    firmware keeps simavr's time, which falls behind the wall clock when this 2-core machine is busy, so the three
    tests that time it against the host's wall clock are left to the bench side's equivalents."""
    with SimulatedUno(elf, bench=bench, realtime=not bench) as uno:
        chosen = [] if bench else ["-v", "-m", "not wall_timing", "-k", " or ".join(RIG_SIDE_KEYWORDS)]
        proc = _conformance(uno.path, "--", "-rs", *chosen)
    assert_suite_passed(proc, clock)
    if not bench:  # every module of the clock ran
        ran = set(re.findall(r"(?:^|/)test_(\w+)\.py [.s]+", proc.stdout, flags=re.MULTILINE))  # -v: a line a module
        assert ran >= set(RIG_SIDE_KEYWORDS), ran
        assert int(re.search(r"(\d+) passed", proc.stdout.strip().splitlines()[-1]).group(1)) > 50


class Probe:
    """Telemetry on demand, through not-visible positions (they step nothing and feed no deadman)."""

    def __init__(self, link: Link) -> None:
        self.link, self.frame = link, 0

    def __call__(self) -> m.Telemetry:
        self.frame += 1
        return self.link.position(
            m.ObjectPosition(frame=self.frame, capture_time=self.frame * 1000, flags=m.PositionFlags.NOT_VISIBLE)
        )

    def until(self, done, timeout_s: float = 5.0) -> m.Telemetry:
        """The first telemetry for which done() holds; fails the test if none does within timeout_s [s, wall]."""
        deadline = time.monotonic() + timeout_s
        while not done(t := self()) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert done(t), f"not there within {timeout_s} s: {t}"
        return t


def test_the_rig_build_drives_modelled_motors_to_their_setpoints_and_stops_them(elf):
    with SimulatedUno(elf, bench=False, realtime=True) as uno:
        link = Link(SerialTransport(uno.path), ack_timeout_s=1.0)
        assert link.identify().clock == m.Clock.WALL
        link.command(m.Configure(telemetry_period=0))
        link.command(m.Jog(actuator=0, position=0.05))
        link.command(m.Jog(actuator=3, position=-0.03))
        probe = Probe(link)
        t = probe.until(lambda t: abs(t.measured[0] - 0.05) < 1e-3 and abs(t.measured[3] + 0.03) < 1e-3)
        assert t.faults == 0 and t.measured[0] == pytest.approx(0.05, abs=1e-3)
        assert t.loop_overruns == 0  # telemetry reports the loops' lateness: none here
        assert t.measured[3] == pytest.approx(-0.03, abs=1e-3)
        link.command(m.EmergencyStop())
        stopped = probe().measured[0]
        time.sleep(0.5)
        t = probe()
        assert m.State(t.state) == m.State.ESTOP and t.measured[0] == pytest.approx(stopped, abs=2e-4)
        link.command(m.Stop())
        link.command(m.Jog(actuator=1, position=0.02))
        t = probe.until(lambda t: abs(t.measured[1] - 0.02) < 1e-3)
        assert m.State(t.state) == m.State.IDLE and t.faults == 0  # a jog, not a run: idle, no fault
        link.command(m.Zero(actuators=0b0010))
        t = probe()
        assert t.measured[1] == pytest.approx(0.0, abs=1e-4) and t.command[1] == 0.0
        link.close()
    stats = uno.stats
    assert stats["actuator_loops"]["count"] > 100
    assert stats["actuator_loops"]["max_cycles"] < LOOP_PERIOD_CYCLES  # the loops fit their period
    assert stats["main_loop_pass"]["max_cycles"] < RX_BUFFER_CYCLES  # no pass lets the RX buffer fill
    assert 0 < stats["never_used_ram_bytes"] < 2048  # the stack never met the data


def next_boot(link: Link, timeout_s: float = 5.0) -> m.Boot:
    """The firmware's next boot message, within timeout_s [s, wall]."""
    deadline = time.monotonic() + timeout_s
    while (remaining := deadline - time.monotonic()) > 0:
        if isinstance(msg := link.receive(remaining), m.Boot):
            return msg
    raise AssertionError(f"no boot message within {timeout_s} s")


def test_an_emergency_stop_stays_latched_across_a_reset_until_the_host_sends_stop(elf):
    """The reset pin (the reset button, or the host opening the Uno's port) restarts the MCU with its RAM kept: it
    boots in estop and stays so until stop; a reset after the stop boots idle."""
    with SimulatedUno(elf, bench=False, realtime=True) as uno:
        link = Link(SerialTransport(uno.path), ack_timeout_s=1.0)
        link.identify()
        link.command(m.Configure(telemetry_period=0))
        link.command(m.EmergencyStop())
        probe = Probe(link)
        assert m.State(probe().state) == m.State.ESTOP
        uno.process.send_signal(signal.SIGUSR1)  # the reset pin
        assert next_boot(link).reset_cause == m.ResetCause.EXTERNAL
        assert link.identify().clock == m.Clock.WALL  # the rig again, not the bench
        t = probe()
        assert m.State(t.state) == m.State.ESTOP and t.faults == m.Faults.ESTOP
        with pytest.raises(CommandRefused):  # a jog is refused: nothing may move
            link.command(m.Jog(actuator=0, position=0.02))
        link.command(m.Stop())  # the host's clear: the one way out
        link.command(m.Jog(actuator=0, position=0.02))
        t = probe.until(lambda t: abs(t.measured[0] - 0.02) < 1e-3)
        assert m.State(t.state) == m.State.IDLE and t.faults == 0
        uno.process.send_signal(signal.SIGUSR1)
        assert next_boot(link).reset_cause == m.ResetCause.EXTERNAL
        link.identify()
        t = probe()
        assert m.State(t.state) == m.State.IDLE and t.faults == 0  # cleared latches stay cleared
        link.close()


def test_a_closed_loop_trial_runs_with_the_avr_binary_in_place_of_the_virtual_mcu(elf, tmp_path):
    with SimulatedUno(elf, bench=True) as uno:
        proc = subprocess.run(
            [
                sys.executable,
                "-m",
                "mantaray.cli",
                "sim",
                "run",
                "--port",
                uno.path,
                "--duration",
                "4",
                "--json",
                "--out",
                str(tmp_path),
            ],
            cwd=REPO,
            capture_output=True,
            text=True,
            timeout=300,
        )
    result = json.loads(proc.stdout)
    assert proc.returncode == (0 if result["success"] else 1), proc.stderr  # the exit status says the outcome
    assert result["sim_time_s"] == pytest.approx(4.0, abs=0.01) and result["link_clean"]
    assert not result["fell_off"]
    start, target = result["start_m"], result["target_m"]
    initial = ((start[0] - target[0]) ** 2 + (start[1] - target[1]) ** 2) ** 0.5
    assert result["final_error_m"] < 0.5 * initial  # the AVR's controller steered it there
    assert uno.stats["byte_handling"]["count"] > 0


ACTING_SCHEDULE = ControllerSettings.load(
    REPO / "docs" / "results" / "avr_timing" / "scheduled_acting.toml"
)  # all at work


@pytest.mark.parametrize("settings", [ACTING_SCHEDULE, ControllerSettings("cascade")], ids=["scheduled", "cascade"])
def test_the_controllers_beyond_the_paper_steer_a_closed_loop_trial_in_the_avr_binary(elf, tmp_path, settings):
    path = tmp_path / "settings.toml"
    path.write_text(settings.dumps())
    with SimulatedUno(elf, bench=True) as uno:
        proc = subprocess.run(
            [
                sys.executable,
                "-m",
                "mantaray.cli",
                "sim",
                "run",
                "--port",
                uno.path,
                "--duration",
                "4",
                "--settings",
                str(path),
                "--json",
                "--out",
                str(tmp_path),
            ],
            cwd=REPO,
            capture_output=True,
            text=True,
            timeout=300,
        )
    result = json.loads(proc.stdout)
    assert proc.returncode == (0 if result["success"] else 1), proc.stderr
    assert result["controller"] == settings.controller and result["link_clean"] and not result["fell_off"]
    assert result["time_to_reach_s"] is not None and result["time_to_reach_s"] < 2.0  # [s] steered there


def test_positions_as_fast_as_the_link_allows_lose_no_byte_while_the_loops_run(elf):
    """Running on the rig side (loops on modelled motors), one position in flight at a time, back to back."""
    with SimulatedUno(elf, bench=False, realtime=True) as uno:
        link = Link(SerialTransport(uno.path), ack_timeout_s=1.0)
        link.identify()
        link.command(m.Configure(telemetry_period=0))
        link.command(m.SetTarget(x=0.1, y=-0.05))
        link.command(m.Start())
        t0, answered, frame, first = time.monotonic(), 0, 0, None
        while time.monotonic() - t0 < 3.0:
            frame += 1
            t = link.position(m.ObjectPosition(frame=frame, capture_time=frame * 8000, x=0.0, y=0.0))
            answered += t.position_frame == frame
            first = first or t
        # on the firmware's own clock (the simulated AVR's time, which a busy host slows down with it)
        rate_hz = (frame - 1) / (((t.time - first.time) & 0xFFFFFFFF) / 1000)
        link.close()
    assert answered == frame  # every position answered by its telemetry
    assert t.crc_errors == 0 and t.frame_errors == 0  # nothing lost or overrun on the way in
    assert m.State(t.state) in (m.State.RUNNING, m.State.REACHED) and t.faults == 0
    assert rate_hz > 60  # several times the camera's 12 Hz, in AVR time


@pytest.fixture(scope="module")
def mega_elf():
    return ensure_elf(ARRAY_RIG)


def test_the_protocol_conformance_suite_passes_against_the_mega_binary(mega_elf):
    """The 2 x 2 array's image on the bench side (simulated clock), with the array's rig file."""
    with SimulatedUno(mega_elf, bench=True, harness=ARRAY_RIG.simavr_harness) as mega:
        proc = _conformance(mega.path, "--rig", "protocol/rigs/array_2x2.toml", "--", "-rs")
    assert_suite_passed(proc, "simulated")


def test_the_mega_build_drives_the_arrays_nine_actuators_through_two_multiplexers(mega_elf):
    """The 2 x 2 array's image in the ATmega2560 harness: it reports the array's shape, reads all nine encoders (eight
    on one multiplexer, the ninth on another) without a fault, and drives all nine at once within the rig's loop
    period; the centre actuator, a corner of every module, shows in telemetry as module 0's corner 3."""
    array = rig.load(rig.RIGS / "array_2x2.toml")
    with SimulatedUno(mega_elf, bench=False, realtime=True, harness=ARRAY_RIG.simavr_harness) as mega:
        link = Link(SerialTransport(mega.path), ack_timeout_s=1.0, description=array)
        reply = link.identify()
        assert (reply.modules_x, reply.modules_y, reply.actuator_count) == (2, 2, 9)
        assert link.rig_differences == []
        link.command(m.Configure(telemetry_period=0))
        for actuator in (0, 1, 2, 3, 5, 6, 7, 8):
            link.command(m.Jog(actuator=actuator, position=-0.02))
        link.command(m.Jog(actuator=4, position=0.03))
        t = Probe(link).until(lambda t: abs(t.measured[3] - 0.03) < 1e-3)
        assert t.faults == 0 and t.fault_actuator == 255 and t.module == 0
        assert t.measured[:3] == pytest.approx((-0.02,) * 3, abs=1e-3)  # actuators 0, 1, 3 where jogged
        link.close()
    stats = mega.stats
    assert stats["actuator_loops"]["count"] > 100
    assert stats["actuator_loops"]["max_cycles"] < ARRAY_RIG.value("actuator_period_us") * 16  # [cycles] fit the period


def test_the_mega_reads_its_encoders_after_a_reset_that_left_a_multiplexer_channel_on(mega_elf):
    """A reset keeps the multiplexers powered, with the second one's channel on (the loops read actuator 8 last):
    at boot the firmware turns every multiplexer off before it reads, so no two encoders answer at once."""
    array = rig.load(rig.RIGS / "array_2x2.toml")
    with SimulatedUno(mega_elf, bench=False, realtime=True, harness=ARRAY_RIG.simavr_harness) as mega:
        link = Link(SerialTransport(mega.path), ack_timeout_s=1.0, description=array)
        link.identify()
        link.command(m.Configure(telemetry_period=0))
        assert Probe(link)().faults == 0
        mega.process.send_signal(signal.SIGUSR1)  # the reset pin
        assert next_boot(link).reset_cause == m.ResetCause.EXTERNAL
        link.identify()
        link.command(m.Configure(telemetry_period=0))
        t = Probe(link)()
        assert t.faults == 0 and t.fault_actuator == 255
        link.close()
