"""`mantaray sim fidelity`: the fidelity gate, does a cheaper physics keep a finer one's outcomes."""

from __future__ import annotations

import argparse
import json
import signal
import sys
from pathlib import Path

from mantaray.outputs import writable_dir

from .cli_common import interruptible, output, workers


def run(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """`sim fidelity`: the paired sample run (or --runs loaded), compared, and the verdict as the exit status."""
    import shlex

    from . import fidelity as G
    from .experiment import ExperimentMismatch
    from .model import SimulationUnstable
    from .results_file import ResultsFileBusy

    try:
        sample, runs, candidate, finer, shift_m, sample_text = _gate(args)
    except ExperimentMismatch as exc:
        return _refused(f"{exc} (the gate keeps its runs in --trials-dir {args.trials_dir})")
    except (ValueError, ResultsFileBusy) as exc:
        return _refused(str(exc))
    try:
        interrupted = sample is not None and not _run_missing(sample, runs, args.jobs)
    except SimulationUnstable as exc:
        return _refused(f"{exc}; the finished trials are kept in {args.trials_dir}", 3)
    try:
        report = G.compare(runs)
    except G.GateMismatch as exc:
        return _refused(str(exc))
    report.update(
        candidate=candidate.label,
        finer=finer.label,
        shift_m=shift_m,
        sample_text=sample_text,
        command=shlex.join(["mantaray", *sys.argv[1:]]),
    )
    p = runs[0].finer.experiment
    out = output(
        parser,
        writable_dir,
        args.out
        or f"out/fidelity/{p.object_name}_{p.plant}{G.fixed_slug(p.plant_set)}_alpha{p.alpha_m:g}"
        f"_{candidate.slug}_vs_{finer.slug}",
    )
    paths = G.write_report(report, out)
    if interrupted:
        print(
            f"\ninterrupted: the finished trials are in {args.trials_dir}, the report of the {report['pairs']} "
            f"paired so far in {paths[1]}; the same command continues",
            file=sys.stderr,
        )
        return 130
    print(json.dumps(report) if args.json else _verdict_line(report, candidate, finer, paths[1]))
    return {G.KEEPS: 0, G.CHANGES: 1}.get(report["verdict"], 3)


def _gate(args: argparse.Namespace):
    """(sample, runs, candidate, finer, shift [m], the sample in words) from the arguments: the three runs of each arm
    opened, or with --runs the three files loaded (sample None: nothing to run). ValueError for a bad argument."""
    from . import fidelity as G

    if args.runs:
        runs = G.load_runs(*args.runs)
        candidate, finer = (G.run_fidelity(getattr(runs[0], n)) for n in ("candidate", "finer"))
        return None, runs, candidate, finer, runs[0].floor.experiment.start_shift_m, f"the runs {', '.join(args.runs)}"
    candidate, finer = G.parse_fidelity(args.candidate), G.parse_fidelity(args.finer)
    arms = tuple(G.Arm.parse(c) for c in (args.controller or ("manhattan", "euclidean")))
    sample = G.GateSample(
        object_name=args.object,
        plant=args.plant,
        plant_set=tuple(sorted(args.set)),  # the same values given in any order name the same runs
        alpha_m=args.alpha,
        arms=arms,
        cells_per_stratum=args.cells_per_stratum,
        trials_per_cell=args.trials_per_cell,
        seed=args.seed,
        duration_s=args.duration,
    )
    sample.experiment(arms[0], candidate, args.shift)  # the protocol's own checks, before any work
    runs = G.open_runs(sample, candidate, finer, Path(args.trials_dir), args.shift)
    text = (
        f"{args.object} on the {sample.plant_label} plant, α = {args.alpha:g} m, "
        f"{', '.join(a.label for a in arms)}: {len(sample.cells())} cells "
        f"({args.cells_per_stratum} from each stratum) x {args.trials_per_cell} trials, seed "
        f"{args.seed}, T = {args.duration:g} s"
    )
    return sample, runs, candidate, finer, args.shift, text


def _run_missing(sample, runs: list, jobs: int | None) -> bool:
    """Every arm's missing trials run, with progress; False if interrupted (what finished is kept)."""
    from . import fidelity as G
    from .progress import Progress

    left = G.missing_trials(runs)
    total = 3 * sum(len(r.finer.experiment.cell_ids()) * r.finer.experiment.trials_per_cell for r in runs)
    bar = Progress(total, initial=total - left, unit="trial", label="fidelity")
    interruptible()
    try:
        G.run_missing(sample, runs, workers(jobs), on_record=lambda record: bar.update(1))
    except KeyboardInterrupt:  # the trials paired so far still get their report (a few seconds: a second Ctrl-C,
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # or one forwarded by a driver, must not cut it), no verdict
        return False
    finally:
        bar.close()
    return True


def _refused(why: str, status: int = 2) -> int:
    print(f"mantaray sim fidelity: {why}", file=sys.stderr)
    return status


def _verdict_line(report: dict, candidate, finer, path) -> str:
    if report["verdict"] is None:
        return (
            f"{candidate.label} against {finer.label}: incomplete ({report['pairs']} of {report['expected_pairs']} "
            f"paired trials); {path}"
        )
    return (
        f"{candidate.label} {report['verdict']} of {finer.label} ({report['pairs']} paired trials)"
        + "".join(f"\n  {c}" for c in report["changed"])
        + f"\n{path}"
    )
