"""The board's commands: `mantaray monitor`, `stop`, `estop`, `jog` and `zero`, and the arguments every command
that talks to a board takes."""

from __future__ import annotations

import argparse
import math
import shlex
import sys
import time

from mantaray.arguments import number
from mantaray.protocol import messages as m
from mantaray.protocol import rig

from .board_state import state_text
from .ports import PortError, check_port


# ------------------------------------------------------------------------------------------- the board's state
def _leaving(telemetry: m.Telemetry, session) -> str:
    """The board's state, for a command that only an idle board takes, and the command that leaves it."""
    stop = f"`mantaray stop --port {shlex.quote(session.port)}`"
    state, text = m.State(telemetry.state), state_text(telemetry, session.identity)
    if state == m.State.FAULT:
        return f"the board is in {text}: clear it with {stop} first (it levels the surface)"
    if state == m.State.ESTOP:
        return f"the board is in {text}, the emergency stop (latched): clear it with {stop} first"
    if state in (m.State.RUNNING, m.State.REACHED):
        return f"the board is {text}: a run is going on (mantaray rig?); end it, or {stop}, first"
    return f"the board is {text}"


def _refused(name: str, session, refused) -> int:
    """A command the board refused, in one line (exit 2); refused for the board's state (bad_state), which state
    and how to leave it."""
    text = str(refused)
    if refused.code == m.ErrorCode.BAD_STATE:
        text = f"{refused.command.NAME} refused: {_leaving(session.probe(), session)}"
    print(f"mantaray {name}: {text}", file=sys.stderr)
    return 2


# ------------------------------------------------------------------------------------------- monitor
def _attach(args: argparse.Namespace, parser: argparse.ArgumentParser, reconnect_timeout_s: float = 30.0):
    """A session on the firmware at --port that sets nothing up on it, identified and announced; a path that is no
    serial device is a usage error."""
    from .session import RigSession

    try:
        check_port(args.port)
    except PortError as exc:
        parser.error(str(exc))
    session = RigSession(
        args.port,
        reconnect_timeout_s=reconnect_timeout_s,
        report=lambda text: print(f"mantaray {args.command}: {text}", file=sys.stderr),
        description=args.rig,
    ).attach()
    identity = session.identity
    assert identity is not None  # attach() identified the board
    print(
        f"{args.port}: protocol {identity.protocol_version}, firmware {identity.firmware_major}."
        f"{identity.firmware_minor}.{identity.firmware_patch}, clock {m.Clock(identity.clock).name.lower()}"
    )
    return session


def _checked(parser: argparse.ArgumentParser, command: m.Message) -> m.Message:
    """The command once the schema's field rules pass (Message.check); a field they refuse is a usage error."""
    try:
        return command.check()
    except ValueError as exc:
        parser.error(str(exc))


def cmd_monitor(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Show the firmware's telemetry live, decoded, without changing anything on it, until --count, --seconds or
    Ctrl-C. A board that goes away (unplugged, or reset by a replug) is waited for as mantaray rig waits for it, up
    to --reconnect-timeout, and the monitor goes on by itself once it is back: what happens to the board at the
    bench is what one watches it for. A board that stays away ends it (exit 1)."""
    from .session import BoardLost

    session = _attach(args, parser, args.reconnect_timeout)
    shown = 0
    try:
        deadline = time.monotonic() + args.seconds if args.seconds else math.inf
        while time.monotonic() < deadline and (not args.count or shown < args.count):
            msg = session.receive(0.2)
            if isinstance(msg, m.Telemetry):
                print(_telemetry_line(msg), flush=True)
                shown += 1
            elif isinstance(msg, m.Boot):
                print(f"firmware reset ({m.ResetCause(msg.reset_cause).name.lower()})", flush=True)
    except KeyboardInterrupt:
        pass
    except BoardLost as exc:
        print(f"mantaray monitor: board lost: {exc}", file=sys.stderr)
        return 1
    finally:
        session.close()
    if shown == 0:
        print(
            "no telemetry arrived: the firmware's telemetry_period is 0 (set by a host), or nothing is running",
            file=sys.stderr,
        )
    return 0


def _telemetry_line(msg: m.Telemetry) -> str:
    faults = ",".join(f.name.lower() for f in m.Faults if msg.faults & f) or "-"
    return (
        f"{msg.time / 1000:9.3f} s  {m.State(msg.state).name.lower():8s} faults {faults:16s} "
        f"tilt {msg.tilt_zx:+6.2f} {msg.tilt_zy:+6.2f} deg  cmd "
        + " ".join(f"{a:+.4f}" for a in msg.command)
        + "  meas "
        + " ".join(f"{a:+.4f}" for a in msg.measured)
        + f"  frame {msg.position_frame} age {msg.position_age} ms  errors {msg.crc_errors}/{msg.frame_errors}"
    )


# ------------------------------------------------------------------------------------------- stop, estop
def cmd_stop(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Stop the board: it levels the surface and stops driving (the controller off, a jog ended) and stays usable,
    idle, for jog, zero or a run. Also how a fault or an emergency stop is cleared. The s key of mantaray rig sends
    the same, through the same session. Prints the state the board reports afterwards (exit 1 if not IDLE)."""
    return _stop(args, parser, emergency=False)


def cmd_estop(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Emergency stop: the board cuts its actuators' power at once, whatever it is doing, and stays so (ESTOP,
    latched) until `mantaray stop`. The e and space keys of mantaray rig send the same, through the same session.
    Opening an Uno's port resets the board first (unless another program holds the port open); the motor supply's
    own emergency-stop button needs no software at all. Prints the state the board reports afterwards (exit 1 if
    not ESTOP)."""
    return _stop(args, parser, emergency=True)


def _stop(args: argparse.Namespace, parser: argparse.ArgumentParser, emergency: bool) -> int:
    """stop or emergency_stop through a session attached to the board, and the state it reports afterwards."""
    session = _attach(args, parser)
    try:
        if emergency:
            session.emergency_stop()
        else:
            session.stop()
        telemetry = session.probe()
    finally:
        session.close()
    state = m.State(telemetry.state)
    clear = f": `mantaray stop --port {shlex.quote(args.port)}` clears it" if state == m.State.ESTOP else ""
    print(f"{args.port}: the board is in {state_text(telemetry, session.identity)}{clear}")
    return 0 if state == (m.State.ESTOP if emergency else m.State.IDLE) else 1


# ------------------------------------------------------------------------------------------- jog, zero
JOG_SETTLE_M = 1e-3  # [m] a carriage this close to its jog target has arrived


def cmd_jog(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Move one carriage to a position (+ lowers its corner) and report where its encoder says it got to, to check
    each motor's and encoder's direction and the pulley. The firmware must be idle (`mantaray stop` makes it so);
    the carriage then holds there until `stop` (which levels the surface) or `start`."""
    from .link import CommandRefused

    jog = _checked(parser, m.Jog(actuator=args.actuator, position=args.position))
    description = args.rig
    if args.actuator >= description.actuator_count:  # the firmware refuses it too, but only once connected
        parser.error(
            f"--actuator must be 0..{description.actuator_count - 1} ({description.describe()}, "
            f"{description.path.name}), got {args.actuator}"
        )
    if abs(args.position) > description.actuator_range_m:
        parser.error(
            f"--position must be within ±{description.actuator_range_m:g} m (the actuators' travel, "
            f"{description.path.name}), got {args.position:g}"
        )
    session = _attach(args, parser)
    try:
        session.command(jog)
        measured, waited_s, arrived = _settle(session, args.actuator, args.position, args.wait)
    except CommandRefused as exc:
        return _refused("jog", session, exc)
    finally:
        session.close()
    print(
        f"actuator {args.actuator}: commanded {args.position:+.4f} m, measured {measured:+.4f} m "
        + (
            f"after {waited_s:.1f} s"
            if arrived
            else f"after {args.wait:g} s: NOT ARRIVED (check the motor's and the encoder's direction, and the wiring)"
        )
    )
    return 0 if arrived else 1


def _settle(session, actuator: int, position_m: float, wait_s: float) -> tuple[float, float, bool]:
    """The carriage's encoder read until it is within JOG_SETTLE_M of position_m [m] or wait_s [s] have passed:
    (measured [m], waited [s], arrived)."""
    t0 = time.monotonic()
    while True:  # telemetry on demand: a not-visible frame steps nothing and feeds no deadman
        measured = session.probe().measured[actuator]
        waited_s = time.monotonic() - t0
        arrived = abs(measured - position_m) < JOG_SETTLE_M
        if arrived or waited_s > wait_s:
            return measured, waited_s, arrived
        time.sleep(0.05)


def cmd_zero(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Take the present position of the named carriages as 0 m, the reference height z0 (homing), after jogging
    them there. The firmware must be idle (`mantaray stop` makes it so)."""
    from .link import CommandRefused

    count = args.rig.actuator_count
    actuators = list(range(count)) if args.actuators == "all" else args.actuators
    if max(actuators) >= count:  # the firmware refuses it too, but only once connected
        parser.error(
            f"--actuators must be within 0..{count - 1} ({args.rig.describe()}, {args.rig.path.name}), "
            f"got {max(actuators)}"
        )
    zero = _checked(parser, m.Zero(actuators=sum(1 << i for i in actuators)))
    session = _attach(args, parser)
    try:
        session.command(zero)
    except CommandRefused as exc:
        return _refused("zero", session, exc)
    finally:
        session.close()
    print(f"actuators {', '.join(map(str, actuators))}: their present positions are now 0 m")
    return 0


def _actuators(text: str) -> list[int] | str:
    """Actuator indices within the protocol's bounds, or "all" (the rig's own count is checked once --rig is known)."""
    spec = next(f for f in m.Jog.FIELDS if f.name == "actuator")
    if text == "all":
        return text
    try:
        chosen = sorted({int(v) for v in text.split(",")})
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected actuator indices like 0,2 or all, got {text!r}") from None
    if not all(spec.min <= i <= spec.max for i in chosen):
        raise argparse.ArgumentTypeError(f"actuators are {spec.min:g}..{spec.max:g}, got {text!r}")
    return chosen


# ------------------------------------------------------------------------------------------- parsers
def add_port_argument(parser: argparse.ArgumentParser) -> None:
    """--port and --rig, as every command that talks to a board takes them (the port is checked by
    ports.check_port before any work; the board is refused at identify unless it was built for the rig)."""
    parser.add_argument(
        "--port",
        required=True,
        default=argparse.SUPPRESS,
        help="serial device path of the firmware: a board (/dev/ttyACM0, "
        "/dev/ttyUSB0), or the /dev/pts/N that mantaray vmcu or simavr prints",
    )
    parser.add_argument(
        "--rig",
        type=rig.rig_file,
        default=rig.default(),
        metavar="FILE",
        help="the rig the board drives: its rig file (default protocol/rig.toml, one module; arrays: "
        "protocol/rigs/*.toml); a board built for another is refused",
    )


def add_reconnect_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """--reconnect-timeout: rig and monitor wait the same way for a board that went away."""
    parser.add_argument(
        "--reconnect-timeout",
        type=number(0, above=True),
        default=30.0,
        help=f"how long to wait for a board that went away (unplugged, reset) before {what} ends [s]",
    )


def add_parsers(sub: argparse._SubParsersAction, fmt: type[argparse.HelpFormatter]) -> None:
    monitor = sub.add_parser(
        "monitor", help="live decoded telemetry from a firmware", description=cmd_monitor.__doc__, formatter_class=fmt
    )
    add_port_argument(monitor)
    add_reconnect_argument(monitor, "the monitor")
    monitor.add_argument(
        "--count", type=number(0, integer=True), default=0, help="stop after this many telemetry frames (0: never)"
    )
    monitor.add_argument("--seconds", type=number(0), default=0.0, help="stop after this long (0: never)")
    monitor.set_defaults(func=lambda args: cmd_monitor(args, monitor))

    stop = sub.add_parser(
        "stop",
        help="stop the board: level, stop driving, stay usable (clears a fault or an e-stop)",
        description=cmd_stop.__doc__,
        formatter_class=fmt,
    )
    add_port_argument(stop)
    stop.set_defaults(func=lambda args: cmd_stop(args, stop))

    estop = sub.add_parser(
        "estop",
        help="emergency stop: the actuators' power cut, latched until mantaray stop",
        description=cmd_estop.__doc__,
        formatter_class=fmt,
    )
    add_port_argument(estop)
    estop.set_defaults(func=lambda args: cmd_estop(args, estop))

    actuator = next(f for f in m.Jog.FIELDS if f.name == "actuator")
    jog = sub.add_parser(
        "jog",
        help="move one carriage and read its encoder (bring-up)",
        description=cmd_jog.__doc__,
        formatter_class=fmt,
    )
    add_port_argument(jog)
    jog.add_argument(
        "--actuator",
        type=int,
        required=True,
        choices=range(int(actuator.min), int(actuator.max) + 1),
        metavar="I",
        help="which carriage (PROTOCOL.md §5: on one module 0 -x-y, 1 +x-y, 2 -x+y, 3 +x+y; an array numbers its "
        "grid's nodes row by row)",
    )
    jog.add_argument("--position", type=float, required=True, help="where to [m], + lowers the corner")
    jog.add_argument(
        "--wait", type=number(0, above=True), default=10.0, help="give up waiting for the carriage after this [s]"
    )
    jog.set_defaults(func=lambda args: cmd_jog(args, jog))

    zero = sub.add_parser(
        "zero",
        help="take the carriages' present positions as 0 m (homing)",
        description=cmd_zero.__doc__,
        formatter_class=fmt,
    )
    add_port_argument(zero)
    zero.add_argument("--actuators", type=_actuators, default="all", metavar="I,J|all", help="which carriages")
    zero.set_defaults(func=lambda args: cmd_zero(args, zero))
