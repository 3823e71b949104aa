"""One tuning session, what `mantaray sim tune` runs: the baseline, the search, the confirmation at a finer fidelity
and the final check on the full protocol, each continued from what the study and its files already hold."""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..evaluation.progress import Progress
from ..model.rig import Fidelity
from . import study as S
from . import tune as T


@dataclass(frozen=True)
class TuningPlan:
    """What a session does after opening its study."""

    candidates: int  # the candidates the study should hold when the search is done
    per_axis: bool  # x and y tuned apart
    confirm: int = 0  # the best K candidates scored again at confirm_at (0: none)
    confirm_at: Fidelity | None = None
    final_trials: int = 0  # trials per cell of the final check on the full protocol (0: none)
    final_seed: int = 0
    final_cells: int | None = None  # cells a side of the final check's grid (None: the protocol's)
    title: str = ""  # what the final check's heatmaps are titled with, before its trials and seed


def run_tuning(
    study, evidence: T.TuningEvidence, plan: TuningPlan, pool, out: Path, new_progress: Callable[[], Progress]
) -> tuple[dict | None, dict | None]:
    """The session on the pool: (the final check's result, the confirmation's), None for each not asked for or
    with no candidate to check. new_progress() makes the bar of the search's candidates, after the baseline so
    that its rate counts candidates only."""
    if study.user_attrs.get("baseline") is None:  # the paper's Manhattan on the same sample, once per study
        _say("first the paper's Manhattan on the search's sample, what each candidate is measured against")
        study.set_user_attr("baseline", evidence.baseline(pool))
    progress = new_progress()
    try:
        S.run_study(
            study, evidence, T.knobs(evidence.controller, plan.per_axis), {}, plan.candidates, pool, _noted(progress)
        )
    finally:
        progress.close()
    checked, confirmation, final = evidence, None, None
    if plan.confirm_at is not None:
        at = plan.confirm_at
        _say(f"the {plan.confirm} best candidates again at {at.label}")
        bar = Progress(
            min(plan.confirm, len(S.completed(study))), unit="candidate", label="tune: confirm", line_every_s=0
        )
        confirmation = T.confirm(
            study, evidence, at, plan.confirm, pool,
            lambda number, score: bar.update(1, note=f"#{number}: misses {score['misses']:.3f}"),
        )  # fmt: skip
        bar.close()
        checked = dataclasses.replace(evidence, resolution=at.resolution, timestep_s=at.timestep_s)
    best = T.best_settings(study, evidence)
    if plan.final_trials and best is not None:
        path = out / "final" / "results.jsonl"
        final = T.final_check(checked, best, plan.final_trials, plan.final_seed, pool, path, cells=plan.final_cells)
        final["figures"] = _final_heatmaps(path, plan.title, plan.final_seed)
    return final, confirmation


def _say(text: str) -> None:
    print(f"tune: {text}", file=sys.stderr, flush=True)


def _noted(progress: Progress) -> Callable[[int, int, dict], None]:
    """The search's progress, each candidate with what it scored."""

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

    return report_candidate


def _final_heatmaps(path: Path, title: str, seed: int) -> list[str]:
    """The final check's heatmaps under both rules (and cells.csv, summary.json) beside its trials, as sim heatmap
    draws them, titled with its trials per cell and seed."""
    from ..evaluation.results_file import ResultsFile
    from ..evaluation.summary import heatmap_outputs

    results = ResultsFile.load(path)
    title = f"{title}, {results.experiment.trials_per_cell} trials/cell, seed {seed}"
    summary = heatmap_outputs(results, path.parent, title)
    return [summary["figure"], summary["reach_figure"]]
