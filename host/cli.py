"""The rig's closed loop on the bench, `mantaray rig`, and the parsers of every rig command (host/cli_board.py,
host/cli_camera.py)."""

from __future__ import annotations

import argparse
import math

from mantaray.arguments import number, reporter
from mantaray.outputs import writable_dir
from mantaray.protocol import messages as m
from mantaray.protocol.codec import bounds_text
from mantaray.protocol.rig import Grid

from . import cli_board, cli_camera
from .cli_board import add_port_argument, add_reconnect_argument
from .cli_controller import add_controller_arguments, add_gains_argument, controller_settings
from .cli_view import add_view_arguments, start_live
from .ports import check_port


def _half_surface_m(description) -> tuple[float, float]:
    """[m] half the surface's sides, with the modules as configured on the firmware (protocol defaults): one
    module's, or the whole array's of the rig file (--rig)."""
    return Grid(description.modules_x, description.modules_y, m.Configure.module_x, m.Configure.module_y).half_extent_m


_report = reporter("rig")


def _xy(text: str) -> tuple[float, float]:
    from .rig_run import fabric_point

    try:
        return fabric_point(text, (math.inf, math.inf))  # on the surface: checked once --rig is known (_course)
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
    from .rig_run import EXIT_STATUS
    from .runlog import RunLog

    course = _course(args, parser)
    setup, source, tracker, out = _rig_inputs(args, parser, course.at(0.0))
    settings = {k: v for k, v in vars(args).items() if k != "func"} | {"rig": str(args.rig.path)}
    live = start_live(parser, args, _report)
    try:
        if live is not None:
            _report(f"live view at {live.options.page_url}")
        log = RunLog.new(out, "rig", {"args": settings})
        view = _view(log.path.with_suffix(".rrd"), live, settings)
        try:
            run = _rig_run(args, setup, source, tracker, log, course, view)
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


def _rig_run(args: argparse.Namespace, setup, source, tracker, log, course, view):
    """The closed loop on the rig for these arguments, not yet started: its stop rules, port and reconnection."""
    from .rig_run import RigRun, StopRules

    stop = StopRules(
        args.tolerance,
        args.hold,
        args.timeout,
        _half_surface_m(args.rig),
        (m.Configure.module_x / 2, m.Configure.module_y / 2),
    )
    return RigRun(
        args.port,
        setup,
        source,
        tracker,
        log,
        course,
        stop,
        reconnect_timeout_s=args.reconnect_timeout,
        view=view,
        description=args.rig,
    )


def _view(recording, live, settings: dict):
    """The run's view: its recording, and the live server's stream when --live started one. It plots the four
    actuators telemetry reports (the driven module's)."""
    from .view import REPORTED_ACTUATORS, RunView

    grpc_url = None if live is None else live.options.grpc_url
    module_m = (m.Configure.module_x, m.Configure.module_y)
    return RunView("mantaray_rig", recording, grpc_url, settings, REPORTED_ACTUATORS, module_m, _report)


def _course(args: argparse.Namespace, parser: argparse.ArgumentParser):
    """--target, or the circle of --path circle about it, which must lie on the fabric (one module's, or the array's
    of --rig)."""
    from .rig_run import Course

    (cx, cy), (hx, hy) = args.target, _half_surface_m(args.rig)
    if abs(cx) > hx or abs(cy) > hy:
        parser.error(f"--target {cx:g},{cy:g} is not on the fabric (|x| <= {hx:g} m, |y| <= {hy:g} m)")
    if args.path is None:
        return Course(args.target)
    if not (args.radius > 0 and args.period > 0):
        parser.error("--path circle needs --radius > 0 and --period > 0")
    if abs(cx) + args.radius > hx or abs(cy) + args.radius > hy:
        parser.error(
            f"the circle of radius {args.radius:g} m about {cx:g},{cy:g} is not on the fabric "
            f"(|x| <= {hx:g} m, |y| <= {hy:g} m)"
        )
    return Course(args.target, args.radius, args.period)


def _rig_inputs(args: argparse.Namespace, parser: argparse.ArgumentParser, target_m: tuple[float, float]):
    """(the firmware's Setup, the camera, the tracker, the output folder), each checked before any work: a mistake
    in any of them is a usage error in one line."""
    from .tracker import Calibration, FrameSource, Tracker

    if args.marker_height >= args.camera_height:
        parser.error(
            f"--marker-height ({args.marker_height:g} m) must be below the camera (--camera-height "
            f"{args.camera_height:g} m)"
        )
    setup = rig_setup(args, parser, target_m)
    try:
        calibration = Calibration.load(args.calibration) if args.calibration else None
        source = FrameSource(args.camera)  # a camera that does not open is the user's to fix, before work
        check_port(args.port)
        out = writable_dir(args.out)
    except (ValueError, OSError, KeyError) as exc:
        parser.error(str(exc))
    tracker = Tracker(
        marker_height_m=args.marker_height,
        camera_height_m=args.camera_height,
        calibration=calibration,
        blobs=(args.blob,) if args.blob else (),
    )
    return setup, source, tracker, out


def rig_setup(args: argparse.Namespace, parser: argparse.ArgumentParser, target_m: tuple[float, float]):
    """The firmware's Setup for `mantaray rig`'s arguments: configure, the controller's settings and --gains as
    they are given (the firmware's numbers), the target; a value the schema refuses is a usage error."""
    from .session import Setup

    settings = controller_settings(parser, args)
    try:
        configure = settings.configure(
            m.Configure(tolerance=args.tolerance, noise_amplitude=args.alpha, telemetry_period=0)
        ).check()
    except ValueError as exc:
        parser.error(str(exc))
    return Setup(configure, settings.gains({}), target_m, settings.commands())


# ------------------------------------------------------------------------------------------- parsers
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
    add_gains_argument(rig)
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
    rig.add_argument("--calibration", help="camera calibration (.npz from mantaray calibrate-camera): full pose")
    rig.add_argument(
        "--blob",
        type=_hsv_range,
        metavar="H,S,V:H,S,V",
        help="track a colour blob in this HSV range instead of the object's marker (the egg)",
    )
    rig.add_argument("--out", default="out/rig", help="directory for the run log and the figure")
    add_view_arguments(rig)
    rig.set_defaults(func=lambda args: cmd_rig(args, rig))
    cli_board.add_parsers(sub, fmt)
    cli_camera.add_parsers(sub, fmt)
