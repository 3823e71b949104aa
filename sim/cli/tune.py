"""`mantaray sim tune`: tune a controller's settings for a plant (an Optuna study, then the full protocol)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from mantaray.outputs import writable_dir

from .common import candidates, check_ray, fidelity, interruptible, output, worker_pool


def run(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """`sim tune`: the search checked and opened, then run (sim/search/tune_run.py) and reported."""
    from ..evaluation.experiment import ExperimentMismatch
    from ..evaluation.results_file import ResultsFileBusy
    from ..search import study as S
    from ..search import tune as T
    from ..search.tune_run import run_tuning

    evidence, plan = _evidence(args, parser)
    start = _tuning_start(parser, args, evidence) if args.start_from else None
    out = output(
        parser, writable_dir, args.out or f"out/tune/{args.object}_{args.controller}_alpha{args.alpha:g}_{args.plant}"
    )
    try:
        study = T.open_tuning(out / "study.db", evidence, args.per_axis, start)
        _check_confirmed(study, plan, out)
    except (S.StudyMismatch, T.StartMismatch) as exc:
        return _refused(str(exc))
    interruptible()
    try:
        with worker_pool(parser, args) as pool:
            final, confirmation = run_tuning(
                study, evidence, plan, pool, out, lambda: candidates(study, out, args.candidates, "tune")
            )
    except ExperimentMismatch as exc:
        return _refused(
            f"{exc} (the final check there began with other settings, other --final options or on another model: "
            f"give the same ones to continue it, or delete {out / 'final'} to check anew)"
        )
    except ResultsFileBusy as exc:
        return _refused(str(exc))
    except KeyboardInterrupt:
        T.write_report(study, evidence, out, study.user_attrs.get("baseline"))
        print(
            f"\ninterrupted: {len(S.finished(study))} candidates are in {out / 'study.db'}; the same command "
            f"continues (report so far in {out / 'report.json'})",
            file=sys.stderr,
        )
        return 130
    report = T.write_report(study, evidence, out, study.user_attrs.get("baseline"), final, confirmation)
    print(json.dumps(report) if args.json else _summary_line(report, final, out))
    return 0 if args.json or report["best"] is not None else 1


def _evidence(args: argparse.Namespace, parser: argparse.ArgumentParser):
    """The search's evidence and what the session does after it; a usage error for what cannot be."""
    from ..search import tune as T
    from ..search.tune_run import TuningPlan

    at = fidelity(parser, args.confirm_at) if args.confirm else None
    if at is not None and (at.resolution, at.timestep_s) == (args.resolution, args.timestep):
        parser.error(
            f"--confirm-at {args.confirm_at} is the fidelity the search runs at ({at.label}): confirm at a "
            f"finer one, or search at a cheaper one (--resolution, --timestep)"
        )
    if args.final_trials and args.final_seed == args.seed:
        parser.error("--final-seed must differ from --seed: the final check must not run the trials the search saw")
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
    check_ray(parser, args)
    plan = TuningPlan(
        candidates=args.candidates,
        per_axis=args.per_axis,
        confirm=args.confirm,
        confirm_at=at,
        final_trials=args.final_trials,
        final_seed=args.final_seed,
        final_cells=args.final_cells,
        title=f"{args.object}, {args.controller} tuned for the {args.plant} plant, α = {args.alpha:g} m",
    )
    return evidence, plan


def _check_confirmed(study, plan, out: Path) -> None:
    """A study that answers with candidates confirmed at one fidelity continues only with that confirmation."""
    from ..search import study as S
    from ..search import tune as T

    confirmed = T.confirmed_at(study)
    if confirmed is not None and (plan.confirm_at is None or plan.confirm_at.spec != confirmed):
        raise S.StudyMismatch(
            f"the study in {out / 'study.db'} answers with candidates confirmed at {confirmed}: continue it with "
            f"--confirm K --confirm-at {confirmed}, or search anew (another --out)"
        )


def _refused(why: str) -> int:
    print(f"mantaray sim tune: {why}", file=sys.stderr)
    return 2


def _summary_line(report: dict, final: dict | None, out: Path) -> str:
    best, base = report["best"], report["baseline_on_the_sample"]
    if best is None:  # every candidate diverged
        return f"{report['candidates']} candidates, none that the physics could run; report {out / 'report.json'}"
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
    return line + f"; settings {out / 'settings.toml'}, report {out / 'report.json'}"


def _tuning_start(parser: argparse.ArgumentParser, args: argparse.Namespace, evidence) -> dict[str, float]:
    """--start-from's settings as the search's knobs; a file for another controller or plant is a usage error."""
    from mantaray.host.controller_settings import ControllerSettings, SettingsError

    from ..search import tune as T

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
            f"(sim/search/tune.py, SPACE), so the search starts from the nearest bound there",
            file=sys.stderr,
        )
    return start
