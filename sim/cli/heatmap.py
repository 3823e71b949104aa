"""`mantaray sim heatmap`: the paper's success map (Fig. 2), and the files it is written to."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from mantaray.arguments import reporter
from mantaray.host.cli_controller import controller_settings
from mantaray.host.cli_view import start_live
from mantaray.outputs import writable_dir

from ..model.plant import DEFAULT_PLANT
from .common import check_ray, interruptible, output, plant_for_settings, workers


def run(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """`sim heatmap`: the protocol checked, its results file opened or continued, the missing trials run."""
    from ..evaluation.executors import RayUnavailable, run
    from ..evaluation.progress import Progress
    from ..model.model import SimulationUnstable

    experiment = _experiment(args, parser)
    check_ray(parser, args)
    out = output(parser, writable_dir, args.out or _default_out(args, experiment))
    opened = _results_file(out / "results.jsonl", experiment)
    if opened is None:
        return 2
    results, todo, total = opened
    live = _live(parser, args)
    bar = Progress(total, initial=total - len(todo), unit="trial", label="heatmap")  # on stderr, beside --json
    interruptible()
    try:
        for batch in _rounds(experiment, results, todo, bar):
            run(results, _records(args, experiment, batch, live), progress=lambda record: bar.update(1))
        if live is not None:
            live.linger(args.linger, _report)
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
        _report(f"{exc}; the {len(results.records)} finished trials are kept in {out / 'results.jsonl'}")
        return 1
    except RayUnavailable as exc:
        bar.close()
        _report(str(exc))
        return 2
    finally:
        if live is not None:
            live.close()
    bar.close()
    _write_outputs(args, experiment, results, out)
    return 0


def _rounds(experiment, results, todo: list, bar):
    """The missing trials to run, in one go; for an adaptive run round by round (sim/evaluation/adaptive.py), each round's
    open cells found from the trials before it, and the bar's total from the cells still open."""
    if not experiment.adaptive:
        yield todo
        return
    from ..evaluation.adaptive import open_cells, trials_left

    for r in range(experiment.trials_per_cell):
        cells = open_cells(experiment.cell_ids(), results.records, experiment.trials_per_cell, r)
        later = sum(1 for record in results.records.values() if record["k"] >= r)
        bar.set_total(len(results.records) - later + trials_left(cells, experiment.trials_per_cell, r))
        keep = set(cells)
        yield [t for t in results.missing() if t.k == r and t.cell in keep]


def _live(parser: argparse.ArgumentParser, args: argparse.Namespace):
    """The live view's server when --live asks for one, else None."""
    live = start_live(parser, args, _report)
    if live is not None:
        _report(f"live view of one worker's trials at {live.options.page_url}")
    return live


def _results_file(path: Path, experiment):
    """(the run's results file, its missing trials, the run's trial count): the file opened or continued (what it
    holds reported on stderr), or None where it cannot be (another experiment's, unreadable, or in use: said in one
    line)."""
    from ..evaluation.experiment import ExperimentMismatch
    from ..evaluation.results_file import ResultsFile, ResultsFileBusy

    try:
        results = ResultsFile.open(path, experiment)
    except (ExperimentMismatch, ValueError, ResultsFileBusy) as exc:
        _report(str(exc))
        return None
    for warning in results.warnings():
        _report(f"warning: {warning}")
    todo, total = results.missing(), len(experiment.cell_ids()) * experiment.trials_per_cell
    if len(todo) < total:
        print(f"continuing {path}: {total - len(todo)} of {total} trials already done", file=sys.stderr)
    return results, todo, total


def _write_outputs(args: argparse.Namespace, experiment, results, out: Path) -> None:
    """The map, its figure and summary written to out, and the summary (or --json) printed."""
    from ..evaluation.summary import heatmap_outputs

    title = (
        f"{args.object}, {experiment.controller}, α = {args.alpha:g} m, ε = {args.tolerance:g} m, T = {args.duration:g} s, "
        + (
            f"adaptive, at most {experiment.trials_per_cell}"
            if experiment.adaptive
            else f"{experiment.trials_per_cell}"
        )
        + " trials/cell"
    )
    summary = heatmap_outputs(results, out, title)
    print(json.dumps(summary) if args.json else _summary_line(args, experiment, summary, out))


def _experiment(args: argparse.Namespace, parser: argparse.ArgumentParser):
    """The experiment the arguments describe; a usage error for one that cannot be."""
    from ..evaluation.experiment import Experiment

    if args.live and args.executor == "ray":
        parser.error("--live shows the trial of a worker of this machine: use it with --executor local")

    settings = controller_settings(parser, args)
    try:
        return Experiment(
            object_name=args.object,
            controller=settings.controller,
            cells=args.cells,
            trials_per_cell=args.trials,
            tolerance_m=args.tolerance,
            duration_s=args.duration,
            alpha_m=args.alpha,
            seed=args.seed,
            resolution=args.resolution,
            timestep_s=args.timestep,
            only_cells=args.only_cells,
            plant=plant_for_settings(parser, settings, args.plant),
            plant_set=tuple(sorted(args.set)),
            stop_when_reached=args.stop_when_reached,
            settings=settings.values,
            adaptive=args.adaptive,
        )
    except ValueError as exc:
        parser.error(str(exc))


def _default_out(args: argparse.Namespace, experiment) -> str:
    """out/heatmap/ and a name for what the map is of: object, controller (or settings file), α and plant."""
    from ..evaluation.fidelity import fixed_slug

    plant = ("" if experiment.plant == DEFAULT_PLANT else f"_{experiment.plant}") + fixed_slug(experiment.plant_set)
    tuned = f"_{Path(args.settings).stem}" if args.settings else ""
    adaptive = "_adaptive" if experiment.adaptive else ""
    return f"out/heatmap/{args.object}_{experiment.controller}{tuned}_alpha{args.alpha:g}{plant}{adaptive}"


def _records(args: argparse.Namespace, experiment, todo: list, live):
    """The missing trials' records as they finish, on this machine's workers (one of them shown live) or on Ray."""
    from ..evaluation.executors import Watch, run_local, run_ray

    if args.executor == "ray":
        return run_ray(experiment, todo, args.jobs, args.ray_address)
    return run_local(experiment, todo, workers(args.jobs), None if live is None else Watch(live.options.grpc_url))


def _summary_line(args: argparse.Namespace, experiment, summary: dict, out: Path) -> str:
    cells = len(experiment.cell_ids())
    return (
        f"{args.object}, {experiment.controller}: score {summary['score']:.1f} of {cells} cells "
        f"(within ε at any frame: {summary['reach_score']:.1f}); regions: "
        + ", ".join(f"{name} {r['cells']} cells ({r['area_m2']:.4f} m²)" for name, r in summary["regions"].items())
        + (
            f"; adaptive: {summary['trials']} of {cells * experiment.trials_per_cell} trials"
            if experiment.adaptive
            else ""
        )
        + f"; {out}/results.jsonl, cells.csv, summary.json, heatmap.png"
    )


_report = reporter("sim heatmap")
