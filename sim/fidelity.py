"""The fidelity gate: whether a cheaper physics configuration keeps a finer one's trial outcomes, beyond the noise floor.

A fidelity is the fabric's resolution and the physics step. The gate runs one paired sample three times: at the
candidate fidelity, at the finer one, and at the finer one with every start moved by a tenth of a millimetre (the
noise floor: how many outcomes a perturbation far below anything physical flips, since a rolling object's path is
chaotic). Trial k of a cell is the same start, target and noise seed in all three. For each outcome it asks two
questions of the candidate against the finer run, each a paired test:
- bias: does the candidate shift the outcome one way (McNemar's exact test; a bootstrap interval of the mean
  difference for time to reach and final error)?
- scatter: does it flip more outcomes than the perturbation does (McNemar on the per-trial flips; a bootstrap
  interval of |candidate - finer| - |perturbed - finer|)?
Every test is held to 0.05 divided by the number of tests (Bonferroni), so the verdict as a whole is a 5 % test.
The candidate "keeps the finer one's outcomes" when no test finds a difference, and "changes them" otherwise.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import findings as F
from .experiment import Experiment
from .paired import discordance, mean_interval
from .plant import DEFAULT_PLANT
from .results_file import ResultsFile, write_whole
from .rig import FIDELITIES, Fidelity

PERTURBATION_M = 1e-4  # [m] how far the noise floor's run moves every start
SIGNIFICANCE = 0.05  # the whole verdict's false-alarm rate, split evenly over its tests
BINARY = (("success", "within ε at T"), ("reached", "reached"), ("fell_off", "fell off"))
CONTINUOUS = (("time_to_reach_s", "time to reach [s]"), ("final_error_m", "final error [m]"))
KEEPS, CHANGES = "keeps the finer one's outcomes", "changes them"
APART = {"candidate": ("resolution", "timestep_s"), "floor": ("start_shift_m",)}  # what each run may differ in


class GateMismatch(ValueError):
    """Two runs the gate was given are not the same trials: comparing them would mean nothing."""


def fixed_slug(plant_set: tuple[tuple[str, float | str], ...]) -> str:
    """Values fixed over a plant, as file names carry them: _KEY=VALUE each, or nothing."""
    return "".join(f"_{k}={v}" for k, v in plant_set)


def parse_fidelity(text: str) -> Fidelity:
    """A named fidelity (fast, reference) or RESOLUTION:TIMESTEP (15:0.002)."""
    if text in FIDELITIES:
        return FIDELITIES[text]
    parts = text.split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        fidelity = Fidelity(int(parts[0]), float(parts[1]))
    except ValueError:
        raise ValueError(
            f"a fidelity is {' or '.join(FIDELITIES)} or RESOLUTION:TIMESTEP (like 15:0.002), got {text!r}"
        ) from None
    Experiment(resolution=fidelity.resolution, timestep_s=fidelity.timestep_s)  # the protocol's own checks
    return fidelity


@dataclass(frozen=True)
class Arm:
    """A controller the gate runs: one of the firmware's with its boot values, or a settings file's."""

    label: str
    controller: str
    settings: tuple[tuple[str, float], ...] = ()
    plant: str | None = None  # the plant a settings file was tuned for (its gains are that plant's reading)

    @classmethod
    def parse(cls, text: str) -> Arm:
        """A controller's name, or the path of a settings file (TOML, as mantaray sim tune writes)."""
        from mantaray.host.controller_settings import ControllerSettings
        from mantaray.protocol import messages as m

        if text.upper() in m.Controller.__members__:
            return cls(text.lower(), text.lower())
        if not Path(text).is_file():
            raise ValueError(
                f"a controller is one of {', '.join(c.lower() for c in m.Controller.__members__)} or "
                f"a settings file; {text!r} is neither"
            )
        settings = ControllerSettings.load(text)  # a SettingsError (a ValueError) says what is wrong with it
        digest = hashlib.sha1(repr(settings.values).encode()).hexdigest()[:6]
        return cls(f"{settings.controller}-{digest}", settings.controller, settings.values, settings.plant)


@dataclass(frozen=True)
class GateSample:
    """The paired sample: a stratified draw of the paper's cells (findings.STRATA), every arm on each."""

    object_name: str = "sphere"
    plant: str = DEFAULT_PLANT
    plant_set: tuple[tuple[str, float | str], ...] = ()  # values fixed over the plant's (sim/plant.toml keys)
    alpha_m: float = 0.0  # [m]
    arms: tuple[Arm, ...] = (Arm("manhattan", "manhattan"), Arm("euclidean", "euclidean"))
    cells_per_stratum: int = 8
    trials_per_cell: int = 5
    seed: int = 77  # a draw no search or heatmap of docs/results.md uses
    duration_s: float = 10.0  # [s] T: to its end, so every outcome is measured

    def __post_init__(self) -> None:
        for arm in self.arms:
            if arm.plant is not None and arm.plant != self.plant:
                raise ValueError(
                    f"the {arm.label} settings were tuned for the {arm.plant} plant, not {self.plant}: "
                    f"their gains are the firmware's numbers for that plant"
                )
        if len({arm.label for arm in self.arms}) != len(self.arms):
            raise ValueError(f"each controller once, got {', '.join(arm.label for arm in self.arms)}")

    def cells(self) -> tuple[int, ...]:
        return F.stratified_sample(Experiment.cells, self.cells_per_stratum, self.seed)

    def run_order(self):
        """The order the gate runs its trials in, as a sort key of a Trial: trial number, then (j, s) for the j-th
        cell drawn from stratum s (findings.stratified_draw). Every prefix of the order is a stratified sample, the
        first trial of the cells each stratum drew first."""
        drawn = F.stratified_draw(Experiment.cells, self.cells_per_stratum, self.seed)
        place = {cell: (j, s) for s, cells in enumerate(drawn.values()) for j, cell in enumerate(cells)}
        return lambda trial: (trial.k, *place[trial.cell])

    @property
    def plant_label(self) -> str:
        """The plant as named, with the values fixed over it: polyester, or polyester with fabric.stretch=threads."""
        fixed = ", ".join(f"{k}={v}" for k, v in self.plant_set)
        return f"{self.plant} with {fixed}" if fixed else self.plant

    def experiment(self, arm: Arm, fidelity: Fidelity, shift_m: float = 0.0) -> Experiment:
        return Experiment(
            object_name=self.object_name,
            controller=arm.controller,
            settings=arm.settings,
            trials_per_cell=self.trials_per_cell,
            duration_s=self.duration_s,
            alpha_m=self.alpha_m,
            seed=self.seed,
            resolution=fidelity.resolution,
            timestep_s=fidelity.timestep_s,
            only_cells=self.cells(),
            plant=self.plant,
            plant_set=self.plant_set,
            start_shift_m=shift_m,
        )

    def results_path(self, trials_dir: Path, arm: Arm, fidelity: Fidelity, shift_m: float = 0.0) -> Path:
        """Where one arm's run at one fidelity keeps its trials: shared by every gate that needs that run."""
        shift = f"_moved{shift_m * 1000:g}mm" if shift_m else ""
        return (
            Path(trials_dir)
            / f"{self.object_name}_{arm.label}_alpha{self.alpha_m:g}_{self.plant}{fixed_slug(self.plant_set)}"
            f"_seed{self.seed}_{fidelity.slug}{shift}.jsonl"
        )


@dataclass(frozen=True)
class Runs:
    """One arm's three runs of the sample."""

    label: str
    candidate: ResultsFile
    finer: ResultsFile
    floor: ResultsFile


def check_paired(runs: Runs) -> None:
    """Refuse runs that are not the same trials (GateMismatch, naming the field), or a floor that moved nothing."""
    base = runs.finer.experiment.to_json()
    for name in ("candidate", "floor"):
        other = getattr(runs, name).experiment.to_json()
        differ = sorted(k for k in set(base) | set(other) if k not in APART[name] and base.get(k) != other.get(k))
        if differ:
            raise GateMismatch(
                f"{runs.label}: the {name} run ({getattr(runs, name).path}) and the finer run "
                f"({runs.finer.path}) differ in "
                + "; ".join(f"{k} ({other.get(k)!r} against {base.get(k)!r})" for k in differ)
                + ": they are not the same trials"
            )
    if runs.floor.model != runs.finer.model:
        raise GateMismatch(
            f"{runs.label}: the floor run ({runs.floor.path}) ran on another model than the finer run "
            f"({runs.floor.model} against {runs.finer.model}): not the same physics"
        )
    if runs.candidate.model and runs.finer.model and runs.candidate.model["mujoco"] != runs.finer.model["mujoco"]:
        raise GateMismatch(
            f"{runs.label}: the candidate ran on MuJoCo {runs.candidate.model['mujoco']}, the finer run "
            f"on {runs.finer.model['mujoco']}: a gate compares fidelities, not versions"
        )
    for name in ("candidate", "floor"):
        if getattr(runs, name).plant_values != runs.finer.plant_values:
            raise GateMismatch(
                f"{runs.label}: the {name} run and the finer run were run on the plant's values of "
                f"different days (sim/plant.toml changed between them): not the same plant"
            )
    if runs.floor.experiment.start_shift_m <= 0:
        raise GateMismatch(
            f"{runs.label}: the floor run ({runs.floor.path}) moves no start (start_shift_m 0): it "
            f"measures no noise floor"
        )


def _paired(runs: list[Runs]) -> dict[str, list[dict]]:
    """The trials every run of an arm holds, in the same order in all three, pooled over the arms."""
    out = {"candidate": [], "finer": [], "floor": []}
    for r in runs:
        keys = sorted(set(r.candidate.records) & set(r.finer.records) & set(r.floor.records))
        for name in out:
            out[name] += [getattr(r, name).records[k] for k in keys]
    return out


def _values(records: list[dict], key: str) -> np.ndarray:
    """A continuous outcome per trial, NaN where it is not defined (never reached; fell off: no final error)."""

    def value(r: dict) -> float:
        if key == "final_error_m" and (r["fell_off"] or r.get("final_error_m") is None):
            return np.nan
        v = r.get(key)
        return np.nan if v is None else float(v)

    return np.array([value(r) for r in records])


def compare(runs: list[Runs]) -> dict:
    """The gate's tests on the pooled pairs, per-arm counts, and the verdict."""
    for r in runs:
        check_paired(r)
    pooled = _paired(runs)
    tests = 2 * (len(BINARY) + len(CONTINUOUS))
    alpha = SIGNIFICANCE / tests
    changed, outcomes = [], {}
    for key, label in BINARY:
        c, f, fl = (np.array([bool(r[key]) for r in pooled[n]], dtype=bool) for n in ("candidate", "finer", "floor"))
        bias, floor = discordance(c, f), discordance(fl, f)
        scatter = discordance(c != f, fl != f)  # trials only the candidate flips against those only the floor does
        outcomes[key] = {
            "label": label,
            "rate": {"candidate": _rate(c), "finer": _rate(f), "floor": _rate(fl)},
            "candidate_vs_finer": bias.to_json(),
            "floor_vs_finer": floor.to_json(),
            "more_flips_than_floor": {**scatter.to_json(), "p": round(scatter.p_more_in_a, 6)},
        }
        if bias.p_two_sided < alpha:
            changed.append(
                f"{label}: a bias ({bias.only_a} trials only at the candidate, {bias.only_b} only at the "
                f"finer; p = {bias.p_two_sided:.2g})"
            )
        if scatter.p_more_in_a < alpha:
            changed.append(
                f"{label}: more flips than the noise floor ({bias.flips} against {floor.flips}; "
                f"p = {scatter.p_more_in_a:.2g})"
            )
    for key, label in CONTINUOUS:
        c, f, fl = (_values(pooled[n], key) for n in ("candidate", "finer", "floor"))
        both, all3 = np.isfinite(c) & np.isfinite(f), np.isfinite(c) & np.isfinite(f) & np.isfinite(fl)
        bias = mean_interval(c[both] - f[both], level=1 - alpha, seed=1)
        floor = mean_interval(
            fl[np.isfinite(fl) & np.isfinite(f)] - f[np.isfinite(fl) & np.isfinite(f)], level=1 - alpha, seed=2
        )
        scatter = mean_interval(np.abs(c[all3] - f[all3]) - np.abs(fl[all3] - f[all3]), level=1 - 2 * alpha, seed=3)
        outcomes[key] = {
            "label": label,
            "mean": {n: _mean(v) for n, v in (("candidate", c), ("finer", f), ("floor", fl))},
            "candidate_minus_finer": bias.to_json(),
            "floor_minus_finer": floor.to_json(),
            "excess_scatter": scatter.to_json(),
        }
        if not (math.isnan(bias.low) or bias.low <= 0 <= bias.high):  # NaN: too few to test
            changed.append(
                f"{label}: a bias (mean difference {bias.mean:+.4g}, interval {bias.low:+.4g} .. {bias.high:+.4g})"
            )
        if not math.isnan(scatter.low) and scatter.low > 0:
            changed.append(
                f"{label}: more scatter than the noise floor (|candidate - finer| exceeds "
                f"|perturbed - finer| by {scatter.mean:.4g} on average, at least {scatter.low:.4g})"
            )
    pairs = len(pooled["finer"])
    expected = sum(len(r.finer.experiment.cell_ids()) * r.finer.experiment.trials_per_cell for r in runs)
    return {
        "pairs": pairs,
        "expected_pairs": expected,
        "complete": pairs == expected,
        "tests": tests,
        "alpha_per_test": alpha,
        "outcomes": outcomes,
        "per_arm": {r.label: _arm_counts(r) for r in runs},
        "changed": changed,
        "verdict": None if pairs < expected else (CHANGES if changed else KEEPS),
    }


def _rate(x: np.ndarray) -> float | None:
    return round(float(x.mean()), 4) if x.size else None


def _mean(x: np.ndarray) -> float | None:
    x = x[np.isfinite(x)]
    return round(float(x.mean()), 5) if x.size else None


def _arm_counts(r: Runs) -> dict:
    """One arm's outcome counts in each run and its flips against the finer run, for the report's table."""
    pooled = _paired([r])
    out = {"pairs": len(pooled["finer"])}
    for key, _ in BINARY:
        counts = {n: int(sum(bool(x[key]) for x in pooled[n])) for n in pooled}
        flips = {
            n: discordance([bool(x[key]) for x in pooled[n]], [bool(x[key]) for x in pooled["finer"]]).flips
            for n in ("candidate", "floor")
        }
        out[key] = {"count": counts, "flips": flips}
    return out


def report_markdown(report: dict) -> str:
    """The gate's report as a page: the verdict first, then the tests and each arm's counts."""
    lines = [
        f"# Fidelity gate: {report['candidate']} against {report['finer']}",
        "",
        f"{report['sample_text']}. Noise floor: the finer run with every start moved "
        f"{report['shift_m'] * 1000:g} mm. Reproduce: `{report['command']}`",
        "",
    ]
    if report["verdict"] is None:
        lines.append(
            f"**Incomplete**: {report['pairs']} of {report['expected_pairs']} paired trials so far; "
            f"the same command continues it."
        )
    else:
        lines.append(
            f"**Verdict: {report['candidate']} {report['verdict']}** ({report['pairs']} paired trials; "
            f"{report['tests']} tests, each at p < {report['alpha_per_test']:.4f})."
        )
    lines += (
        [""]
        + [f"- {c}" for c in report["changed"]]
        + [
            "",
            "| outcome | candidate | finer | perturbed finer | "
            "candidate vs finer: only candidate / only finer (p) | flips: candidate / floor (p more) |",
            "|---|---|---|---|---|---|",
        ]
    )
    for key, _ in BINARY:
        o = report["outcomes"][key]
        cf, fl, sc = o["candidate_vs_finer"], o["floor_vs_finer"], o["more_flips_than_floor"]
        lines.append(
            f"| {o['label']} | {o['rate']['candidate']} | {o['rate']['finer']} | {o['rate']['floor']} | "
            f"{cf['only_a']} / {cf['only_b']} ({cf['p']:.3g}) | {cf['flips']} / {fl['flips']} ({sc['p']:.3g}) |"
        )
    lines += [
        "",
        "| outcome | candidate | finer | perturbed finer | candidate − finer: mean [interval] (n) | "
        "excess scatter over the floor: mean [interval] |",
        "|---|---|---|---|---|---|",
    ]
    for key, _ in CONTINUOUS:
        o = report["outcomes"][key]
        b, s = o["candidate_minus_finer"], o["excess_scatter"]
        lines.append(
            f"| {o['label']} | {o['mean']['candidate']} | {o['mean']['finer']} | {o['mean']['floor']} | "
            f"{b['mean']} [{b['low']} .. {b['high']}] ({b['n']}) | {s['mean']} [{s['low']} .. {s['high']}] |"
        )
    lines += [
        "",
        "Per controller (counts of trials; flips against the finer run):",
        "",
        "| controller | pairs | "
        + " | ".join(f"{label}: candidate / finer / floor (flips c / f)" for _, label in BINARY)
        + " |",
        "|---|---|" + "---|" * len(BINARY),
    ]
    for label, a in report["per_arm"].items():
        lines.append(
            f"| {label} | {a['pairs']} | "
            + " | ".join(
                f"{a[k]['count']['candidate']} / {a[k]['count']['finer']} / {a[k]['count']['floor']} "
                f"({a[k]['flips']['candidate']} / {a[k]['flips']['floor']})"
                for k, _ in BINARY
            )
            + " |"
        )
    return "\n".join(lines) + "\n"


def write_report(report: dict, out: Path) -> tuple[Path, Path]:
    """report.json and report.md in out, each written whole (an interruption leaves the old one or the new)."""
    out.mkdir(parents=True, exist_ok=True)
    write_whole(out / "report.json", (json.dumps(report, indent=1, ensure_ascii=False) + "\n").encode())
    write_whole(out / "report.md", report_markdown(report).encode())
    return out / "report.json", out / "report.md"


def open_runs(
    sample: GateSample, candidate: Fidelity, finer: Fidelity, trials_dir: Path, shift_m: float = PERTURBATION_M
) -> list[Runs]:
    """Every arm's three runs, opened (created, or continued where an earlier gate left them). Three different runs:
    a candidate that is the finer fidelity, or a floor that moves nothing, would be the finer run again."""
    if candidate == finer:
        raise ValueError(f"the candidate and the finer fidelity are both {finer.label}: nothing to compare")
    if not shift_m > 0:
        raise ValueError(f"the noise floor must move every start (a shift > 0 m), got {shift_m:g}")
    fidelity = {"candidate": candidate, "finer": finer, "floor": finer}
    opened: dict[str, dict[str, ResultsFile]] = {}
    for arm in sample.arms:
        for name, experiment in (
            ("candidate", sample.experiment(arm, candidate)),
            ("finer", sample.experiment(arm, finer)),
            ("floor", sample.experiment(arm, finer, shift_m)),
        ):
            path = sample.results_path(trials_dir, arm, fidelity[name], experiment.start_shift_m)
            opened.setdefault(arm.label, {})[name] = ResultsFile.open(path, experiment)
    return [Runs(label, **files) for label, files in opened.items()]


def missing_trials(runs: list[Runs]) -> int:
    return sum(len(getattr(r, name).missing()) for r in runs for name in ("candidate", "finer", "floor"))


def run_missing(sample: GateSample, runs: list[Runs], jobs: int, on_record=None) -> None:
    """Run what each run lacks on `jobs` local workers, appending every trial to its file as it finishes. The
    trials go round every arm's three runs in the sample's run order (GateSample.run_order), so that a gate
    stopped part way holds the same trials in each run: a smaller stratified sample, already paired."""
    from . import executors as X

    position = sample.run_order()
    files = [getattr(r, name) for r in runs for name in ("finer", "candidate", "floor")]
    todo = sorted(
        ((i, t) for i, results in enumerate(files) for t in results.missing()),
        key=lambda job: (*position(job[1]), job[0]),
    )
    X.run_into(files, todo, jobs, on_record)


def load_runs(candidate: str | Path, finer: str | Path, floor: str | Path) -> list[Runs]:
    """Three existing results files (heatmap runs, say) as one arm's runs, for compare()."""
    files = [ResultsFile.load(p) for p in (candidate, finer, floor)]
    return [Runs(files[1].experiment.controller, *files)]


def run_fidelity(results: ResultsFile) -> Fidelity:
    return Fidelity(results.experiment.resolution, results.experiment.timestep_s)
