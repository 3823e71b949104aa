"""The rig's commands: `mantaray rig` (the closed loop on the bench), `monitor`, `markers` and `calibrate`."""

from __future__ import annotations

import argparse
import math
import shlex
import sys
import time

from mantaray.arguments import (
    add_controller_arguments,
    add_view_arguments,
    controller_settings,
    number,
    parse_gains,
    reporter,
    start_live,
)
from mantaray.outputs import IMAGE_SUFFIXES, OutputError, writable_dir, writable_file
from mantaray.protocol import messages as m
from mantaray.protocol import rig as rig_description
from mantaray.protocol.codec import bounds_text

from .ports import PortError, check_port


def _half_module_m() -> tuple[float, float]:
    """[m] half the module's sides, as configured on the firmware (protocol defaults)."""
    return m.Configure.module_x / 2, m.Configure.module_y / 2


_report = reporter("rig")


def _xy(text: str) -> tuple[float, float]:
    from .rig_run import fabric_point

    try:
        return fabric_point(text, _half_module_m())
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _hsv_range(text: str):
    from .tracker import BlobColour

    try:
        low, high = (tuple(int(v) for v in part.split(",")) for part in text.split(":"))
        if not len(low) == len(high) == 3:
            raise ValueError
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected H,S,V:H,S,V (OpenCV's H 0..179, S and V 0..255), got {text!r}"
        ) from None
    return BlobColour(low, high)


# ------------------------------------------------------------------------------------------- rig
def cmd_rig(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Run the closed loop on the rig: camera -> tracker -> firmware, until success, timeout, a key or Ctrl-C.

    The Uno runs the controller; this host tracks the object (ArUco marker, or a colour blob with --blob)
    and sends its position at the camera's rate. It stops when the object has stayed within the tolerance
    for --hold seconds (a fixed target), at --timeout, or on Ctrl-C, which levels the surface and stops the
    motors. Run from a terminal, the key s stops the same way, and e or space is the emergency stop: the
    actuators' power is cut and stays cut (latched) until `mantaray stop` (keys are read only from a terminal in
    the foreground: under nohup, from a pipe or in the background the run goes on without them). A board that
    goes away (unplugged, reset) is waited for up to --reconnect-timeout and set up again. Every run writes a log
    of its own (configuration, every position and telemetry frame) and the paper's Fig. 3-style plot."""
    from .rig_run import EXIT_STATUS, RigRun, StopRules
    from .runlog import RunLog
    from .view import RunView

    course = _course(args, parser)
    setup, source, tracker, out = _rig_inputs(args, parser, course.at(0.0))
    settings = {k: v for k, v in vars(args).items() if k != "func"}
    live = start_live(parser, args, _report)
    try:
        if live is not None:
            _report(f"live view at {live.options.page_url}")
        log = RunLog.new(out, "rig", {"args": settings})
        view = RunView(
            "mantaray_rig",
            log.path.with_suffix(".rrd"),
            None if live is None else live.options.grpc_url,
            settings,
            rig_description.ACTUATOR_COUNT,
            (m.Configure.module_x, m.Configure.module_y),
            _report,
        )
        try:
            run = RigRun(
                args.port,
                setup,
                source,
                tracker,
                log,
                course,
                StopRules(args.tolerance, args.hold, args.timeout, _half_module_m()),
                reconnect_timeout_s=args.reconnect_timeout,
                view=view,
            )
            outcome = run.run()
        finally:
            recording = view.close()
        if live is not None and outcome != "interrupted":
            live.linger(args.linger, _report)
    finally:
        if live is not None:
            live.close()
    figure = run.figure(log.path.with_suffix(".png"))
    print(
        f"{outcome}: {len(run.loop.t_s)} frames; log {log.path}; figure {figure}"
        + (f"; recording {recording}" if recording else "")
    )
    return EXIT_STATUS.get(outcome, 1)


def _course(args: argparse.Namespace, parser: argparse.ArgumentParser):
    """--target, or the circle of --path circle about it, which must lie on the fabric."""
    from .rig_run import Course

    if args.path is None:
        return Course(args.target)
    if not (args.radius > 0 and args.period > 0):
        parser.error("--path circle needs --radius > 0 and --period > 0")
    (cx, cy), (hx, hy) = args.target, _half_module_m()
    if abs(cx) + args.radius > hx or abs(cy) + args.radius > hy:
        parser.error(
            f"the circle of radius {args.radius:g} m about {cx:g},{cy:g} is not on the fabric "
            f"(|x| <= {hx:g} m, |y| <= {hy:g} m)"
        )
    return Course(args.target, args.radius, args.period)


def _rig_inputs(args: argparse.Namespace, parser: argparse.ArgumentParser, target_m: tuple[float, float]):
    """(the firmware's Setup, the camera, the tracker, the output folder), each checked before any work: a mistake
    in any of them is a usage error in one line."""
    from .session import Setup
    from .tracker import Calibration, FrameSource, Tracker

    if args.marker_height >= args.camera_height:
        parser.error(
            f"--marker-height ({args.marker_height:g} m) must be below the camera (--camera-height "
            f"{args.camera_height:g} m)"
        )
    settings = controller_settings(parser, args)
    try:
        configure = settings.configure(
            m.Configure(tolerance=args.tolerance, noise_amplitude=args.alpha, telemetry_period=0)
        ).check()
        gains = settings.gains(_gains(args))
        calibration = Calibration.load(args.calibration) if args.calibration else None
        source = FrameSource(args.camera)  # a camera that does not open is the user's to fix, before work
        check_port(args.port)
        out = writable_dir(args.out)
    except (ValueError, OSError, KeyError) as exc:
        parser.error(str(exc))
    tracker = Tracker(
        marker_height_m=args.marker_height, camera_height_m=args.camera_height, calibration=calibration, blob=args.blob
    )
    return Setup(configure, gains, target_m, settings.commands()), source, tracker, out


def _gains(args: argparse.Namespace) -> dict:
    """--gains for each PID the controller runs (axis -> configure_pid fields, schema-checked); {} without it."""
    from .session import controller_axes

    if args.gains is None:
        return {}
    gains = {axis: m.ConfigurePid(axis, *args.gains).check().as_dict() for axis in controller_axes(args.controller)}
    for fields in gains.values():
        del fields["axis"]
    return gains


# ------------------------------------------------------------------------------------------- the board's state
def _board_state(telemetry: m.Telemetry) -> str:
    """The state telemetry reports, with its faults: IDLE, FAULT (position_timeout), ESTOP."""
    faults = [f.name.lower() for f in m.Faults if telemetry.faults & f and f != m.Faults.ESTOP]  # its own state
    return m.State(telemetry.state).name + (f" ({', '.join(faults)})" if faults else "")


def _leaving(telemetry: m.Telemetry, port: str) -> str:
    """The board's state, for a command that only an idle board takes, and the command that leaves it."""
    stop = f"`mantaray stop --port {shlex.quote(port)}`"
    state = m.State(telemetry.state)
    if state == m.State.FAULT:
        return f"the board is in {_board_state(telemetry)}: clear it with {stop} first (it levels the surface)"
    if state == m.State.ESTOP:
        return f"the board is in {_board_state(telemetry)}, the emergency stop (latched): clear it with {stop} first"
    if state in (m.State.RUNNING, m.State.REACHED):
        return f"the board is {_board_state(telemetry)}: a run is going on (mantaray rig?); end it, or {stop}, first"
    return f"the board is {_board_state(telemetry)}"


def _refused(name: str, session, refused) -> int:
    """A command the board refused, in one line (exit 2); refused for the board's state (bad_state), which state
    and how to leave it."""
    text = str(refused)
    if refused.code == m.ErrorCode.BAD_STATE:
        text = f"{refused.command.NAME} refused: {_leaving(session.probe(), session.port)}"
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
    print(f"{args.port}: the board is in {_board_state(telemetry)}{clear}")
    return 0 if state == (m.State.ESTOP if emergency else m.State.IDLE) else 1


# ------------------------------------------------------------------------------------------- jog, zero
JOG_SETTLE_M = 1e-3  # [m] a carriage this close to its jog target has arrived


def cmd_jog(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Move one carriage to a position (+ lowers its corner) and report where its encoder says it got to, to check
    each motor's and encoder's direction and the pulley. The firmware must be idle (`mantaray stop` makes it so);
    the carriage then holds there until `stop` (which levels the surface) or `start`."""
    from mantaray.protocol.rig import ACTUATOR_RANGE_M

    from .link import CommandRefused

    jog = _checked(parser, m.Jog(actuator=args.actuator, position=args.position))
    if abs(args.position) > ACTUATOR_RANGE_M:  # the firmware refuses it too, but only once connected
        parser.error(
            f"--position must be within ±{ACTUATOR_RANGE_M:g} m (the actuators' travel, protocol/rig.toml), "
            f"got {args.position:g}"
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

    zero = _checked(parser, m.Zero(actuators=sum(1 << i for i in args.actuators)))
    session = _attach(args, parser)
    try:
        session.command(zero)
    except CommandRefused as exc:
        return _refused("zero", session, exc)
    finally:
        session.close()
    print(f"actuators {', '.join(map(str, args.actuators))}: their present positions are now 0 m")
    return 0


def _actuators(text: str) -> list[int]:
    spec = next(f for f in m.Jog.FIELDS if f.name == "actuator")
    if text == "all":
        return list(range(int(spec.min), int(spec.max) + 1))
    try:
        chosen = sorted({int(v) for v in text.split(",")})
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected actuator indices like 0,2 or all, got {text!r}") from None
    if not all(spec.min <= i <= spec.max for i in chosen):
        raise argparse.ArgumentTypeError(f"actuators are {spec.min:g}..{spec.max:g}, got {text!r}")
    return chosen


# ------------------------------------------------------------------------------------------- markers
def cmd_markers(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Write a printable sheet of the rig's ArUco markers at true size (PDF or PNG; print at 100 %)."""
    from .marker_sheet import DPI_RANGE, write_marker_sheet

    if not DPI_RANGE[0] <= args.dpi <= DPI_RANGE[1]:
        parser.error(f"--dpi must be {DPI_RANGE[0]}..{DPI_RANGE[1]}, got {args.dpi}")
    try:
        out = writable_file(args.out, (".pdf", ".png"))
    except OutputError as exc:
        parser.error(str(exc))
    try:
        count = write_marker_sheet(out, args.dpi)
    except OutputError as exc:  # the write itself failed (a full disk): nothing is left at out
        print(f"mantaray markers: {exc}", file=sys.stderr)
        return 2
    print(f"{out}: {count} markers on A4 at true size" + (f", {args.dpi} dpi" if out.suffix == ".png" else ""))
    return 0


# ------------------------------------------------------------------------------------------- calibrate
def _squares(text: str) -> tuple[int, int]:
    try:
        nx, ny = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected squares like 7x5, got {text!r}") from None
    if nx < 2 or ny < 2:
        raise argparse.ArgumentTypeError(f"a ChArUco board needs at least 2 x 2 squares, got {text!r}")
    return nx, ny


def cmd_calibrate(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Calibrate the camera with a ChArUco board: --board-out writes the board to print; then show it to the
    camera from several angles (or give a video of that) and the intrinsics go to --out (.npz)."""
    from .charuco import calibrate_from_frames, charuco_board

    _check_calibrate_arguments(args, parser)
    board = charuco_board(args.squares, args.square_mm, args.marker_mm)
    if args.board_out:
        _write_board(args, parser, board)
    if args.camera is None:
        return 0
    frames = _read_frames(args.camera, args.frames)
    try:
        calibration, rms, used = calibrate_from_frames(board, frames)
    except ValueError as exc:
        print(f"mantaray calibrate: {exc}", file=sys.stderr)
        return 1
    calibration.save(args.out)
    k = calibration.camera_matrix
    print(
        f"{args.out}: fx {k[0, 0]:.1f} fy {k[1, 1]:.1f} cx {k[0, 2]:.1f} cy {k[1, 2]:.1f} px, "
        f"reprojection RMS {rms:.3f} px from {used} of {len(frames)} frames"
    )
    return 0


def _check_calibrate_arguments(args: argparse.Namespace, parser: argparse.ArgumentParser) -> None:
    """The board's sizes, something to do, and the outputs writable, before any work."""
    if not 0 < args.marker_mm < args.square_mm:
        parser.error(
            f"the marker ({args.marker_mm:g} mm) must be smaller than its square ({args.square_mm:g} mm) "
            f"and larger than 0"
        )
    if args.camera is None and not args.board_out:
        parser.error("give --camera (index or video file) to calibrate, or --board-out to print the board")
    try:
        if args.board_out:
            writable_file(args.board_out, IMAGE_SUFFIXES)
        if args.camera is not None:
            writable_file(args.out, (".npz",))
    except OutputError as exc:
        parser.error(str(exc))


def _write_board(args: argparse.Namespace, parser: argparse.ArgumentParser, board) -> None:
    import cv2

    from .charuco import PRINT_DPI, board_image

    if not cv2.imwrite(args.board_out, board_image(board, args.squares, args.square_mm)):
        parser.error(f"could not write {args.board_out!r} (an image: .png, .jpg, .tif ...)")
    print(f"{args.board_out}: {args.squares[0]} x {args.squares[1]} squares of {args.square_mm} mm at {PRINT_DPI} dpi")


def _read_frames(camera: str, most: int) -> list:
    """Up to `most` frames from the camera or video (fewer when a video ends first)."""
    from .tracker import FrameSource

    source = FrameSource(camera)
    frames: list = []
    while len(frames) < most and (grabbed := source.read()) is not None:
        frames.append(grabbed[0])
    source.close()
    return frames


# ------------------------------------------------------------------------------------------- parsers
def add_port_argument(parser: argparse.ArgumentParser) -> None:
    """--port, as every command that talks to a board takes it (checked by ports.check_port before any work)."""
    parser.add_argument(
        "--port",
        required=True,
        default=argparse.SUPPRESS,
        help="serial device path of the firmware: a board (/dev/ttyACM0, "
        "/dev/ttyUSB0), or the /dev/pts/N that mantaray vmcu or simavr prints",
    )


def add_reconnect_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """--reconnect-timeout: rig and monitor wait the same way for a board that went away."""
    parser.add_argument(
        "--reconnect-timeout",
        type=number(0, above=True),
        default=30.0,
        help=f"how long to wait for a board that went away (unplugged, reset) before {what} ends [s]",
    )


def add_parsers(sub: argparse._SubParsersAction) -> None:
    fmt = argparse.ArgumentDefaultsHelpFormatter
    rig = sub.add_parser(
        "rig",
        help="the closed loop on the real rig: camera, tracker, Uno",
        description=cmd_rig.__doc__,
        formatter_class=fmt,
    )
    add_port_argument(rig)
    rig.add_argument("--camera", required=True, help="camera index (0, 1, ...) or a video file")
    rig.add_argument(
        "--target",
        type=_xy,
        required=True,
        metavar="X,Y",
        help="target [m] in the fabric frame (with --path: the circle's centre); write "
        "--target=-0.1,0.1 when X is negative",
    )
    rig.add_argument("--path", choices=["circle"], help="follow a path instead of a fixed target (paper Fig. 1A)")
    rig.add_argument("--radius", type=float, default=0.1, help="circle radius [m]")
    rig.add_argument("--period", type=float, default=30.0, help="time for one lap of the circle [s]")
    add_controller_arguments(rig)
    rig.add_argument(
        "--alpha",
        type=float,
        default=0.05,
        help=f"noise amplitude α [m], {bounds_text(m.Configure, 'noise_amplitude')} (paper's hardware: 0.05)",
    )
    rig.add_argument("--tolerance", type=float, default=0.02, help=f"ε [m], {bounds_text(m.Configure, 'tolerance')}")
    rig.add_argument(
        "--gains",
        type=parse_gains,
        metavar="KP,KI,KD[,ILIM]",
        help="PID gains for the controller's axes [deg/m, deg/(m s), deg s/m, deg]; default the paper's",
    )
    rig.add_argument("--hold", type=number(0), default=1.0, help="seconds within ε that count as reached")
    add_reconnect_argument(rig, "the run")
    rig.add_argument(
        "--timeout", type=number(0, above=True), default=60.0, help="give up after this many seconds (paper: 60)"
    )
    rig.add_argument(
        "--marker-height",
        type=number(0),
        default=0.0,
        help="height [m] of the object's marker (or blob) above the corner markers' plane",
    )
    rig.add_argument(
        "--camera-height",
        type=number(0, above=True),
        default=1.0,
        help="camera above that plane [m], without --calibration",
    )
    rig.add_argument("--calibration", help="camera calibration (.npz from mantaray calibrate): full pose")
    rig.add_argument(
        "--blob",
        type=_hsv_range,
        metavar="H,S,V:H,S,V",
        help="track a colour blob in this HSV range instead of the object's marker (the egg)",
    )
    rig.add_argument("--out", default="out/rig", help="directory for the run log and the figure")
    add_view_arguments(rig)
    rig.set_defaults(func=lambda args: cmd_rig(args, rig))

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
        help="which carriage (PROTOCOL.md, geometry: 0 -x-y, 1 +x-y, 2 -x+y, 3 +x+y)",
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

    markers = sub.add_parser(
        "markers", help="a printable marker sheet at true size", description=cmd_markers.__doc__, formatter_class=fmt
    )
    markers.add_argument("--out", default="out/markers.pdf", help="the sheet: .pdf or .png")
    markers.add_argument("--dpi", type=int, default=300, help="resolution of a PNG sheet")
    markers.set_defaults(func=lambda args: cmd_markers(args, markers))

    calibrate = sub.add_parser(
        "calibrate",
        help="camera calibration with a ChArUco board",
        description=cmd_calibrate.__doc__,
        formatter_class=fmt,
    )
    calibrate.add_argument("--camera", help="camera index or video file showing the board")
    calibrate.add_argument("--out", default="out/camera.npz", help="the calibration (for mantaray rig --calibration)")
    calibrate.add_argument("--board-out", help="write the board to print (PNG at 300 dpi)")
    calibrate.add_argument(
        "--squares", type=_squares, default=(7, 5), metavar="NXxNY", help="board squares, at least 2 x 2"
    )
    calibrate.add_argument("--square-mm", type=number(0, above=True), default=30.0, help="square side [mm]")
    calibrate.add_argument("--marker-mm", type=number(0, above=True), default=22.0, help="marker side [mm]")
    calibrate.add_argument("--frames", type=number(1, integer=True), default=200, help="read at most this many frames")
    calibrate.set_defaults(func=lambda args: cmd_calibrate(args, calibrate))
