"""`mantaray sim run`: one target-reaching trial, the firmware in the loop over a pty (or a --port)."""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import os
import sys
from pathlib import Path

from mantaray.arguments import controller_settings, reporter, start_live
from mantaray.outputs import writable_dir
from mantaray.protocol import messages as m

from .cli_common import output, plant_for_settings


def run(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """`sim run`: one trial set up from the arguments, run, and reported."""
    from mantaray.host.link import Link
    from mantaray.host.ports import check_port
    from mantaray.host.transport import SerialTransport
    from mantaray.host.view import RunView
    from mantaray.host.vmcu import VirtualMcu
    from mantaray.plots import path_phase_figure

    from .bridge import Bridge, TrialSpec
    from .experiment import controller_gains
    from .mjcf import N_ACTUATORS
    from .plant import Plant
    from .trial_view import TrialView

    settings = controller_settings(parser, args)
    args.plant = plant_for_settings(parser, settings, args.plant)
    plant = Plant(args.plant).set(dict(args.set))
    rig = plant.rig(args.object)
    if args.vision:
        rig = rig.with_vision(args.vision)
    half = (rig.frame.size_x_m / 2, rig.frame.size_y_m / 2)
    _inside(parser, "--start", args.start, half)
    _inside(parser, "--target", args.target, half)
    try:
        check_port(args.port)
        tracking = plant.tracking(
            rate_hz=args.rate, latency_s=args.latency, noise_m=args.noise, drop_rate=args.drop, vision=args.vision
        )
        spec = TrialSpec(
            args.start,
            args.target,
            controller=args.controller,
            duration_s=args.duration,
            alpha_m=args.alpha,
            tolerance_m=args.tolerance,
            seed=args.seed,
            gains=controller_gains(args.controller, args.gains, plant.gain_scale),
            settings=settings.values,
        )
    except ValueError as exc:
        parser.error(str(exc))

    from .video import FPS_RANGE

    if args.video and not FPS_RANGE[0] <= args.video_fps <= FPS_RANGE[1]:
        parser.error(
            f"--video-fps must be {FPS_RANGE[0]:g}..{FPS_RANGE[1]:g} frames per second, got {args.video_fps:g}"
        )
    out = output(parser, writable_dir, args.out)
    stem = _trial_stem(args)
    progress = None
    if not args.json:
        from .progress import Progress

        bar = Progress(float(args.duration), unit="sim s", units="simulated s", label="sim run", line_every_s=5.0)

        def progress(t_s: float) -> None:
            bar.update(t_s - bar.done)

    if args.viewer and not os.environ.get("DISPLAY"):
        parser.error("--viewer needs a display (DISPLAY is not set); use --video to record one instead")
    live = start_live(parser, args, _report)
    with contextlib.ExitStack() as stack:
        if live is not None:
            stack.callback(live.close)
            _report(f"live view at {live.options.page_url}")
        port = args.port or stack.enter_context(VirtualMcu(clock="wall" if args.realtime else "sim")).path
        link = Link(SerialTransport(port))
        stack.callback(link.close)
        bridge = Bridge(link, rig, tracking, lockstep=not args.realtime)
        view = RunView(
            "mantaray_sim_run",
            out / f"{stem}.rrd",
            None if live is None else live.options.grpc_url,
            {**_settings(args), "plant": args.plant, "object": rig.object.name},
            N_ACTUATORS,
            (rig.frame.size_x_m, rig.frame.size_y_m),
            _report,
            world=True,
        )
        trial_view = bridge.view = TrialView(view, bridge.model, bridge.data, rig, link, lockstep=not args.realtime)
        viewer = None
        if args.viewer:
            import mujoco.viewer

            viewer = bridge.viewer = mujoco.viewer.launch_passive(bridge.model, bridge.data)
        if args.video:
            from .video import Recorder

            bridge.recorder = Recorder(bridge.model, fps=args.video_fps)
        try:
            result = bridge.run(spec, progress=progress)
        except ValueError as exc:  # model.fabric_height: the sheet sags inside its corners there
            if "not over the fabric" not in str(exc):
                raise
            parser.error(
                f"--start {args.start[0]:g},{args.start[1]:g} is not over the hanging sheet (it sags in from "
                f"the frame at its corners): start further in"
            )
        finally:
            recording = trial_view.close()
        if viewer is not None:
            viewer.close()
        if live is not None:
            live.linger(args.linger, _report)
    if progress is not None:
        bar.close()

    summary = {**result.summary(), "plant": args.plant, "plant_set": dict(args.set)}
    spec = result.spec
    outcome = "fell off" if result.fell_off else ("success" if result.success else "not within ε at T")
    summary["figure"] = str(
        path_phase_figure(
            result.true_xy_m,
            result.tilt_deg,
            spec.start_m,
            [spec.target_m],
            spec.tolerance_m,
            f"{result.object_name}, {spec.controller}, α = {spec.alpha_m:g} m: {outcome}\n"
            f"final error {result.final_error_m * 100:.1f} cm (ε = {spec.tolerance_m * 100:g} cm)",
            (rig.frame.size_x_m, rig.frame.size_y_m),
            settings.configure(m.Configure()).tilt_limit,
            out / f"{stem}.png",
            t_s=result.t_s,
            command_m=result.command_m,
            range_m=rig.actuators.range_m,
        )
    )
    summary["trajectory"] = str(save_trajectory(result, out / f"{stem}.npz"))
    summary["recording"] = None if recording is None else str(recording)
    if args.video:
        summary["video"] = str(bridge.recorder.save(out / f"{stem}.mp4"))
    for message in result.watch.messages:
        print(f"mantaray sim run: link: {message}", file=sys.stderr)
    if result.watch.unseen_frames:
        print(
            f"mantaray sim run: warning: the tracker ({args.vision}) saw no object in {result.watch.unseen_frames} "
            f"of {len(result.t_s)} camera frames; the firmware got those as not visible (NaN in the trajectory's "
            f"measured_xy_m)"
            + (
                " — a marker on a rolling object turns away from the camera: track it with --vision blob"
                if args.vision == "aruco"
                else ""
            ),
            file=sys.stderr,
        )
    if args.json:
        print(json.dumps(summary))
    else:
        # one word per meaning: SUCCESS is within ε at T (the exit status); "reached" is within ε at some frame
        outcome = "FELL OFF" if result.fell_off else ("SUCCESS" if result.success else "NOT WITHIN ε AT T")
        reach = (
            "never reached ε"
            if result.time_to_reach_s is None
            else f"reached ε first at {result.time_to_reach_s:.2f} s"
        )
        print(
            f"{outcome}: {args.object}, {args.controller}, {args.plant} plant"
            + "".join(f", {k}={v}" for k, v in args.set)
            + f", start {args.start[0]:+.3f},{args.start[1]:+.3f} -> "
            f"target {args.target[0]:+.3f},{args.target[1]:+.3f} m; final error {result.final_error_m * 100:.1f} cm "
            f"(ε {args.tolerance * 100:g} cm), {reach}; {result.sim_time_s:.1f} sim s in {result.wall_time_s:.1f} wall s "
            f"({result.sim_time_s / result.wall_time_s:.2f}x, physics {result.physics_share:.0%}); "
            f"figure {summary['figure']}" + (f", video {summary['video']}" if args.video else "")
        )
    return 0 if result.success else 1


def _inside(parser: argparse.ArgumentParser, name: str, xy: tuple[float, float], half: tuple[float, float]) -> None:
    if abs(xy[0]) > half[0] or abs(xy[1]) > half[1]:
        parser.error(f"{name} {xy[0]:g},{xy[1]:g} is outside the fabric (|x| <= {half[0]:g} m, |y| <= {half[1]:g} m)")


_report = reporter("sim run")


def _settings(args: argparse.Namespace) -> dict:
    """What the trial was: every argument but where its outputs go and how it is watched."""
    watching = ("out", "json", "video", "video_fps", "viewer", "live", "live_port", "bind", "linger")
    return {k: v for k, v in sorted(vars(args).items()) if k not in (*watching, "func", "command", "sim_command")}


def _trial_stem(args: argparse.Namespace) -> str:
    """The file name of one trial's outputs: what it was, readably, and a digest of every other setting, so two
    different trials never overwrite each other's files and the same trial run again does."""
    digest = hashlib.sha1(repr(_settings(args)).encode()).hexdigest()[:6]
    (sx, sy), (tx, ty) = args.start, args.target
    return f"{args.object}_{args.controller}_{sx:+.3f},{sy:+.3f}_to_{tx:+.3f},{ty:+.3f}_seed{args.seed}_{digest}"


def save_trajectory(result, path: Path) -> Path:
    import numpy as np

    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(
        path,
        t_s=result.t_s,
        true_xy_m=result.true_xy_m,
        measured_xy_m=result.measured_xy_m,
        tilt_deg=result.tilt_deg,
        command_m=result.command_m,
        measured_m=result.measured_m,
        state=result.state,
        start_m=result.spec.start_m,
        target_m=result.spec.target_m,
    )
    return path
