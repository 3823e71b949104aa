"""`mantaray sim calibrate`: fit the plant to the paper's findings or to rig logs (an Optuna study)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from mantaray.outputs import writable_dir

from .common import candidates, check_ray, interruptible, output, worker_pool


def run(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """`sim calibrate`: the evidence checked, the study opened or continued, searched, and reported."""
    from mantaray.host.runlog import RunLogError

    from ..search import calibrate as C
    from ..search import study as S

    evidence, keys, fixed = _evidence(args, parser)
    check_ray(parser, args)
    out = output(parser, writable_dir, args.out or f"out/calibration/{'log' if args.log else 'findings'}")
    try:
        study = S.open_study(out / "study.db", evidence, keys, fixed)
    except S.StudyMismatch as exc:
        return _refused(str(exc))
    progress = candidates(study, out, args.candidates, "calibrate")
    fig3 = None
    interruptible()
    try:
        with worker_pool(parser, args) as pool:
            S.run_study(study, evidence, keys, fixed, args.candidates, pool, _noted(progress, evidence.kind))
            best = S.best_trial(study)
            if args.fig3 and best is not None and evidence.kind == "findings":
                fig3 = C.fig3_for(best, args.plant, pool, out / "fig3.png", args.resolution, args.timestep)
    except RunLogError as exc:  # a log the simulation cannot start (say, off the fabric's corner)
        progress.close()
        return _refused(str(exc))
    except KeyboardInterrupt:
        progress.close()
        C.write_report(study, evidence, out)
        print(
            f"\ninterrupted: {len(S.completed(study))} candidates are in {out / 'study.db'}; the same command "
            f"continues the search (report so far in {out / 'report.md'})",
            file=sys.stderr,
        )
        return 130
    progress.close()
    _print_report(C.write_report(study, evidence, out, fig3), out / "report.md", args.json)
    return 0


def _print_report(report: dict, path: Path, as_json: bool) -> None:
    """The search's outcome on stdout: the report as JSON, or one line naming the best candidate and the report."""
    best = report["best"]
    if as_json:
        print(json.dumps(report))
    elif best:
        print(
            f"{report['candidates']} candidates; best #{best['number']}: objectives {best['objectives']}; report {path}"
        )
    else:
        print(f"no candidate evaluated; {path}")


def _evidence(args: argparse.Namespace, parser: argparse.ArgumentParser):
    """(evidence, the keys searched, the values fixed) from the arguments; a usage error for what cannot be."""
    from mantaray.host.runlog import RunLogError

    from ..model import parameters as P
    from ..model.plant import Plant
    from ..search import calibrate as C
    from ..search.logfit import LogEvidence, check_logs

    try:
        fixed = dict(args.set)
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
            evidence.experiments(fixed)  # refuses bad sizes and durations before anything runs
    except (P.ParameterError, RunLogError, ValueError) as exc:
        parser.error(str(exc))
    if not keys:
        parser.error("nothing to search: every parameter named is fixed by --set")
    return evidence, keys, fixed


def _noted(progress, kind: str):
    """The search's progress, each candidate with what it scored."""

    def report_candidate(n: int, total: int, info: dict) -> None:
        if "unstable" in info:
            note = "the physics diverged: scored the worst of every objective"
        else:
            note = "objectives " + " ".join(f"{v:.3f}" for v in info["objectives"])
            note += f", {info['passed']} findings hold" if kind == "findings" else ""
        progress.update(1, note=note)

    return report_candidate


def _refused(why: str) -> int:
    print(f"mantaray sim calibrate: {why}", file=sys.stderr)
    return 2
