"""An experiment's map from its results file: success rate per cell, the paper's totals and its regions, and the
files `sim heatmap` writes of them (cells.csv, summary.json, the figures)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .results_file import ResultsFile

SUCCESS_REGION_AT = 0.9  # [-] cells with at least this success rate form the success region ...
FAILURE_REGION_AT = 0.1  # [-] ... at most this the failure region; those between are uncertain


@dataclass(frozen=True)
class Summary:
    """Per-cell rates and the paper's totals for one results file."""

    rates: np.ndarray  # [cells, cells] success rate per cell, [iy, ix]; NaN where no trial ran
    reach_rates: np.ndarray  # the same under the paper's stopping rule (within epsilon at any frame)
    fell_rates: np.ndarray  # share of trials that fell off
    trials_per_cell: np.ndarray  # [cells, cells] trials counted in each cell
    score: float  # sum of per-cell success rates (the paper: 171.3 Manhattan, 108.2 Euclidean)
    reach_score: float
    region_cells: dict[str, int]  # success / uncertain / failure: cells in each region
    cell_area_m2: float

    @property
    def trials(self) -> int:
        """Trials counted, over all cells."""
        return int(self.trials_per_cell.sum())

    def region_area_m2(self, region: str) -> float:
        return self.region_cells[region] * self.cell_area_m2

    def to_json(self) -> dict:
        return {
            "trials": self.trials,
            "score": round(self.score, 2),
            "reach_score": round(self.reach_score, 2),
            "cells_run": int(np.isfinite(self.rates).sum()),
            "regions": {
                name: {"cells": n, "area_m2": round(self.region_area_m2(name), 5)}
                for name, n in self.region_cells.items()
            },
            "thresholds": {"success_at": SUCCESS_REGION_AT, "failure_at": FAILURE_REGION_AT},
        }


def summarize(results: ResultsFile) -> Summary:
    p = results.experiment
    n = p.cells
    counts = np.zeros((3, n * n))  # successes, reaches, falls
    totals = np.zeros(n * n)
    for r in results.records.values():
        totals[r["cell"]] += 1
        counts[:, r["cell"]] += (r["success"], r["reached"], r["fell_off"])
    with np.errstate(invalid="ignore", divide="ignore"):
        rates = np.where(totals > 0, counts / np.maximum(totals, 1), np.nan).reshape(3, n, n)
    done = np.isfinite(rates[0])
    regions = {
        "success": int((rates[0][done] >= SUCCESS_REGION_AT).sum()),
        "failure": int((rates[0][done] <= FAILURE_REGION_AT).sum()),
    }
    regions["uncertain"] = int(done.sum()) - regions["success"] - regions["failure"]
    f = p.rig().module
    return Summary(
        rates=rates[0],
        reach_rates=rates[1],
        fell_rates=rates[2],
        trials_per_cell=totals.reshape(n, n).astype(int),
        score=float(np.nansum(rates[0])),
        reach_score=float(np.nansum(rates[1])),
        region_cells=regions,
        cell_area_m2=f.size_x_m * f.size_y_m / n**2,
    )


def heatmap_outputs(results, out: Path, title: str) -> dict:
    """Write per-cell rates (CSV), the summary (JSON) and the figure beside the results file; return the summary."""
    from mantaray.plots import heatmap_figure

    from .experiment import cell_bounds

    s = summarize(results)
    p = results.experiment
    f = p.rig().module
    rows = ["cell,ix,iy,x_lo_m,y_lo_m,trials,success_rate,reach_rate,fell_rate"]
    for cell in p.cell_ids():
        ix, iy = cell % p.cells, cell // p.cells
        x_lo, _, y_lo, _ = cell_bounds(p, (f.size_x_m, f.size_y_m), cell)
        rows.append(
            f"{cell},{ix},{iy},{x_lo:.4f},{y_lo:.4f},{s.trials_per_cell[iy, ix]},{s.rates[iy, ix]:.3f},"
            f"{s.reach_rates[iy, ix]:.3f},{s.fell_rates[iy, ix]:.3f}"
        )
    (out / "cells.csv").write_text("\n".join(rows) + "\n")
    summary = {"protocol": p.to_json(), **s.to_json()}
    size = (f.size_x_m, f.size_y_m)
    summary["figure"] = str(
        heatmap_figure(
            s.rates,
            size,
            f"{title}\nscore {s.score:.1f} of {len(p.cell_ids())} (within ε at any frame: {s.reach_score:.1f})",
            out / "heatmap.png",
        )
    )
    summary["reach_figure"] = str(
        heatmap_figure(
            s.reach_rates,
            size,
            f"{title}\nwithin ε at any frame (where the paper's loop stops): score {s.reach_score:.1f}",
            out / "heatmap_reach.png",
        )
    )
    (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    return summary
