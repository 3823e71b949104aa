"""The fidelity gate: whether a cheaper physics configuration gives a finer one's answers, at the rig's repeatability.

A fidelity is the fabric's resolution and the physics step. The gate runs one paired sample at the candidate
fidelity and at the finer one (trial k of a cell is the same start, target and noise seed in both), and judges the
answers a user reads, controller by controller: the rates (reached, within ε at T, fell off), the mean time to reach
and the median final error. Each answer's paired difference, candidate minus finer, has a 90 % interval
(sim/evaluation/equivalence.py); the two fidelities give the same answer when it lies inside the margin (two one-sided tests
at 5 %: ±5 percentage points on a rate, ±0.5 s, ±5 mm), a different one when it lies wholly outside, and the
sample cannot tell otherwise: undecided, with the pairs that would decide it. The same for the contrast of every
two controllers ((A − B) at the candidate minus (A − B) at the finer), which is what a user's claim rests on.
The verdict: "keeps the finer one's answers" when every answer is equivalent, "changes the finer one's answers"
when any is different, else undecided.

Reported beside the verdict, not in it: the rates per zone of the workspace (findings.STRATA), and the flips (trials
whose outcome the candidate changes) against a floor: the finer run again with every start moved by the rig's
repeatability (REPEATABILITY_M), and, as a diagnostic of chaos, by any other shift asked for (0.1 mm, say).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..model.plant import DEFAULT_PLANT
from ..model.rig import FIDELITIES, Fidelity
from . import findings as F
from .equivalence import DIFFERENT, EQUIVALENT, LEVEL, Judged, mean_difference
from .equivalence import UNDECIDED as OPEN
from .experiment import Experiment, Trial
from .paired import MIN_BOOTSTRAP_N, discordance, mean_interval, median_difference_interval
from .results_file import ResultsFile, write_whole

# [m] How far the floor's run moves every start: the rig's repeatability, where an object is put down by hand and
# found by the tracker. It is larger than the tracker's position noise: 0.24 mm RMS on frames the MuJoCo scene
# renders (the cube's marker), 0.45 mm for the sphere's colour blob in the loop (`python3
# benchmarks/speed/tracker_speed.py --frames 40`, this machine, 2026-12-06).
REPEATABILITY_M = 0.002
RATE_MARGIN = 0.05  # [-] two fidelities give the same rate within 5 percentage points
TIME_MARGIN_S = 0.5  # [s] ... the same mean time to reach within half a second
ERROR_MARGIN_M = 0.005  # [m] ... the same median final error within 5 mm
RATES = (("reached", "reached"), ("success", "within ε at T"), ("fell_off", "fell off"))
KEEPS, CHANGES, UNDECIDED = "keeps the finer one's answers", "changes the finer one's answers", "undecided"
APART = {"candidate": ("resolution", "timestep_s"), "floor": ("start_shift_m",)}  # what each run may differ in


class GateMismatch(ValueError):
    """Two runs the gate was given are not the same trials: comparing them would mean nothing."""


def fixed_slug(plant_set: tuple[tuple[str, float | str], ...]) -> str:
    """Values fixed over a plant, as file names carry them: _KEY=VALUE each, or nothing."""
    return "".join(f"_{k}={v}" for k, v in plant_set)


def parse_fidelity(text: str, coarser: Fidelity | None = None) -> Fidelity:
    """A named fidelity (fast, reference), RESOLUTION:TIMESTEP (15:0.002), or `finer`: Fidelity.finer() of the
    coarser one it is checked against (which must then be given)."""
    if text in FIDELITIES:
        return FIDELITIES[text]
    if text == "finer":
        if coarser is None:
            raise ValueError("`finer` names the mesh a fidelity is checked against: give that fidelity before it")
        return coarser.finer()
    parts = text.split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        fidelity = Fidelity(int(parts[0]), float(parts[1]))
    except ValueError:
        raise ValueError(
            f"a fidelity is {', '.join(FIDELITIES)}, finer or RESOLUTION:TIMESTEP (like 15:0.002), got {text!r}"
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
    plant_set: tuple[tuple[str, float | str], ...] = ()  # values fixed over the plant's (sim/model/plant.toml keys)
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
    """One arm's runs of the sample: at the candidate, at the finer fidelity, and the finer one's floors (its starts
    moved)."""

    label: str
    candidate: ResultsFile
    finer: ResultsFile
    floors: tuple[ResultsFile, ...] = ()

    def files(self) -> list[ResultsFile]:
        return [self.finer, self.candidate, *self.floors]


def check_paired(runs: Runs) -> None:
    """Refuse runs that are not the same trials (GateMismatch, naming the field), or a floor that moved nothing."""
    base = runs.finer.experiment.to_json()
    others = [("candidate", runs.candidate), *(("floor", f) for f in runs.floors)]
    for name, results in others:
        other = results.experiment.to_json()
        differ = sorted(k for k in set(base) | set(other) if k not in APART[name] and base.get(k) != other.get(k))
        if differ:
            raise GateMismatch(
                f"{runs.label}: the {name} run ({results.path}) and the finer run ({runs.finer.path}) differ in "
                + "; ".join(f"{k} ({other.get(k)!r} against {base.get(k)!r})" for k in differ)
                + ": they are not the same trials"
            )
        if results.plant_values != runs.finer.plant_values:
            raise GateMismatch(
                f"{runs.label}: the {name} run and the finer run were run on the plant's values of "
                f"different days (sim/model/plant.toml changed between them): not the same plant"
            )
    if runs.candidate.model and runs.finer.model and runs.candidate.model["mujoco"] != runs.finer.model["mujoco"]:
        raise GateMismatch(
            f"{runs.label}: the candidate ran on MuJoCo {runs.candidate.model['mujoco']}, the finer run "
            f"on {runs.finer.model['mujoco']}: a gate compares fidelities, not versions"
        )
    for floor in runs.floors:
        if floor.model != runs.finer.model:
            raise GateMismatch(
                f"{runs.label}: the floor run ({floor.path}) ran on another model than the finer run "
                f"({floor.model} against {runs.finer.model}): not the same physics"
            )
        if floor.experiment.start_shift_m <= 0:
            raise GateMismatch(
                f"{runs.label}: the floor run ({floor.path}) moves no start (start_shift_m 0): it measures no floor"
            )


def _common(*files: ResultsFile) -> list[str]:
    """The keys of the trials every one of the files holds, in one order."""
    return sorted(set.intersection(*(set(f.records) for f in files)))


def _flags(records: list[dict], key: str) -> np.ndarray:
    return np.array([bool(r[key]) for r in records], dtype=bool)


def _values(records: list[dict], key: str) -> np.ndarray:
    """A number per trial, NaN where it is not defined (never reached; fell off: no final error)."""

    def value(r: dict) -> float:
        if key == "final_error_m" and (r["fell_off"] or r.get("final_error_m") is None):
            return np.nan
        v = r.get(key)
        return np.nan if v is None else float(v)

    return np.array([value(r) for r in records])


def _rate(x: np.ndarray) -> float | None:
    return round(float(x.mean()), 4) if x.size else None


def _rate_difference(c: list[dict], f: list[dict], key: str) -> tuple[np.ndarray, np.ndarray, Judged]:
    """A rate's flags at the candidate and at the finer run over the same trials, and their paired difference judged."""
    a, b = _flags(c, key), _flags(f, key)
    return a, b, mean_difference(a.astype(int) - b.astype(int), RATE_MARGIN)


def _answers(r: Runs) -> dict:
    """One arm's judged answers on the trials both its candidate and finer runs hold."""
    keys = _common(r.candidate, r.finer)
    c, f = ([run.records[k] for k in keys] for run in (r.candidate, r.finer))
    out = {}
    for key, label in RATES:
        a, b, d = _rate_difference(c, f, key)
        out[key] = {"label": label, "candidate": _rate(a), "finer": _rate(b), "difference": d}
    a, b = _values(c, "time_to_reach_s"), _values(f, "time_to_reach_s")
    both = np.isfinite(a) & np.isfinite(b)
    mean = mean_interval(a[both] - b[both], level=LEVEL, seed=1)
    out["time_to_reach_s"] = {
        "label": "mean time to reach [s] (both reached)",
        "candidate": _round(a[both].mean()) if both.any() else None,
        "finer": _round(b[both].mean()) if both.any() else None,
        "difference": Judged(mean.n, mean.mean, mean.low, mean.high, TIME_MARGIN_S),
    }
    a, b = _values(c, "final_error_m"), _values(f, "final_error_m")
    both = np.isfinite(a) & np.isfinite(b)
    median = median_difference_interval(a[both], b[both], level=LEVEL, seed=2)
    out["final_error_m"] = {
        "label": "median final error [m] (on the sheet in both)",
        "candidate": _round(np.median(a[both])) if both.any() else None,
        "finer": _round(np.median(b[both])) if both.any() else None,
        "difference": Judged(median.n, median.mean, median.low, median.high, ERROR_MARGIN_M),
    }
    return out


def _contrast(x: Runs, y: Runs) -> dict:
    """Each rate's contrast of two arms, (x − y) at the candidate minus (x − y) at the finer fidelity, judged on the
    trials all four runs hold."""
    keys = _common(x.candidate, x.finer, y.candidate, y.finer)
    out = {}
    for key, label in RATES:
        xc, xf, yc, yf = (
            _flags([run.records[k] for k in keys], key).astype(int)
            for run in (x.candidate, x.finer, y.candidate, y.finer)
        )
        out[key] = {
            "label": label,
            "candidate": _rate(xc - yc),
            "finer": _rate(xf - yf),
            "difference": mean_difference((xc - yc) - (xf - yf), RATE_MARGIN),
        }
    return out


def _zones(r: Runs) -> dict:
    """Each rate per zone of the workspace (findings.STRATA of the trial's cell), candidate against finer, with the
    interval of their paired difference: reported, not judged."""
    cells = r.finer.experiment.cells
    keys = _common(r.candidate, r.finer)
    out = {}
    for zone in F.STRATA:
        inside = [k for k in keys if F.stratum(*F.cell_centre(r.finer.records[k]["cell"], cells)) == zone]
        if not inside:
            continue
        c, f = ([run.records[k] for k in inside] for run in (r.candidate, r.finer))
        out[zone] = {"pairs": len(inside)}
        for key, _ in RATES:
            a, b, d = _rate_difference(c, f, key)
            out[zone][key] = {"candidate": _rate(a), "finer": _rate(b), "low": _round(d.low), "high": _round(d.high)}
    return out


def _flips(r: Runs) -> list[dict]:
    """Per floor: the trials each rate flips at the candidate and at the floor, against the finer run, on the trials
    all three hold, and the one-sided exact p that the candidate flips more (reported, not judged)."""
    out = []
    for floor in r.floors:
        keys = _common(r.candidate, r.finer, floor)
        c, f, fl = ([run.records[k] for k in keys] for run in (r.candidate, r.finer, floor))
        row = {"shift_m": floor.experiment.start_shift_m, "pairs": len(keys)}
        for key, _ in RATES:
            a, b, m = _flags(c, key), _flags(f, key), _flags(fl, key)
            more = discordance(a != b, m != b)
            row[key] = {"candidate": int((a != b).sum()), "floor": int((m != b).sum()), "p": round(more.p_more_in_a, 6)}
        out.append(row)
    return out


def _round(x: float | None, digits: int = 5) -> float | None:
    return None if x is None or math.isnan(x) else round(float(x), digits)


def compare(runs: list[Runs]) -> dict:
    """The gate's judged answers per arm and per contrast of two arms, what it reports beside them, and the verdict
    (None while any run lacks trials of the sample)."""
    for r in runs:
        check_paired(r)
    arms = {r.label: _answers(r) for r in runs}
    contrasts = {f"{x.label} − {y.label}": _contrast(x, y) for i, x in enumerate(runs) for y in runs[i + 1 :]}
    judged = [(f"{arm}: {a['label']}", a["difference"]) for arm, answers in arms.items() for a in answers.values()]
    judged += [
        (f"{pair}: {a['label']}", a["difference"]) for pair, answers in contrasts.items() for a in answers.values()
    ]
    pairs = {r.label: len(_common(r.candidate, r.finer)) for r in runs}
    expected = {r.label: len(r.finer.experiment.cell_ids()) * r.finer.experiment.trials_per_cell for r in runs}
    complete = all(len(f.records) >= expected[r.label] for r in runs for f in r.files())
    changed = [f"{name}: {_said(j)}" for name, j in judged if j.status == DIFFERENT]
    undecided = [f"{name}: {_said(j)}" for name, j in judged if j.status == OPEN]
    needed = _pairs_to_decide(judged, min(pairs.values()) if pairs else 0)
    if not complete:
        verdict = None
    elif changed:
        verdict = CHANGES
    else:
        verdict = KEEPS if all(j.status == EQUIVALENT for _, j in judged) else UNDECIDED
    return {
        "pairs": sum(pairs.values()),
        "expected_pairs": sum(expected.values()),
        "pairs_per_arm": pairs,
        "complete": complete,
        "shifts_m": sorted({f.experiment.start_shift_m for r in runs for f in r.floors}),
        "level": LEVEL,
        "margins": {"rate": RATE_MARGIN, "time_to_reach_s": TIME_MARGIN_S, "final_error_m": ERROR_MARGIN_M},
        "per_arm": {arm: _json(answers) for arm, answers in arms.items()},
        "contrasts": {pair: _json(answers) for pair, answers in contrasts.items()},
        "zones": {r.label: _zones(r) for r in runs},
        "flips": {r.label: _flips(r) for r in runs},
        "changed": changed,
        "undecided": undecided,
        "pairs_to_decide": needed,
        "verdict": verdict,
    }


def _json(answers: dict) -> dict:
    return {key: {**a, "difference": a["difference"].to_json()} for key, a in answers.items()}


def _said(j: Judged) -> str:
    """A judged difference in words: its estimate and interval against the margin, on how many pairs."""
    if j.n == 0:
        return "no pair to measure it on"
    if math.isnan(j.low):
        return f"{j.estimate:+.4g} from {j.n} pairs, too few for an interval"
    return f"{j.estimate:+.4g} [{j.low:+.4g} .. {j.high:+.4g}] against ±{j.margin:g} ({j.n} pairs)"


def _pairs_to_decide(judged: list[tuple[str, Judged]], pairs: int) -> int:
    """The pairs per arm at which every open answer would be decided: each answer's own count (Judged.pairs_to_decide)
    scaled by the share of the pairs it is measured on (a time to reach only on trials reached in both); one with too
    few for an interval asks for MIN_BOOTSTRAP_N of its own, one with none for twice the pairs. The pairs there are
    if none is open."""
    needed = pairs
    for _, j in judged:
        if j.status != OPEN:
            continue
        if j.n == 0:
            needed = max(needed, 2 * pairs)
            continue
        own = MIN_BOOTSTRAP_N if math.isnan(j.low) else j.pairs_to_decide
        needed = max(needed, math.ceil(own * pairs / j.n))
    return needed


def report_markdown(report: dict) -> str:
    """The gate's report as a page: the verdict first, then each arm's answers, the contrasts, the zones, the flips."""
    m = report["margins"]
    floors = ", ".join(f"{s * 1000:g} mm" for s in report["shifts_m"]) or "none"
    lines = [
        f"# Fidelity gate: {report['candidate']} against {report['finer']}",
        "",
        f"{report['sample_text']}. Judged: each answer's paired difference (candidate − finer) with its "
        f"{report['level']:.0%} interval against ±{m['rate'] * 100:g} percentage points on a rate, "
        f"±{m['time_to_reach_s']:g} s on the mean time to reach, ±{m['final_error_m'] * 1000:g} mm on the median "
        f"final error (two one-sided tests at 5 %). Floors (the finer run with every start moved): {floors}. "
        f"Reproduce: `{report['command']}`",
        "",
    ]
    if report["verdict"] is None:
        lines.append(
            f"**Incomplete**: {report['pairs']} of {report['expected_pairs']} paired trials so far; "
            f"the same command continues it."
        )
    elif report["verdict"] == UNDECIDED:
        more = report["pairs_to_decide"]
        lines.append(
            f"**Undecided** ({report['pairs']} paired trials): {len(report['undecided'])} answers straddle their "
            f"margin or have too few pairs; about {more} pairs per controller would decide them (`--until-decided`)."
        )
    else:
        lines.append(f"**Verdict: {report['candidate']} {report['verdict']}** ({report['pairs']} paired trials).")
    lines += [""] + [f"- changes: {c}" for c in report["changed"]] + [f"- undecided: {c}" for c in report["undecided"]]
    for title, table in (("Per controller", report["per_arm"]), ("Contrasts of two controllers", report["contrasts"])):
        lines += [
            "",
            f"## {title}",
            "",
            "| | answer | candidate | finer | candidate − finer [interval] (pairs) | |",
            "|---|---|---|---|---|---|",
        ]
        for name, answers in table.items():
            for a in answers.values():
                d = a["difference"]
                lines.append(
                    f"| {name} | {a['label']} | {a['candidate']} | {a['finer']} | {d['estimate']} "
                    f"[{d['low']} .. {d['high']}] ({d['n']}) | {d['status']} |"
                )
    lines += [
        "",
        "## Per zone (reported, not judged): candidate / finer [interval of the difference]",
        "",
        "| controller | zone | pairs | " + " | ".join(label for _, label in RATES) + " |",
        "|---|---|---|" + "---|" * len(RATES),
    ]
    for arm, zones in report["zones"].items():
        for zone, z in zones.items():
            lines.append(
                f"| {arm} | {zone} | {z['pairs']} | "
                + " | ".join(
                    f"{z[k]['candidate']} / {z[k]['finer']} [{z[k]['low']} .. {z[k]['high']}]" for k, _ in RATES
                )
                + " |"
            )
    lines += [
        "",
        "## Flips against the floors (reported, not judged): trials whose outcome differs from the finer "
        "run's, at the candidate / at the floor (one-sided p that the candidate flips more)",
        "",
        "| controller | floor | pairs | " + " | ".join(label for _, label in RATES) + " |",
        "|---|---|---|" + "---|" * len(RATES),
    ]
    for arm, rows in report["flips"].items():
        for row in rows:
            lines.append(
                f"| {arm} | {row['shift_m'] * 1000:g} mm | {row['pairs']} | "
                + " | ".join(f"{row[k]['candidate']} / {row[k]['floor']} ({row[k]['p']:.3g})" for k, _ in RATES)
                + " |"
            )
    return "\n".join(lines) + "\n"


def write_report(report: dict, out: Path) -> tuple[Path, Path]:
    """report.json and report.md in out, each written whole (an interruption leaves the old one or the new)."""
    out.mkdir(parents=True, exist_ok=True)
    write_whole(out / "report.json", (json.dumps(report, indent=1, ensure_ascii=False) + "\n").encode())
    write_whole(out / "report.md", report_markdown(report).encode())
    return out / "report.json", out / "report.md"


def grown(sample: GateSample, pairs_to_decide: int, max_pairs: int) -> GateSample | str:
    """The sample with as many trials per cell as give each arm pairs_to_decide pairs, or max_pairs if that is fewer
    (its cells stay the same, so every trial run so far is one of it); or, where it holds max_pairs already, why it
    stops."""
    cells = len(sample.cells())
    per_cell = min(math.ceil(pairs_to_decide / cells), max_pairs // cells)
    if per_cell <= sample.trials_per_cell:
        return (
            f"about {pairs_to_decide} pairs per controller would decide it; the sample holds "
            f"{cells * sample.trials_per_cell}, and --max-pairs allows {max_pairs}"
        )
    return dataclasses.replace(sample, trials_per_cell=per_cell)


def open_runs(
    sample: GateSample,
    candidate: Fidelity,
    finer: Fidelity,
    trials_dir: Path,
    shifts_m: tuple[float, ...] = (REPEATABILITY_M,),
    create: bool = True,
    candidate_only: bool = False,
) -> list[Runs]:
    """Every arm's runs, opened (created, or continued where an earlier gate left them): the candidate, the finer
    fidelity and one floor per shift (with create False, a run that has no file yet is left without one). With
    candidate_only the finer runs and floors are read as they stand, not held (a gate running them may go on
    beside), and each must exist. Different runs: a candidate that is the finer fidelity, or a floor that moves
    nothing, would be the finer run again."""
    if candidate == finer:
        raise ValueError(f"the candidate and the finer fidelity are both {finer.label}: nothing to compare")
    if not all(s > 0 for s in shifts_m):
        raise ValueError(f"a floor must move every start (a shift > 0 m), got {', '.join(f'{s:g}' for s in shifts_m)}")
    if len(set(shifts_m)) != len(shifts_m):
        raise ValueError(f"each shift once, got {', '.join(f'{s:g}' for s in shifts_m)}")

    def opened(arm: Arm, fidelity: Fidelity, shift_m: float = 0.0) -> ResultsFile:
        path = sample.results_path(trials_dir, arm, fidelity, shift_m)
        experiment = sample.experiment(arm, fidelity, shift_m)
        if not create and not path.exists():  # nothing run yet: an empty run, kept in memory, no file written
            return ResultsFile(path, experiment)
        return ResultsFile.open(path, experiment)

    def held(arm: Arm, fidelity: Fidelity, shift_m: float = 0.0) -> ResultsFile:
        path = sample.results_path(trials_dir, arm, fidelity, shift_m)
        if not path.exists():
            raise ValueError(
                f"--candidate-only judges the candidate on the trials the finer run holds, and {path} holds none: "
                f"run the gate without it first"
            )
        return ResultsFile.read(path, sample.experiment(arm, fidelity, shift_m))

    other = held if candidate_only else opened
    return [
        Runs(arm.label, opened(arm, candidate), other(arm, finer), tuple(other(arm, finer, s) for s in shifts_m))
        for arm in sample.arms
    ]


def _missing(runs: list[Runs], candidate_only: bool) -> list[tuple[ResultsFile, list[Trial]]]:
    """(run, the trials it lacks) for every run the gate adds to: all of them, or with candidate_only the candidate
    alone, for the trials its finer run and every floor hold."""
    if not candidate_only:
        return [(f, f.missing()) for r in runs for f in r.files()]
    held = [(r.candidate, set(_common(r.finer, *r.floors))) for r in runs]
    return [(f, [t for t in f.missing() if t.key in keys]) for f, keys in held]


def missing_trials(runs: list[Runs], candidate_only: bool = False) -> int:
    return sum(len(trials) for _, trials in _missing(runs, candidate_only))


def run_missing(sample: GateSample, runs: list[Runs], jobs: int, on_record=None, candidate_only: bool = False) -> None:
    """Run what each run lacks (with candidate_only, what the candidate lacks of its finer run's trials) on `jobs`
    local workers, appending every trial to its file as it finishes. The trials go round every arm's runs in the
    sample's run order (GateSample.run_order), so that a gate stopped part way holds the same trials in each run: a
    smaller stratified sample, already paired."""
    from . import executors as X

    position = sample.run_order()
    missing = _missing(runs, candidate_only)
    files = [f for f, _ in missing]
    todo = sorted(
        ((i, t) for i, (_, trials) in enumerate(missing) for t in trials),
        key=lambda job: (*position(job[1]), job[0]),
    )
    X.run_into(files, todo, jobs, on_record)


def load_runs(candidate: str | Path, finer: str | Path, *floors: str | Path) -> list[Runs]:
    """Existing results files (heatmap runs, say) as one arm's runs, for compare(): the candidate, the finer run and
    any floors (the finer run with its starts moved)."""
    c, f, *fl = (ResultsFile.load(p) for p in (candidate, finer, *floors))
    return [Runs(f.experiment.controller, c, f, tuple(fl))]


def run_fidelity(results: ResultsFile) -> Fidelity:
    return Fidelity(results.experiment.resolution, results.experiment.timestep_s)
