"""Equivalence of paired answers: a difference's 90 % interval against a margin, and how many pairs would decide it.

Two one-sided tests at 5 % each (TOST) say two runs give the same answer within a margin M exactly when the
difference's two-sided 90 % interval lies inside (−M, +M); they differ when it lies wholly outside; otherwise the
sample cannot tell (undecided), and an interval's half-width shrinks as 1/√n, so the pairs that would decide it are
projected from the one measured.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

LEVEL = 0.90  # the intervals' two-sided level: two one-sided tests at 5 % each
Z = 1.6448536269514722  # the standard normal's 95th percentile
EQUIVALENT, DIFFERENT, UNDECIDED = "equivalent", "different", "undecided"


@dataclass(frozen=True)
class Judged:
    """One answer's paired difference (first run minus second), its interval and what they say against the margin."""

    n: int  # pairs behind it
    estimate: float
    low: float
    high: float
    margin: float

    @property
    def status(self) -> str:
        if math.isnan(self.low) or math.isnan(self.high):
            return UNDECIDED
        if -self.margin < self.low and self.high < self.margin:
            return EQUIVALENT
        if self.low >= self.margin or self.high <= -self.margin:
            return DIFFERENT
        return UNDECIDED

    @property
    def pairs_to_decide(self) -> int | None:
        """The pairs (in all, these included) at which this interval, narrowed as 1/√n about the estimate (where
        its centre tends as the pairs grow), would decide it; this many when decided. An estimate on the margin
        asks for twice the pairs (more pairs move it off the margin, or show it is there); None where there is no
        interval to narrow (too few pairs)."""
        if self.status != UNDECIDED:
            return self.n
        if math.isnan(self.low) or math.isnan(self.high) or self.n == 0:
            return None
        half = (self.high - self.low) / 2
        room = abs(self.margin - abs(self.estimate))  # the half-width that would put the interval on its side
        if room < 1e-9 * self.margin:
            return 2 * self.n
        return max(self.n + 1, math.ceil(self.n * (half / room) ** 2))

    def to_json(self, digits: int = 5) -> dict:
        return {
            "n": self.n,
            "estimate": _round(self.estimate, digits),
            "low": _round(self.low, digits),
            "high": _round(self.high, digits),
            "margin": self.margin,
            "status": self.status,
            "pairs_to_decide": self.pairs_to_decide,
        }


def mean_difference(differences, margin: float) -> Judged:
    """The mean of per-pair differences (a rate's: −1, 0 or +1 each; a contrast's: −2 .. +2) with the adjusted Wald
    interval of Agresti and Min: half a pair added at +1 and at −1 and one at 0 (half a pair to each cell of the
    2 × 2 table, for a rate), so a sample with no discordant pair still has an interval of the right order."""
    d = np.asarray(differences, dtype=float)
    n = int(d.size)
    if n == 0:
        return Judged(0, math.nan, math.nan, math.nan, margin)
    n_adj = n + 2
    mean_adj = float(d.sum()) / n_adj
    second = (float(np.square(d).sum()) + 1.0) / n_adj
    half = Z * math.sqrt(max(second - mean_adj**2, 0.0) / n_adj)
    return Judged(n, float(d.mean()), mean_adj - half, mean_adj + half, margin)


def _round(x: float, digits: int) -> float | None:
    return None if math.isnan(x) else round(x, digits)
