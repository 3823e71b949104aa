"""The rig's commands: `mantaray rig` (the closed loop on the bench), `monitor`, `markers` and `calibrate`."""
from __future__ import annotations

import argparse
import math
import signal
import sys
import time

from mantaray.arguments import number
from mantaray.outputs import IMAGE_SUFFIXES, OutputError, writable_dir, writable_file
from mantaray.protocol import messages as m
from mantaray.protocol.codec import bounds_text, choices

from .runlog import RunLog


def parse_gains(text: str) -> tuple[float, float, float, float]:
    """KP,KI,KD[,ILIMIT] of a PID [deg/m, deg/(m s), deg s/m, deg]; without ILIMIT the firmware's boot default."""
    try:
        values = tuple(float(v) for v in text.replace(",", " ").split())
    except ValueError:
        values = ()
    if len(values) == 3:
        values += (m.PID_DEFAULTS[m.Axis.X]["integral_limit"],)
    if len(values) != 4 or not all(math.isfinite(v) and v >= 0 for v in values):
        raise argparse.ArgumentTypeError(f"expected KP,KI,KD or KP,KI,KD,ILIMIT (numbers >= 0), got {text!r}")
    return values


def controller_settings(parser: argparse.ArgumentParser, args: argparse.Namespace):
    """The controller settings a command runs with: --settings FILE (its controller), else --controller's boot
    values; a --controller that contradicts the file is a usage error. Sets args.controller."""
    from .controller_settings import ControllerSettings, SettingsError

    try:
        settings = (ControllerSettings.load(args.settings) if args.settings else
                    ControllerSettings(args.controller or "manhattan"))
    except SettingsError as exc:
        parser.error(str(exc))
    if args.controller and args.controller != settings.controller:
        parser.error(f"--controller {args.controller} contradicts {args.settings}, which sets up the "
                     f"{settings.controller} controller")
    args.controller = settings.controller
    if getattr(args, "gains", None) is not None and any(k.startswith("pid.") for k, _ in settings.values):
        parser.error(f"--gains and {args.settings} both set the PIDs' gains: give them in one place")
    return settings


def add_controller_arguments(parser: argparse.ArgumentParser) -> None:
    """--controller and --settings, as every command that runs a controller takes them."""
    parser.add_argument("--controller", choices=choices(m.Controller),
                        help="the tilt controller (default: manhattan, or the one --settings names)")
    parser.add_argument("--settings", metavar="FILE",
                        help="a controller's settings (TOML, as mantaray sim tune writes: host/controller_settings.py)")


def _half_module_m() -> tuple[float, float]:
    """[m] half the module's sides, as configured on the firmware (protocol defaults)."""
    return m.Configure.module_x / 2, m.Configure.module_y / 2


def _xy(text: str) -> tuple[float, float]:
    try:
        x, y = (float(v) for v in text.replace(",", " ").split())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected two numbers X,Y in metres, got {text!r}") from None
    hx, hy = _half_module_m()
    if not (math.isfinite(x) and math.isfinite(y)) or abs(x) > hx or abs(y) > hy:
        raise argparse.ArgumentTypeError(f"{text!r} is not on the fabric (|x| <= {hx:g} m, |y| <= {hy:g} m)")
    return x, y


def _hsv_range(text: str):
    from .tracker import BlobColour

    try:
        low, high = (tuple(int(v) for v in part.split(",")) for part in text.split(":"))
        if not len(low) == len(high) == 3:
            raise ValueError
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected H,S,V:H,S,V (OpenCV's H 0..179, S and V 0..255), got {text!r}") \
            from None
    return BlobColour(low, high)


# ------------------------------------------------------------------------------------------- rig
def targets_along(args, t_s: float) -> tuple[float, float]:
    """The target at run time t_s [s]: fixed, or moving round the circle of --path circle."""
    if args.path is None:
        return args.target
    cx, cy = args.target
    a = 2 * math.pi * t_s / args.period
    return cx + args.radius * math.cos(a), cy + args.radius * math.sin(a)


def cmd_rig(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Run the closed loop on the rig: camera -> tracker -> firmware, until success, timeout or Ctrl-C.

    The Uno runs the controller; this host tracks the object (ArUco marker, or a colour blob with --blob)
    and sends its position at the camera's rate. It stops when the object has stayed within the tolerance
    for --hold seconds (a fixed target), at --timeout, or on Ctrl-C, which levels the surface and stops the
    motors. Every run writes one log (configuration, every position and telemetry frame) and the paper's
    Fig. 3-style plot."""
    from mantaray.plots import path_phase_figure

    from .link import LinkError
    from .loop import STOPPED_REACHED, ClosedLoop, Frame, Tolerance
    from .session import BoardLost, RigSession, Setup, check_port, controller_axes
    from .tracker import Calibration, FrameSource, Tracker

    if args.path is not None:
        if not (args.radius > 0 and args.period > 0):
            parser.error("--path circle needs --radius > 0 and --period > 0")
        cx, cy = args.target
        hx, hy = _half_module_m()
        if abs(cx) + args.radius > hx or abs(cy) + args.radius > hy:
            parser.error(f"the circle of radius {args.radius:g} m about {cx:g},{cy:g} is not on the fabric "
                         f"(|x| <= {hx:g} m, |y| <= {hy:g} m)")
    if args.marker_height >= args.camera_height:
        parser.error(f"--marker-height ({args.marker_height:g} m) must be below the camera (--camera-height "
                     f"{args.camera_height:g} m)")
    settings = controller_settings(parser, args)
    try:
        check_port(args.port)
        configure = settings.configure(m.Configure(tolerance=args.tolerance, noise_amplitude=args.alpha,
                                                   telemetry_period=0)).check()
        gains = {} if args.gains is None else {
            axis: m.ConfigurePid(axis, *args.gains).check().as_dict() for axis in controller_axes(args.controller)}
        for fields in gains.values():
            del fields["axis"]
        gains = settings.gains(gains)
        calibration = Calibration.load(args.calibration) if args.calibration else None
        source = FrameSource(args.camera)            # a camera that does not open is the user's to fix, before work
        out = writable_dir(args.out)
    except (ValueError, OSError, KeyError, LinkError) as exc:
        parser.error(str(exc))
    tracker = Tracker(marker_height_m=args.marker_height, camera_height_m=args.camera_height,
                      calibration=calibration, blob=args.blob)
    stamp = time.strftime("%Y%m%d-%H%M%S")
    log = RunLog(out / f"rig-{stamp}.jsonl", {"args": {k: v for k, v in vars(args).items() if k != "func"}})
    events = []

    def report(text: str) -> None:
        events.append(text)
        log.write("event", {"text": text})
        print(f"mantaray rig: {text}", file=sys.stderr)

    interrupted = False

    def on_sigint(signum, frame):
        """The first Ctrl-C ends the loop after this frame; a second one (say, while reconnecting) at once."""
        nonlocal interrupted
        interrupted = True
        signal.signal(signal.SIGINT, signal.default_int_handler)

    previous = signal.getsignal(signal.SIGINT)
    outcome = "timeout"
    half_m = _half_module_m()
    session = RigSession(args.port, Setup(configure, gains, targets_along(args, 0.0), settings.commands()), report=report,
                         reconnect_timeout_s=args.reconnect_timeout)
    loop = ClosedLoop(session.position)
    seen = {}                                        # the tracker's last observation, for the log

    def frames():
        """The camera's frames, tracked, until Ctrl-C, the end of the video, the timeout or the object off the fabric."""
        nonlocal outcome
        t0 = wall0 = None
        while not interrupted:
            grabbed = source.read()
            if grabbed is None:
                outcome = "camera stopped"
                return
            image, capture_s = grabbed
            if t0 is None:
                t0, wall0 = capture_s, time.monotonic()
            run_s = capture_s - t0
            if source.is_file:                       # a recording plays at its own pace, as a camera would
                time.sleep(max(0.0, run_s - (time.monotonic() - wall0)))
            if run_s > args.timeout:
                return
            obs = seen["obs"] = tracker.observe(image, capture_s)
            if obs.visible and (abs(obs.xy_m[0]) > 2 * half_m[0] or abs(obs.xy_m[1]) > 2 * half_m[1]):
                report(f"the object was seen at {obs.xy_m[0]:+.3f},{obs.xy_m[1]:+.3f} m, off the fabric by more "
                       f"than half a module")    # what the firmware refuses
                outcome = "fell off"
                return
            target = targets_along(args, run_s)
            judged = obs.xy_m if args.path is None and obs.visible else None   # what the camera sees: the rig knows
            yield Frame(run_s, obs.xy_m if obs.visible else None, target, judged_xy_m=judged,   # nothing better
                        deliver=(lambda target=target: move_target(target)) if args.path is not None else None)

    def move_target(target) -> bool:
        """Before a frame along a path: the target moves on (the run goes on)."""
        session.set_target(*target)
        return True

    def record(frame, telemetry) -> None:
        obs = seen["obs"]
        log.write("position", {"frame": loop.frame, "capture_s": round(frame.capture_s, 6), "status": obs.status,
                               "xy_m": obs.xy_m, "corners_seen": list(obs.corners_seen)})
        if telemetry is not None:
            log.write("telemetry", {k: (list(v) if isinstance(v, tuple) else int(v) if isinstance(v, int)
                                        else v) for k, v in vars(telemetry).items()})

    try:
        session.open()
        log.write("identify", {k: v if isinstance(v, float) else int(v) for k, v in vars(session.identity).items()})
        signal.signal(signal.SIGINT, on_sigint)
        session.start()
        stopped = loop.run(frames(), Tolerance(args.tolerance, args.hold), stop_when_reached=True, on_frame=record)
        if stopped == STOPPED_REACHED:
            outcome = "reached"
        if interrupted:
            outcome = "interrupted"
    except KeyboardInterrupt:                        # while connecting, or a second Ctrl-C
        outcome = "interrupted"
    except LinkError as exc:                         # what the session's retries could not absorb: the run ends
        report(f"the run ended: {exc}")
        outcome = "board lost" if isinstance(exc, BoardLost) else "refused"
    finally:
        signal.signal(signal.SIGINT, previous)
        try:
            if session.link is not None and outcome == "board lost":
                session.link.command(m.Stop())       # once: the session's recoveries are spent
            elif session.link is not None:
                session.stop()                       # level the surface, controller off
        except LinkError as exc:
            report(f"could not level the surface and stop ({exc}): the firmware's deadman stops it")
        finally:
            session.close()
            source.close()
            log.write("end", {"outcome": outcome})
            log.close()
    rows = loop.arrays()
    xy = rows["measured_xy_m"]
    targets = rows["target_m"] if args.path is not None and len(xy) else [args.target]   # a path, or one target
    figure = path_phase_figure(xy, rows["tilt_deg"], xy[0] if len(xy) and math.isfinite(xy[0][0]) else None,
                               targets, args.tolerance, f"rig: {outcome}", (configure.module_x, configure.module_y),
                               configure.tilt_limit, out / f"rig-{stamp}.png", t_s=rows["t_s"] if len(xy) else None,
                               command_m=rows["command_m"] if len(xy) else None)
    print(f"{outcome}: {len(xy)} frames; log {log.path}; figure {figure}")
    return {"reached": 0, "interrupted": 130}.get(outcome, 1)


# ------------------------------------------------------------------------------------------- monitor
def _connect(args: argparse.Namespace, parser: argparse.ArgumentParser):
    """The firmware on --port, identified and announced; a path that is no serial device is a usage error."""
    from .link import LinkError
    from .session import check_port, connect

    try:
        check_port(args.port)
    except LinkError as exc:
        parser.error(str(exc))
    link, identity = connect(args.port)
    print(f"{args.port}: protocol {identity.protocol_version}, firmware {identity.firmware_major}."
          f"{identity.firmware_minor}.{identity.firmware_patch}, clock {m.Clock(identity.clock).name.lower()}")
    for text in link.rig_differences:
        print(f"warning: {text}", file=sys.stderr)
    return link


def _checked(parser: argparse.ArgumentParser, command: m.Message) -> m.Message:
    """The command once the schema's field rules pass (Message.check); a field they refuse is a usage error."""
    try:
        return command.check()
    except ValueError as exc:
        parser.error(str(exc))


def cmd_monitor(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Show the firmware's telemetry live, decoded, without changing anything on it (Ctrl-C ends)."""
    link = _connect(args, parser)
    shown = 0
    try:
        deadline = time.monotonic() + args.seconds if args.seconds else math.inf
        while time.monotonic() < deadline and (not args.count or shown < args.count):
            msg = link.receive(0.2)
            if isinstance(msg, m.Telemetry):
                faults = ",".join(f.name.lower() for f in m.Faults if msg.faults & f) or "-"
                print(f"{msg.time / 1000:9.3f} s  {m.State(msg.state).name.lower():8s} faults {faults:16s} "
                      f"tilt {msg.tilt_zx:+6.2f} {msg.tilt_zy:+6.2f} deg  cmd "
                      + " ".join(f"{a:+.4f}" for a in msg.command) + "  meas "
                      + " ".join(f"{a:+.4f}" for a in msg.measured)
                      + f"  frame {msg.position_frame} age {msg.position_age} ms  errors {msg.crc_errors}/"
                        f"{msg.frame_errors}", flush=True)
                shown += 1
            elif isinstance(msg, m.Boot):
                print(f"firmware reset ({m.ResetCause(msg.reset_cause).name.lower()})", flush=True)
    except KeyboardInterrupt:
        pass
    finally:
        link.close()
    if shown == 0:
        print("no telemetry arrived: the firmware's telemetry_period is 0 (set by a host), or nothing is running",
              file=sys.stderr)
    return 0


# ------------------------------------------------------------------------------------------- jog, zero
JOG_SETTLE_M = 1e-3     # [m] a carriage this close to its jog target has arrived


def cmd_jog(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Move one carriage to a position (+ lowers its corner) and report where its encoder says it got to, to check
    each motor's and encoder's direction and the pulley. The firmware must be idle; the carriage then holds there
    until `stop` (which levels the surface) or `start`."""
    from .link import CommandRefused

    from mantaray.protocol.rig import ACTUATOR_RANGE_M

    jog = _checked(parser, m.Jog(actuator=args.actuator, position=args.position))
    if abs(args.position) > ACTUATOR_RANGE_M:      # the firmware refuses it too, but only once connected
        parser.error(f"--position must be within ±{ACTUATOR_RANGE_M:g} m (the actuators' travel, protocol/rig.toml), "
                     f"got {args.position:g}")
    link = _connect(args, parser)
    try:
        link.command(jog)
        t0, frame = time.monotonic(), 0
        while True:       # telemetry on demand: a not-visible frame steps nothing and feeds no deadman
            frame += 1
            t = link.position(m.ObjectPosition(frame=frame, capture_time=frame * 50_000,
                                               flags=m.PositionFlags.NOT_VISIBLE))
            arrived = abs(t.measured[args.actuator] - args.position) < JOG_SETTLE_M
            if arrived or time.monotonic() - t0 > args.wait:
                break
            time.sleep(0.05)
    except CommandRefused as exc:
        print(f"mantaray jog: {exc}", file=sys.stderr)
        return 2
    finally:
        link.close()
    measured = t.measured[args.actuator]
    print(f"actuator {args.actuator}: commanded {args.position:+.4f} m, measured {measured:+.4f} m "
          + (f"after {time.monotonic() - t0:.1f} s" if arrived else f"after {args.wait:g} s: NOT ARRIVED "
             f"(check the motor's and the encoder's direction, and the wiring)"))
    return 0 if arrived else 1


def cmd_zero(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Take the present position of the named carriages as 0 m, the reference height z0 (homing), after jogging
    them there. The firmware must be idle."""
    from .link import CommandRefused

    zero = _checked(parser, m.Zero(actuators=sum(1 << i for i in args.actuators)))
    link = _connect(args, parser)
    try:
        link.command(zero)
    except CommandRefused as exc:
        print(f"mantaray zero: {exc}", file=sys.stderr)
        return 2
    finally:
        link.close()
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
    count = write_marker_sheet(out, args.dpi)
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
    import cv2

    from .charuco import PRINT_DPI, board_image, calibrate_from_frames, charuco_board

    if not 0 < args.marker_mm < args.square_mm:
        parser.error(f"the marker ({args.marker_mm:g} mm) must be smaller than its square ({args.square_mm:g} mm) "
                     f"and larger than 0")
    try:
        if args.board_out:
            writable_file(args.board_out, IMAGE_SUFFIXES)
        if args.camera is not None:
            writable_file(args.out, (".npz",))
    except OutputError as exc:
        parser.error(str(exc))
    board = charuco_board(args.squares, args.square_mm, args.marker_mm)
    if args.board_out:
        if not cv2.imwrite(args.board_out, board_image(board, args.squares, args.square_mm)):
            parser.error(f"could not write {args.board_out!r} (an image: .png, .jpg, .tif ...)")
        print(f"{args.board_out}: {args.squares[0]} x {args.squares[1]} squares of {args.square_mm} mm at "
              f"{PRINT_DPI} dpi")
        if args.camera is None:
            return 0
    if args.camera is None:
        parser.error("give --camera (index or video file) to calibrate, or --board-out to print the board")
    from .tracker import FrameSource

    source = FrameSource(args.camera)
    frames = []
    while len(frames) < args.frames and (grabbed := source.read()) is not None:
        frames.append(grabbed[0])
    source.close()
    try:
        calibration, rms, used = calibrate_from_frames(board, frames)
    except ValueError as exc:
        print(f"mantaray calibrate: {exc}", file=sys.stderr)
        return 1
    calibration.save(args.out)
    k = calibration.camera_matrix
    print(f"{args.out}: fx {k[0, 0]:.1f} fy {k[1, 1]:.1f} cx {k[0, 2]:.1f} cy {k[1, 2]:.1f} px, "
          f"reprojection RMS {rms:.3f} px from {used} of {len(frames)} frames")
    return 0


# ------------------------------------------------------------------------------------------- parsers
def add_parsers(sub: argparse._SubParsersAction) -> None:
    fmt = argparse.ArgumentDefaultsHelpFormatter
    rig = sub.add_parser("rig", help="the closed loop on the real rig: camera, tracker, Uno",
                         description=cmd_rig.__doc__, formatter_class=fmt)
    rig.add_argument("--port", required=True, help="serial device of the Uno (e.g. /dev/ttyACM0)")
    rig.add_argument("--camera", required=True, help="camera index (0, 1, ...) or a video file")
    rig.add_argument("--target", type=_xy, required=True, metavar="X,Y",
                     help="target [m] in the fabric frame (with --path: the circle's centre); write "
                          "--target=-0.1,0.1 when X is negative")
    rig.add_argument("--path", choices=["circle"], help="follow a path instead of a fixed target (paper Fig. 1A)")
    rig.add_argument("--radius", type=float, default=0.1, help="circle radius [m]")
    rig.add_argument("--period", type=float, default=30.0, help="time for one lap of the circle [s]")
    add_controller_arguments(rig)
    rig.add_argument("--alpha", type=float, default=0.05, help=f"noise amplitude α [m], {bounds_text(m.Configure, 'noise_amplitude')} (paper's hardware: 0.05)")
    rig.add_argument("--tolerance", type=float, default=0.02, help=f"ε [m], {bounds_text(m.Configure, 'tolerance')}")
    rig.add_argument("--gains", type=parse_gains, metavar="KP,KI,KD[,ILIM]",
                     help="PID gains for the controller's axes [deg/m, deg/(m s), deg s/m, deg]; default the paper's")
    rig.add_argument("--hold", type=number(0), default=1.0, help="seconds within ε that count as reached")
    rig.add_argument("--reconnect-timeout", type=number(0, above=True), default=30.0,
                     help="how long to wait for a board that went away (unplugged, reset) before the run ends [s]")
    rig.add_argument("--timeout", type=number(0, above=True), default=60.0, help="give up after this many seconds (paper: 60)")
    rig.add_argument("--marker-height", type=number(0), default=0.0,
                     help="height [m] of the object's marker (or blob) above the corner markers' plane")
    rig.add_argument("--camera-height", type=number(0, above=True), default=1.0, help="camera above that plane [m], without "
                     "--calibration")
    rig.add_argument("--calibration", help="camera calibration (.npz from mantaray calibrate): full pose")
    rig.add_argument("--blob", type=_hsv_range, metavar="H,S,V:H,S,V",
                     help="track a colour blob in this HSV range instead of the object's marker (the egg)")
    rig.add_argument("--out", default="out/rig", help="directory for the run log and the figure")
    rig.set_defaults(func=lambda args: cmd_rig(args, rig))

    monitor = sub.add_parser("monitor", help="live decoded telemetry from a firmware", description=cmd_monitor.__doc__,
                             formatter_class=fmt)
    monitor.add_argument("--port", required=True, help="serial device path of the firmware")
    monitor.add_argument("--count", type=number(0, integer=True), default=0, help="stop after this many telemetry frames (0: never)")
    monitor.add_argument("--seconds", type=number(0), default=0.0, help="stop after this long (0: never)")
    monitor.set_defaults(func=lambda args: cmd_monitor(args, monitor))

    actuator = next(f for f in m.Jog.FIELDS if f.name == "actuator")
    jog = sub.add_parser("jog", help="move one carriage and read its encoder (bring-up)", description=cmd_jog.__doc__,
                         formatter_class=fmt)
    jog.add_argument("--port", required=True, help="serial device path of the firmware")
    jog.add_argument("--actuator", type=int, required=True, choices=range(int(actuator.min), int(actuator.max) + 1),
                     help="which carriage (PROTOCOL.md, geometry: 0 -x-y, 1 +x-y, 2 -x+y, 3 +x+y)")
    jog.add_argument("--position", type=float, required=True, help="where to [m], + lowers the corner")
    jog.add_argument("--wait", type=number(0, above=True), default=10.0, help="give up waiting for the carriage after this [s]")
    jog.set_defaults(func=lambda args: cmd_jog(args, jog))

    zero = sub.add_parser("zero", help="take the carriages' present positions as 0 m (homing)",
                          description=cmd_zero.__doc__, formatter_class=fmt)
    zero.add_argument("--port", required=True, help="serial device path of the firmware")
    zero.add_argument("--actuators", type=_actuators, default="all", metavar="I,J|all", help="which carriages")
    zero.set_defaults(func=lambda args: cmd_zero(args, zero))

    markers = sub.add_parser("markers", help="a printable marker sheet at true size", description=cmd_markers.__doc__,
                             formatter_class=fmt)
    markers.add_argument("--out", default="out/markers.pdf", help="the sheet: .pdf or .png")
    markers.add_argument("--dpi", type=int, default=300, help="resolution of a PNG sheet")
    markers.set_defaults(func=lambda args: cmd_markers(args, markers))

    calibrate = sub.add_parser("calibrate", help="camera calibration with a ChArUco board",
                               description=cmd_calibrate.__doc__, formatter_class=fmt)
    calibrate.add_argument("--camera", help="camera index or video file showing the board")
    calibrate.add_argument("--out", default="out/camera.npz", help="the calibration (for mantaray rig --calibration)")
    calibrate.add_argument("--board-out", help="write the board to print (PNG at 300 dpi)")
    calibrate.add_argument("--squares", type=_squares, default=(7, 5), metavar="NXxNY",
                           help="board squares, at least 2 x 2")
    calibrate.add_argument("--square-mm", type=number(0, above=True), default=30.0, help="square side [mm]")
    calibrate.add_argument("--marker-mm", type=number(0, above=True), default=22.0, help="marker side [mm]")
    calibrate.add_argument("--frames", type=number(1, integer=True), default=200, help="read at most this many frames")
    calibrate.set_defaults(func=lambda args: cmd_calibrate(args, calibrate))
