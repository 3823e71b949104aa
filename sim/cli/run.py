"""`mantaray sim run`: one target-reaching trial, the firmware in the loop over a pty (or a --port)."""

from __future__ import annotations

import argparse
import hashlib
import json
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING

from mantaray.arguments import reporter
from mantaray.host.cli_controller import controller_settings
from mantaray.host.cli_view import start_live
from mantaray.outputs import writable_dir
from mantaray.protocol import messages as m
from mantaray.protocol import rig as rig_description

from .common import output, plant_for_settings

if TYPE_CHECKING:
    from ..model.rig import Rig
    from ..model.tracking import Tracking
    from ..trial.bridge import TrialSpec
    from ..trial.trial_run import TrialOutputs


@dataclass(frozen=True)
class RunRequest:
    """What `sim run` runs, settled once from its arguments: the rig, camera, trial and outputs, and the names the
    arguments may leave to defaults (the controller a settings file sets, the plant it was tuned on, the rig file)."""

    rig: Rig
    tracking: Tracking
    spec: TrialSpec
    outputs: TrialOutputs
    controller: str
    plant: str
    rig_file: rig_description.RigDescription


def run(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """`sim run`: one trial set up from the arguments, run (sim/trial/trial_run.py), and reported."""
    from ..trial.trial_run import run_trial

    request = _trial(args, parser)
    outputs = request.outputs
    bar, progress = _progress(args)
    try:
        result, paths = run_trial(
            request.rig,
            request.tracking,
            request.spec,
            outputs,
            _report,
            port=args.port,
            realtime=args.realtime,
            progress=progress,
        )
    except ValueError as exc:  # model.fabric_height: the sheet sags inside its corners there
        if "not over the fabric" not in str(exc):
            raise
        parser.error(
            f"--start {args.start[0]:g},{args.start[1]:g} is not over the hanging sheet (it sags in from the frame "
            "at its corners): start further in"
        )
    finally:
        if outputs.live is not None:
            outputs.live.close()
        if bar is not None:
            bar.close()
    _warnings(args, result)
    summary = {**result.summary(), "plant": request.plant, "plant_set": dict(args.set), **paths}
    print(json.dumps(summary) if args.json else _summary_line(args, request, result, paths))
    return 0 if result.success else 1


def _trial(args: argparse.Namespace, parser: argparse.ArgumentParser) -> RunRequest:
    """The rig, camera model, trial and outputs the arguments ask for; a usage error for any that cannot be."""
    from mantaray.host.ports import check_port

    from ..model.plant import Plant
    from ..trial.bridge import TrialSpec
    from ..trial.trial_run import TrialOutputs
    from ..trial.video import FPS_RANGE

    settings = controller_settings(parser, args)
    plant_name = plant_for_settings(parser, settings, args.plant)
    plant = Plant(plant_name).set(dict(args.set))
    rig_file = args.rig or rig_description.default()
    resolved = {**vars(args), "controller": settings.controller, "plant": plant_name, "rig": rig_file}
    try:
        rig = plant.rig(args.object, resolution=args.resolution, timestep_s=args.timestep)
    except ValueError as exc:
        parser.error(f"--resolution, --timestep: {exc}")
    try:
        rig = rig.with_description(rig_file)
    except ValueError as exc:  # a rig file whose actuators the simulated rig lacks, or no firmware is built for
        parser.error(f"--rig: {exc}")
    if args.vision:
        if rig.module.grid.module_count > 1:
            parser.error("--vision tracks on one module's camera and markers; an array (--rig) runs on the truth")
        rig = rig.with_vision(args.vision)
    half = rig.module.grid.half_extent_m
    _inside(parser, "--start", args.start, half)
    _inside(parser, "--target", args.target, half)
    if args.video and not FPS_RANGE[0] <= args.video_fps <= FPS_RANGE[1]:
        parser.error(
            f"--video-fps must be {FPS_RANGE[0]:g}..{FPS_RANGE[1]:g} frames per second, got {args.video_fps:g}"
        )
    if args.viewer and not os.environ.get("DISPLAY"):
        parser.error("--viewer needs a display (DISPLAY is not set); use --video to record one instead")
    try:
        check_port(args.port)
        tracking = plant.tracking(
            rate_hz=args.rate, latency_s=args.latency, noise_m=args.noise, drop_rate=args.drop, vision=args.vision
        )
        spec = TrialSpec(
            args.start,
            args.target,
            controller=settings.controller,
            duration_s=args.duration,
            alpha_m=args.alpha,
            tolerance_m=args.tolerance,
            seed=args.seed,
            gain_scale=plant.gain_scale,
            settings=settings.values,
        )
    except ValueError as exc:
        parser.error(str(exc))
    outputs = TrialOutputs(
        out=output(parser, writable_dir, args.out),
        stem=_trial_stem(resolved),
        metadata={**_settings(resolved), "object": rig.object.name},
        tilt_limit_deg=settings.configure(m.Configure()).tilt_limit,
        video_fps=args.video_fps if args.video else None,
        viewer=args.viewer,
        live=start_live(parser, args, _report),
        linger_s=args.linger,
    )
    if outputs.live is not None:
        _report(f"live view at {outputs.live.options.page_url}")
    return RunRequest(rig, tracking, spec, outputs, settings.controller, plant_name, rig_file)


def _progress(args: argparse.Namespace):
    """A bar over simulated time and the callback that moves it (none with --json)."""
    if args.json:
        return None, None
    from ..evaluation.progress import Progress

    bar = Progress(float(args.duration), unit="sim s", units="simulated s", label="sim run", line_every_s=5.0)
    return bar, lambda t_s: bar.update(t_s - bar.done)


def _warnings(args: argparse.Namespace, result) -> None:
    """What the link and the tracker noticed, on stderr."""
    for message in result.watch.messages:
        _report(f"link: {message}")
    if result.watch.unseen_frames:
        _report(
            f"warning: the tracker ({args.vision}) saw no object in {result.watch.unseen_frames} of "
            f"{len(result.t_s)} camera frames; the firmware got those as not visible (NaN in the trajectory's "
            "measured_xy_m)"
            + (
                " — a marker on a rolling object turns away from the camera: track it with --vision blob"
                if args.vision == "aruco"
                else ""
            )
        )


HEADLINE = {"fell off": "FELL OFF", "success": "SUCCESS", "not within ε at T": "NOT WITHIN ε AT T"}  # the line's start


def _summary_line(args: argparse.Namespace, request: RunRequest, result, paths: dict) -> str:
    from ..trial.trial_run import outcome_words

    reach = (
        "never reached ε" if result.time_to_reach_s is None else f"reached ε first at {result.time_to_reach_s:.2f} s"
    )
    return (
        f"{HEADLINE[outcome_words(result)]}: {args.object}, {request.controller}, {request.plant} plant"
        + "".join(f", {k}={v}" for k, v in args.set)
        + f", start {args.start[0]:+.3f},{args.start[1]:+.3f} -> target {args.target[0]:+.3f},{args.target[1]:+.3f} "
        f"m; final error {result.final_error_m * 100:.1f} cm (ε {args.tolerance * 100:g} cm), {reach}; "
        f"{result.sim_time_s:.1f} sim s in {result.wall_time_s:.1f} wall s "
        f"({result.sim_time_s / result.wall_time_s:.2f}x, physics {result.physics_share:.0%}); "
        f"figure {paths['figure']}" + (f", video {paths['video']}" if "video" in paths else "")
    )


def _inside(parser: argparse.ArgumentParser, name: str, xy: tuple[float, float], half: tuple[float, float]) -> None:
    if abs(xy[0]) > half[0] or abs(xy[1]) > half[1]:
        parser.error(f"{name} {xy[0]:g},{xy[1]:g} is outside the fabric (|x| <= {half[0]:g} m, |y| <= {half[1]:g} m)")


_report = reporter("sim run")


def _settings(resolved: dict) -> dict:
    """What the trial was: every argument, with the defaults settled, but where its outputs go and how it is
    watched."""
    watching = ("out", "json", "video", "video_fps", "viewer", "live", "live_port", "bind", "linger")
    settings = {k: v for k, v in sorted(resolved.items()) if k not in (*watching, "func", "command", "sim_command")}
    return {**settings, "rig": resolved["rig"].name}  # the rig by its build's name


def _trial_stem(resolved: dict) -> str:
    """The file name of one trial's outputs: what it was, readably, and a digest of every other setting, so two
    different trials never overwrite each other's files and the same trial run again does."""
    digest = hashlib.sha1(repr(_settings(resolved)).encode()).hexdigest()[:6]
    (sx, sy), (tx, ty) = resolved["start"], resolved["target"]
    return (
        f"{resolved['object']}_{resolved['controller']}_{sx:+.3f},{sy:+.3f}_to_{tx:+.3f},{ty:+.3f}"
        f"_seed{resolved['seed']}_{digest}"
    )
