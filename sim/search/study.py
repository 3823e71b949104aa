"""The search's Optuna study, resumable in SQLite: open or continue it, run candidates against an evidence, the best.

What it searches is a list of dimensions (plant parameters for sim/search/calibrate.py, controller settings for sim/search/tune.py)
and what scores a candidate is an Evidence. Interrupting the search loses at most the candidate being evaluated (it is
queued again), and the same command continues.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Protocol as Interface

from ..model.plant import Plant

STUDY_NAME = "calibrate"  # the study's name in its file (tuning's studies carry it too)


class StudyMismatch(ValueError):
    """The study file holds a search with another configuration: continuing it would mix two searches."""


class Evidence(Interface):
    """What a candidate plant is scored against (FindingsEvidence, logfit.LogEvidence)."""

    kind: str
    seed: int  # seeds the sampler (with how far the study got)
    objective_names: tuple[str, ...]  # all minimised
    penalty: tuple[float, ...]  # what a plant that cannot be simulated scores

    def evaluate(self, values: dict[str, float | str], pool) -> tuple[tuple[float, ...], dict]:
        """(objectives, details for the report) of the plant with these values set over the base plant."""


class Dimension(Interface):
    """One searched value: a plant parameter (parameters.Parameter) or a controller setting (tune.Knob)."""

    key: str
    scale: str  # linear | log | one_minus_log
    choices: tuple[str, ...] | None  # a categorical one's values

    def search_bounds(self) -> tuple[float, float]: ...


def suggest(trial, p: Dimension) -> float | str:
    """Sample one parameter on its declared scale within its search bounds."""
    if p.choices:
        return trial.suggest_categorical(p.key, list(p.choices))
    low, high = p.search_bounds()
    if p.scale == "one_minus_log":
        return 1.0 - trial.suggest_float(f"1 - {p.key}", 1.0 - high, 1.0 - low, log=True)
    return trial.suggest_float(p.key, low, high, log=p.scale == "log")


def open_study(path: Path, evidence, keys: Sequence[Dimension], fixed: dict):
    """Create the study file, or open the one there if it holds the same search (else StudyMismatch)."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    path.parent.mkdir(parents=True, exist_ok=True)
    config = {
        "evidence": dataclasses.asdict(evidence),
        "fixed": fixed,
        "searched": {p.key: [p.scale, *(p.choices or p.search_bounds())] for p in keys},
        "plant": Plant(evidence.plant).values,
    }  # the plant as declared now: an edited table is another search
    config = json.loads(json.dumps(config))
    storage = f"sqlite:///{path}"
    n_objectives = len(evidence.objective_names)
    study = optuna.create_study(
        storage=storage, study_name=STUDY_NAME, load_if_exists=True, directions=["minimize"] * n_objectives
    )
    # Seeded by the search's seed and how far it got: a resumed search goes on, instead of repeating the draws
    # it began with.
    seed = evidence.seed * 100_003 + len(study.trials)
    study.sampler = (
        optuna.samplers.TPESampler(seed=seed, multivariate=True)
        if n_objectives == 1
        else optuna.samplers.TPESampler(seed=seed)
    )
    stored = study.user_attrs.get("config")
    if stored is not None and stored == config:
        requeue_abandoned(study, {p.key for p in keys})
    if stored is None:
        study.set_user_attr("config", config)
    elif stored != config:
        changed = sorted(k for k in set(stored) | set(config) if stored.get(k) != config.get(k))
        raise StudyMismatch(
            f"{path} holds a search with another configuration ({', '.join(changed)} differ); use "
            f"another --out, or the same options to continue it"
        )
    return study


def requeue_abandoned(study, searched: set[str]) -> None:
    """Candidates left running by a search that was killed (not interrupted) fail, and are queued again when all
    their values had been drawn (one killed while drawing them is no candidate yet).

    One search runs on a study at a time (its pool uses every core), so a running candidate found on opening
    belongs to a process that is gone."""
    import optuna

    for t in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.RUNNING,)):
        study.tell(t.number, state=optuna.trial.TrialState.FAIL)
        if set(t.params) == searched:
            _queue_again(study, t.params)


def _queue_again(study, params: dict) -> None:
    """Queue a candidate's values for the next ask, unless they are queued already (Optuna's skip_if_exists would
    also skip them for the failed trial that had them)."""
    import optuna

    waiting = study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.WAITING,))
    if all(t.system_attrs.get("fixed_params") != params for t in waiting):
        study.enqueue_trial(params)


def completed(study) -> list:
    import optuna

    return [t for t in study.get_trials(deepcopy=False) if t.state == optuna.trial.TrialState.COMPLETE]


def finished(study) -> list:
    """Candidates scored in full or stopped early by the pruner: what a search's --candidates counts."""
    import optuna

    return [
        t
        for t in study.get_trials(deepcopy=False)
        if t.state in (optuna.trial.TrialState.COMPLETE, optuna.trial.TrialState.PRUNED)
    ]


def run_study(
    study,
    evidence,
    keys: Sequence[Dimension],
    fixed: dict,
    candidates: int,
    pool,
    progress: Callable[[int, int, dict], None] | None = None,
) -> None:
    """Evaluate candidates until the study holds `candidates` finished ones (completed, or pruned where the evidence
    scores in rungs: evidence.prune). An interruption fails the candidate in flight and queues its values again, so
    the next run evaluates it first."""
    import optuna

    from ..model.model import SimulationUnstable

    while len(finished(study)) < candidates:
        trial = study.ask()
        values = dict(fixed)
        try:
            for p in keys:
                values[p.key] = suggest(trial, p)
        except BaseException:  # interrupted while drawing: no candidate yet, nothing to run again
            study.tell(trial, state=optuna.trial.TrialState.FAIL)
            raise
        t0 = time.perf_counter()
        try:
            objectives, details = (
                evidence.evaluate_in_rungs(values, pool, trial)
                if getattr(evidence, "prune", False)
                else evidence.evaluate(values, pool)
            )
        except optuna.TrialPruned:
            trial.set_user_attr("values", values)
            trial.set_user_attr("wall_s", round(time.perf_counter() - t0, 1))
            study.tell(trial, state=optuna.trial.TrialState.PRUNED)
            if progress is not None:
                progress(len(finished(study)), candidates, {"pruned": True, **trial.user_attrs["details"]})
            continue
        except KeyboardInterrupt:
            study.tell(trial, state=optuna.trial.TrialState.FAIL)
            _queue_again(study, trial.params)
            raise
        except SimulationUnstable as exc:
            # A plant MuJoCo cannot integrate at this step scores the worst of every objective, so the sampler
            # learns to avoid its region (a failed candidate would teach it nothing); it is never the best.
            objectives, details = evidence.penalty, {"unstable": str(exc), "passed": -1}
        except BaseException:
            study.tell(trial, state=optuna.trial.TrialState.FAIL)
            raise
        if not all(math.isfinite(v) for v in objectives):  # a measure no trial gave: as bad as it gets
            objectives, details = evidence.penalty, {**details, "not_finite": True, "passed": -1}
        trial.set_user_attr("details", details)
        trial.set_user_attr("values", values)
        trial.set_user_attr("wall_s", round(time.perf_counter() - t0, 1))
        study.tell(trial, list(objectives))
        if progress is not None:
            progress(len(finished(study)), candidates, {"objectives": objectives, **details})


def best_trial(study):
    """The candidate that satisfies the most findings, then has the smallest sum of objectives."""
    done = [t for t in completed(study) if t.user_attrs["details"]["passed"] >= 0]
    if not done:
        return None
    return min(done, key=lambda t: (-t.user_attrs["details"]["passed"], sum(t.values)))


def importances(study, evidence) -> dict[str, dict[str, float]]:
    """Per objective: how much each searched parameter mattered (Optuna's PED-ANOVA; needs a few candidates)."""
    import optuna

    if len(completed(study)) < 4:
        return {}
    out = {}
    with warnings.catch_warnings():  # PED-ANOVA is marked experimental, and reminds that low values are the good ones
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        warnings.filterwarnings("ignore", message="PedAnovaImportanceEvaluator computes", category=UserWarning)
        evaluator = optuna.importance.PedAnovaImportanceEvaluator()
        for i, name in enumerate(evidence.objective_names):
            try:
                out[name] = {
                    k: round(float(v), 4)
                    for k, v in optuna.importance.get_param_importances(
                        study, evaluator=evaluator, target=lambda t, i=i: t.values[i]
                    ).items()
                }
            except (RuntimeError, ValueError) as exc:  # e.g. every candidate gave the same value
                out[name] = {"(not computable)": str(exc)}
    return out


def pareto_figure(study, evidence, title: str, path: Path) -> Path | None:
    """Each pair of objectives, every candidate a dot, the Pareto front ringed: where the objectives conflict; title
    may name {candidates}, how many are drawn."""
    import numpy as np

    from mantaray.plots import pareto_figure as draw

    done = completed(study)
    if len(evidence.objective_names) < 2 or not done:
        return None
    front = {t.number for t in study.best_trials}
    return draw(
        np.array([t.values for t in done]),
        np.array([t.number in front for t in done]),
        evidence.objective_names,
        title.format(candidates=len(done)),
        path,
    )
