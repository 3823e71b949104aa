"""What `mantaray sim heatmap --adaptive` saves: each committed full map against its adaptive twin of the same seed.

Run: python3 benchmarks/experiments/adaptive_savings.py
An adaptive run's trials are each cell's first trials of the full run of its seed (trials are drawn from (seed, cell,
k) alone), and which it runs is a function of those trials (sim/evaluation/adaptive.py; tests/test_adaptive.py checks the
command runs exactly this twin), so the twin of every committed 20 x 20, N = 10 map (docs/results/*.jsonl.gz) is
found from its trials without running one. For each: the trials the twin runs against the full run's, the cells
whose region (success >= 0.9, failure <= 0.1, uncertain between) moves, on the map the run is judged by and on the
map under the paper's stopping rule (reached), and the change of the paper's score (the sum of the cells' rates).
Writes docs/results/adaptive/savings.md and savings.json, and docs/figures/adaptive_savings.png.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from mantaray.plots import savings_figure
from mantaray.sim.evaluation import adaptive as A
from mantaray.sim.evaluation.results_file import ResultsFile

REPO = Path(__file__).resolve().parents[2]
OUT = REPO / "docs" / "results" / "adaptive"
FIGURE = REPO / "docs" / "figures" / "adaptive_savings.png"
AIM_SAVED, AIM_MOVED = 2.0, 0.05  # issue 40: at least 2x fewer trials, at most 5 % of the cells moved


def _map(records: dict[str, dict], cells: list[int], key: str) -> dict[int, tuple[int, int]]:
    counts = {c: [0, 0] for c in cells}
    for r in records.values():
        counts[r["cell"]][0] += bool(r[key])
        counts[r["cell"]][1] += 1
    return {c: (k, n) for c, (k, n) in counts.items()}


def measured(path: Path) -> dict | None:
    """The twin's savings on one committed map, or None for a map that is not a full 20 x 20, N = 10 one."""
    results = ResultsFile.load(path)
    p = results.experiment
    cells = p.cell_ids()
    if p.cells != 20 or p.only_cells is not None or p.trials_per_cell != 10 or len(results.records) != 4000:
        return None
    twin = A.twin(results.records, cells, p.trials_per_cell)
    row = {"run": path.name.removesuffix(".jsonl.gz"), "trials_full": len(results.records), "trials_twin": len(twin)}
    for key, name in (("success", "judged"), ("reached", "reached")):
        full, part = _map(results.records, cells, key), _map(twin, cells, key)
        row[f"moved_{name}"] = sum(A.region(*full[c]) != A.region(*part[c]) for c in cells) / len(cells)
        row[f"score_change_{name}"] = sum(k / n for k, n in part.values()) - sum(k / n for k, n in full.values())
    row["fidelity"] = f"{p.resolution} x {p.resolution}, {p.timestep_s * 1000:g} ms"
    row["plant"], row["seed"], row["alpha_m"] = p.plant, p.seed, p.alpha_m
    row["saved"] = row["trials_full"] / row["trials_twin"]
    return row


def table(rows: list[dict]) -> str:
    lines = [
        "# What `sim heatmap --adaptive` saves, on every committed full map",
        "",
        "Written by `python3 benchmarks/experiments/adaptive_savings.py`: each committed 20 x 20, N = 10 map "
        "(docs/results/*.jsonl.gz; fidelity, plant and seed in the row) against its adaptive twin of the same seed, "
        "found from its trials (sim/evaluation/adaptive.py). Moved: the share of the 400 cells whose region differs, on the "
        "map the run is judged by and on the map of reached; score: the change of the sum of the cells' rates. "
        f"The aim (issue 40): at least {AIM_SAVED:g}x fewer trials with at most {AIM_MOVED:.0%} of the cells moved.",
        "",
        "| run | fidelity | plant | seed | trials (full → adaptive) | fewer | moved (judged) | moved (reached) | "
        "score change (judged) | meets the aim |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        meets = r["saved"] >= AIM_SAVED and r["moved_judged"] <= AIM_MOVED
        lines.append(
            f"| {r['run']} | {r['fidelity']} | {r['plant']} | {r['seed']} | {r['trials_full']} → {r['trials_twin']} "
            f"| {r['saved']:.2f}x | {r['moved_judged']:.1%} | {r['moved_reached']:.1%} | "
            f"{r['score_change_judged']:+.1f} | {'yes' if meets else 'no'} |"
        )
    saved = [r["saved"] for r in rows]
    lines += [
        "",
        f"Over the {len(rows)} maps: {min(saved):.2f}x to {max(saved):.2f}x fewer trials (median "
        f"{np.median(saved):.2f}x); {sum(r['saved'] >= AIM_SAVED and r['moved_judged'] <= AIM_MOVED for r in rows)} "
        f"of {len(rows)} meet the aim.",
    ]
    return "\n".join(lines) + "\n"


def figure(rows: list[dict]) -> None:
    savings_figure(
        [(r["run"], r["saved"], 100 * r["moved_judged"]) for r in rows],
        (AIM_SAVED, 100 * AIM_MOVED),
        "sim heatmap --adaptive on the committed maps (the aim: right of and below the dashed lines)",
        FIGURE,
    )


def main() -> int:
    rows = [r for path in sorted((REPO / "docs" / "results").glob("*.jsonl.gz")) if (r := measured(path))]
    if not rows:
        print("no committed full map in docs/results/", file=sys.stderr)
        return 1
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "savings.json").write_text(json.dumps(rows, indent=1) + "\n")
    (OUT / "savings.md").write_text(table(rows))
    figure(rows)
    print(table(rows))
    print(f"{(OUT / 'savings.md').relative_to(REPO)}, {FIGURE.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
