"""`mantaray sim ...`: the simulation's commands; `sim run` is the main job (firmware in the loop over a pty)."""
from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
from pathlib import Path

from .objects import OBJECTS


def _point(text: str) -> tuple[float, float]:
    parts = text.replace(",", " ").split()
    try:
        x, y = (float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected two numbers X,Y in metres, got {text!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise argparse.ArgumentTypeError(f"coordinates must be finite, got {text!r}")
    return x, y


def _inside(parser: argparse.ArgumentParser, name: str, xy: tuple[float, float], half: tuple[float, float]) -> None:
    if abs(xy[0]) > half[0] or abs(xy[1]) > half[1]:
        parser.error(f"{name} {xy[0]:g},{xy[1]:g} is outside the fabric (|x| <= {half[0]:g} m, |y| <= {half[1]:g} m)")


def cmd_run(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """One target-reaching trial: the native firmware on a pty drives the simulated rig in lock-step.

    With --port, the firmware on that serial device path (a board, the AVR simulator) drives it instead."""
    from mantaray.host.link import Link
    from mantaray.host.transport import SerialTransport
    from mantaray.host.vmcu import VirtualMcu

    from .bridge import Bridge, Tracking, TrialSpec
    from .plots import trajectory_figure
    from .rig import Rig

    rig = Rig().with_object(args.object)
    half = (rig.frame.size_x_m / 2, rig.frame.size_y_m / 2)
    _inside(parser, "--start", args.start, half)
    _inside(parser, "--target", args.target, half)
    try:
        tracking = Tracking(rate_hz=args.rate, latency_s=args.latency, noise_m=args.noise, drop_rate=args.drop)
        spec = TrialSpec(args.start, args.target, controller=args.controller, duration_s=args.duration,
                         alpha_m=args.alpha, tolerance_m=args.tolerance, seed=args.seed)
    except ValueError as exc:
        parser.error(str(exc))

    out = Path(args.out)
    stem = f"{args.object}_{args.controller}_seed{args.seed}"
    progress = None
    if not args.json and sys.stderr.isatty():
        from tqdm import tqdm
        bar = tqdm(total=round(args.duration, 2), unit="sim s", bar_format="{l_bar}{bar}| {n:.1f}/{total} sim s "
                   "[{elapsed}<{remaining}]", file=sys.stderr)

        def progress(t_s: float) -> None:
            bar.update(round(t_s - bar.n, 3))

    if args.viewer and not os.environ.get("DISPLAY"):
        parser.error("--viewer needs a display (DISPLAY is not set); use --video to record one instead")
    with contextlib.ExitStack() as stack:
        port = args.port or stack.enter_context(VirtualMcu(clock="wall" if args.realtime else "sim")).path
        link = Link(SerialTransport(port))
        stack.callback(link.close)
        bridge = Bridge(link, rig, tracking, lockstep=not args.realtime)
        viewer = None
        if args.viewer:
            import mujoco.viewer
            viewer = bridge.viewer = mujoco.viewer.launch_passive(bridge.model, bridge.data)
        if args.video:
            from .video import Recorder
            bridge.recorder = Recorder(bridge.model, fps=args.video_fps)
        result = bridge.run(spec, progress=progress)
        if viewer is not None:
            viewer.close()
    if progress is not None:
        bar.close()

    summary = result.summary()
    summary["figure"] = str(trajectory_figure(result, (rig.frame.size_x_m, rig.frame.size_y_m),
                                              26.565051, out / f"{stem}.png"))
    summary["trajectory"] = str(_save_trajectory(result, out / f"{stem}.npz"))
    if args.video:
        summary["video"] = str(bridge.recorder.save(out / f"{stem}.mp4"))
    for message in result.watch.messages:
        print(f"mantaray sim run: link: {message}", file=sys.stderr)
    if args.json:
        print(json.dumps(summary))
    else:
        outcome = "FELL OFF" if result.fell_off else ("REACHED" if result.success else "NOT REACHED")
        reach = "never within tolerance" if result.time_to_reach_s is None else f"first within tolerance at {result.time_to_reach_s:.2f} s"
        print(f"{outcome}: {args.object}, {args.controller}, start {args.start[0]:+.3f},{args.start[1]:+.3f} -> "
              f"target {args.target[0]:+.3f},{args.target[1]:+.3f} m; final error {result.final_error_m * 100:.1f} cm "
              f"(ε {args.tolerance * 100:g} cm), {reach}; {result.sim_time_s:.1f} sim s in {result.wall_time_s:.1f} wall s "
              f"({result.sim_time_s / result.wall_time_s:.2f}x, physics {result.physics_share:.0%}); "
              f"figure {summary['figure']}" + (f", video {summary['video']}" if args.video else ""))
    return 0 if result.success else 1


def _save_trajectory(result, path: Path) -> Path:
    import numpy as np

    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, t_s=result.t_s, true_xy_m=result.true_xy_m, measured_xy_m=result.measured_xy_m,
                        tilt_deg=result.tilt_deg, command_m=result.command_m, state=result.state,
                        start_m=result.spec.start_m, target_m=result.spec.target_m)
    return path


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register `sim` and its subcommands on the top-level parser's subparsers."""
    sim = sub.add_parser("sim", help="the MuJoCo rig with the firmware in the loop",
                         description="The simulated MANTA-RAY: the native firmware drives a MuJoCo model of the rig "
                                     "over a virtual serial port, through the same protocol as the hardware.")
    sim_sub = sim.add_subparsers(dest="sim_command", metavar="SUBCOMMAND")
    run = sim_sub.add_parser(
        "run", help="one target-reaching trial (the main job)", description=cmd_run.__doc__ + (
            " Exit status 0 when the object ends within the tolerance, 1 when it does not, 2 on bad arguments. "
            "Writes the trajectory plot (paper Fig. 3 style), the trajectory (.npz) and, on request, a video."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    run.add_argument("--object", choices=sorted(OBJECTS), default="sphere", help="the paper's object (Table I)")
    run.add_argument("--controller", choices=["manhattan", "euclidean"], default="manhattan",
                     help="Manhattan: two PIDs (Algorithm 1); Euclidean: one along the error (Algorithm 2)")
    run.add_argument("--start", type=_point, default=(0.05, -0.05), metavar="X,Y", help="object start [m]")
    run.add_argument("--target", type=_point, default=(-0.05, 0.05), metavar="X,Y", help="target p_d [m]")
    run.add_argument("--duration", type=float, default=10.0, help="runtime T [s]; success is judged at its end")
    run.add_argument("--seed", type=int, default=1, help="seed of the actuator noise and the camera model")
    run.add_argument("--alpha", type=float, default=0.0, help="noise amplitude α [m] (paper: 0.1 cube, 0.05 bunny)")
    run.add_argument("--tolerance", type=float, default=0.02, help="ε [m]")
    run.add_argument("--rate", type=float, default=12.0, help="camera rate [Hz] (paper: 12)")
    run.add_argument("--latency", type=float, default=0.0, help="camera latency [s], below one frame period")
    run.add_argument("--noise", type=float, default=0.0, help="camera noise, standard deviation [m] per axis")
    run.add_argument("--drop", type=float, default=0.0, help="share of camera frames lost [0..1)")
    run.add_argument("--out", default="out/sim", help="directory for the figure, trajectory and video")
    run.add_argument("--json", action="store_true", help="print one JSON object instead of the sentence")
    run.add_argument("--video", action="store_true", help="also render an MP4 from the overhead camera")
    run.add_argument("--video-fps", type=float, default=30.0, help="video frame rate [1/s]")
    run.add_argument("--port", help="serial device path of a firmware to use instead of starting the virtual MCU "
                     "(a simulated-clock firmware runs in lock-step; a board needs --realtime)")
    run.add_argument("--realtime", action="store_true",
                     help="run in real time against a wall-clock virtual MCU instead of lock-step")
    run.add_argument("--viewer", action="store_true", help="show the MuJoCo viewer (needs a display; implies "
                     "nothing about pacing: add --realtime to watch at real speed)")
    run.set_defaults(func=lambda args: cmd_run(args, run))
    sim.set_defaults(func=lambda args: (sim.print_help(), 2)[1])
