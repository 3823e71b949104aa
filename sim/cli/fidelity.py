"""`mantaray sim fidelity`: the fidelity gate, does a cheaper physics give a finer one's answers."""

from __future__ import annotations

import argparse
import json
import signal
import sys
from pathlib import Path

from mantaray.outputs import writable_dir

from .common import interruptible, output, workers


def run(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """`sim fidelity`: the paired sample run (or --runs loaded), compared, grown while undecided with
    --until-decided, and the verdict as the exit status."""
    import shlex

    from ..evaluation import fidelity as G
    from ..evaluation.experiment import ExperimentMismatch
    from ..evaluation.results_file import ResultsFileBusy
    from ..model.model import SimulationUnstable

    try:
        sample, runs, candidate, finer, sample_text = _gate(args)
        sample, runs, report, interrupted = _compared(args, sample, runs, candidate, finer)
    except ExperimentMismatch as exc:
        return _refused(f"{exc} (the gate keeps its runs in --trials-dir {args.trials_dir})")
    except (ValueError, ResultsFileBusy) as exc:  # a GateMismatch is a ValueError too
        return _refused(str(exc))
    except SimulationUnstable as exc:
        return _refused(f"{exc}; the finished trials are kept in {args.trials_dir}", 3)
    report.update(
        candidate=candidate.label,
        finer=finer.label,
        sample_text=sample_text if sample is None else _described(sample),
        command=shlex.join(["mantaray", *sys.argv[1:]]),
    )
    out = _out_dir(parser, args, runs, candidate, finer)
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


def _compared(args: argparse.Namespace, sample, runs, candidate, finer):
    """(sample, runs, report, interrupted): the missing trials run and compared, and with --until-decided the sample
    grown and run again while the verdict is undecided and a larger one can decide it."""
    from ..evaluation import fidelity as G

    while True:
        interrupted = (
            sample is not None
            and not args.report_only
            and not _run_missing(sample, runs, args.jobs, args.candidate_only)
        )
        report = G.compare(runs)
        if (
            interrupted
            or sample is None
            or args.report_only
            or not args.until_decided
            or report["verdict"] != G.UNDECIDED
        ):
            break
        more = G.grown(sample, report["pairs_to_decide"], args.max_pairs)
        if isinstance(more, str):
            print(f"undecided at {report['pairs']} paired trials, and it stays so: {more}", file=sys.stderr)
            break
        print(
            f"undecided at {min(report['pairs_per_arm'].values())} pairs per controller: growing the sample to "
            f"{more.trials_per_cell} trials per cell ({len(more.cells()) * more.trials_per_cell} pairs)",
            file=sys.stderr,
            flush=True,
        )
        sample = more
        runs = G.open_runs(sample, candidate, finer, Path(args.trials_dir), _shifts(args))
    return sample, runs, report, interrupted


def _out_dir(parser: argparse.ArgumentParser, args: argparse.Namespace, runs, candidate, finer) -> Path:
    """--out, else out/fidelity/ named by the sample's object, plant, alpha and the two fidelities."""
    from ..evaluation import fidelity as G

    p = runs[0].finer.experiment
    return output(
        parser,
        writable_dir,
        args.out
        or f"out/fidelity/{p.object_name}_{p.plant}{G.fixed_slug(p.plant_set)}_alpha{p.alpha_m:g}"
        f"_{candidate.slug}_vs_{finer.slug}",
    )


def _shifts(args: argparse.Namespace) -> tuple[float, ...]:
    from ..evaluation import fidelity as G

    return tuple(args.shift or (G.REPEATABILITY_M,))


def _gate(args: argparse.Namespace):
    """(sample, runs, candidate, finer, the runs in words) from the arguments: every arm's runs opened, or with --runs
    the files loaded (sample None: nothing to run). ValueError for a bad argument."""
    from ..evaluation import fidelity as G

    if args.runs:
        if len(args.runs) < 2:
            raise ValueError("--runs takes the candidate's results file and the finer run's, then any floors")
        runs = G.load_runs(*args.runs)
        candidate, finer = (G.run_fidelity(getattr(runs[0], n)) for n in ("candidate", "finer"))
        return None, runs, candidate, finer, f"the runs {', '.join(args.runs)}"
    candidate = G.parse_fidelity(args.candidate)
    finer = G.parse_fidelity(args.finer, candidate)
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
    for shift_m in _shifts(args):
        sample.experiment(arms[0], candidate, shift_m)  # the protocol's own checks, before any work
    runs = G.open_runs(
        sample,
        candidate,
        finer,
        Path(args.trials_dir),
        _shifts(args),
        create=not args.report_only,
        candidate_only=args.candidate_only,
    )
    return sample, runs, candidate, finer, _described(sample)


def _described(sample) -> str:
    return (
        f"{sample.object_name} on the {sample.plant_label} plant, α = {sample.alpha_m:g} m, "
        f"{', '.join(a.label for a in sample.arms)}: {len(sample.cells())} cells "
        f"({sample.cells_per_stratum} from each stratum) x {sample.trials_per_cell} trials, seed "
        f"{sample.seed}, T = {sample.duration_s:g} s"
    )


def _run_missing(sample, runs: list, jobs: int | None, candidate_only: bool) -> bool:
    """Every arm's missing trials run (with candidate_only, the candidate's on the finer run's trials), with
    progress; False if interrupted (what finished is kept)."""
    from ..evaluation import fidelity as G
    from ..evaluation.progress import Progress

    left = G.missing_trials(runs, candidate_only)
    if candidate_only:
        total = left + sum(len(r.candidate.records) for r in runs)
    else:
        total = sum(
            len(r.finer.experiment.cell_ids()) * r.finer.experiment.trials_per_cell * len(r.files()) for r in runs
        )
    bar = Progress(total, initial=total - left, unit="trial", label="fidelity")
    interruptible()
    try:
        G.run_missing(
            sample, runs, workers(jobs), on_record=lambda record: bar.update(1), candidate_only=candidate_only
        )
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
    from ..evaluation import fidelity as G

    head = f"{candidate.label} against {finer.label}"
    if report["verdict"] is None:
        return f"{head}: incomplete ({report['pairs']} of {report['expected_pairs']} paired trials); {path}"
    if report["verdict"] == G.UNDECIDED:
        more = report["pairs_to_decide"]
        return (
            f"{head}: undecided at {report['pairs']} paired trials"
            + f"; about {more} pairs per controller would decide it (--until-decided)"
            + "".join(f"\n  {c}" for c in report["undecided"])
            + f"\n{path}"
        )
    return (
        f"{candidate.label} {report['verdict']} ({finer.label}; {report['pairs']} paired trials)"
        + "".join(f"\n  {c}" for c in report["changed"])
        + f"\n{path}"
    )
