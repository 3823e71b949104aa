"""`mantaray sim replay`: one trial of a results file run again, exactly, as a recording (and live) for the viewer."""

from __future__ import annotations

import argparse
from pathlib import Path

from mantaray.arguments import reporter
from mantaray.host.cli_view import start_live
from mantaray.outputs import writable_dir

from .common import load_results, output

OUTCOME = ("success", "reached", "fell_off", "final_error_m", "time_to_reach_s")  # what a replay must give again


def run(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """`sim replay`: the trial found by cell and number, run in this process with its view, compared."""
    from ..evaluation.executors import TrialRunner, Watch
    from ..model.model import SimulationUnstable

    results = load_results(parser, args.results, "replay")
    trial = _trial(parser, args, results)
    out = output(parser, writable_dir, args.out or str(results.path.parent))
    stem = results.path.name.removesuffix(".gz").removesuffix(".jsonl")
    recording = Path(out) / f"{stem}_cell{trial.cell}_trial{trial.k}.rrd"
    live = start_live(parser, args, _report)
    try:
        if live is not None:
            _report(f"live view at {live.options.page_url}")
        runner = TrialRunner(results.experiment, Watch(None if live is None else live.options.grpc_url, recording))
        try:
            record = runner.run(trial)
        except SimulationUnstable as exc:
            _report(f"{exc}; the trial could not be replayed")
            return 1
        if live is not None:
            live.linger(args.linger, _report)
    finally:
        if live is not None:
            live.close()
    stored = results.records.get(trial.key)
    verdict = _verdict(stored, record)
    if record.get("final_error_m") is None:  # a start not over the fabric: nothing ran, nothing was recorded
        print(
            f"cell {trial.cell}, trial {trial.k}: its start is not over the fabric, so it counts as fallen off "
            f"({verdict}); there is nothing to record"
        )
        return 0 if stored is None or verdict.startswith("as") else 1
    outcome = "fell off" if record["fell_off"] else ("success" if record["success"] else "not within ε at T")
    where = f"recording {recording} (open it with: rerun {recording})" if recording.exists() else "no recording"
    print(
        f"cell {trial.cell}, trial {trial.k}: {outcome}, final error {record['final_error_m'] * 100:.1f} cm "
        f"({verdict}); {where}"
    )
    return 0 if stored is None or verdict.startswith("as") else 1


_report = reporter("sim replay")


def _trial(parser: argparse.ArgumentParser, args: argparse.Namespace, results):
    """The trial --cell and --trial name, of a results file this checkout's model would replay the same."""
    from ..evaluation.experiment import trials
    from ..model.mjcf import model_identity

    experiment = results.experiment
    cells = experiment.cell_ids()
    if args.cell not in cells:
        parser.error(f"--cell {args.cell} is not a cell of this run (it has cells {cells[0]}..{cells[-1]})")
    if args.trial >= experiment.trials_per_cell:
        parser.error(f"--trial {args.trial}: this run has trials 0..{experiment.trials_per_cell - 1} in each cell")
    if results.model is not None and results.model != model_identity(experiment.rig()):
        parser.error(
            f"{results.path} was run on another model ({results.model}); this checkout's would not replay its "
            f"trials the same: check out the version that ran it"
        )
    (trial,) = [t for t in trials(experiment) if (t.cell, t.k) == (args.cell, args.trial)]
    return trial


def _verdict(stored: dict | None, record: dict) -> str:
    """How the replay's outcome compares with the results file's."""
    if stored is None:
        return "not in the results file yet"
    differ = [k for k in OUTCOME if stored.get(k) != record.get(k)]
    return "as the results file has it" if not differ else f"unlike the results file in {', '.join(differ)}"
