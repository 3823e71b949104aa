"""`mantaray sim tune`: tune a controller's settings for a plant (an Optuna study, then the full protocol)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from mantaray.outputs import writable_dir

from .cli_common import candidates, check_ray, fidelity, interruptible, output, worker_pool
from .cli_heatmap import heatmap_outputs


def run(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """`sim tune`: the search checked and opened, run with its baseline, confirmation and final check."""
    import dataclasses

    from . import study as S
    from . import tune as T
    from .experiment import ExperimentMismatch
    from .progress import Progress
    from .results_file import ResultsFileBusy

    at = fidelity(parser, args.confirm_at) if args.confirm else None
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
    check_ray(parser, args)
    start = _tuning_start(parser, args, evidence) if args.start_from else None
    out = output(
        parser, writable_dir, args.out or f"out/tune/{args.object}_{args.controller}_alpha{args.alpha:g}_{args.plant}"
    )
    try:
        study = T.open_tuning(out / "study.db", evidence, args.per_axis, start)
    except (S.StudyMismatch, T.StartMismatch) as exc:
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

    interruptible()
    final = confirmation = None
    try:
        with worker_pool(parser, args) as pool:
            baseline = study.user_attrs.get("baseline")
            if baseline is None:  # the paper's Manhattan on the same sample, once per study
                print(
                    "tune: first the paper's Manhattan on the search's sample, what each candidate is measured against",
                    file=sys.stderr,
                    flush=True,
                )
                baseline = evidence.baseline(pool)
                study.set_user_attr("baseline", baseline)
            progress = candidates(study, out, args.candidates, "tune")  # its rate counts candidates only
            S.run_study(
                study, evidence, T.knobs(args.controller, args.per_axis), {}, args.candidates, pool, report_candidate
            )
            progress.close()
            checked = evidence
            if at is not None:
                print(f"tune: the {args.confirm} best candidates again at {at.label}", file=sys.stderr, flush=True)
                bar = Progress(
                    min(args.confirm, len(S.completed(study))), unit="candidate", label="tune: confirm", line_every_s=0
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
            f"\ninterrupted: {len(S.finished(study))} candidates are in {out / 'study.db'}; the same command "
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


def _final_heatmaps(path: Path, args: argparse.Namespace) -> list[str]:
    """The final check's heatmaps under both rules (and cells.csv, summary.json) beside its trials, as sim heatmap
    draws them."""
    from .results_file import ResultsFile

    results = ResultsFile.load(path)
    title = (
        f"{args.object}, {args.controller} tuned for the {args.plant} plant, α = {args.alpha:g} m, "
        f"{results.protocol.trials_per_cell} trials/cell, seed {args.final_seed}"
    )
    summary = heatmap_outputs(results, path.parent, title)
    return [summary["figure"], summary["reach_figure"]]
