"""The paper's findings F1-F6 as numbers computed from trial records, each with the rule that says whether it holds.

A record is a line of a heatmap results file (sim/evaluation/results_file.py trial_record): its cell, target, and whether it
ended within epsilon at T (success), was within epsilon at some frame (reached) and fell off. The rule that
counts as success is a reading of the paper (sim/model/plant.toml reading.success_rule): "end" or "reached".

- F1 central targets (|x|, |y| < 0.10 m) succeed at >= 90 % for both controllers (the paper: 100 %).
- F2 Manhattan reaches the corners: its corner rate is above the failure region (> 10 %).
- F3 Euclidean does not: its corner rate is in the failure region (<= 10 %; the paper: "entirely unreachable").
- F4 Manhattan's map is square-shaped, Euclidean's diamond-shaped. The shape index q is the rank correlation
  of the cells' rates with closeness in the L-infinity norm (squares) minus that with closeness in the L1 norm
  (diamonds): q > 0 for Manhattan and q < 0 for Euclidean.
- F5 the totals (sums of the 400 cell rates): Manhattan 171.3, Euclidean 108.2, each within 20 %. A sample of
  cells estimates a total stratum by stratum (each stratum's mean cell rate times its number of cells).
- F6 (the hardware experiment, Fig. 3): every object of Table I starting at the centre reaches a random target in
  [-0.2, 0.2]^2 m with the Manhattan controller within 60 s, 5 of 5 trials each.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from ..model.rig import Module
from .summary import FAILURE_REGION_AT

MODULE_M = (Module().size_x_m, Module().size_y_m)  # [m] the paper's module; the findings' zones are drawn on it
PAPER_CELLS = 20  # per side: the paper's grid, over which its totals are summed
CENTRAL_HALF_M = 0.10  # [m] F1: central targets have |x|, |y| below this
CENTRAL_AT = 0.9  # [-] F1: central success rate at least this
CORNER_FROM_M = 0.175  # [m] F2, F3: corner targets have |x| and |y| above this (7.5 cm squares)
PAPER_TOTALS = {"manhattan": 171.3, "euclidean": 108.2}  # F5: the paper's scores
TOTAL_TOLERANCE = 0.20  # [-] F5: each total within this fraction of the paper's
FIG3_TRIALS = 5  # F6: trials per object (the paper: five)
FIG3_DURATION_S = 60.0  # [s] F6: the hardware runs' runtime (the paper: one minute)
FIG3_TARGET_HALF_M = 0.2  # [m] F6: targets uniform in [-0.2, 0.2]^2
FIG3_ALPHA_M = {
    "sphere": 0.0,
    "cube": 0.1,
    "disk": 0.05,
    "cylinder": 0.1,
    "apple": 0.05,
    "egg": 0.01,
    "bunny": 0.05,
}  # [m] F6: the paper's alpha for each object (Fig. 3's captions)
STRATA = ("centre", "axes", "diagonals", "edges", "corners")
RULES = ("end", "reached")


def outcome(record: dict, rule: str) -> bool:
    """Whether a trial counts as a success under the rule: end (within eps at T) or reached (at any frame)."""
    if rule not in RULES:
        raise ValueError(f"success rule must be one of {', '.join(RULES)}, got {rule!r}")
    return bool(record["success"] if rule == "end" else record["reached"])


def cell_centre(cell: int, cells: int, module_m: tuple[float, float] = MODULE_M) -> tuple[float, float]:
    """Centre (x, y) [m] of a cell (index ix + iy * cells) of a cells x cells grid on the module."""
    ix, iy = cell % cells, cell // cells
    return (-module_m[0] / 2 + (ix + 0.5) * module_m[0] / cells, -module_m[1] / 2 + (iy + 0.5) * module_m[1] / cells)


def stratum(x_m: float, y_m: float) -> str:
    """The stratum of a point: centre (|x|, |y| < 0.10 m), corners (both > 0.175 m), edges (one > 0.175 m), and
    between those the ring, split into axes (within 22.5 deg of an axis) and diagonals."""
    ax, ay = abs(x_m), abs(y_m)
    if max(ax, ay) < CENTRAL_HALF_M:
        return "centre"
    if min(ax, ay) > CORNER_FROM_M:
        return "corners"
    if max(ax, ay) > CORNER_FROM_M:
        return "edges"
    return "axes" if min(ax, ay) < math.tan(math.radians(22.5)) * max(ax, ay) else "diagonals"


def strata_cells(cells: int) -> dict[str, list[int]]:
    """The cells of a cells x cells grid by stratum of their centres."""
    out = {name: [] for name in STRATA}
    for cell in range(cells * cells):
        out[stratum(*cell_centre(cell, cells))].append(cell)
    return out


def stratified_draw(cells: int, per_stratum: int, seed: int) -> dict[str, list[int]]:
    """per_stratum cells drawn without replacement from each stratum (all of a smaller one), from the seed alone, in
    the order drawn: the first k of each stratum are a smaller sample of the same kind, nested in the larger."""
    rng = np.random.default_rng([seed, cells, per_stratum])
    strata = strata_cells(cells)
    return {
        name: [int(c) for c in rng.choice(strata[name], size=min(per_stratum, len(strata[name])), replace=False)]
        for name in STRATA
    }


def stratified_sample(cells: int, per_stratum: int, seed: int, first: int | None = None) -> tuple[int, ...]:
    """stratified_draw's cells, each stratum's sorted; with first, only the first that many drawn of each stratum."""
    return tuple(c for drawn in stratified_draw(cells, per_stratum, seed).values() for c in sorted(drawn[:first]))


# ------------------------------------------------------------------------------------------- per controller
@dataclass(frozen=True)
class MapStats:
    """What one controller's trials show: the rates the findings read, under one success rule."""

    trials: int
    central_rate: float  # F1: share of successes among trials with a central target (NaN: none)
    corner_rate: float  # F2 / F3: among trials with a corner target
    shape_index: float  # F4: rank correlation with L-inf closeness minus with L1 closeness (NaN: too few)
    total: float  # F5: estimated sum of the cell rates over the grid, scaled to the paper's 400 cells
    # (NaN if a stratum had no cell run)
    strata_rates: dict[str, float]  # mean cell rate by stratum (NaN where no cell was run)
    fell_rate: float


def _ranks(values: np.ndarray) -> np.ndarray:
    """Ranks 1..n with ties given their mean rank."""
    order = np.argsort(values, kind="mergesort")
    ranks = np.empty(len(values))
    ranks[order] = np.arange(1, len(values) + 1)
    for v in np.unique(values):
        tie = values == v
        ranks[tie] = ranks[tie].mean()
    return ranks


def rank_correlation(a: np.ndarray, b: np.ndarray) -> float:
    """Spearman's rho of a and b (NaN if either is constant)."""
    ra, rb = _ranks(np.asarray(a, float)), _ranks(np.asarray(b, float))
    if ra.std() == 0 or rb.std() == 0:
        return math.nan
    return float(np.corrcoef(ra, rb)[0, 1])


def shape_index(centres: np.ndarray, rates: np.ndarray) -> float:
    """F4's index: rho(rate, -L-inf norm of the cell centre) - rho(rate, -L1 norm): > 0 square, < 0 diamond; 0 for a
    map whose rates are all the same (it has no shape); NaN for fewer than three cells."""
    if len(rates) < 3:
        return math.nan
    if np.all(rates == rates[0]):
        return 0.0
    linf = rank_correlation(rates, -np.abs(centres).max(axis=1))
    l1 = rank_correlation(rates, -np.abs(centres).sum(axis=1))
    return linf - l1


def map_stats(records: Iterable[dict], cells: int, rule: str) -> MapStats:
    """The findings' numbers for one controller's records on a cells x cells grid."""
    records = list(records)
    by_cell: dict[int, list[bool]] = {}
    central, corner = [], []
    for r in records:
        ok = outcome(r, rule)
        by_cell.setdefault(r["cell"], []).append(ok)
        tx, ty = r["target_m"]
        if max(abs(tx), abs(ty)) < CENTRAL_HALF_M:
            central.append(ok)
        if min(abs(tx), abs(ty)) > CORNER_FROM_M:
            corner.append(ok)
    cell_ids = sorted(by_cell)
    rates = np.array([np.mean(by_cell[c]) for c in cell_ids])
    centres = np.array([cell_centre(c, cells) for c in cell_ids]).reshape(-1, 2)
    strata_rates, total = {}, 0.0
    members = strata_cells(cells)
    for name in STRATA:
        run = [rate for c, rate in zip(cell_ids, rates, strict=True) if c in set(members[name])]
        strata_rates[name] = float(np.mean(run)) if run else math.nan
        if members[name]:
            total += len(members[name]) * strata_rates[name]
    total *= PAPER_CELLS**2 / cells**2
    return MapStats(
        trials=len(records),
        central_rate=float(np.mean(central)) if central else math.nan,
        corner_rate=float(np.mean(corner)) if corner else math.nan,
        shape_index=shape_index(centres, rates),
        total=total,
        strata_rates=strata_rates,
        fell_rate=float(np.mean([r["fell_off"] for r in records])) if records else math.nan,
    )


# ------------------------------------------------------------------------------------------- the findings
@dataclass(frozen=True)
class Finding:
    name: str  # F1 .. F6
    claim: str  # the paper's claim
    holds: bool | None  # None: not measured
    measured: str  # what we measured, in words and numbers


def _fmt(x: float) -> str:
    return "n/a" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.2f}"


def heatmap_findings(manhattan: MapStats, euclidean: MapStats) -> list[Finding]:
    """F1-F5 from the two controllers' statistics under the same rule."""
    m, e = manhattan, euclidean
    f1 = m.central_rate >= CENTRAL_AT and e.central_rate >= CENTRAL_AT
    totals_ok = all(
        abs(s.total / PAPER_TOTALS[name] - 1) <= TOTAL_TOLERANCE for name, s in (("manhattan", m), ("euclidean", e))
    )
    ratio = m.total / e.total if e.total > 0 else math.inf
    return [
        Finding(
            "F1",
            "central targets succeed (100 %) with both controllers",
            f1,
            f"central rate Manhattan {_fmt(m.central_rate)}, Euclidean {_fmt(e.central_rate)} (need >= {CENTRAL_AT})",
        ),
        Finding(
            "F2",
            "Manhattan extends reachability to the corners",
            m.corner_rate > FAILURE_REGION_AT,
            f"Manhattan corner rate {_fmt(m.corner_rate)} (need > {FAILURE_REGION_AT})",
        ),
        Finding(
            "F3",
            "corners are entirely unreachable with Euclidean",
            e.corner_rate <= FAILURE_REGION_AT,
            f"Euclidean corner rate {_fmt(e.corner_rate)} (need <= {FAILURE_REGION_AT})",
        ),
        Finding(
            "F4",
            "Manhattan's uncertain region is square, Euclidean's a diamond",
            m.shape_index > 0 > e.shape_index,
            f"shape index Manhattan {_fmt(m.shape_index)} (need > 0), Euclidean {_fmt(e.shape_index)} (need < 0)",
        ),
        Finding(
            "F5",
            f"totals: Manhattan {PAPER_TOTALS['manhattan']}, Euclidean {PAPER_TOTALS['euclidean']} (ratio "
            f"{PAPER_TOTALS['manhattan'] / PAPER_TOTALS['euclidean']:.2f})",
            totals_ok,
            f"Manhattan {m.total:.1f}, Euclidean {e.total:.1f} (ratio {ratio:.2f}; each within "
            f"{TOTAL_TOLERANCE:.0%} of the paper's)",
        ),
    ]


def fig3_finding(records: Iterable[dict]) -> Finding:
    """F6 from the Fig. 3 trials (records with object and reached): every object reaches its target every time."""
    records = list(records)
    by_object: dict[str, list[bool]] = {}
    for r in records:
        by_object.setdefault(r["object"], []).append(bool(r["reached"]) and not r["fell_off"])
    complete = set(by_object) == set(FIG3_ALPHA_M) and all(len(v) >= FIG3_TRIALS for v in by_object.values())
    holds = complete and all(all(v) for v in by_object.values())
    words = ", ".join(f"{name} {sum(v)}/{len(v)}" for name, v in sorted(by_object.items()))
    return Finding(
        "F6",
        "every object reaches a random target within 60 s, 5 of 5 (Fig. 3)",
        holds if records else None,
        words or "not run",
    )


def _short(gap: float) -> float:
    """How far a measure falls short of its finding: the gap if positive, else 0; NaN stays NaN."""
    return gap if math.isnan(gap) else max(0.0, gap)


# The largest value each objective can take: both central rates 0; the corner rates and shape indices as wrong as
# they can be; both totals at the floor of 1.
WORST_OBJECTIVES = (
    2 * CENTRAL_AT,
    FAILURE_REGION_AT + (1 - FAILURE_REGION_AT) + 2 + 2,
    math.log(PAPER_TOTALS["manhattan"]) + math.log(PAPER_TOTALS["euclidean"]),
)


def objectives(manhattan: MapStats, euclidean: MapStats) -> tuple[float, float, float]:
    """What the calibration search minimises (each 0 when its findings hold):
    (central shortfall, F1; corners and shape shortfall, F2-F4; log-distance of the totals from the paper's, F5)."""
    m, e = manhattan, euclidean
    # A measure the trials could not give (no central or corner target, too few cells) is NaN, and so is the
    # objective it enters: the search scores such a candidate as the worst (study.run_study).
    central = _short(CENTRAL_AT - m.central_rate) + _short(CENTRAL_AT - e.central_rate)
    corners = (
        _short(FAILURE_REGION_AT - m.corner_rate)
        + _short(e.corner_rate - FAILURE_REGION_AT)
        + _short(-m.shape_index)
        + _short(e.shape_index)
    )
    floor = 1.0  # [-] a total of 0 (nothing succeeds) counts as 1
    totals = sum(
        abs(math.log(max(s.total, floor) / PAPER_TOTALS[name])) if math.isfinite(s.total) else math.nan
        for name, s in (("manhattan", m), ("euclidean", e))
    )
    return central, corners, totals
