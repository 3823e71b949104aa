"""Fits the plant to evidence: an Optuna search over the declared parameter space (sim/model/plant.toml), resumable in SQLite.

The evidence is pluggable. `FindingsEvidence` scores a candidate plant by the paper's findings F1-F5
(sim/evaluation/findings.py) on a stratified sample of heatmap cells, both controllers, the paper's gains; several
objectives at once, since the findings may pull against each other. `logfit.LogEvidence` scores it by how
well the simulation, driven by a rig log's commands, reproduces the logged trajectory.

The search is a study of sim/search/study.py, resumable in SQLite. Every candidate evaluates the same trials (common random
numbers), drawn from the search's seed, which is never the seed of the heatmaps it is judged on.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path

from mantaray.protocol import messages as m

from ..evaluation import findings as F
from ..evaluation.experiment import Experiment, trials
from ..model import parameters as P
from ..model.plant import DEFAULT_PLANT, Plant
from ..model.rig import DEFAULT_FIDELITY
from .study import best_trial, completed, importances, pareto_figure

CELLS = Experiment.cells  # the paper's 20 x 20 grid, on which the strata and the totals are defined


# ------------------------------------------------------------------------------------------- the search space
def searched(keys: list[str] | None, fixed: dict[str, float | str]) -> list[P.Parameter]:
    """The parameters the search samples: the given keys (default: every one declared search = true), less the fixed."""
    chosen = [P.lookup(k) for k in keys] if keys else [p for p in P.parameters().values() if p.search]
    return [p for p in chosen if p.key not in fixed]


# ------------------------------------------------------------------------------------------- heatmap findings
@dataclass(frozen=True)
class FindingsEvidence:
    """The paper's findings F1-F5 on a stratified sample of cells: the sphere, both controllers, alpha 0."""

    plant: str = DEFAULT_PLANT
    cells_per_stratum: int = 4  # cells drawn from each of the five strata (findings.STRATA)
    trials_per_cell: int = 3
    duration_s: float = 10.0  # [s] T
    seed: int = 12  # the search's draw; the heatmaps judged afterwards use another
    resolution: int = DEFAULT_FIDELITY.resolution  # [vertices per side] (sim/model/rig.py, FIDELITIES)
    timestep_s: float = DEFAULT_FIDELITY.timestep_s  # [s]
    kind: str = "findings"
    objective_names: tuple[str, ...] = (
        "central shortfall (F1)",
        "corners and shape shortfall (F2-F4)",
        "log distance of the totals (F5)",
    )
    penalty: tuple[float, ...] = F.WORST_OBJECTIVES  # what a plant that cannot be simulated scores

    def experiments(self, values: dict[str, float | str]) -> dict[str, Experiment]:
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
        experiments = self.experiments(values)
        jobs = [(p, t) for p in experiments.values() for t in trials(p)]
        records = {c: [] for c in experiments}
        for record, (experiment, _) in zip(pool.map(jobs), jobs, strict=True):
            records[experiment.controller].append(record)
        rule = Plant(self.plant).set(values).success_rule
        stats = {c: F.map_stats(records[c], CELLS, rule) for c in experiments}
        found = F.heatmap_findings(stats["manhattan"], stats["euclidean"])
        details = {
            "rule": rule,
            "findings": {f.name: {"holds": f.holds, "measured": f.measured} for f in found},
            "passed": sum(bool(f.holds) for f in found),
            "stats": {c: dataclasses.asdict(s) for c, s in stats.items()},
        }
        return F.objectives(stats["manhattan"], stats["euclidean"]), details


def fig3_for(best, plant: str, pool, path: Path, resolution: int, timestep_s: float) -> dict:
    """F6 for the best candidate: the paper's Fig. 3 experiment on it, its figure at path [resolution: vertices per
    side, timestep_s: s]."""
    from mantaray.plots import fig3_figure

    from ..evaluation.fig3 import run_fig3

    records = run_fig3(pool, plant, best.user_attrs["values"], resolution=resolution, timestep_s=timestep_s)
    finding = F.fig3_finding(records)
    runs: dict[str, list[dict]] = {}
    for r in records:
        runs.setdefault(r["object"], []).append(r)
    figure = fig3_figure(
        runs,
        Experiment.tolerance_m,
        F.MODULE_M,
        m.Configure.tilt_limit,
        f"Fig. 3 on calibration candidate #{best.number}",
        path,
    )
    return {"holds": finding.holds, "measured": finding.measured, "figure": str(figure)}


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
    figure = pareto_figure(
        study, evidence, "calibration: {candidates} candidates (0: the findings hold)", out / "pareto.png"
    )
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
