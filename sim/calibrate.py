"""Fits the plant to evidence: an Optuna search over the declared parameter space (sim/plant.toml), resumable in SQLite.

The evidence is pluggable. `FindingsEvidence` scores a candidate plant by the paper's findings F1-F5
(sim/findings.py) on a stratified sample of heatmap cells, both controllers, the paper's gains; several
objectives at once, since the findings may pull against each other. `logfit.LogEvidence` scores it by how
well the simulation, driven by a rig log's commands, reproduces the logged trajectory.

The study is an SQLite file: interrupting the search loses at most the candidate being evaluated (it is
queued again), and the same command continues. Every candidate evaluates the same trials (common random
numbers), drawn from the search's seed, which is never the seed of the heatmaps it is judged on.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol as Interface

from . import findings as F
from . import parameters as P
from .experiment import Experiment, trials
from .plant import DEFAULT_PLANT, Plant
from .rig import DEFAULT_FIDELITY

CELLS = Experiment.cells  # the paper's 20 x 20 grid, on which the strata and the totals are defined

STUDY_NAME = "calibrate"


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


# ------------------------------------------------------------------------------------------- the search space
def searched(keys: list[str] | None, fixed: dict[str, float | str]) -> list[P.Parameter]:
    """The parameters the search samples: the given keys (default: every one declared search = true), less the fixed."""
    chosen = [P.lookup(k) for k in keys] if keys else [p for p in P.parameters().values() if p.search]
    return [p for p in chosen if p.key not in fixed]


def suggest(trial, p: P.Parameter) -> float | str:
    """Sample one parameter on its declared scale within its search bounds."""
    if p.choices:
        return trial.suggest_categorical(p.key, list(p.choices))
    low, high = p.search_bounds()
    if p.scale == "one_minus_log":
        return 1.0 - trial.suggest_float(f"1 - {p.key}", 1.0 - high, 1.0 - low, log=True)
    return trial.suggest_float(p.key, low, high, log=p.scale == "log")


# ------------------------------------------------------------------------------------------- heatmap findings
@dataclass(frozen=True)
class FindingsEvidence:
    """The paper's findings F1-F5 on a stratified sample of cells: the sphere, both controllers, alpha 0."""

    plant: str = DEFAULT_PLANT
    cells_per_stratum: int = 4  # cells drawn from each of the five strata (findings.STRATA)
    trials_per_cell: int = 3
    duration_s: float = 10.0  # [s] T
    seed: int = 12  # the search's draw; the heatmaps judged afterwards use another
    resolution: int = DEFAULT_FIDELITY.resolution  # [vertices per side] (sim/rig.py, FIDELITIES)
    timestep_s: float = DEFAULT_FIDELITY.timestep_s  # [s]
    kind: str = "findings"
    objective_names: tuple[str, ...] = (
        "central shortfall (F1)",
        "corners and shape shortfall (F2-F4)",
        "log distance of the totals (F5)",
    )
    penalty: tuple[float, ...] = F.WORST_OBJECTIVES  # what a plant that cannot be simulated scores

    def protocols(self, values: dict[str, float | str]) -> dict[str, Experiment]:
        rule = Plant(self.plant).set(values).success_rule
        sample = F.stratified_sample(CELLS, self.cells_per_stratum, self.seed)
        return {
            c: Experiment(
                controller=c,
                trials_per_cell=self.trials_per_cell,
                duration_s=self.duration_s,
                seed=self.seed,
                resolution=self.resolution,
                timestep_s=self.timestep_s,
                only_cells=sample,
                plant=self.plant,
                plant_set=tuple(values.items()),
                stop_when_reached=rule == "reached",
            )
            for c in ("manhattan", "euclidean")
        }

    def evaluate(self, values: dict[str, float | str], pool) -> tuple[tuple[float, ...], dict]:
        protocols = self.protocols(values)
        jobs = [(p, t) for p in protocols.values() for t in trials(p)]
        records = {c: [] for c in protocols}
        for record, (protocol, _) in zip(pool.map(jobs), jobs, strict=True):
            records[protocol.controller].append(record)
        rule = Plant(self.plant).set(values).success_rule
        stats = {c: F.map_stats(records[c], CELLS, rule) for c in protocols}
        found = F.heatmap_findings(stats["manhattan"], stats["euclidean"])
        details = {
            "rule": rule,
            "findings": {f.name: {"holds": f.holds, "measured": f.measured} for f in found},
            "passed": sum(bool(f.holds) for f in found),
            "stats": {c: dataclasses.asdict(s) for c, s in stats.items()},
        }
        return F.objectives(stats["manhattan"], stats["euclidean"]), details


# ------------------------------------------------------------------------------------------- the study
def open_study(path: Path, evidence, keys: list[P.Parameter], fixed: dict):
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
    keys: list[P.Parameter],
    fixed: dict,
    candidates: int,
    pool,
    progress: Callable[[int, int, dict], None] | None = None,
) -> None:
    """Evaluate candidates until the study holds `candidates` finished ones (completed, or pruned where the evidence
    scores in rungs: evidence.prune). An interruption fails the candidate in flight and queues its values again, so
    the next run evaluates it first."""
    import optuna

    from .model import SimulationUnstable

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


def pareto_figure(study, evidence, path: Path) -> Path | None:
    """Each pair of objectives, every candidate a dot, the Pareto front ringed: where the findings conflict."""
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
        f"calibration: {len(done)} candidates (0: the findings hold)",
        path,
    )


# ------------------------------------------------------------------------------------------- the report
def findings_table(details: dict, fig3: dict | None) -> str:
    """Markdown table of F1-F6 for one candidate."""
    rows = ["| finding | holds | measured |", "|---|---|---|"]
    for name, f in details.get("findings", {}).items():
        rows.append(f"| {name} | {'yes' if f['holds'] else 'no'} | {f['measured']} |")
    if fig3 is not None:
        rows.append(
            f"| F6 | {'yes' if fig3['holds'] else 'no' if fig3['holds'] is not None else 'not run'} | "
            f"{fig3['measured']} |"
        )
    return "\n".join(rows)


def write_report(study, evidence, out: Path, fig3: dict | None = None) -> dict:
    """report.json and report.md (best candidate, its findings, importances) and pareto.png in out; returns the JSON."""
    best = best_trial(study)
    done = completed(study)
    report = {
        "evidence": evidence.kind,
        "candidates": len(done),
        "objectives": list(evidence.objective_names),
        "best": None
        if best is None
        else {
            "number": best.number,
            "objectives": [round(v, 4) for v in best.values],
            "values": best.user_attrs["values"],
            "details": best.user_attrs["details"],
        },
        "pareto_front": [{"number": t.number, "objectives": [round(v, 4) for v in t.values]} for t in study.best_trials]
        if done
        else [],
        "importances": importances(study, evidence),
    }
    if fig3 is not None:
        report["fig3"] = fig3
    figure = pareto_figure(study, evidence, out / "pareto.png")
    report["pareto_figure"] = None if figure is None else str(figure)
    out.mkdir(parents=True, exist_ok=True)
    (out / "report.json").write_text(json.dumps(report, indent=1) + "\n")
    lines = [f"# Calibration report ({evidence.kind} evidence, {len(done)} candidates)", ""]
    if best is None:
        lines.append("No candidate finished yet.")
    else:
        lines += [
            f"Best candidate: #{best.number}, objectives "
            + ", ".join(f"{n} {v:.3f}" for n, v in zip(evidence.objective_names, best.values, strict=True)),
            "",
            "| parameter | value |",
            "|---|---|",
        ]
        lines += [
            f"| `{k}` | {v:.6g} |" if isinstance(v, float) else f"| `{k}` | {v} |"
            for k, v in best.user_attrs["values"].items()
        ]
        if evidence.kind == "findings":
            lines += [
                "",
                f"Findings (success rule: {best.user_attrs['details']['rule']}):",
                "",
                findings_table(best.user_attrs["details"], fig3),
            ]
        else:
            lines += [
                "",
                "Trajectory error per log [m]: "
                + ", ".join(f"{k} {v:.4f}" for k, v in best.user_attrs["details"]["errors_m"].items()),
            ]
    for objective, ranked in report["importances"].items():
        lines += [
            "",
            f"Importance for {objective}: "
            + ", ".join(f"{k} {v:.2f}" if isinstance(v, float) else f"{k}: {v}" for k, v in list(ranked.items())[:8]),
        ]
    if figure is not None:
        lines += ["", f"![Pareto front]({figure.name})"]
    (out / "report.md").write_text("\n".join(lines) + "\n")
    return report
