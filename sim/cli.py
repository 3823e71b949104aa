"""`mantaray sim ...`: the simulation's commands; `sim run` is the main job (firmware in the loop over a pty)."""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import math
import os
import signal
import sys
from pathlib import Path

from mantaray.arguments import number
from mantaray.host.cli import add_controller_arguments, controller_settings, parse_gains
from mantaray.outputs import FIGURE_SUFFIXES, OutputError, writable_dir, writable_file
from mantaray.protocol import messages as m
from mantaray.protocol.codec import bounds_text, choices

from .objects import OBJECTS
from .parameters import plant_names
from .plant import DEFAULT_PLANT
from .rig import VISION_MODES


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
    from mantaray.host.ports import check_port
    from mantaray.host.transport import SerialTransport
    from mantaray.host.vmcu import VirtualMcu
    from mantaray.plots import path_phase_figure

    from .bridge import Bridge, TrialSpec
    from .experiment import controller_gains
    from .plant import Plant

    settings = controller_settings(parser, args)
    args.plant = _plant(parser, settings, args.plant)
    plant = Plant(args.plant)
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
    out = _output(parser, writable_dir, args.out)
    stem = _trial_stem(args)
    progress = None
    if not args.json:
        from .progress import Progress

        bar = Progress(float(args.duration), unit="sim s", units="simulated s", label="sim run", line_every_s=5.0)

        def progress(t_s: float) -> None:
            bar.update(t_s - bar.done)

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
        try:
            result = bridge.run(spec, progress=progress)
        except ValueError as exc:  # model.fabric_height: the sheet sags inside its corners there
            if "not over the fabric" not in str(exc):
                raise
            parser.error(
                f"--start {args.start[0]:g},{args.start[1]:g} is not over the hanging sheet (it sags in from "
                f"the frame at its corners): start further in"
            )
        if viewer is not None:
            viewer.close()
    if progress is not None:
        bar.close()

    summary = {**result.summary(), "plant": args.plant}
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
    summary["trajectory"] = str(_save_trajectory(result, out / f"{stem}.npz"))
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
            f"{outcome}: {args.object}, {args.controller}, {args.plant} plant, start {args.start[0]:+.3f},{args.start[1]:+.3f} -> "
            f"target {args.target[0]:+.3f},{args.target[1]:+.3f} m; final error {result.final_error_m * 100:.1f} cm "
            f"(ε {args.tolerance * 100:g} cm), {reach}; {result.sim_time_s:.1f} sim s in {result.wall_time_s:.1f} wall s "
            f"({result.sim_time_s / result.wall_time_s:.2f}x, physics {result.physics_share:.0%}); "
            f"figure {summary['figure']}" + (f", video {summary['video']}" if args.video else "")
        )
    return 0 if result.success else 1


def _output(parser: argparse.ArgumentParser, check, *args):
    """An output path checked before any work (mantaray.outputs); a bad one is a usage error."""
    try:
        return check(*args)
    except OutputError as exc:
        parser.error(str(exc))


def _trial_stem(args: argparse.Namespace) -> str:
    """The file name of one trial's outputs: what it was, readably, and a digest of every other setting, so two
    different trials never overwrite each other's files and the same trial run again does."""
    settings = {
        k: v
        for k, v in sorted(vars(args).items())
        if k not in ("out", "json", "video", "viewer", "func", "command", "sim_command")
    }
    digest = hashlib.sha1(repr(settings).encode()).hexdigest()[:6]
    (sx, sy), (tx, ty) = args.start, args.target
    return f"{args.object}_{args.controller}_{sx:+.3f},{sy:+.3f}_to_{tx:+.3f},{ty:+.3f}_seed{args.seed}_{digest}"


def _save_trajectory(result, path: Path) -> Path:
    import numpy as np

    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(
        path,
        t_s=result.t_s,
        true_xy_m=result.true_xy_m,
        measured_xy_m=result.measured_xy_m,
        tilt_deg=result.tilt_deg,
        command_m=result.command_m,
        state=result.state,
        start_m=result.spec.start_m,
        target_m=result.spec.target_m,
    )
    return path


def _plant(parser: argparse.ArgumentParser, settings, given: str | None) -> str:
    from .plant import plant_for

    try:
        return plant_for(settings, given)
    except ValueError as exc:
        parser.error(str(exc))


def _cells(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(v) for v in text.replace(",", " ").split())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected cell indices like 0,21,210, got {text!r}") from None


def _heatmap_outputs(results, out: Path, title: str) -> dict:
    """Write per-cell rates (CSV), the summary (JSON) and the figure beside the results file; return the summary."""
    from mantaray.plots import heatmap_figure

    from .experiment import cell_bounds
    from .summary import summarize

    s = summarize(results)
    p = results.protocol
    f = p.rig().frame
    rows = ["cell,ix,iy,x_lo_m,y_lo_m,trials,success_rate,reach_rate,fell_rate"]
    for cell in p.cell_ids():
        ix, iy = cell % p.cells, cell // p.cells
        x_lo, _, y_lo, _ = cell_bounds(p, (f.size_x_m, f.size_y_m), cell)
        rows.append(
            f"{cell},{ix},{iy},{x_lo:.4f},{y_lo:.4f},{s.trials_per_cell[iy, ix]},{s.rates[iy, ix]:.3f},"
            f"{s.reach_rates[iy, ix]:.3f},{s.fell_rates[iy, ix]:.3f}"
        )
    (out / "cells.csv").write_text("\n".join(rows) + "\n")
    summary = {"protocol": p.to_json(), **s.to_json()}
    size = (f.size_x_m, f.size_y_m)
    summary["figure"] = str(
        heatmap_figure(
            s.rates,
            size,
            f"{title}\nscore {s.score:.1f} of {len(p.cell_ids())} (within ε at any frame: {s.reach_score:.1f})",
            out / "heatmap.png",
        )
    )
    summary["reach_figure"] = str(
        heatmap_figure(
            s.reach_rates,
            size,
            f"{title}\nwithin ε at any frame (where the paper's loop stops): score {s.reach_score:.1f}",
            out / "heatmap_reach.png",
        )
    )
    (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    return summary


def cmd_heatmap(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """The paper's evaluation (Fig. 2): success rate per cell of the workspace, trials in parallel.

    Each cell gets N trials with a random target inside the cell and a random start anywhere on the fabric;
    a trial succeeds if the object ends within ε of its target at the end of T without falling off. The
    firmware core runs in-process (the same C++ as the virtual MCU). Results go to OUT/results.jsonl, one
    line per trial as it finishes: interrupt the run and the same command continues where it stopped."""
    from .executors import RayUnavailable, run, run_local, run_ray
    from .experiment import Experiment, ExperimentMismatch
    from .model import SimulationUnstable
    from .results_file import ResultsFile, ResultsFileBusy

    settings = controller_settings(parser, args)
    args.plant = _plant(parser, settings, args.plant)
    try:
        protocol = Experiment(
            object_name=args.object,
            controller=args.controller,
            cells=args.cells,
            trials_per_cell=args.trials,
            tolerance_m=args.tolerance,
            duration_s=args.duration,
            alpha_m=args.alpha,
            seed=args.seed,
            gains=args.gains,
            resolution=args.resolution,
            timestep_s=args.timestep,
            only_cells=args.only_cells,
            plant=args.plant,
            stop_when_reached=args.stop_when_reached,
            settings=settings.values,
        )
    except ValueError as exc:
        parser.error(str(exc))
    if args.jobs is not None and args.jobs < 1:
        parser.error(f"--jobs must be at least 1, got {args.jobs}")
    plant = "" if args.plant == DEFAULT_PLANT else f"_{args.plant}"
    _check_ray(parser, args)
    tuned = f"_{Path(args.settings).stem}" if args.settings else ""
    out = _output(
        parser,
        writable_dir,
        args.out or f"out/heatmap/{args.object}_{args.controller}{tuned}_alpha{args.alpha:g}{plant}",
    )
    try:
        results = ResultsFile.open(out / "results.jsonl", protocol)
    except (ExperimentMismatch, ValueError, ResultsFileBusy) as exc:
        print(f"mantaray sim heatmap: {exc}", file=sys.stderr)
        return 2
    for warning in results.warnings():
        print(f"mantaray sim heatmap: warning: {warning}", file=sys.stderr)
    todo = results.missing()
    total = len(protocol.cell_ids()) * protocol.trials_per_cell
    if len(todo) < total:
        print(
            f"continuing {out / 'results.jsonl'}: {total - len(todo)} of {total} trials already done", file=sys.stderr
        )
    from .progress import Progress

    bar = Progress(total, initial=total - len(todo), unit="trial", label="heatmap")  # on stderr, beside --json
    _interruptible()
    try:
        if args.executor == "ray":
            records = run_ray(protocol, todo, args.jobs, args.ray_address)
        else:
            records = run_local(protocol, todo, args.jobs or os.cpu_count() or 1)
        run(results, records, progress=lambda record: bar.update(1))
    except KeyboardInterrupt:
        bar.close()
        print(
            f"\ninterrupted: {len(results.records)} of {total} trials are in {out / 'results.jsonl'}; "
            f"the same command continues the run",
            file=sys.stderr,
        )
        return 130
    except SimulationUnstable as exc:
        bar.close()
        print(
            f"mantaray sim heatmap: {exc}; the {len(results.records)} finished trials are kept in "
            f"{out / 'results.jsonl'}",
            file=sys.stderr,
        )
        return 1
    except RayUnavailable as exc:
        bar.close()
        print(f"mantaray sim heatmap: {exc}", file=sys.stderr)
        return 2
    bar.close()
    title = (
        f"{args.object}, {args.controller}, α = {args.alpha:g} m, ε = {args.tolerance:g} m, T = {args.duration:g} s, "
        f"{protocol.trials_per_cell} trials/cell"
    )
    summary = _heatmap_outputs(results, out, title)
    if args.json:
        print(json.dumps(summary))
    else:
        regions = summary["regions"]
        print(
            f"{args.object}, {args.controller}: score {summary['score']:.1f} of {len(protocol.cell_ids())} cells "
            f"(within ε at any frame: {summary['reach_score']:.1f}); regions: "
            + ", ".join(f"{name} {r['cells']} cells ({r['area_m2']:.4f} m²)" for name, r in regions.items())
            + f"; {out}/results.jsonl, cells.csv, summary.json, heatmap.png"
        )
    return 0


def cmd_compare(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """The difference map of two heatmap runs (first minus second), like the paper's Euclidean - Manhattan."""
    from mantaray.plots import heatmap_figure

    from .results_file import ResultsFile
    from .summary import summarize

    _output(parser, writable_file, args.out, FIGURE_SUFFIXES)
    runs = []
    for given in (args.first, args.second):
        path = Path(given)
        path = path / "results.jsonl" if path.is_dir() else path
        if not path.exists():
            parser.error(f"no heatmap results at {given}")
        try:
            runs.append(ResultsFile.load(path))
        except ValueError as exc:
            parser.error(str(exc))
        for warning in runs[-1].warnings():
            print(f"mantaray sim compare: warning: {warning}", file=sys.stderr)
    (a, b), (pa, pb) = [summarize(r) for r in runs], [r.protocol for r in runs]
    # what success means, and where it is measured, must be the same in both runs; object, controller, alpha,
    # gains and plant are what a comparison is for
    differ = [name for name in ("cells", "tolerance_m", "duration_s") if getattr(pa, name) != getattr(pb, name)]
    if set(pa.cell_ids()) != set(pb.cell_ids()):
        differ.append("only_cells")
    if differ:
        parser.error(
            "the runs measure success differently ("
            + "; ".join(f"{name} {getattr(pa, name)} against {getattr(pb, name)}" for name in differ)
            + "): compare runs that "
            "differ only in what is being compared"
        )
    if not args.reached and (pa.stop_when_reached or pb.stop_when_reached):
        parser.error(
            "a run that stops at its first frame within ε (--stop-when-reached) has no end-of-T success; "
            "compare with --reached"
        )
    for given, results in zip((args.first, args.second), runs, strict=True):
        left = len(results.missing())
        if left:
            print(
                f"mantaray sim compare: warning: {given} is incomplete ({left} of "
                f"{left + len(results.records)} trials not run); its rates are over the trials that ran",
                file=sys.stderr,
            )
    f = pa.rig().frame
    label = [f"{p.object_name} {p.controller} α={p.alpha_m:g}" for p in (pa, pb)]
    rule = "within ε at any frame" if args.reached else "within ε at T"
    (rates_a, score_a), (rates_b, score_b) = [
        (s.reach_rates, s.reach_score) if args.reached else (s.rates, s.score) for s in (a, b)
    ]
    figure = heatmap_figure(
        rates_a - rates_b,
        (f.size_x_m, f.size_y_m),
        f"{label[0]} − {label[1]} ({rule})\nscores {score_a:.1f} − {score_b:.1f} = {score_a - score_b:+.1f}",
        args.out,
        difference=True,
    )
    relative = f" ({(score_a - score_b) / score_b:+.0%} of the second)" if score_b > 0 else ""
    print(
        f"{rule}: {label[0]}: score {score_a:.1f}; {label[1]}: score {score_b:.1f}; difference "
        f"{score_a - score_b:+.1f}{relative}; figure {figure}"
    )
    return 0


def cmd_calibrate(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Fit the simulated plant to evidence with an Optuna search over the declared parameter space (sim/plant.toml).

    Evidence is the paper's findings F1-F5 (default: a stratified sample of heatmap cells, the sphere, both
    controllers, the paper's gains, several objectives at once) or, with --log, rig logs: the simulation driven
    by each log's commands should retrace its trajectory. The study is OUT/study.db (SQLite): interrupt it and the
    same command continues; --candidates is the total the study should hold. Writes OUT/report.md, report.json
    (best candidate, its findings, parameter importances) and pareto.png; --fig3 also runs the paper's
    hardware experiment (F6) on the best candidate."""
    from mantaray.host.runlog import RunLogError

    from . import calibrate as C
    from . import parameters as P
    from .logfit import LogEvidence, check_logs
    from .plant import Plant, parse_setting

    try:
        fixed = dict(parse_setting(text) for text in args.set)
        keys = C.searched(args.params.split(",") if args.params else None, fixed)
        Plant(args.plant).set(fixed)
        if args.log:
            check_logs(args.log, args.object, args.horizon)
            evidence = LogEvidence(
                logs=tuple(str(Path(p).resolve()) for p in args.log),
                object_name=args.object,
                plant=args.plant,
                horizon_s=args.horizon,
                resolution=args.resolution,
                timestep_s=args.timestep,
                seed=args.seed,
            )
        else:
            evidence = C.FindingsEvidence(
                plant=args.plant,
                cells_per_stratum=args.cells_per_stratum,
                trials_per_cell=args.trials_per_cell,
                duration_s=args.duration,
                seed=args.seed,
                resolution=args.resolution,
                timestep_s=args.timestep,
            )
            evidence.protocols(fixed)  # refuses bad sizes and durations before anything runs
    except (P.ParameterError, RunLogError, ValueError) as exc:
        parser.error(str(exc))
    if not keys:
        parser.error("nothing to search: every parameter named is fixed by --set")
    if args.candidates < 0 or (args.jobs is not None and args.jobs < 1):
        parser.error("--candidates must be >= 0 and --jobs >= 1")
    _check_ray(parser, args)
    out = _output(parser, writable_dir, args.out or f"out/calibration/{'log' if args.log else 'findings'}")
    try:
        study = C.open_study(out / "study.db", evidence, keys, fixed)
    except C.StudyMismatch as exc:
        print(f"mantaray sim calibrate: {exc}", file=sys.stderr)
        return 2
    progress = _candidates(study, out, args.candidates, "calibrate")

    def report_candidate(n: int, total: int, info: dict) -> None:
        if "unstable" in info:
            note = "the physics diverged: scored the worst of every objective"
        else:
            note = "objectives " + " ".join(f"{v:.3f}" for v in info["objectives"])
            note += f", {info['passed']} findings hold" if evidence.kind == "findings" else ""
        progress.update(1, note=note)

    pool = _pool(parser, args)
    fig3 = None
    _interruptible()
    try:
        with pool:
            C.run_study(study, evidence, keys, fixed, args.candidates, pool, report_candidate)
            best = C.best_trial(study)
            if args.fig3 and best is not None and evidence.kind == "findings":
                fig3 = _fig3_for(best, args, pool, out)
    except RunLogError as exc:  # a log the simulation cannot start (say, off the fabric's corner)
        progress.close()
        print(f"mantaray sim calibrate: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        progress.close()
        C.write_report(study, evidence, out)
        print(
            f"\ninterrupted: {len(C.completed(study))} candidates are in {out / 'study.db'}; the same command "
            f"continues the search (report so far in {out / 'report.md'})",
            file=sys.stderr,
        )
        return 130
    progress.close()
    report = C.write_report(study, evidence, out, fig3)
    if args.json:
        print(json.dumps(report))
    else:
        best = report["best"]
        print(
            f"{report['candidates']} candidates; best #{best['number']}: objectives {best['objectives']}; "
            f"report {out / 'report.md'}"
            if best
            else f"no candidate evaluated; {out / 'report.md'}"
        )
    return 0


def _candidates(study, out: Path, candidates: int, label: str):
    """The progress of a search toward `candidates`, saying so when it continues a study that holds some already."""
    from . import calibrate as C
    from .progress import Progress

    done = len(C.finished(study))
    if 0 < done < candidates:
        print(f"continuing {out / 'study.db'}: {done} of {candidates} candidates already evaluated", file=sys.stderr)
    return Progress(max(candidates, done), initial=done, unit="candidate", label=label, line_every_s=0)


def _check_ray(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """--executor and --ray-address, before any work: Ray (and Ray Client, for a ray:// address) installed, the
    cluster's address answering; else one line and exit status 2."""
    from .executors import RayUnavailable, check_ray

    if args.ray_address and args.executor != "ray":
        parser.error("--ray-address needs --executor ray")
    if args.executor == "ray":
        try:
            check_ray(args.ray_address)
        except RayUnavailable as exc:
            parser.exit(2, f"{parser.prog}: {exc}\n")


def _pool(parser: argparse.ArgumentParser, args: argparse.Namespace):
    """The worker pool --executor asks for (checked by _check_ray): this machine's processes (--jobs), or Ray (a
    cluster at --ray-address); a cluster that answers but not as Ray does is one line and exit status 2."""
    from .executors import LocalPool, RayPool, RayUnavailable

    if args.executor == "ray":
        try:
            return RayPool(args.jobs, args.ray_address)
        except RayUnavailable as exc:
            parser.exit(2, f"{parser.prog}: {exc}\n")
    return LocalPool(args.jobs or os.cpu_count() or 1)


def _tuning_start(parser: argparse.ArgumentParser, args: argparse.Namespace, evidence) -> dict[str, float]:
    """--start-from's settings as the search's knobs; a file for another controller or plant is a usage error."""
    from mantaray.host.controller_settings import ControllerSettings, SettingsError

    from . import tune as T

    try:
        settings = ControllerSettings.load(args.start_from)
    except SettingsError as exc:
        parser.error(str(exc))
    if settings.controller != args.controller:
        parser.error(
            f"--start-from {args.start_from} sets up the {settings.controller} controller, not the "
            f"{args.controller} one this search tunes"
        )
    if settings.plant not in (None, args.plant):
        parser.error(
            f"--start-from {args.start_from} holds gains for the {settings.plant} plant, not for "
            f"{args.plant}, which reads them otherwise"
        )
    try:
        start, clipped = T.start_values(settings, args.per_axis, evidence.gain_scale)
    except SettingsError as exc:
        parser.error(f"--start-from {args.start_from}: {exc}")
    if clipped:
        print(
            f"tune: --start-from {args.start_from}: {', '.join(clipped)} lie outside the search's range "
            f"(sim/tune.py, SPACE), so the search starts from the nearest bound there",
            file=sys.stderr,
        )
    return start


def cmd_tune(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Tune a controller's settings for a plant: an Optuna search on a stratified sample of heatmap cells, then the
    paper's full protocol with the best settings on another seed (the search never sees those trials).

    A candidate scores the targets it misses under both success rules (within ε at T, and within ε at any frame).
    The study is OUT/study.db (SQLite): interrupt it and the same command continues; --candidates is the total the
    study should hold. Writes OUT/settings.toml (for mantaray rig --settings, sim run and sim heatmap),
    report.json (both scores, beside the paper's Manhattan on the same sample) and history.png; the final check's
    trials go to OUT/final/results.jsonl (resumable too), its heatmaps under both rules beside them."""
    import dataclasses

    from . import calibrate as C
    from . import tune as T
    from .experiment import ExperimentMismatch
    from .progress import Progress
    from .results_file import ResultsFileBusy

    at = _fidelity(parser, args.confirm_at) if args.confirm else None
    if at is not None and (at.resolution, at.timestep_s) == (args.resolution, args.timestep):
        parser.error(
            f"--confirm-at {args.confirm_at} is the fidelity the search runs at ({at.label}): confirm at a "
            f"finer one, or search at a cheaper one (--resolution, --timestep)"
        )
    try:
        evidence = T.TuningEvidence(
            controller=args.controller,
            object_name=args.object,
            alpha_m=args.alpha,
            plant=args.plant,
            cells_per_stratum=args.cells_per_stratum,
            trials_per_cell=args.trials_per_cell,
            duration_s=args.duration,
            seed=args.seed,
            resolution=args.resolution,
            timestep_s=args.timestep,
            prune=args.prune,
        )
        evidence.experiment(T.settings_of(args.controller, T.boot_values(args.controller)))  # refuses bad sizes now
        if args.final_trials:
            evidence.final_experiment(
                T.settings_of(args.controller, {}), args.final_trials, args.final_seed, args.final_cells
            )
    except ValueError as exc:
        parser.error(str(exc))
    if args.final_trials and args.final_seed == args.seed:
        parser.error("--final-seed must differ from --seed: the final check must not run the trials the search saw")
    _check_ray(parser, args)
    start = _tuning_start(parser, args, evidence) if args.start_from else None
    out = _output(
        parser, writable_dir, args.out or f"out/tune/{args.object}_{args.controller}_alpha{args.alpha:g}_{args.plant}"
    )
    try:
        study = T.open_tuning(out / "study.db", evidence, args.per_axis, start)
    except (C.StudyMismatch, T.StartMismatch) as exc:
        print(f"mantaray sim tune: {exc}", file=sys.stderr)
        return 2
    confirmed = T.confirmed_at(study)
    if confirmed is not None and (at is None or at.spec != confirmed):
        print(
            f"mantaray sim tune: the study in {out / 'study.db'} answers with candidates confirmed at {confirmed}: "
            f"continue it with --confirm K --confirm-at {confirmed}, or search anew (another --out)",
            file=sys.stderr,
        )
        return 2
    progress = None

    def report_candidate(n: int, total: int, info: dict) -> None:
        note = (
            "the physics diverged: scored the worst"
            if "unstable" in info
            else f"stopped after {info['trials']} trials (within ε at T {info['success']:.2f}, reached "
            f"{info['reached']:.2f})"
            if info.get("pruned")
            else f"misses {info['objectives'][0]:.3f} (within ε at T {info['success']:.2f}, reached "
            f"{info['reached']:.2f}, fell off {info['fell_off']:.2f})"
        )
        progress.update(1, note=note)

    _interruptible()
    final = confirmation = None
    try:
        with _pool(parser, args) as pool:
            baseline = study.user_attrs.get("baseline")
            if baseline is None:  # the paper's Manhattan on the same sample, once per study
                print(
                    "tune: first the paper's Manhattan on the search's sample, what each candidate is measured against",
                    file=sys.stderr,
                    flush=True,
                )
                baseline = evidence.baseline(pool)
                study.set_user_attr("baseline", baseline)
            progress = _candidates(study, out, args.candidates, "tune")  # its rate counts candidates only
            C.run_study(
                study, evidence, T.knobs(args.controller, args.per_axis), {}, args.candidates, pool, report_candidate
            )
            progress.close()
            checked = evidence
            if at is not None:
                print(f"tune: the {args.confirm} best candidates again at {at.label}", file=sys.stderr, flush=True)
                bar = Progress(
                    min(args.confirm, len(C.completed(study))), unit="candidate", label="tune: confirm", line_every_s=0
                )
                confirmation = T.confirm(
                    study,
                    evidence,
                    at,
                    args.confirm,
                    pool,
                    lambda number, score: bar.update(1, note=f"#{number}: misses {score['misses']:.3f}"),
                )
                bar.close()
                checked = dataclasses.replace(evidence, resolution=at.resolution, timestep_s=at.timestep_s)
            best = T.best_settings(study, evidence)
            if args.final_trials and best is not None:
                final_path = out / "final" / "results.jsonl"
                final = T.final_check(
                    checked, best, args.final_trials, args.final_seed, pool, final_path, cells=args.final_cells
                )
                final["figures"] = _final_heatmaps(final_path, args)
    except ExperimentMismatch as exc:
        print(
            f"mantaray sim tune: {exc} (the final check there began with other settings, other --final options or "
            f"on another model: give the same ones to continue it, or delete {out / 'final'} to check anew)",
            file=sys.stderr,
        )
        return 2
    except ResultsFileBusy as exc:
        print(f"mantaray sim tune: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        if progress is not None:
            progress.close()
        T.write_report(study, evidence, out, study.user_attrs.get("baseline"))
        print(
            f"\ninterrupted: {len(C.finished(study))} candidates are in {out / 'study.db'}; the same command "
            f"continues (report so far in {out / 'report.json'})",
            file=sys.stderr,
        )
        return 130
    report = T.write_report(study, evidence, out, baseline, final, confirmation)
    if args.json:
        print(json.dumps(report))
    else:
        best, base = report["best"], report["baseline_on_the_sample"]
        if best is None:  # every candidate diverged
            print(f"{report['candidates']} candidates, none that the physics could run; report {out / 'report.json'}")
            return 1
        line = (
            f"{report['candidates']} candidates; best #{best['number']}: within ε at T {best['success']:.2f}, "
            f"reached {best['reached']:.2f}, fell off {best['fell_off']:.2f} on the search's sample (the paper's "
            f"Manhattan: {base['success']:.2f}, {base['reached']:.2f}, {base['fell_off']:.2f})"
        )
        if final is not None:
            line += (
                f"; full protocol on seed {final['seed']}: score {final['score']:.1f}, reached "
                f"{final['reach_score']:.1f}, fell off {final['fell_off']:.2f}"
            )
        print(line + f"; settings {out / 'settings.toml'}, report {out / 'report.json'}")
    return 0


def _final_heatmaps(path: Path, args: argparse.Namespace) -> list[str]:
    """The final check's heatmaps under both rules (and cells.csv, summary.json) beside its trials, as sim heatmap
    draws them."""
    from .results_file import ResultsFile

    results = ResultsFile.load(path)
    title = (
        f"{args.object}, {args.controller} tuned for the {args.plant} plant, α = {args.alpha:g} m, "
        f"{results.protocol.trials_per_cell} trials/cell, seed {args.final_seed}"
    )
    summary = _heatmap_outputs(results, path.parent, title)
    return [summary["figure"], summary["reach_figure"]]


def _interruptible() -> None:
    """A long run ends as on Ctrl-C (what it did is kept, the same command continues it) on SIGINT, also when
    started in the background, where SIGINT comes ignored, and on SIGTERM (a stopped session's kill)."""
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, _interrupt)


def _interrupt(signum, frame) -> None:
    """SIGTERM as Ctrl-C."""
    raise KeyboardInterrupt


def _fig3_for(best, args: argparse.Namespace, pool, out: Path) -> dict:
    """F6 for the best candidate: the paper's Fig. 3 experiment on it, with its figure."""

    from mantaray.plots import fig3_figure

    from .experiment import Experiment
    from .fig3 import run_fig3
    from .findings import MODULE_M, fig3_finding

    records = run_fig3(
        pool, args.plant, best.user_attrs["values"], resolution=args.resolution, timestep_s=args.timestep
    )
    finding = fig3_finding(records)
    runs: dict[str, list[dict]] = {}
    for r in records:
        runs.setdefault(r["object"], []).append(r)
    figure = fig3_figure(
        runs,
        Experiment.tolerance_m,
        MODULE_M,
        m.Configure.tilt_limit,
        f"Fig. 3 on calibration candidate #{best.number}",
        out / "fig3.png",
    )
    return {"holds": finding.holds, "measured": finding.measured, "figure": str(figure)}


def cmd_fidelity(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """The fidelity gate: does a cheaper physics configuration (the candidate) keep a finer one's trial outcomes?

    It runs one paired sample (a stratified draw of the paper's cells, every controller on each) at the candidate,
    at the finer fidelity, and at the finer one with every start moved 0.1 mm (the noise floor), and tests each
    outcome (within ε at T, reached, fell off, time to reach, final error) for a bias and for more flips than the
    floor. The verdict: the candidate "keeps the finer one's outcomes" or "changes them", with the numbers. Trials
    go to --trials-dir as they finish, shared by every gate that needs the same run: interrupt it and the same
    command continues. --runs compares three existing heatmap results files instead. Exit status: 0 keeps, 1 changes,
    2 a usage error, 3 no verdict (the sample is incomplete, or the physics diverged)."""
    import shlex

    from . import fidelity as G
    from .experiment import ExperimentMismatch
    from .model import SimulationUnstable
    from .progress import Progress
    from .results_file import ResultsFileBusy

    try:
        if args.runs:
            runs = G.load_runs(*args.runs)
            candidate, finer = (G.run_fidelity(getattr(runs[0], n)) for n in ("candidate", "finer"))
            shift_m, sample_text = runs[0].floor.protocol.start_shift_m, f"the runs {', '.join(args.runs)}"
        else:
            candidate, finer = G.parse_fidelity(args.candidate), G.parse_fidelity(args.finer)
            arms = tuple(G.Arm.parse(c) for c in (args.controller or ("manhattan", "euclidean")))
            sample = G.GateSample(
                object_name=args.object,
                plant=args.plant,
                alpha_m=args.alpha,
                arms=arms,
                cells_per_stratum=args.cells_per_stratum,
                trials_per_cell=args.trials_per_cell,
                seed=args.seed,
                duration_s=args.duration,
            )
            shift_m = args.shift
            sample.protocol(arms[0], candidate, shift_m)  # the protocol's own checks, before any work
            runs = G.open_runs(sample, candidate, finer, Path(args.trials_dir), shift_m)
            sample_text = (
                f"{args.object} on the {args.plant} plant, α = {args.alpha:g} m, "
                f"{', '.join(a.label for a in arms)}: {len(sample.cells())} cells "
                f"({args.cells_per_stratum} from each stratum) x {args.trials_per_cell} trials, seed "
                f"{args.seed}, T = {args.duration:g} s"
            )
    except ExperimentMismatch as exc:
        print(
            f"mantaray sim fidelity: {exc} (the gate keeps its runs in --trials-dir {args.trials_dir})", file=sys.stderr
        )
        return 2
    except (ValueError, ResultsFileBusy) as exc:
        print(f"mantaray sim fidelity: {exc}", file=sys.stderr)
        return 2
    if not args.runs:
        left = G.missing_trials(runs)
        total = 3 * sum(len(r.finer.protocol.cell_ids()) * r.finer.protocol.trials_per_cell for r in runs)
        bar = Progress(total, initial=total - left, unit="trial", label="fidelity")
        _interruptible()
        try:
            G.run_missing(runs, _jobs(parser, args.jobs), on_record=lambda record: bar.update(1))
        except KeyboardInterrupt:
            bar.close()
            print(
                f"\ninterrupted: the finished trials are in {args.trials_dir}; the same command continues",
                file=sys.stderr,
            )
            return 130
        except SimulationUnstable as exc:
            bar.close()
            print(f"mantaray sim fidelity: {exc}; the finished trials are kept in {args.trials_dir}", file=sys.stderr)
            return 3
        bar.close()
    try:
        report = G.compare(runs)
    except G.GateMismatch as exc:
        print(f"mantaray sim fidelity: {exc}", file=sys.stderr)
        return 2
    report.update(
        candidate=candidate.label,
        finer=finer.label,
        shift_m=shift_m,
        sample_text=sample_text,
        command=shlex.join(["mantaray", *sys.argv[1:]]),
    )
    p = runs[0].finer.protocol
    out = _output(
        parser,
        writable_dir,
        args.out or f"out/fidelity/{p.object_name}_{p.plant}_alpha{p.alpha_m:g}_{candidate.slug}_vs_{finer.slug}",
    )
    paths = G.write_report(report, out)
    if args.json:
        print(json.dumps(report))
    elif report["verdict"] is None:
        print(
            f"{candidate.label} against {finer.label}: incomplete ({report['pairs']} of {report['expected_pairs']} "
            f"paired trials); {paths[1]}"
        )
    else:
        print(
            f"{candidate.label} {report['verdict']} of {finer.label} ({report['pairs']} paired trials)"
            + "".join(f"\n  {c}" for c in report["changed"])
            + f"\n{paths[1]}"
        )
    return {G.KEEPS: 0, G.CHANGES: 1}.get(report["verdict"], 3)


def _fidelity(parser: argparse.ArgumentParser, text: str):
    """A fidelity argument (fast, reference, RESOLUTION:TIMESTEP); a bad one is a usage error."""
    from .fidelity import parse_fidelity

    try:
        return parse_fidelity(text)
    except ValueError as exc:
        parser.error(str(exc))


def _jobs(parser: argparse.ArgumentParser, jobs: int | None) -> int:
    """--jobs as given, else every core."""
    return jobs or os.cpu_count() or 1


def _add_fidelity_arguments(parser: argparse.ArgumentParser) -> None:
    """--resolution and --timestep, defaulting to the named fidelity the searches and maps run in (sim/rig.py)."""
    from .rig import DEFAULT_FIDELITY, FIDELITIES

    named = ", ".join(f"{name} {f.label}" for name, f in FIDELITIES.items())
    parser.add_argument(
        "--resolution",
        type=int,
        default=DEFAULT_FIDELITY.resolution,
        help=f"fabric vertices per side (odd); the named fidelities: {named}",
    )
    parser.add_argument("--timestep", type=float, default=DEFAULT_FIDELITY.timestep_s, help="physics step [s]")


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register `sim` and its subcommands on the top-level parser's subparsers."""
    sim = sub.add_parser(
        "sim",
        help="the MuJoCo rig with the firmware in the loop",
        description="The simulated MANTA-RAY: the native firmware drives a MuJoCo model of the rig "
        "over a virtual serial port, through the same protocol as the hardware.",
    )
    sim_sub = sim.add_subparsers(dest="sim_command", metavar="SUBCOMMAND")
    run = sim_sub.add_parser(
        "run",
        help="one target-reaching trial (the main job)",
        description=cmd_run.__doc__
        + (
            " Exit status 0 when the object ends within the tolerance, 1 when it does not, 2 on bad arguments. "
            "Writes the trajectory plot (paper Fig. 3 style), the trajectory (.npz) and, on request, a video."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    run.add_argument("--object", choices=sorted(OBJECTS), default="sphere", help="the paper's object (Table I)")
    add_controller_arguments(run)
    run.add_argument("--start", type=_point, default=(0.05, -0.05), metavar="X,Y", help="object start [m]")
    run.add_argument("--target", type=_point, default=(-0.05, 0.05), metavar="X,Y", help="target p_d [m]")
    run.add_argument("--duration", type=float, default=10.0, help="runtime T [s]; success is judged at its end")
    run.add_argument("--seed", type=int, default=1, help="seed of the actuator noise and the camera model")
    run.add_argument(
        "--alpha",
        type=float,
        default=0.0,
        help=f"noise amplitude α [m], {bounds_text(m.Configure, 'noise_amplitude')} (paper: 0.1 cube, 0.05 bunny)",
    )
    run.add_argument("--tolerance", type=float, default=0.02, help=f"ε [m], {bounds_text(m.Configure, 'tolerance')}")
    run.add_argument(
        "--gains",
        type=parse_gains,
        metavar="KP,KI,KD[,ILIM]",
        help="PID gains for the controller's axes [deg/m, deg/(m s), deg s/m, deg]; default the paper's",
    )
    run.add_argument(
        "--plant",
        choices=plant_names(),
        help="the simulated plant (sim/plant.toml): its parameters, camera latency and readings "
        f"(default: the one --settings was tuned for, else {DEFAULT_PLANT})",
    )
    run.add_argument("--rate", type=float, help="camera rate [Hz] (default the plant's: the paper's 12)")
    run.add_argument("--latency", type=float, help="camera latency [s], below one frame period (default the plant's)")
    run.add_argument("--noise", type=float, default=0.0, help="camera noise, standard deviation [m] per axis")
    run.add_argument("--drop", type=float, default=0.0, help="share of camera frames lost [0..1)")
    run.add_argument(
        "--vision",
        choices=VISION_MODES,
        help="positions from the host's tracker on rendered "
        "1280x720 overhead frames (ArUco marker on the object, or colour blob) instead of the truth",
    )
    run.add_argument("--out", default="out/sim", help="directory for the figure, trajectory and video")
    run.add_argument("--json", action="store_true", help="print one JSON object instead of the sentence")
    run.add_argument("--video", action="store_true", help="also render an MP4 from the overhead camera")
    run.add_argument("--video-fps", type=float, default=30.0, help="video frame rate [1/s]")
    run.add_argument(
        "--port",
        help="serial device path of a firmware to use instead of starting the virtual MCU "
        "(a simulated-clock firmware runs in lock-step; a board needs --realtime)",
    )
    run.add_argument(
        "--realtime", action="store_true", help="run in real time against a wall-clock virtual MCU instead of lock-step"
    )
    run.add_argument(
        "--viewer",
        action="store_true",
        help="show the MuJoCo viewer (needs a display; implies "
        "nothing about pacing: add --realtime to watch at real speed)",
    )
    run.set_defaults(func=lambda args: cmd_run(args, run))

    heat = sim_sub.add_parser(
        "heatmap",
        help="the paper's success heatmap (Fig. 2) over the workspace",
        description=cmd_heatmap.__doc__,
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    heat.add_argument("--object", choices=sorted(OBJECTS), default="sphere", help="the paper's object (Table I)")
    add_controller_arguments(heat)
    heat.add_argument("--cells", type=int, default=20, help="cells per side of the workspace (paper: 20)")
    heat.add_argument("--trials", type=int, default=10, help="trials per cell, N (paper: 10)")
    heat.add_argument("--tolerance", type=float, default=0.02, help=f"ε [m], {bounds_text(m.Configure, 'tolerance')}")
    heat.add_argument("--duration", type=float, default=10.0, help="runtime T [s] (paper: 10)")
    heat.add_argument(
        "--alpha",
        type=float,
        default=0.0,
        help=f"noise amplitude α [m], {bounds_text(m.Configure, 'noise_amplitude')} (paper: 0.1 cube, 0.05 bunny)",
    )
    heat.add_argument(
        "--gains",
        type=parse_gains,
        metavar="KP,KI,KD[,ILIM]",
        help="PID gains for the controller's axes [deg/m, deg/(m s), deg s/m, deg]; default the paper's",
    )
    heat.add_argument("--seed", type=int, default=2026, help="seed of the whole run: starts, targets and noise")
    heat.add_argument(
        "--plant",
        choices=plant_names(),
        help=f"the simulated plant (sim/plant.toml) (default: the one --settings was tuned for, else {DEFAULT_PLANT})",
    )
    heat.add_argument(
        "--stop-when-reached",
        action="store_true",
        help="end each trial at its first frame within ε, as the paper's loop does: faster, and the map "
        "under the paper's stopping rule is the same, but 'ends within ε at T' is then not measured",
    )
    _add_fidelity_arguments(heat)
    heat.add_argument("--only-cells", type=_cells, metavar="I,J,...", help="run only these cells (index ix + iy*cells)")
    heat.add_argument(
        "--jobs", type=int, help="parallel workers (default: every core; with ray: every CPU of the cluster)"
    )
    heat.add_argument(
        "--executor",
        choices=["local", "ray"],
        default="local",
        help="local processes, or Ray actors (a local Ray instance, or --ray-address)",
    )
    heat.add_argument("--ray-address", help="address of a running Ray cluster (e.g. ray://head:10001)")
    heat.add_argument(
        "--out",
        help="directory for results.jsonl, cells.csv, summary.json, heatmap.png and heatmap_reach.png (the paper's stopping rule) "
        "(default out/heatmap/OBJECT_CONTROLLER_alphaA, with _PLANT for a plant other than polyester)",
    )
    heat.add_argument(
        "--json", action="store_true", help="print the summary as JSON on stdout (progress stays on stderr)"
    )
    heat.set_defaults(func=lambda args: cmd_heatmap(args, heat))

    cal = sim_sub.add_parser(
        "calibrate",
        help="fit the plant to the paper's findings or to rig logs (Optuna, resumable)",
        description=cmd_calibrate.__doc__,
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    cal.add_argument(
        "--out",
        help="directory for study.db, report.md, report.json, pareto.png "
        "(default out/calibration/findings, or out/calibration/log with --log)",
    )
    cal.add_argument(
        "--candidates",
        type=int,
        default=100,
        help="candidates the study should hold when done (0: only write the report)",
    )
    cal.add_argument(
        "--params",
        metavar="KEY,KEY",
        help="search only these parameters (keys of sim/plant.toml; default every one declared search = true)",
    )
    cal.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="fix a parameter (checked against its declared range); repeatable",
    )
    cal.add_argument("--plant", choices=plant_names(), default=DEFAULT_PLANT, help="the plant the values are set over")
    cal.add_argument(
        "--log",
        action="append",
        metavar="RUN.jsonl",
        help="fit to this rig log (mantaray rig's output) instead of the findings; repeatable",
    )
    cal.add_argument("--object", choices=sorted(OBJECTS), default="sphere", help="the object of the rig logs")
    cal.add_argument("--horizon", type=float, help="with --log: compare only the first HORIZON seconds of each run")
    cal.add_argument(
        "--cells-per-stratum",
        type=int,
        default=4,
        help="cells drawn from each of centre, axes, diagonals, edges and corners",
    )
    cal.add_argument("--trials-per-cell", type=int, default=3)
    cal.add_argument("--duration", type=float, default=10.0, help="runtime T [s] (paper: 10)")
    cal.add_argument(
        "--seed",
        type=int,
        default=12,
        help="seed of the search and its trials (the heatmaps judged afterwards use another)",
    )
    _add_fidelity_arguments(cal)
    cal.add_argument("--fig3", action="store_true", help="also run the paper's Fig. 3 experiment (F6) on the best")
    cal.add_argument("--jobs", type=int, help="parallel workers (default: every core; with ray: every CPU)")
    cal.add_argument("--executor", choices=["local", "ray"], default="local")
    cal.add_argument("--ray-address", help="address of a running Ray cluster")
    cal.add_argument(
        "--json", action="store_true", help="print the report as JSON on stdout (progress stays on stderr)"
    )
    cal.set_defaults(func=lambda args: cmd_calibrate(args, cal))

    tune = sim_sub.add_parser(
        "tune",
        help="tune a controller's settings for a plant (Optuna, resumable)",
        description=cmd_tune.__doc__,
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    tune.add_argument(
        "--controller",
        choices=choices(m.Controller),
        default="scheduled",
        help="the controller whose settings are searched (sim/tune.py, SPACE, says which)",
    )
    tune.add_argument(
        "--per-axis",
        action="store_true",
        help="search each PID's gains on its own (x and y apart) instead of one set for all: for a rig "
        "that is not symmetric",
    )
    tune.add_argument("--object", choices=sorted(OBJECTS), default="sphere", help="the paper's object (Table I)")
    tune.add_argument(
        "--alpha",
        type=float,
        default=0.0,
        help=f"noise amplitude α [m], {bounds_text(m.Configure, 'noise_amplitude')} (paper: 0.1 cube, 0.05 bunny)",
    )
    tune.add_argument("--plant", choices=plant_names(), default="paper", help="the plant to tune for (sim/plant.toml)")
    tune.add_argument(
        "--start-from",
        metavar="FILE",
        help="a settings file of the same controller (say, tuned for another object) to try second, "
        "after the boot values, so the search starts from what is known; for a new study only",
    )
    tune.add_argument(
        "--candidates",
        type=number(1, integer=True),
        default=60,
        help="candidates the study should hold when done (a resumed search goes on to this total)",
    )
    tune.add_argument(
        "--cells-per-stratum",
        type=number(1, integer=True),
        default=4,
        help="cells drawn from each of centre, axes, diagonals, edges and corners",
    )
    tune.add_argument("--trials-per-cell", type=number(1, integer=True), default=3)
    tune.add_argument(
        "--confirm",
        type=number(0, integer=True),
        default=0,
        metavar="K",
        help="after the search, score its K best candidates again on the same sample at --confirm-at, "
        "and take the best there: a search screened at a cheaper fidelity answers at the finer one "
        "(the report gives the rank correlation of the two scores; 0: no confirmation)",
    )
    tune.add_argument(
        "--confirm-at",
        default="reference",
        metavar="FIDELITY",
        help="the fidelity of the confirmation and of the final check: fast, reference or RESOLUTION:TIMESTEP",
    )
    tune.add_argument(
        "--prune",
        action="store_true",
        help="score each candidate a rung of the sample at a time (1, 2, 4 ... cells per stratum, the same "
        "for every candidate) and stop one whose misses are not among the better half at a rung "
        "(Optuna's successive halving): more candidates for the same trials; --candidates then "
        "counts the stopped ones too",
    )
    tune.add_argument("--duration", type=float, default=10.0, help="runtime T [s] (paper: 10)")
    tune.add_argument("--seed", type=number(0, integer=True), default=31, help="seed of the search and its sample")
    tune.add_argument(
        "--final-trials",
        type=number(0, integer=True),
        default=10,
        help="trials per cell of the final check on the full protocol (paper: 10; 0: no final check)",
    )
    tune.add_argument(
        "--final-cells",
        type=number(1, integer=True),
        default=20,
        help="cells per side of the final check's workspace (paper: 20)",
    )
    tune.add_argument(
        "--final-seed",
        type=number(0, integer=True),
        default=2026,
        help="seed of the final check (the paper protocol's; never the search's)",
    )
    _add_fidelity_arguments(tune)
    tune.add_argument(
        "--out",
        help="directory for study.db, settings.toml, report.json, history.png and final/ "
        "(default out/tune/OBJECT_CONTROLLER_alphaA_PLANT)",
    )
    tune.add_argument(
        "--jobs", type=number(1, integer=True), help="parallel workers (default: every core; ray: every CPU)"
    )
    tune.add_argument("--executor", choices=["local", "ray"], default="local")
    tune.add_argument("--ray-address", help="address of a running Ray cluster")
    tune.add_argument(
        "--json", action="store_true", help="print the report as JSON on stdout (progress stays on stderr)"
    )
    tune.set_defaults(func=lambda args: cmd_tune(args, tune))

    gate = sim_sub.add_parser(
        "fidelity",
        help="the fidelity gate: does a cheaper physics keep a finer one's outcomes",
        description=cmd_fidelity.__doc__,
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    gate.add_argument(
        "--candidate",
        default="fast",
        help="the configuration under test: fast, reference, or "
        "RESOLUTION:TIMESTEP [vertices per side : s] (like 15:0.002)",
    )
    gate.add_argument("--finer", default="reference", help="the configuration whose outcomes it must keep")
    gate.add_argument("--object", choices=sorted(OBJECTS), default="sphere", help="the paper's object (Table I)")
    gate.add_argument("--plant", choices=plant_names(), default=DEFAULT_PLANT, help="the plant (sim/plant.toml)")
    gate.add_argument(
        "--alpha", type=float, default=0.0, help=f"noise amplitude α [m], {bounds_text(m.Configure, 'noise_amplitude')}"
    )
    gate.add_argument(
        "--controller",
        action="append",
        metavar="NAME|FILE",
        help="a controller with its boot values, or a settings file (TOML, as mantaray sim tune writes); "
        "repeatable (default: manhattan and euclidean)",
    )
    gate.add_argument(
        "--cells-per-stratum",
        type=number(1, integer=True),
        default=8,
        help="cells drawn from each of centre, axes, diagonals, edges and corners",
    )
    gate.add_argument("--trials-per-cell", type=number(1, integer=True), default=5)
    gate.add_argument("--seed", type=number(0, integer=True), default=77, help="seed of the sample's cells and trials")
    gate.add_argument("--duration", type=float, default=10.0, help="runtime T [s]; every trial runs to its end")
    gate.add_argument("--shift", type=float, default=1e-4, help="[m] how far the noise floor's run moves every start")
    gate.add_argument(
        "--runs",
        nargs=3,
        metavar=("CANDIDATE", "FINER", "FLOOR"),
        help="compare three existing results files (the floor: the finer run with its starts moved) "
        "instead of running the sample",
    )
    gate.add_argument("--jobs", type=number(1, integer=True), help="parallel workers (default: every core)")
    gate.add_argument(
        "--trials-dir",
        default="out/fidelity/trials",
        help="where each run keeps its trials (one results file per controller, fidelity and shift)",
    )
    gate.add_argument(
        "--out",
        help="directory for report.json and report.md (default out/fidelity/OBJECT_PLANT_alphaA_CANDIDATE_vs_FINER)",
    )
    gate.add_argument(
        "--json", action="store_true", help="print the report as JSON on stdout (progress stays on stderr)"
    )
    gate.set_defaults(func=lambda args: cmd_fidelity(args, gate))

    compare = sim_sub.add_parser(
        "compare",
        help="difference map of two heatmap runs (first minus second)",
        description=cmd_compare.__doc__,
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    compare.add_argument("first", help="results.jsonl of a heatmap run, or its directory")
    compare.add_argument("second", help="the run to subtract")
    compare.add_argument("--out", default="out/heatmap/difference.png", help="figure to write")
    compare.add_argument(
        "--reached",
        action="store_true",
        help="compare the rates of reaching ε at any frame (the paper's stopping rule) instead of ending within ε at T",
    )
    compare.set_defaults(func=lambda args: cmd_compare(args, compare))
    sim.set_defaults(func=lambda args: (sim.print_help(), 2)[1])
