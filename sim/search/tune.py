"""Tunes a controller's settings for a plant (mantaray sim tune): an Optuna search on a stratified sample of heatmap
cells, resumable in SQLite (a study of sim/search/study.py), then the full protocol on another seed.

The search scores a candidate by the targets it misses under both success rules (within epsilon at T, and within
epsilon at any frame), summed over the sample's trials, which are drawn from the search's own seed: the final check,
the paper's protocol on its seed 2026, runs trials the search never saw. Its settings are a file that
`mantaray rig --settings` and the firmware take as they are (host/controller_settings.py).
"""

from __future__ import annotations

import dataclasses
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mantaray.host.controller_settings import ControllerSettings, SettingsError
from mantaray.host.session import controller_axes
from mantaray.protocol import messages as m

from ..evaluation import findings as F
from ..evaluation.experiment import Experiment, trials
from ..model.plant import Plant, firmware_gain, paper_gain
from ..model.rig import DEFAULT_FIDELITY, Fidelity
from .study import best_trial, completed, finished, open_study

EVERY_PID = "pid.*."  # a knob on every PID the controller runs (x and y alike: the rig is symmetric)


@dataclass(frozen=True)
class Knob:
    """One searched setting: a key of host/controller_settings.py (or pid.*.NAME) and its range.

    A knob on a gain the paper gives (kP, kI, kD of its PIDs) is in the paper's units: the firmware gets it as the
    plant reads them (plant.firmware_gain: 180/pi times on a plant that reads them per radian), so the paper's own
    gains are in range on every plant and the search starts from them."""

    key: str
    low: float
    high: float
    scale: str = "linear"  # linear | log
    choices = None  # (study.Dimension's: a knob is never categorical)

    def search_bounds(self) -> tuple[float, float]:
        return self.low, self.high


TILT = Knob("configure.tilt_limit", 5.0, m.Configure().tilt_limit)  # [deg] at most the geometric limit
VELOCITY_FILTER = Knob("configure.velocity_filter", 0.0, 0.5)  # [s]
POSITION_PID = [
    Knob("pid.*.kp", 3.0, 150.0, "log"),
    Knob("pid.*.ki", 0.0, 100.0),
    Knob("pid.*.kd", 0.0, 100.0),
    Knob("pid.*.integral_limit", 1.0, m.PID_DEFAULTS[m.Axis.X]["integral_limit"]),
]
#                 the paper's [deg/m], [deg/(m s)], [deg s/m]; [deg]
SPACE = {
    "manhattan": [TILT, *POSITION_PID],
    "euclidean": [TILT, *POSITION_PID],
    "scheduled": [
        TILT,
        *POSITION_PID,
        VELOCITY_FILTER,
        Knob("configure_schedule.edge_zone", 0.01, 0.25),
        Knob("configure_schedule.edge_gain", 0.0, 1.0),
        Knob("configure_schedule.edge_tilt", 0.0, 1.0),
        Knob("configure_schedule.edge_brake", 0.0, 10.0),
        Knob("configure_schedule.brake_speed", 0.0, 1.0),
    ],
    "cascade": [
        TILT,
        VELOCITY_FILTER,
        Knob("configure_cascade.position_gain", 0.3, 30.0, "log"),
        Knob("configure_cascade.speed_limit", 0.02, 1.0, "log"),
        Knob("pid.*.kp", 10.0, 2000.0, "log"),
        Knob("pid.*.ki", 0.0, 500.0),
        Knob("pid.*.kd", 0.0, 50.0),
        Knob("pid.*.integral_limit", 1.0, m.PID_DEFAULTS[m.Axis.VX]["integral_limit"]),
    ],
    #             [deg s/m], [deg/m], [deg s^2/m], [deg]
}


def knobs(controller: str, per_axis: bool = False) -> list[Knob]:
    """The controller's searched settings: SPACE's, or with per_axis each pid.* knob one knob per PID it runs (for a
    rig that is not symmetric)."""
    if not per_axis:
        return SPACE[controller]
    out = []
    for knob in SPACE[controller]:
        if knob.key.startswith(EVERY_PID):
            name = knob.key[len(EVERY_PID) :]
            out += [
                dataclasses.replace(knob, key=f"pid.{axis.name.lower()}.{name}") for axis in controller_axes(controller)
            ]
        else:
            out.append(knob)
    return out


def settings_of(controller: str, values: dict[str, float], gain_scale: float = 1.0) -> ControllerSettings:
    """The controller's settings for a candidate: pid.*.NAME set on each of its PIDs (pid.AXIS.NAME on that one),
    each as the firmware takes it (plant.firmware_gain with gain_scale)."""
    flat = {}
    for key, value in values.items():
        for axis, name in _pids(controller, key):
            flat[f"pid.{axis.name.lower()}.{name}"] = firmware_gain(axis, name, value, gain_scale)
        if not key.startswith("pid."):
            flat[key] = value
    return ControllerSettings(controller, tuple(flat.items()))


def _pids(controller: str, key: str) -> list[tuple[m.Axis, str]]:
    """(axis, field) of each PID a knob's key sets: pid.*.NAME every PID the controller runs, pid.AXIS.NAME one."""
    if not key.startswith("pid."):
        return []
    section, _, name = key.rpartition(".")
    if key.startswith(EVERY_PID):
        return [(axis, name) for axis in controller_axes(controller)]
    return [(m.Axis[section[len("pid.") :].upper()], name)]


def firmware_boot(controller: str) -> dict[str, float]:
    """What the firmware runs each knob's setting at after boot (its numbers: the gains as configure_pid takes them),
    by knob key, per axis and shared (pid.*. as the first PID's)."""
    axes = controller_axes(controller)
    return {
        "configure.tilt_limit": m.Configure().tilt_limit,
        "configure.velocity_filter": m.Configure().velocity_filter,
        **{f"{EVERY_PID}{k}": v for k, v in m.PID_DEFAULTS[axes[0]].items()},
        **{f"pid.{a.name.lower()}.{k}": v for a in axes for k, v in m.PID_DEFAULTS[a].items()},
        **{f"configure_schedule.{s.name}": getattr(m.ConfigureSchedule(), s.name) for s in m.ConfigureSchedule.FIELDS},
        **{f"configure_cascade.{s.name}": getattr(m.ConfigureCascade(), s.name) for s in m.ConfigureCascade.FIELDS},
    }


def boot_values(controller: str, per_axis: bool = False) -> dict[str, float]:
    """The knobs at the firmware's boot values (the paper's gains for its controllers), clipped into their ranges:
    the search's first candidate, so it starts from what the controller does untuned."""
    boot = firmware_boot(controller)
    return {k.key: float(np.clip(boot[k.key], k.low, k.high)) for k in knobs(controller, per_axis)}


def start_values(
    settings: ControllerSettings, per_axis: bool = False, gain_scale: float = 1.0
) -> tuple[dict[str, float], list[str]]:
    """The knobs that set up these settings as the firmware runs them (settings_of's inverse: a paper_gain knob is
    the firmware's number in the paper's units, plant.paper_gain; a setting the file leaves out is the firmware's boot value), each
    clipped into its range, and the knobs that had to be clipped: a candidate to start a search from, such as
    settings tuned for another object. Without per_axis a pid.* knob needs the same value on every PID
    (SettingsError otherwise)."""
    boot, given = firmware_boot(settings.controller), dict(settings.values)
    axes = [a.name.lower() for a in controller_axes(settings.controller)]
    out, clipped = {}, []
    for knob in knobs(settings.controller, per_axis):
        if knob.key.startswith(EVERY_PID):
            name = knob.key[len(EVERY_PID) :]
            each = {given.get(f"pid.{a}.{name}", boot[f"pid.{a}.{name}"]) for a in axes}
            if len(each) > 1:
                raise SettingsError(
                    f"the PIDs {', '.join(axes)} differ in {name}: a search with one set of gains "
                    f"for all cannot start there (search them apart: --per-axis)"
                )
            value = each.pop()
        else:
            value = given.get(knob.key, boot[knob.key])
        pids = _pids(settings.controller, knob.key)
        value = paper_gain(*pids[0], value, gain_scale) if pids else value
        out[knob.key] = float(np.clip(value, knob.low, knob.high))
        if out[knob.key] != value:
            clipped.append(knob.key)
    return out, clipped


@dataclass(frozen=True)
class TuningEvidence:
    """A controller's settings scored on a stratified sample of cells (findings.STRATA) of one object on one plant."""

    controller: str = "scheduled"
    object_name: str = "sphere"
    alpha_m: float = 0.0  # [m] the firmware's noise amplitude
    plant: str = "paper"
    cells_per_stratum: int = 4  # cells drawn from each of the five strata
    trials_per_cell: int = 3
    duration_s: float = 10.0  # [s] T
    seed: int = 31  # the sample's and the sampler's; the final check uses another
    resolution: int = DEFAULT_FIDELITY.resolution  # [vertices per side] (sim/model/rig.py, FIDELITIES)
    timestep_s: float = DEFAULT_FIDELITY.timestep_s  # [s]
    gains_in_paper_units: bool = True  # the paper's gains' knobs read by plant.firmware_gain (the study's record)
    prune: bool = False  # score in rungs of the sample and stop a hopeless candidate early
    kind: str = "tuning"
    objective_names: tuple[str, ...] = ("targets missed under both success rules, per trial",)
    penalty: tuple[float, ...] = (2.0,)  # every target missed twice: what settings that cannot run score

    def experiment(self, settings: ControllerSettings, **changes) -> Experiment:
        """The sample's experiment with these settings (changes: another design, such as the full protocol)."""
        design = dict(
            controller=self.controller,
            object_name=self.object_name,
            alpha_m=self.alpha_m,
            trials_per_cell=self.trials_per_cell,
            duration_s=self.duration_s,
            seed=self.seed,
            resolution=self.resolution,
            timestep_s=self.timestep_s,
            plant=self.plant,
            only_cells=F.stratified_sample(Experiment.cells, self.cells_per_stratum, self.seed),
            settings=settings.values,
        )
        return Experiment(**{**design, **changes})

    def score(self, experiment: Experiment, pool) -> tuple[tuple[float, ...], dict]:
        return _score(pool.map([(experiment, t) for t in trials(experiment)]))

    def rungs(self) -> list[int]:
        """Cells per stratum at each rung of a pruned search: 1, 2, 4, ... up to the whole sample's."""
        out = [1]
        while out[-1] < self.cells_per_stratum:
            out.append(min(2 * out[-1], self.cells_per_stratum))
        return out

    def pruner(self):
        """Successive halving over the rungs: at each, a candidate goes on only if its misses so far are among the
        better half of the candidates' at that rung (their first rung's trials are the smallest resource)."""
        import optuna

        first = len(F.STRATA) * self.trials_per_cell  # trials of the first rung (a smaller stratum: fewer)
        return optuna.pruners.SuccessiveHalvingPruner(min_resource=first, reduction_factor=2, min_early_stopping_rate=0)

    def evaluate_in_rungs(self, values: dict[str, float], pool, trial) -> tuple[tuple[float, ...], dict]:
        """evaluate() a rung at a time: after each, report the misses so far to the study's pruner, which may stop
        the candidate (optuna.TrialPruned, with the details so far in trial.user_attrs["details"]). Every candidate
        runs the same nested cells, so candidates stay paired at every rung."""
        import optuna

        experiment = self.experiment(settings_of(self.controller, values, self.gain_scale))
        records, done = [], set()
        for k in self.rungs():
            cells = F.stratified_sample(Experiment.cells, self.cells_per_stratum, self.seed, first=k)
            todo = [t for t in trials(experiment) if t.cell in cells and t.cell not in done]
            records += pool.map([(experiment, t) for t in todo])
            done |= set(cells)
            objectives, details = _score(records)
            trial.report(objectives[0], step=len(records))
            if k < self.cells_per_stratum and trial.should_prune():
                trial.set_user_attr("details", details)
                raise optuna.TrialPruned(f"misses {objectives[0]:.3f} after {len(records)} trials")
        return objectives, details

    @property
    def gain_scale(self) -> float:
        return Plant(self.plant).gain_scale

    def evaluate(self, values: dict[str, float], pool) -> tuple[tuple[float, ...], dict]:
        return self.score(self.experiment(settings_of(self.controller, values, self.gain_scale)), pool)

    def baseline(self, pool) -> dict:
        """The paper's Manhattan with its gains on the same sample: what the tuned settings are measured against."""
        return self.score(self.experiment(ControllerSettings("manhattan"), controller="manhattan"), pool)[1]

    def final_experiment(
        self, settings: ControllerSettings, trials_per_cell: int, seed: int, cells: int = Experiment.cells
    ) -> Experiment:
        """The paper's whole protocol (every cell of its 20 x 20) with these settings, on a seed the search did not
        use."""
        return self.experiment(settings, only_cells=None, trials_per_cell=trials_per_cell, seed=seed, cells=cells)


def final_check(
    evidence: TuningEvidence,
    settings: ControllerSettings,
    trials_per_cell: int,
    seed: int,
    pool,
    path: Path,
    cells: int = Experiment.cells,
) -> dict:
    """Run (or continue: path is a resumable results file) the full protocol with the settings; its summary."""
    from ..evaluation.executors import run
    from ..evaluation.progress import Progress
    from ..evaluation.results_file import ResultsFile
    from ..evaluation.summary import summarize

    experiment = evidence.final_experiment(settings, trials_per_cell, seed, cells)
    results = ResultsFile.open(path, experiment)
    todo = results.missing()
    total = cells**2 * trials_per_cell
    progress = Progress(total, initial=total - len(todo), unit="trial", label="tune: final check")
    try:
        run(results, pool.imap([(experiment, t) for t in todo]), lambda record: progress.update(1))
    finally:
        progress.close()
    summary = summarize(results)
    return {
        "results": str(path),
        "seed": seed,
        "cells": cells,
        "trials_per_cell": trials_per_cell,
        **summary.to_json(),
        "fell_off": round(float(np.nanmean(summary.fell_rates)), 4),
    }


def open_tuning(path: Path, evidence: TuningEvidence, per_axis: bool = False, start: dict[str, float] | None = None):
    """The study (new, or the one in path if it holds the same search: the same knobs too); a new one starts from
    the boot values, then from start (knob values) when given. StartMismatch if the study began without them."""
    study = open_study(path, evidence, knobs(evidence.controller, per_axis), {})
    if evidence.prune:
        study.pruner = evidence.pruner()
    if not study.trials:
        study.enqueue_trial(boot_values(evidence.controller, per_axis))
        if start is not None:
            study.enqueue_trial(start)
            study.set_user_attr("start_from", start)
    elif start is not None and study.user_attrs.get("start_from") != start:
        raise StartMismatch(
            f"the study in {path} began from other values than these: a start is for a new study "
            f"(continue it without one, or give another --out)"
        )
    return study


def _score(records: list[dict]) -> tuple[tuple[float, ...], dict]:
    """Targets missed under both success rules per trial, the rates behind it, and each cell's [misses, trials]
    (what replay_pruned() needs to score any rung of the sample again)."""
    rates = {k: float(np.mean([bool(r[k]) for r in records])) for k in ("success", "reached", "fell_off")}
    cells: dict[str, list[int]] = {}
    for r in records:
        kept = cells.setdefault(str(r["cell"]), [0, 0])
        kept[0] += (not r["success"]) + (not r["reached"])
        kept[1] += 1
    return (2.0 - rates["success"] - rates["reached"],), {**rates, "trials": len(records), "passed": 0, "cells": cells}


def replay_pruned(evidence: TuningEvidence, candidates: list) -> list[dict]:
    """What a pruned search (evidence.prune) would have run of an unpruned search's candidates, taken in the same
    order: each one's rungs scored again from the misses it had in each cell, and put to the pruned search's own
    pruner. Exact where the sampler's draws do not depend on the scores (a random sampler): the pruned search would
    have drawn the same candidates. Returns, per candidate: its number, the trials the pruned search would have run
    on it, and its misses per trial where it would have completed (None where it would have been stopped)."""
    import optuna

    replay = optuna.create_study(
        direction="minimize", pruner=evidence.pruner(), sampler=optuna.samplers.RandomSampler(seed=0)
    )  # draws nothing that is used
    out = []
    for t in candidates:
        if "cells" not in t.user_attrs["details"]:
            raise ValueError(
                f"candidate #{t.number} has no misses per cell (scored before they were kept, or its "
                f"physics diverged): it cannot be replayed"
            )
        cells = t.user_attrs["details"]["cells"]
        trial = replay.ask()
        misses = n = 0
        seen: set[int] = set()
        for k in evidence.rungs():
            for cell in F.stratified_sample(Experiment.cells, evidence.cells_per_stratum, evidence.seed, first=k):
                if cell not in seen and str(cell) in cells:
                    seen.add(cell)
                    misses, n = misses + cells[str(cell)][0], n + cells[str(cell)][1]
            trial.report(misses / n, step=n)
            if k < evidence.cells_per_stratum and trial.should_prune():
                replay.tell(trial, state=optuna.trial.TrialState.PRUNED)
                out.append({"number": t.number, "trials": n, "misses": None})
                break
        else:
            replay.tell(trial, misses / n)
            out.append({"number": t.number, "trials": n, "misses": misses / n})
    return out


class StartMismatch(ValueError):
    """A start given for a study that began without it."""


def best_settings(study, evidence: TuningEvidence) -> ControllerSettings | None:
    """The best candidate's settings (the best confirmed one, where the search's best were confirmed at a finer
    fidelity), naming the plant they were tuned for (their gains are its reading)."""
    best = confirmed_best(study) or best_trial(study)
    if best is None:
        return None
    settings = settings_of(evidence.controller, best.user_attrs["values"], evidence.gain_scale)
    return dataclasses.replace(settings, plant=evidence.plant)


CONFIRMED = "confirmed"  # the study's user attribute: {RESOLUTION:TIMESTEP: {candidate number: its score}}, one
# fidelity per study
CONFIRMED_NOW = "confirmed_now"  # ... and the candidates the last confirm() ranked, whose best is the answer


def confirm(study, evidence: TuningEvidence, at: Fidelity, k: int, pool, progress=None) -> dict:
    """Score the search's k best candidates again, on the same sample at the fidelity `at` (the reference, when the
    search screened at a cheaper one): the best there is the search's answer, and the rank correlation of the two
    scores over those candidates says whether the cheaper fidelity ranks them as `at` does. Resumable: each score
    is kept in the study as it comes."""
    if (at.resolution, at.timestep_s) == (evidence.resolution, evidence.timestep_s):
        raise ValueError(f"the search already ran at {at.label}: confirm at a finer fidelity than it screened at")
    finer = dataclasses.replace(evidence, resolution=at.resolution, timestep_s=at.timestep_s, prune=False)
    ranked = sorted((t for t in completed(study) if t.user_attrs["details"]["passed"] >= 0), key=lambda t: t.values[0])[
        :k
    ]
    kept = study.user_attrs.get(CONFIRMED, {})
    if kept and at.spec not in kept:
        raise ValueError(
            f"this study's best candidates were confirmed at {', '.join(kept)}, not {at.spec}: confirm "
            f"at that fidelity, or search anew (another --out)"
        )
    study.set_user_attr(CONFIRMED_NOW, [t.number for t in ranked])
    scores = kept.get(at.spec, {})
    for t in ranked:
        if str(t.number) not in scores:
            objectives, details = finer.evaluate(t.user_attrs["values"], pool)
            scores[str(t.number)] = {"misses": objectives[0], **details}
            study.set_user_attr(CONFIRMED, {**kept, at.spec: scores})
        if progress is not None:
            progress(t.number, scores[str(t.number)])
    screened = [t.values[0] for t in ranked]
    there = [scores[str(t.number)]["misses"] for t in ranked]
    best = ranked[int(np.argmin(there))] if ranked else None
    return {
        "fidelity": at.label,
        "spec": at.spec,
        "candidates": len(ranked),
        "rank_correlation": F.rank_correlation(np.array(screened), np.array(there)) if len(ranked) > 1 else None,
        "best": None
        if best is None
        else {"number": best.number, "screened_misses": best.values[0], **scores[str(best.number)]},
        "scores": {
            str(t.number): {"screened": t.values[0], "confirmed": scores[str(t.number)]["misses"]} for t in ranked
        },
    }


def confirmed_at(study) -> str | None:
    """The fidelity (RESOLUTION:TIMESTEP) a study's best candidates were confirmed at, if they were."""
    kept = study.user_attrs.get(CONFIRMED, {})
    return next(iter(kept), None)


def confirmed_best(study):
    """The candidate with the fewest misses at the finer fidelity among those the last confirm() scored (None: none
    confirmed)."""
    kept = study.user_attrs.get(CONFIRMED, {})
    if not kept:
        return None
    (scores,) = kept.values()  # confirm() keeps one fidelity's
    now = [str(n) for n in study.user_attrs.get(CONFIRMED_NOW, [])]
    number = min(now, key=lambda n: scores[n]["misses"])
    return next(t for t in completed(study) if t.number == int(number))


def history_figure(study, evidence: TuningEvidence, baseline: dict | None, path: Path) -> Path | None:
    """Each candidate's misses and the best so far, against the paper's Manhattan on the same sample."""
    done = completed(study)
    if not done:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    numbers = [t.number for t in done]
    misses = [t.values[0] for t in done]
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(numbers, misses, "o", ms=3, color="0.5", label="candidate")
    ax.plot(numbers, np.minimum.accumulate(misses), "-", color="C0", label="best so far")
    if baseline is not None:
        ax.axhline(
            2.0 - baseline["success"] - baseline["reached"],
            color="C3",
            ls="--",
            label="the paper's Manhattan, its gains",
        )
    ax.set_xlabel("candidate")
    ax.set_ylabel("targets missed per trial, both rules (0..2)")
    ax.set_title(
        f"tuning {evidence.controller}: {evidence.object_name}, α = {evidence.alpha_m:g} m, {evidence.plant} plant"
    )
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def write_report(
    study,
    evidence: TuningEvidence,
    out: Path,
    baseline: dict | None,
    final: dict | None = None,
    confirmation: dict | None = None,
) -> dict:
    """OUT/settings.toml (the best settings), report.json and history.png."""
    best = confirmed_best(study) or best_trial(study)
    settings = best_settings(study, evidence)

    def here(path) -> str:  # a path of the report's, from its own folder (which may be copied elsewhere)
        return os.path.relpath(path, out)

    report = {
        "evidence": dataclasses.asdict(evidence),
        "candidates": len(completed(study)),
        "pruned": len(finished(study)) - len(completed(study)),
        "trials_run": sum(t.user_attrs.get("details", {}).get("trials", 0) for t in finished(study)),
        "baseline_on_the_sample": baseline,
        "best": None
        if best is None
        else {
            "number": best.number,
            "misses": best.values[0],
            **best.user_attrs["details"],
            "knobs": best.user_attrs["values"],  # SPACE's units: the paper's gains' in the paper's
            "settings": dict(settings.values),
        },  # the firmware's numbers
        "confirmation": confirmation,
        "final_check": None
        if final is None
        else {**final, "results": here(final["results"]), "figures": [here(f) for f in final.get("figures", [])]},
    }
    if settings is not None:
        (out / "settings.toml").write_text(
            settings.dumps(
                f"{evidence.controller} settings tuned by mantaray sim tune for the {evidence.object_name} "
                f"(α = {evidence.alpha_m:g} m) on the {evidence.plant} plant: candidate #{best.number} of "
                f"{report['candidates']}\nuse: mantaray rig --settings settings.toml, or mantaray sim run (or sim heatmap) "
                f"--settings settings.toml, which runs on the plant named here"
            )
        )
    figure = history_figure(study, evidence, baseline, out / "history.png")
    report["figure"] = None if figure is None else here(figure)
    (out / "report.json").write_text(json.dumps(report, indent=1) + "\n")
    return report
